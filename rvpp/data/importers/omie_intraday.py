"""OMIE intraday auction marginal price files (``marginalpibc_YYYYMMDDSS.V``).

OMIE publishes one file per delivery day and intraday session (also as yearly ``.zip``
archives of the daily files, which are read too). The name carries what the content does
not: ``YYYYMMDD`` the delivery day, ``SS`` the session number (``01`` is the first
session), ``V`` the version. The content has the layout of the day-ahead files
(:mod:`rvpp.data.importers.omie`)::

    MARGINALPIBC;
    2024;07;01;13;61.20;61.20;
    ...
    *

Each data line is ``YEAR;MONTH;DAY;PERIOD;PRICE_PT;PRICE_ES;`` [EUR/MWh]. The sessions a
file may belong to come from a preset (:data:`PRESETS`):

* ``iberian_2024``: the three pan-European intraday auctions of the Iberian market since
  14 June 2024, IDA1 (gate closure 15:00 on the day before, all periods of the day), IDA2
  (22:00 on the day before, all periods), IDA3 (10:00 on the day, periods from 12:00);
* ``tool_seven``: the seven intraday sessions the seed paper's authors' tool models, IDM1 to
  IDM7, whose windows open at 00:00, 00:00, 04:00, 07:00, 12:00, 16:00 and 20:00 local.

Quirks of the source, each handled here:

* Periods are numbered from 1 at local midnight in Spain and placed by elapsed time, as in
  the day-ahead files (23 or 25 hourly periods on the days the clocks change).
* A session's file holds the periods of its window only: IDA3's starts at 12:00 local
  (hourly period 13, or 12 on the 23-hour day and 14 on the 25-hour day). A line for a
  period before the window is refused, as a sign of a file of another session.
* The intraday auctions moved to quarter-hourly periods before the day-ahead market did:
  from delivery day 2025-03-19 (:data:`QUARTER_HOURS_FROM`) by the market reform timeline
  as third parties record it; OMIE's own notice was not available to check. Either way a
  file is refused rather than misread: on a quarter-hourly day, a file whose periods all
  fit in the day's hourly count is an hourly file and is refused; on an hourly day a period
  beyond the day's hours cannot be placed and is refused.
* Lines must be dated the delivery day of the file's name; a line of another day (the old
  first sessions also traded the last hours of the day before) is refused, not moved.
* Corrected files are republished with a higher version; two versions of one day and
  session with different prices are refused rather than guessed, identical ones kept once.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd

from ...errors import DataImportError
from ..files import excerpt
from ..intraday import PRESET_SESSIONS, IntradaySettings
from . import omie
from .report import Imported, Rows, SourceFile, assemble, check_year, decode, fingerprint, read_bytes

SOURCE = "OMIE intraday auction marginal prices (marginalpibc)"
TIMEZONE = omie.TIMEZONE
HEADER = "MARGINALPIBC"
PREFIX = "marginalpibc"
QUARTER_HOURS_FROM = dt.date(2025, 3, 19)
# marginalpibc_YYYYMMDDSS.V: delivery day, session number (two digits), version
FILE_NAME = re.compile(r"marginalpibc_(\d{4})(\d{2})(\d{2})(\d{2})\.(\d{1,3})", re.IGNORECASE)
NAME_RULE = "an OMIE intraday price file is named marginalpibc_YYYYMMDDSS.V (day, session number, version)"


@dataclass(frozen=True)
class Session:
    """An intraday session: its name and the local clock hour its delivery window starts at."""

    name: str
    first_hour: int

    @property
    def column(self) -> str:
        """The history column of its prices: ``price_ida2`` [EUR/MWh]."""
        return f"price_{self.name.lower()}"


# The sessions of the case's presets (rvpp.data.intraday), each by the hour its window opens.
PRESETS: dict[str, tuple[Session, ...]] = {
    preset: tuple(Session(s.name, s.window_minutes // 60) for s in sessions)
    for preset, sessions in PRESET_SESSIONS.items()}
DEFAULT_PRESET = IntradaySettings().preset


def sessions_of(preset: str) -> tuple[Session, ...]:
    """The sessions of a preset, or a named error listing the presets."""
    if preset not in PRESETS:
        raise DataImportError(f"--sessions {excerpt(preset)!r} is not a preset of intraday sessions; choose "
                              + " or ".join(PRESETS))
    return PRESETS[preset]


def looks_like(text: str) -> bool:
    """True for the text of a marginalpibc file."""
    return text.lstrip().upper().startswith(HEADER)


@dataclass(frozen=True)
class FileName:
    """What a file's name says: delivery day, session (1-based number) and version."""

    day: dt.date
    number: int
    version: int


