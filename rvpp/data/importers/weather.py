"""Weather CSV files: a time column and an air temperature [°C], optionally its day-ahead forecast.

A weather file is any comma-, semicolon- or tab-separated table with a header line, such as a
national met service's station download or a reanalysis export saved as CSV::

    time,temperature,temperature_forecast
    2018-01-01T00:00:00+01:00,6.2,5.8
    2018-01-01T01:00:00+01:00,5.9,5.5

The columns are found by name (case does not matter, a unit in brackets after the name is
read, e.g. ``temperature [°C]`` or ``t2m (K)``): the time from :data:`TIME_NAMES`, the
temperature from :data:`TEMPERATURE_NAMES` and the forecast from :data:`FORECAST_NAMES`,
or named by the user (:class:`WeatherColumns`, ``--weather-columns``). They become the
series ``temperature`` and ``temperature_forecast`` [°C].

Quirks of such files, each handled here:

* **Times**: ISO 8601 with a UTC offset (``+01:00``, ``Z``) are exact. Times without an
  offset are local to the clock the user names (``--weather-timezone``, e.g. ``UTC`` or
  ``Europe/Madrid``); without it they are refused rather than guessed. On the day clocks
  go forward a local time that does not exist is refused; on the day they go back a local
  time given twice is placed first in summer, then in winter time, and one given once
  cannot be placed and is refused.
* **Each row's time starts its period**, the period being the file's step (the most
  common spacing of its rows, 60 minutes or a whole divisor of it). An instantaneous
  reading at the hour (ERA5's ``t2m``, a synoptic observation) is thus taken for the hour
  that begins then. Rows closer than the step overlap and are refused; a longer spacing is
  a gap, listed. Steps above an hour (3-hourly, daily) are refused: they cannot give hours.
* **Reanalysis temperatures are in kelvin** (ERA5's ``t2m``): a header unit ``K`` is
  converted to °C and said so; a column without a unit is taken as °C, and values outside
  :data:`TEMPERATURE_RANGE_C` are refused, with a hint when they look like kelvin.
* Some downloads describe the site before the table (Open-Meteo's CSV: latitude, longitude,
  elevation and time zone, a blank line, then ``time,temperature_2m (°C)``): up to
  :data:`PREAMBLE_LINES` lines before the header are skipped and said so.
* Spreadsheet exports of continental Europe separate cells by ``;`` and write decimal
  commas (``12,5``); both are read. An empty cell, ``NaN``, ``NA`` or ``-`` is a missing
  value, reported and never filled.

Rows must be in time order; a repeated time with the same values is dropped and listed, one
with other values refused (:func:`rvpp.data.importers.report.assemble`).
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

import numpy as np
import pandas as pd

from ...errors import DataImportError
from ..files import excerpt, excerpt_names
from .report import (FIRST_YEAR, HOUR, LAST_YEAR, Imported, Rows, SourceFile, assemble, check_year, decode,
                     fingerprint, read_bytes)

SOURCE = "Weather table (time, air temperature)"
TIME_NAMES = ("time", "timestamp", "datetime", "date_time", "time_utc", "valid_time", "date")
TEMPERATURE_NAMES = ("temperature", "temp", "t2m", "air_temperature", "temperature_2m", "tas", "t")
FORECAST_NAMES = ("temperature_forecast", "forecast_temperature", "temp_forecast", "t2m_forecast",
                  "temperature_fc", "temp_fc")
SERIES = {"temperature": "temperature", "forecast": "temperature_forecast"}  # role -> canonical series
# The lowest and highest air temperatures measured on Earth are -89.2 °C and 56.7 °C; a value
# outside this range is a wrong unit or a sentinel (-99, -9999, 999), not weather.
TEMPERATURE_RANGE_C = (-90.0, 60.0)
KELVIN_AT_0_C = 273.15
CELSIUS_UNITS = {"°c", "ºc", "degc", "deg c", "c", "celsius", "degrees c", "degree c"}
KELVIN_UNITS = {"k", "kelvin"}
EMPTY = {"", "nan", "na", "n/a", "-"}
ROLES = ("time", "temperature", "forecast")
PREAMBLE_LINES = 10  # lines a download may put before the header (Open-Meteo: site and time zone)
LIMIT_MB = 512.0  # the largest file read, as for the other importers (20 years of 10-minute rows is ~60 MB)

_UNIT = re.compile(r"^(?P<name>.*?)\s*[\[(](?P<unit>[^\])]*)[\])]\s*$")
_TIME = re.compile(r"^(\d{4})-(\d{2})-(\d{2})[T ](\d{2}):(\d{2})(?::(\d{2})(?:\.\d+)?)?\s*"
                   r"(Z|UTC|[+-]\d{2}(?::?\d{2})?)?$")


@dataclass(frozen=True)
class WeatherColumns:
    """Column names the user chose (``None``: found from the module's lists of names)."""

    time: str | None = None
    temperature: str | None = None
    forecast: str | None = None

    @classmethod
    def parse(cls, pairs: list[str] | tuple[str, ...] | None) -> WeatherColumns:
        """``["time=fecha", "temperature=ta"]`` (the words of ``--weather-columns``)."""
        chosen: dict[str, str] = {}
        for pair in pairs or ():
            role, sep, column = str(pair).partition("=")
            role = role.strip().lower()
            if not sep or role not in ROLES or not column.strip():
                raise DataImportError(f"--weather-columns {excerpt(pair)!r} must be ROLE=COLUMN with ROLE one of "
                                      f"{', '.join(ROLES)} (e.g. temperature=t2m)")
            if role in chosen:
                raise DataImportError(f"--weather-columns names the {role} column twice")
            chosen[role] = column.strip()
        return cls(**chosen)


def zone_of(name: str | None) -> ZoneInfo | None:
    """The time zone ``name`` (``--weather-timezone``), refused by name when unknown."""
    if name is None:
        return None
    try:
        return ZoneInfo(str(name))
    except (ZoneInfoNotFoundError, ValueError, TypeError):
        raise DataImportError(f"--weather-timezone {excerpt(name)!r} is not a time zone; give a name such as UTC "
                              "or Europe/Madrid") from None


def read(path: str | Path, columns: WeatherColumns = WeatherColumns(), timezone: str | None = None) -> Imported:
    """Read a weather CSV into ``temperature`` (and ``temperature_forecast``) [°C], on its own
    step; ``timezone``: the clock of times written without an offset."""
    zone = zone_of(timezone)
    data = read_bytes(path, LIMIT_MB)
    name = Path(path).name
    text = decode(data, name)
    delimiter = _delimiter(text)
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    lines = [(reader.line_num, row) for row in reader if any(cell.strip() for cell in row)]
    if not lines:
        raise DataImportError(f"{name}: the file is empty")
    skipped = _header_line(lines, columns, name)
    header = [cell.strip() for cell in lines[skipped][1]]
    found = _columns(header, columns, name)
    body = lines[skipped + 1:]
    if not body:
        raise DataImportError(f"{name}: has a header but no rows of data")
    width = len(header)
    for number, row in body:
        if len(row) != width:
            raise DataImportError(f"{name} line {number}: {len(row)} cells where the header has {width}")
    where = [f"{name} line {number}" for number, _ in body]
    time_index = found["time"][0]
    starts, dst = _instants([row[time_index].strip() for _, row in body], where, zone, header[time_index])
    step = _step(starts, where, header[time_index])
    values, meanings = {}, {}
    notes = [f"skipped {skipped} line(s) before the header (a description of the download)"] if skipped else []
    for role in ("temperature", "forecast"):
        if role not in found:
            continue
        index, unit = found[role]
        series = SERIES[role]
        values[series] = _temperatures([row[index] for _, row in body], where, header[index], unit,
                                       decimal_comma=delimiter != ",")
        what = "air temperature" if role == "temperature" else "day-ahead forecast of the air temperature"
        meanings[series] = f'{what}, column "{excerpt(header[index])}"'
        if unit == "K":
            notes.append(f'column "{excerpt(header[index])}" is in kelvin: converted to °C (− {KELVIN_AT_0_C})')
    rows = Rows()
    rows.add_table(starts, starts + step, pd.DataFrame(values), where)
    file = SourceFile(name, fingerprint(data), len(body))
    return assemble(rows, source=SOURCE, files=[file], timezone=timezone or "UTC", zone=None, meanings=meanings,
                    dst=dst, notes=notes)


def _delimiter(text: str) -> str:
    """The separator: the most frequent of comma, semicolon and tab in the first line (a decimal
    comma comes with a semicolon or a tab, never in a header)."""
    first = next((line for line in text.splitlines() if line.strip()), "")
    counts = {d: first.count(d) for d in (",", ";", "\t")}
    return max(counts, key=lambda d: (counts[d], d == ","))


def _header_line(lines: list[tuple[int, list[str]]], chosen: WeatherColumns, name: str) -> int:
    """How many lines come before the header: the first of :data:`PREAMBLE_LINES` lines whose
    cells name a time and a temperature column (0 when none does, so its error names line 1)."""
    for i, (_, row) in enumerate(lines[:PREAMBLE_LINES + 1]):
        try:
            _columns([cell.strip() for cell in row], chosen, name)
        except DataImportError:
            continue
        return i
    return 0


def _split_unit(cell: str) -> tuple[str, str | None]:
    match = _UNIT.match(cell)
    if match and match.group("name").strip():
        return match.group("name").strip(), match.group("unit").strip()
    return cell.strip(), None


def _columns(header: list[str], chosen: WeatherColumns, name: str) -> dict[str, tuple[int, str | None]]:
    """Each role's column index and temperature unit (``"C"``, ``"K"``, ``None`` for the time)."""
    bare = [_split_unit(cell)[0].lower() for cell in header]
    found: dict[str, tuple[int, str | None]] = {}
    lists = {"time": TIME_NAMES, "temperature": TEMPERATURE_NAMES, "forecast": FORECAST_NAMES}
    for role in ROLES:
        wanted = getattr(chosen, role)
        if wanted is not None:
            at = [i for i, cell in enumerate(header) if wanted.lower() in (cell.lower(), bare[i])]
            if not at:
                raise DataImportError(f'{name}: no column "{excerpt(wanted)}" (the {role} column named by '
                                      f"--weather-columns); the header has {excerpt_names(header)}")
        else:
            at = []
            for candidate in lists[role]:  # the first name of the list the header has wins
                at = [i for i, b in enumerate(bare) if b == candidate]
                if at:
                    break
            if not at:
                if role == "forecast":
                    continue
                raise DataImportError(f"{name}: no {role} column (looked for {', '.join(lists[role])}); the header "
                                      f"has {excerpt_names(header)}; name it with --weather-columns {role}=COLUMN")
        if len(at) > 1:
            raise DataImportError(f'{name}: the header has "{excerpt(header[at[0]])}" {len(at)} times; '
                                  f"keep one {role} column")
        index = at[0]
        if any(index == other for other, _ in found.values()):
            raise DataImportError(f'{name}: column "{excerpt(header[index])}" cannot be both the {role} and '
                                  "another column; name them with --weather-columns")
        found[role] = (index, None if role == "time" else _unit(header[index], name))
    return found


def _unit(cell: str, name: str) -> str:
    unit = _split_unit(cell)[1]
    if unit is None or unit.lower() in CELSIUS_UNITS:
        return "C"
    if unit.lower() in KELVIN_UNITS:
        return "K"
    raise DataImportError(f'{name}: column "{excerpt(cell)}" is in {excerpt(unit)!r}; rvpp reads °C or K')


def _instants(text: list[str], where: list[str], zone: ZoneInfo | None,
              column: str) -> tuple[pd.DatetimeIndex, list[str]]:
    """UTC start of every row, in row order, and a note per clock change met."""
    naive, offsets = [], []
    for i, value in enumerate(text):
        match = _TIME.match(value)
        if not match:
            raise DataImportError(f"{where[i]}: {excerpt(column)} {excerpt(value)!r} is not a time such as "
                                  "2018-01-01T00:00:00+01:00 (ISO 8601, with its UTC offset or a stated "
                                  "--weather-timezone)")
        year, month, day, hour, minute, second, offset = match.groups()
        if not FIRST_YEAR <= int(year) <= LAST_YEAR:
            check_year(int(year), where[i], f"{excerpt(column)} {excerpt(value)!r}")
        try:
            naive.append(dt.datetime(int(year), int(month), int(day), int(hour), int(minute), int(second or 0)))
        except ValueError:
            raise DataImportError(f"{where[i]}: {excerpt(column)} {excerpt(value)!r} is not a valid date and "
                                  "time") from None
        offsets.append(offset)
    with_offset = np.array([offset is not None for offset in offsets])
    if with_offset.any() and not with_offset.all():
        i = int(np.flatnonzero(with_offset != with_offset[0])[0])
        raise DataImportError(f"{where[i]}: {excerpt(column)} {excerpt(text[i])!r} "
                              f"{'has' if with_offset[i] else 'has no'} UTC offset, unlike the first row; "
                              "write every time the same way")
    local = pd.DatetimeIndex(naive)
    if with_offset.all():
        shifts = {offset: _offset(offset) for offset in set(offsets)}
        starts = (local - pd.TimedeltaIndex([shifts[offset] for offset in offsets])).tz_localize("UTC")
        notes = [f"times carry UTC offsets ({', '.join(sorted(shifts))}); clock changes are placed by them"] \
            if len(shifts) > 1 else []
        return _ordered(starts, text, where, column), notes
    if zone is None:
        raise DataImportError(f"{where[0]}: {excerpt(column)} {excerpt(text[0])!r} has no UTC offset; say which "
                              "clock the file's times are on with --weather-timezone (e.g. UTC or Europe/Madrid)")
    summer = local.tz_localize(zone.key, ambiguous=np.ones(len(local), dtype=bool), nonexistent="NaT")
    if summer.isna().any():
        i = int(np.flatnonzero(summer.isna())[0])
        raise DataImportError(f"{where[i]}: local time {naive[i]:%Y-%m-%d %H:%M} does not exist in {zone.key} "
                              "(clocks go forward); it cannot be placed in time")
    twice = np.flatnonzero(local.tz_localize(zone.key, ambiguous="NaT", nonexistent="NaT").isna())
    in_summer = np.ones(len(local), dtype=bool)
    if len(twice):
        repeated = pd.Series(local[twice])
        counts = repeated.map(repeated.value_counts()).to_numpy()
        if (counts != 2).any():
            k = int(np.flatnonzero(counts != 2)[0])
            i = int(twice[k])
            raise DataImportError(f"{where[i]}: local time {naive[i]:%Y-%m-%d %H:%M} occurs twice in {zone.key} "
                                  f"(clocks go back) but the file gives it {counts[k]} time(s); it cannot be "
                                  "placed: write the times with their UTC offsets")
        in_summer[twice] = ~repeated.duplicated(keep="first").to_numpy()  # the first is summer time
    starts = local.tz_localize(zone.key, ambiguous=in_summer).tz_convert("UTC")
    notes = []
    for day in sorted(set(local.normalize().unique().date)):
        hours = _day_hours(day, zone)
        if hours != 24:
            rule = "clocks go forward, one local hour does not exist" if hours < 24 else \
                "clocks go back, one local hour occurs twice: first in summer, then in winter time"
            notes.append(f"{day}: {hours}-hour day in {zone.key} ({rule})")
    return _ordered(starts, text, where, column), notes


def _offset(text: str) -> dt.timedelta:
    if text in ("Z", "UTC"):
        return dt.timedelta(0)
    sign = -1 if text[0] == "-" else 1
    digits = text[1:].replace(":", "")
    return sign * dt.timedelta(hours=int(digits[:2]), minutes=int(digits[2:4] or 0))


def _day_hours(day: dt.date, zone: ZoneInfo) -> int:
    start = dt.datetime.combine(day, dt.time(), tzinfo=zone)
    end = dt.datetime.combine(day + dt.timedelta(days=1), dt.time(), tzinfo=zone)
    return round((end.astimezone(dt.timezone.utc) - start.astimezone(dt.timezone.utc)) / dt.timedelta(hours=1))


def _ordered(starts: pd.DatetimeIndex, text: list[str], where: list[str], column: str) -> pd.DatetimeIndex:
    back = np.flatnonzero(np.diff(starts.asi8) < 0)
    if len(back):
        i = int(back[0]) + 1
        raise DataImportError(f"{where[i]}: {excerpt(column)} {excerpt(text[i])!r} is before the row above it "
                              f"({excerpt(text[i - 1])!r}); rows must be in time order")
    return starts


def _step(starts: pd.DatetimeIndex, where: list[str], column: str) -> pd.Timedelta:
    """The file's period: the most common spacing of its rows (60 minutes or a whole divisor)."""
    index = starts
    spacing = pd.Series(index[1:] - index[:-1])
    spacing = spacing[spacing > pd.Timedelta(0)]
    if spacing.empty:
        raise DataImportError(f"{where[0]}: the file has one time only; give at least two, so its step can be "
                              "told (hourly or finer)")
    step = pd.Timedelta(spacing.value_counts().sort_index(kind="stable").idxmax())
    minutes = step / pd.Timedelta(minutes=1)
    if step > HOUR:
        raise DataImportError(f"{where[0]}: the rows are {minutes:g} minutes apart; a weather file must be hourly or "
                              "finer (a day's mean temperature cannot give its hours)")
    if minutes != int(minutes) or HOUR % step != pd.Timedelta(0):
        raise DataImportError(f"{where[0]}: the rows are {minutes:g} minutes apart, which does not divide the hour; "
                              "rvpp reads hourly data or periods of a whole divisor of 60 minutes")
    off_grid = np.flatnonzero((index - index.floor("h")) % step != pd.Timedelta(0))
    if len(off_grid):
        i = int(off_grid[0])
        raise DataImportError(f"{where[i]}: {excerpt(column)} {starts[i]:%Y-%m-%dT%H:%MZ} is off the file's "
                              f"{minutes:g}-minute grid of UTC hours; rows must start on it")
    return step


def _temperatures(text: list[str], where: list[str], column: str, unit: str, decimal_comma: bool) -> list[float]:
    """The column as °C: a missing cell is NaN; text, infinities and impossible values are refused."""
    out = []
    low, high = TEMPERATURE_RANGE_C
    for i, cell in enumerate(text):
        value = cell.strip()
        if value.lower() in EMPTY:
            out.append(math.nan)
            continue
        try:
            number = float(value.replace(",", ".") if decimal_comma else value)
        except ValueError:
            raise DataImportError(f'{where[i]}: column "{excerpt(column)}" value {excerpt(value)!r} is not a '
                                  "number") from None
        if not math.isfinite(number):
            raise DataImportError(f'{where[i]}: column "{excerpt(column)}" value {excerpt(value)!r} is not a '
                                  "finite number")
        celsius = number - KELVIN_AT_0_C if unit == "K" else number
        if not low <= celsius <= high:
            hint = (" (it looks like kelvin: write the unit in the header, e.g. \"t2m [K]\")"
                    if unit == "C" and 180.0 <= number <= 340.0 else "")
            raise DataImportError(f'{where[i]}: column "{excerpt(column)}" value {excerpt(value)!r} is '
                                  f"{celsius:g} °C, outside {low:g} to {high:g} °C, the air temperatures "
                                  f"possible on Earth{hint}")
        out.append(celsius)
    return out
