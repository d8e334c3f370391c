"""OMIE day-ahead marginal price files (``marginalpdbc_YYYYMMDD.1``).

OMIE publishes one file per delivery day on its website (Day-ahead market prices; also
as yearly ``.zip`` archives of the daily files, which are read too)::

    MARGINALPDBC;
    2018;03;25;1;11.50;11.50;
    ...
    2018;03;25;23;48.00;48.00;
    *

Each data line is ``YEAR;MONTH;DAY;PERIOD;PRICE_PT;PRICE_ES;`` [EUR/MWh]: the Portuguese
price first, then the Spanish one (they differ only when the interconnection is
congested). Quirks of the source, each handled here:

* Periods are numbered from 1 starting at **local midnight in Spain** (Europe/Madrid),
  i.e. period 1 is 00:00-01:00: hour-*ending* numbering (hour 1 ends at 01:00).
  Period ``k`` starts ``(k - 1)`` periods of *elapsed* time after local midnight, so on
  the 23-hour day in March period 3 starts at 03:00 CEST (there is no 02:00), and on the
  25-hour day in October periods 3 and 4 both start at 02:00 local time, first in summer
  time (+02:00, 00:00 UTC) then in winter time (+01:00, 01:00 UTC).
* Hourly periods (23, 24 or 25 a day) until delivery day 2025-09-30; quarter-hourly
  periods (92, 96 or 100 a day) from 2025-10-01, when the day-ahead market moved to a
  15-minute market time unit. The resolution of a day follows that date.
* A period number beyond the day's count (e.g. 24 on a 23-hour day) cannot be placed in
  time and is refused; a day with fewer lines than periods has gaps, listed.
* Corrected files are republished with a higher version suffix (``.2``); giving two
  versions of one day with different prices is refused rather than guessed.
"""

from __future__ import annotations

import datetime as dt
import io
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pandas as pd

from ...errors import DataImportError
from ..files import UNREADABLE_ZIP, excerpt, unpacking
from .report import Imported, Rows, SourceFile, assemble, check_year, decode, fingerprint, read_bytes

SOURCE = "OMIE day-ahead marginal prices (marginalpdbc)"
TIMEZONE = "Europe/Madrid"
HEADER = "MARGINALPDBC"
ZONES = {"PT": 4, "ES": 5}
ZONE_NAMES = {"PT": "Portugal", "ES": "Spain"}
QUARTER_HOURS_FROM = dt.date(2025, 10, 1)
MAX_ZIP_MEMBERS = 5000
MAX_MEMBER_BYTES = 1_000_000


def looks_like(text: str) -> bool:
    """True for the text of a marginalpdbc file."""
    return text.lstrip().upper().startswith(HEADER)


def is_archive(path: Path, data: bytes) -> bool:
    """True for a zip archive (OMIE's yearly downloads)."""
    return data[:4] == b"PK\x03\x04"


def read(paths: list[str | Path], zone: str = "ES") -> Imported:
    """Read marginalpdbc files (or zip archives of them) into one price series ``price_da``."""
    zone = zone.upper()
    if zone not in ZONES:
        raise DataImportError(f"zone={excerpt(zone)!r} is not an OMIE zone; choose ES or PT")
    rows, files, days = Rows(), [], {}  # days: periods met per delivery day
    for path in paths:
        data = read_bytes(path)
        name = Path(path).name
        if is_archive(Path(path), data):
            for member, content in members(name, data):
                _read_text(decode(content, member), member, zone, rows, days)
                files.append(SourceFile(member, fingerprint(content), content.count(b"\n")))
            continue
        _read_text(decode(data, name), name, zone, rows, days)
        files.append(SourceFile(name, fingerprint(data), data.count(b"\n")))
    clock = []
    for day, periods in sorted(days.items()):
        hours, count = day_hours(day), len(periods)
        if hours == 23:
            step = _step(day)
            first = period_start(day, 3 if step == pd.Timedelta(hours=1) else 9, step)
            local = first.tz_convert(TIMEZONE)
            clock.append(f"{day}: 23-hour day (clocks go forward at 02:00); {count} periods, period "
                         f"{3 if step == pd.Timedelta(hours=1) else 9} starts at {local:%H:%M} (+02:00)")
        elif hours == 25:
            clock.append(f"{day}: 25-hour day (clocks go back at 03:00); {count} periods, 02:00 local occurs "
                         "twice: first at +02:00 (00:00 UTC), then at +01:00 (01:00 UTC)")
    notes = [f"periods numbered from local midnight ({TIMEZONE}); quarter-hourly from {QUARTER_HOURS_FROM}"]
    return assemble(rows, source=SOURCE, files=files, timezone=TIMEZONE, zone=f"{zone} ({ZONE_NAMES[zone]})",
                    meanings={"price_da": f"day-ahead marginal price, {ZONE_NAMES[zone]}"}, dst=clock, notes=notes)