def parse_name(name: str) -> FileName:
    """Read ``marginalpibc_2024070102.1``; any other name is refused (the session is only in the name)."""
    found = FILE_NAME.fullmatch(name)
    if found is None:
        raise DataImportError(f'"{excerpt(name)}": {NAME_RULE}; the session cannot be told from the content')
    year, month, day, number, version = (int(g) for g in found.groups())
    check_year(year, f'"{name}"', f"the year {year} of its name")
    try:
        return FileName(dt.date(year, month, day), number, version)
    except ValueError:
        raise DataImportError(f'"{name}": {year:04d}-{month:02d}-{day:02d} in its name is not a date') from None


def read(paths: list[str | Path], preset: str = DEFAULT_PRESET, zone: str = "ES",
         days: tuple[dt.date | None, dt.date | None] | None = None) -> list[Imported]:
    """Read marginalpibc files (or zip archives of them): one :class:`Imported` per session found,
    in the preset's order, each with one series ``price_<session>`` (e.g. ``price_ida2``).

    ``days`` (first, last; either may be ``None``, open), when given, are the delivery days asked for:
    a file of another day is refused by name.
    """
    sessions = sessions_of(preset)
    zone = zone.upper()
    if zone not in omie.ZONES:
        raise DataImportError(f"zone={excerpt(zone)!r} is not an OMIE zone; choose ES or PT")
    if not paths:
        raise DataImportError("no intraday price file given")
    found: dict[int, tuple[Rows, list[SourceFile], set[dt.date]]] = {}
    for path in paths:
        data = read_bytes(path)
        name = Path(path).name
        if omie.is_archive(Path(path), data):
            for member, content in omie.members(name, data, PREFIX):
                _read_file(member[len(name) + 1:], member, content, sessions, preset, zone, days, found)
            continue
        _read_file(name, name, data, sessions, preset, zone, days, found)
    out = []
    for number in sorted(found):
        session = sessions[number - 1]
        rows, files, met = found[number]
        notes = [f"periods numbered from local midnight ({TIMEZONE}); quarter-hourly from {QUARTER_HOURS_FROM}",
                 f"{session.name} delivers from {session.first_hour:02d}:00 local ({preset})"]
        clock = [f"{day}: {omie.day_hours(day)}-hour day" for day in sorted(met) if omie.day_hours(day) != 24]
        item = assemble(rows, source=f"{SOURCE}, {session.name}", files=files, timezone=TIMEZONE,
                        zone=f"{zone} ({omie.ZONE_NAMES[zone]})",
                        meanings={session.column: f"{session.name} marginal price, {omie.ZONE_NAMES[zone]}"},
                        dst=clock, notes=notes)
        # the hours before a window are no gap: the session does not trade them
        gaps = tuple(g for g in item.report.gaps if not _before_window(g.start, g.end, session))
        out.append(replace(item, report=replace(item.report, gaps=gaps)))
    return out


def _before_window(start: pd.Timestamp, end: pd.Timestamp, session: Session) -> bool:
    """True for a stretch from a local midnight to the session's window start of that day."""
    day = start.tz_convert(TIMEZONE).date()
    return start == omie.midnight(day) and end == window_start(day, session)


def window_start(day: dt.date, session: Session) -> pd.Timestamp:
    """UTC instant the session's delivery window starts on ``day`` (its first hour, local clock)."""
    local = pd.Timestamp(day) + pd.Timedelta(hours=session.first_hour)
    return local.tz_localize(TIMEZONE).tz_convert("UTC")


