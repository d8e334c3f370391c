"""ENTSO-E Transparency Platform CSV exports ("Export Data" > CSV).

Three exports are read, one or several files each, in any mix:

* **Day-ahead prices** (12.1.D): ``"MTU (CET/CEST)","Day-ahead Price [EUR/MWh]"`` and
  possibly ``"Currency"`` and an area column; -> ``price_da``.
* **Actual generation per production type** (16.1.B&C): ``"Area","MTU",
  "Biomass  - Actual Aggregated [MW]", ..., "Wind Onshore  - Actual Aggregated [MW]"``;
  -> ``actual_<type>`` (e.g. ``actual_wind_onshore``, ``actual_solar``).
* **Day-ahead wind and solar forecasts** (14.1.D): ``"MTU (CET/CEST)",
  "Generation - Solar  [MW] Day Ahead/ BZN|ES", ... "Generation - Wind Onshore  [MW]
  Day Ahead/ BZN|ES"``; -> ``forecast_<type>``. Intraday and current forecasts are
  listed as ignored. Load exports (6.1.A/B) give ``load_actual`` and ``load_forecast``.

Quirks of the source, each handled here:

* The time column gives each market time unit as ``"DD.MM.YYYY HH:MM - DD.MM.YYYY
  HH:MM"`` in the time zone named by its header (``MTU (CET/CEST)``, ``MTU (UTC)``...;
  a bare ``MTU`` or ``MTU (CET)`` is read as the Central European wall clock,
  CET/CEST). Dates are **day first**: ``01.02.2018`` is 1 February. Newer exports write
  ``DD/MM/YYYY HH:MM:SS``; both are read. The start of the interval is the period start
  (hour-beginning); its length is the MTU (60, 30 or 15 minutes).
* On the day clocks go back, the local hour 02:00-03:00 exists twice. Exports either
  mark each row ``(CEST)`` / ``(CET)`` or write the hour twice without a marker; then the
  first occurrence is summer time (+02:00) and the second winter time (+01:00). A repeated
  local time that occurs only once cannot be placed and is refused.
* On the day clocks go forward, the local hour 02:00-03:00 does not exist; exports may
  still list it with empty values. Such a row is dropped (and reported); with a value it
  is refused.
* ``n/e`` means "not expected" (a type the zone does not report): a column that is
  ``n/e`` throughout is dropped and reported; ``n/e``, ``-``, ``N/A`` or an empty cell
  inside a column are missing values, reported per series and never filled.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import re
from dataclasses import dataclass
from pathlib import Path
from zoneinfo import ZoneInfo

import pandas as pd

from ...errors import DataImportError
from ..files import excerpt, excerpt_names
from .report import Imported, Rows, SourceFile, assemble, check_year, decode, fingerprint, read_bytes, slug

SOURCE = "ENTSO-E Transparency Platform CSV export"
CENTRAL_EUROPE = "Europe/Brussels"  # the CET/CEST wall clock of the platform
HEADER_ZONES = {"CET/CEST": CENTRAL_EUROPE, "CET": CENTRAL_EUROPE, "UTC": "UTC", "WET/WEST": "Europe/Lisbon",
                "EET/EEST": "Europe/Athens", "": CENTRAL_EUROPE}
MARKER_OFFSETS_H = {"CET": 1, "CEST": 2, "WET": 0, "WEST": 1, "EET": 2, "EEST": 3, "UTC": 0}
EMPTY = {"", "-", "n/e", "N/A", "n/a", "NA"}
ALLOWED_MTU_MIN = (15, 30, 60)
COLUMN_CHARS = 80  # column names are quoted in full up to this length

_STAMP = r"(\d{2})[./](\d{2})[./](\d{4})\s+(\d{2}):(\d{2})(?::(\d{2}))?\s*(?:\(([A-Z/]+)\))?"
MTU = re.compile(rf"^\s*{_STAMP}\s*-\s*{_STAMP}\s*(?:\(([A-Z/]+)\))?\s*$")
TIME_HEADER = re.compile(r"^\s*MTU\s*(?:\((?P<zone>[^)]*)\))?\s*$", re.IGNORECASE)
UNIT = r"\s*[\[(](?P<unit>[^\])]+)[\])]"
COLUMNS = (
    (re.compile(rf"^Day-ahead Price{UNIT}\s*(?P<area>.*)$", re.I), "price_da", "day-ahead price"),
    (re.compile(rf"^(?P<type>.+?)\s+-\s+Actual Aggregated{UNIT}\s*$", re.I), "actual", "actual generation"),
    (re.compile(rf"^Generation\s+-\s+(?P<type>.+?){UNIT}\s*Day[ -]Ahead\s*/\s*(?P<area>.*)$", re.I), "forecast",
     "day-ahead generation forecast"),
    (re.compile(rf"^Day-ahead Total Load Forecast{UNIT}\s*-?\s*(?P<area>.*)$", re.I), "load_forecast",
     "day-ahead total load forecast"),
    (re.compile(rf"^Actual Total Load{UNIT}\s*-?\s*(?P<area>.*)$", re.I), "load_actual", "actual total load"),
)
EXPECTED_UNITS = {"price_da": "EUR/MWh", "actual": "MW", "forecast": "MW", "load_forecast": "MW",
                  "load_actual": "MW"}


def looks_like(text: str) -> bool:
    """True for an ENTSO-E CSV export: a header with an ``MTU`` time column."""
    first = text.lstrip().splitlines()[0] if text.strip() else ""
    return any(TIME_HEADER.match(cell) for cell in _cells(first))


@dataclass(frozen=True)
class _Column:
    index: int
    name: str
    meaning: str


def read(paths: list[str | Path], zone: str | None = None) -> list[Imported]:
    """Read each export into its own :class:`Imported` (one per file: the exports differ)."""
    return [read_one(path, zone) for path in paths]


def read_one(path: str | Path, zone: str | None = None) -> Imported:
    """Read one CSV export; ``zone`` (e.g. ``ES``) selects an area when the file holds several."""
    data = read_bytes(path)
    name = Path(path).name
    text = decode(data, name)
    table = list(csv.reader(io.StringIO(text), delimiter=_delimiter(text)))
    table = [row for row in table if any(cell.strip() for cell in row)]
    if not table:
        raise DataImportError(f"{name}: the file is empty")
    header = [cell.strip() for cell in table[0]]
    time_index, clock = _time_column(header, name)
    area_index = next((i for i, h in enumerate(header) if h.lower() == "area"), None)
    columns, ignored, areas = _value_columns(header, name, time_index, area_index)
    body = table[1:]
    wanted_area = _choose_area(body, area_index, areas, zone, name)
    if area_index is not None and wanted_area is not None:
        body = [(n, row) for n, row in enumerate(body, start=2) if row[area_index].strip() == wanted_area]
    else:
        body = list(enumerate(body, start=2))
    columns, never = _drop_not_expected(columns, body)
    notes = [f"ignored column {excerpt(c, COLUMN_CHARS)!r}" for c in ignored]
    notes += [f"dropped {excerpt(c)!r}: 'n/e' (not expected) in every row" for c in never]
    rows, clock_notes, dropped = _rows(body, columns, time_index, clock, name)
    notes += dropped
    file = SourceFile(name, fingerprint(data), len(table) - 1)
    return assemble(rows, source=SOURCE, files=[file], timezone=clock, zone=wanted_area,
                    meanings={c.name: c.meaning for c in columns}, dst=clock_notes, notes=notes)


def _delimiter(text: str) -> str:
    first = text.lstrip().splitlines()[0] if text.strip() else ""
    return ";" if first.count(";") > first.count(",") else ","


def _cells(line: str) -> list[str]:
    return next(csv.reader([line], delimiter=_delimiter(line)), [])


def _time_column(header: list[str], name: str) -> tuple[int, str]:
    for i, cell in enumerate(header):
        match = TIME_HEADER.match(cell)
        if match:
            label = (match.group("zone") or "").strip().upper()
            if label not in HEADER_ZONES:
                raise DataImportError(f'{name}: time column "{excerpt(cell)}" uses the time zone '
                                      f"{excerpt(label)!r}; known: "
                                      + ", ".join(z for z in HEADER_ZONES if z))
            return i, HEADER_ZONES[label]
    raise DataImportError(f'{name}: no "MTU" time column in the header; is this an ENTSO-E CSV export?')


def _value_columns(header: list[str], name: str, time_index: int, area_index: int | None):
    columns, ignored, areas = [], [], set()
    for i, cell in enumerate(header):
        if i in (time_index, area_index) or not cell:
            continue
        for pattern, kind, meaning in COLUMNS:
            match = pattern.match(cell)
            if not match:
                continue
            unit = match.group("unit").strip()
            if unit != EXPECTED_UNITS[kind]:
                raise DataImportError(f'{name}: column "{excerpt(cell)}" is in {excerpt(unit)}; rvpp reads '
                                      f"{EXPECTED_UNITS[kind]}")
            series = kind if kind in ("price_da", "load_forecast", "load_actual") else \
                f"{kind}_{slug(match.group('type'))}"
            area = (match.groupdict().get("area") or "").strip()
            if area:
                areas.add(area)
            what = match.group("type").strip() + " " if "type" in match.groupdict() else ""
            columns.append(_Column(i, series, f"{what}{meaning}".strip()))
            break
        else:
            ignored.append(cell)
    if not columns:
        raise DataImportError(
            f"{name}: no column rvpp reads (day-ahead price [EUR/MWh], actual generation per type [MW], "
            "day-ahead wind and solar forecast [MW], total load [MW]); found: " + excerpt_names(header))
    names = [c.name for c in columns]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise DataImportError(f"{name}: more than one column gives {repeated[0]}")
    return columns, ignored, areas


def _choose_area(body: list[list[str]], area_index: int | None, header_areas: set[str], zone: str | None,
                 name: str) -> str | None:
    areas = set(header_areas)
    if area_index is not None:
        areas |= {row[area_index].strip() for row in body if len(row) > area_index and row[area_index].strip()}
    if not areas:
        return zone
    if zone is None:
        if len(areas) > 1:
            raise DataImportError(f"{name}: the file holds several areas ({excerpt_names(sorted(areas))}); "
                                  "choose one with --zone")
        return next(iter(areas))
    matching = [a for a in areas if a.upper() == zone.upper() or a.upper().endswith("|" + zone.upper())]
    if not matching:
        raise DataImportError(f"{name}: zone {excerpt(zone)!r} is not in the file "
                              f"(areas: {excerpt_names(sorted(areas))})")
    return matching[0]


def _drop_not_expected(columns: list[_Column], body) -> tuple[list[_Column], list[str]]:
    kept, never = [], []
    for column in columns:
        cells = [row[column.index].strip() if len(row) > column.index else "" for _, row in body]
        if cells and all(cell == "n/e" for cell in cells):
            never.append(column.name)
        else:
            kept.append(column)
    return kept, never


def _rows(body, columns: list[_Column], time_index: int, clock: str, name: str):
    """Place every row in UTC; see the module notes for the clock changes."""
    zone = ZoneInfo(clock)
    parsed = []
    for number, row in body:
        where = f"{name} line {number}"
        if len(row) <= time_index:
            raise DataImportError(f"{where}: the row has no time")
        match = MTU.match(row[time_index])
        if not match:
            raise DataImportError(f"{where}: time {excerpt(row[time_index])!r} is not "
                                  '"DD.MM.YYYY HH:MM - DD.MM.YYYY HH:MM"')
        start, end = _naive(match.groups()[0:6], where), _naive(match.groups()[7:13], where)
        check_year(start.year, where, f"time {excerpt(row[time_index])!r}")  # the end only measures the period
        marker = match.group(7) or match.group(15) or match.group(14)
        values = {c.name: _number(row[c.index] if len(row) > c.index else "", where, c.name) for c in columns}
        parsed.append((where, start, end, marker, values))
    if not parsed:
        raise DataImportError(f"{name}: has a header but no rows of data")
    minutes = pd.Series([int((e - s).total_seconds() // 60) for _, s, e, _, _ in parsed]).value_counts()
    step_min = int(minutes.index[0])
    if step_min not in ALLOWED_MTU_MIN:
        raise DataImportError(f"{name}: market time unit of {step_min} minutes; rvpp reads "
                              f"{', '.join(map(str, ALLOWED_MTU_MIN))}-minute data")
    step = dt.timedelta(minutes=step_min)
    seen: dict[dt.datetime, int] = {}
    for _, start, _, marker, _ in parsed:
        if marker is None:
            seen[start] = seen.get(start, 0) + 1
    rows, dropped, marked = Rows(), [], {}
    occurrence: dict[dt.datetime, int] = {}
    for where, start, end, marker, values in parsed:
        utc = _place(start, marker, zone, where, seen, occurrence)
        if utc is None:
            if any(v == v for v in values.values()):
                raise DataImportError(f"{where}: local time {start:%d.%m.%Y %H:%M} does not exist (clocks go "
                                      "forward) but the row has values; it cannot be placed in time")
            dropped.append(f"{where}: dropped the non-existent local time {start:%d.%m.%Y %H:%M} (clocks go "
                           "forward; no values)")
            continue
        wall = end - start
        if wall != step and not _near_clock_change(start, zone):
            raise DataImportError(f"{where}: the period lasts {wall.total_seconds() / 60:g} minutes but the "
                                  f"file's market time unit is {step_min} minutes")
        rows.add(pd.Timestamp(utc), pd.Timestamp(utc + step), values, where)
        if _near_clock_change(start, zone):
            marked[start.date()] = marked.get(start.date(), False) or marker is not None
    return rows, [_clock_note(day, zone, by_marker) for day, by_marker in sorted(marked.items())], dropped


def _naive(groups, where: str) -> dt.datetime:
    day, month, year, hour, minute, second = groups
    try:
        return dt.datetime(int(year), int(month), int(day), int(hour), int(minute), int(second or 0))
    except ValueError:
        raise DataImportError(f"{where}: {day}.{month}.{year} {hour}:{minute} is not a valid time "
                              "(dates are day first: DD.MM.YYYY)") from None


def _number(text: str, where: str, column: str) -> float:
    text = text.strip()
    if text in EMPTY:
        return float("nan")
    try:
        value = float(text)
    except ValueError:
        raise DataImportError(f"{where}: {column} value {excerpt(text)!r} is not a number") from None
    if value != value or abs(value) == float("inf"):
        raise DataImportError(f"{where}: {column} value {excerpt(text)!r} is not a finite number")
    return value


def _place(local: dt.datetime, marker: str | None, zone: ZoneInfo, where: str, seen: dict,
           occurrence: dict) -> dt.datetime | None:
    """UTC instant of a local wall time; ``None`` if it does not exist (spring gap)."""
    utc = dt.timezone.utc
    if marker is not None:
        if marker not in MARKER_OFFSETS_H:
            raise DataImportError(f"{where}: unknown time marker ({marker})")
        instant = (local - dt.timedelta(hours=MARKER_OFFSETS_H[marker])).replace(tzinfo=utc)
        if zone.key != "UTC" and instant.astimezone(zone).replace(tzinfo=None) != local:
            raise DataImportError(f"{where}: {local:%d.%m.%Y %H:%M} ({marker}) is not a time of {zone.key}")
        return instant
    first, second = (local.replace(tzinfo=zone, fold=f).astimezone(utc) for f in (0, 1))
    exists = first.astimezone(zone).replace(tzinfo=None) == local
    if not exists:
        return None
    if first == second:
        return first
    # A repeated local time (clocks go back): first occurrence summer time, second winter time.
    count = occurrence.get(local, 0)
    occurrence[local] = count + 1
    if seen.get(local, 0) != 2:
        raise DataImportError(
            f"{where}: local time {local:%d.%m.%Y %H:%M} occurs twice that day (clocks go back) but the file "
            f"gives it {seen.get(local, 0)} time(s) without a (CEST)/(CET) marker, so it cannot be placed")
    return first if count == 0 else second


def _near_clock_change(local: dt.datetime, zone: ZoneInfo) -> bool:
    day = local.date()
    start = dt.datetime.combine(day, dt.time()).replace(tzinfo=zone)
    end = dt.datetime.combine(day + dt.timedelta(days=1), dt.time()).replace(tzinfo=zone)
    return start.utcoffset() != end.utcoffset()


def _clock_note(day: dt.date, zone: ZoneInfo, marked: bool) -> str:
    start = dt.datetime.combine(day, dt.time()).replace(tzinfo=zone)
    end = dt.datetime.combine(day + dt.timedelta(days=1), dt.time()).replace(tzinfo=zone)
    if end.utcoffset() > start.utcoffset():
        return f"{day}: 23-hour day (clocks go forward at 02:00)"
    how = "by its (CEST)/(CET) marker" if marked else "first occurrence summer time (+02:00), second winter (+01:00)"
    return f"{day}: 25-hour day (clocks go back at 03:00); the repeated hour placed {how}"