def members(name: str, data: bytes, prefix: str = "marginalpdbc"):
    """Daily files whose names start with ``prefix`` inside an archive, with limits against oversized
    or nested content."""
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except UNREADABLE_ZIP:
        raise DataImportError(f'"{name}" is not a readable zip archive') from None
    entries = [e for e in archive.infolist() if not e.is_dir()]
    if len(entries) > MAX_ZIP_MEMBERS:
        raise DataImportError(f'"{name}" holds {len(entries)} files; at most {MAX_ZIP_MEMBERS} are read')
    found = 0
    for entry in sorted(entries, key=lambda e: e.filename):
        member = f"{name}:{Path(entry.filename).name}"
        if not Path(entry.filename).name.lower().startswith(prefix):
            continue
        if entry.file_size > MAX_MEMBER_BYTES:
            raise DataImportError(f"{member} is {entry.file_size / 1e6:.1f} MB unpacked; a daily file is far "
                                  "smaller, so it is refused")
        with unpacking(name, entry, DataImportError):  # damaged, encrypted, an unknown method
            with archive.open(entry) as handle:
                content = handle.read(MAX_MEMBER_BYTES + 1)
        if len(content) > MAX_MEMBER_BYTES:  # the size in the zip's records was wrong
            raise DataImportError(f"{member} unpacks to more than {MAX_MEMBER_BYTES / 1e6:.1f} MB; a daily file "
                                  "is far smaller, so it is refused")
        found += 1
        yield member, content
    if not found:
        raise DataImportError(f'"{name}" holds no {prefix} file')


def _read_text(text: str, name: str, zone: str, rows: Rows, days: dict[dt.date, set[int]]) -> None:
    lines = text.splitlines()
    if not lines or not looks_like(lines[0]):
        raise DataImportError(f'{name}: line 1 must be "MARGINALPDBC;" (an OMIE marginalpdbc file)')
    column = ZONES[zone]
    for where, fields in data_lines(lines, name):
        day = date_of(fields[:3], where)
        period = whole(fields[3], "PERIOD", where)
        step = _step(day)
        count = int(round(day_hours(day) * pd.Timedelta(hours=1) / step))
        if not 1 <= period <= count:
            raise DataImportError(f"{where}: PERIOD={period} does not exist on {day}, which has {count} periods "
                                  f"of {step.total_seconds() / 60:g} minutes")
        start = period_start(day, period, step)
        rows.add(start, start + step, {"price_da": price(fields[column], where)}, where)
        days.setdefault(day, set()).add(period)


def data_lines(lines: list[str], name: str) -> Iterator[tuple[str, list[str]]]:
    """The data lines of an OMIE price file after its header line (day-ahead or intraday): ``(where,
    fields)`` per line, empty lines skipped, each with the six fields
    ``YEAR;MONTH;DAY;PERIOD;PRICE_PT;PRICE_ES``; the closing ``*`` is required and nothing may follow it."""
    ended = False
    for number, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        if line == "*":
            ended = True
            continue
        where = f"{name} line {number}"
        if ended:
            raise DataImportError(f"{where}: data after the closing '*'")
        fields = line.removesuffix(";").split(";")  # one closing ";" per line
        if len(fields) < 6:
            raise DataImportError(f"{where}: expected YEAR;MONTH;DAY;PERIOD;PRICE_PT;PRICE_ES; but found "
                                  f"{len(fields)} fields")
        yield where, fields
    if not ended:
        raise DataImportError(f"{name}: the closing line '*' is missing; the file may be cut short")


def date_of(fields: list[str], where: str) -> dt.date:
    year, month, day = (whole(f, n, where) for f, n in zip(fields, ("YEAR", "MONTH", "DAY")))
    check_year(year, where, f"YEAR={year}")
    try:
        return dt.date(year, month, day)
    except ValueError:
        raise DataImportError(f"{where}: {year:04d}-{month:02d}-{day:02d} is not a date") from None


def whole(text: str, field: str, where: str) -> int:
    try:
        return int(text.strip())
    except ValueError:
        raise DataImportError(f"{where}: {field}={excerpt(text.strip())!r} must be a whole number") from None


def price(text: str, where: str) -> float:
    text = text.strip()
    if not text:
        return float("nan")
    try:
        value = float(text.replace(",", ".") if "." not in text else text)
    except ValueError:
        raise DataImportError(f"{where}: price {excerpt(text)!r} is not a number") from None
    if value != value or abs(value) == float("inf"):
        raise DataImportError(f"{where}: price {excerpt(text)!r} is not a finite number")
    return value


def _step(day: dt.date) -> pd.Timedelta:
    return pd.Timedelta(minutes=15) if day >= QUARTER_HOURS_FROM else pd.Timedelta(hours=1)


def midnight(day: dt.date) -> pd.Timestamp:
    return pd.Timestamp(day).tz_localize(TIMEZONE).tz_convert("UTC")


def day_hours(day: dt.date) -> int:
    return int(round((midnight(day + dt.timedelta(days=1)) - midnight(day)) / pd.Timedelta(hours=1)))


def period_start(day: dt.date, period: int, step: pd.Timedelta) -> pd.Timestamp:
    """UTC start of ``period`` (1-based): elapsed time from local midnight, not clock time."""
    return midnight(day) + (period - 1) * step