def in_window(index: pd.DatetimeIndex, session: Session) -> pd.Series:
    """True for the hours (UTC hour-beginning ``index``) that lie in the session's window of their local day."""
    local = index.tz_convert(TIMEZONE)
    return pd.Series(local.hour >= session.first_hour, index=index)


def _read_file(name: str, where_name: str, data: bytes, sessions: tuple[Session, ...], preset: str, zone: str,
               days: tuple[dt.date | None, dt.date | None] | None, found: dict) -> None:
    """One daily file: its name checked against the preset and the days asked, then its lines."""
    said = parse_name(name)
    if not 1 <= said.number <= len(sessions):
        raise DataImportError(
            f'"{where_name}": session {said.number:02d} is not one of the {len(sessions)} sessions of {preset} '
            f"({sessions[0].name} to {sessions[-1].name}, numbered 01 to {len(sessions):02d})")
    first, last = days or (None, None)
    if (first is not None and said.day < first) or (last is not None and said.day > last):
        asked = f"{first} to {last}" if first and last else f"from {first}" if first else f"up to {last}"
        raise DataImportError(f'"{where_name}" is for delivery day {said.day}, outside the days asked ({asked})')
    session = sessions[said.number - 1]
    rows, files, met = found.setdefault(said.number, (Rows(), [], set()))
    _read_text(decode(data, where_name), where_name, said.day, session, zone, rows)
    files.append(SourceFile(where_name, fingerprint(data), data.count(b"\n")))
    met.add(said.day)


def _read_text(text: str, name: str, day: dt.date, session: Session, zone: str, rows: Rows) -> None:
    lines = text.splitlines()
    if not lines or not looks_like(lines[0]):
        first = excerpt(lines[0].strip(), 40) if lines else ""
        hint = " (a day-ahead file)" if first.upper().startswith(omie.HEADER) else ""
        raise DataImportError(f'{name}: line 1 must be "MARGINALPIBC;" (an OMIE marginalpibc file), '
                              f"not {first!r}{hint}")
    column = omie.ZONES[zone]
    step = _step(day)
    count = int(round(omie.day_hours(day) * pd.Timedelta(hours=1) / step))
    opens = window_start(day, session)
    periods, priced = [], 0
    for where, fields in omie.data_lines(lines, name):
        dated = omie.date_of(fields[:3], where)
        if dated != day:
            raise DataImportError(f"{where}: the line is dated {dated} but the file's name is for {day}; "
                                  "each daily file holds its own day only")
        period = omie.whole(fields[3], "PERIOD", where)
        if not 1 <= period <= count:
            raise DataImportError(f"{where}: PERIOD={period} does not exist on {day}, which has {count} periods "
                                  f"of {step.total_seconds() / 60:g} minutes")
        start = omie.period_start(day, period, step)
        if start < opens:
            raise DataImportError(
                f"{where}: PERIOD={period} starts at {start.tz_convert(TIMEZONE):%H:%M} local, before "
                f"{session.name}'s window opens at {session.first_hour:02d}:00; is the file of another session?")
        price = omie.price(fields[column], where)
        priced += not math.isnan(price)
        rows.add(start, start + step, {session.column: price}, where)
        periods.append(period)
    if not periods:
        raise DataImportError(f"{name}: no data lines")
    if not priced:
        raise DataImportError(f"{name}: no line gives a price for {omie.ZONE_NAMES[zone]} ({zone}); the file may "
                              "be for another zone")
    hours = omie.day_hours(day)
    if step < pd.Timedelta(hours=1) and max(periods) <= hours:
        raise DataImportError(
            f"{name}: its periods stop at {max(periods)}, within the {hours} hours of the day, but from "
            f"{QUARTER_HOURS_FROM} the intraday auctions have {count} quarter-hourly periods a day; an hourly "
            "file is refused rather than read as quarter-hours")


def _step(day: dt.date) -> pd.Timedelta:
    return pd.Timedelta(minutes=15) if day >= QUARTER_HOURS_FROM else pd.Timedelta(hours=1)
