"""Hourly tables with one row per hour: the public Spanish energy dataset and ``time_utc`` tables.

**The Spanish energy dataset** ("Hourly energy demand generation and weather", its
``energy_dataset.csv``; sources credited there: ENTSO-E for generation, load and
forecasts, REE/OMIE for prices)::

    time,generation solar,generation wind onshore,forecast solar day ahead,...,price day ahead,price actual
    2015-01-01 00:00:00+01:00,49.0,6378.0,17.0,...,50.1,65.41

``time`` is the hour-beginning local time with its UTC offset; ``generation <type>`` is
actual output [MW] (``generation solar`` is photovoltaic *and* concentrated solar: the
output after sunset is CSP), ``forecast <type> day ahead`` the TSO's day-ahead forecast
[MW] (the original file spells one column ``forecast wind offshore eday ahead``),
``total load forecast`` / ``total load actual`` system demand [MW], ``price day ahead``
the OMIE day-ahead price for Spain [EUR/MWh]. ``price actual`` is the system operator's
final price, not a day-ahead price, and is ignored. Quirk of the source: the published
file has **day and month swapped** on every date with day <= 12 (and day != month), which
leaves the rows in time order but their labels out of order; such a file is detected
(labels out of order, and in order once swapped back with offsets that match
Europe/Madrid), corrected and the correction reported. Copies already corrected read as
they are. The fall-back hour appears twice with different offsets; times are parsed in UTC.

**``time_utc`` tables**: ``time_utc,time_local,<series>...`` with ``time_utc`` the UTC
start of each hour (``2018-01-01T00:00:00Z``) and ``time_local`` the same instant in
local time with its offset. This is the layout of hourly OMIE price exports
(``price_es_eur_mwh``, ``price_pt_eur_mwh``) and of rvpp's own normalised CSV
(canonical series names, see :mod:`rvpp.data.importers.report`).
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pandas as pd

from ...errors import DataImportError
from ..files import excerpt
from .report import (FIRST_YEAR, HOUR, LAST_YEAR, Imported, Rows, SourceFile, assemble, check_year, decode,
                     fingerprint, read_bytes, slug, unit_of)

DATASET = "Spanish energy dataset (hourly, ENTSO-E and OMIE)"
TIME_UTC = "Hourly table (time_utc, time_local)"
TIMEZONE = "Europe/Madrid"
_OFFSET = re.compile(r"^(\d{4})-(\d{2})-(\d{2})[ T](\d{2}):(\d{2})(?::(\d{2}))?([+-]\d{2}:?\d{2}|Z)$")
_FORECAST = re.compile(r"^forecast (?P<type>.+?) e?day ahead$")
OMIE_PRICES = {"price_es_eur_mwh": "ES", "price_pt_eur_mwh": "PT"}
ZONE_NAMES = {"ES": "Spain", "PT": "Portugal"}
IGNORED = {"price actual": "the system operator's final price, not a day-ahead price"}


def looks_like_dataset(text: str) -> bool:
    header = _header(text)
    return bool(header) and header[0] == "time" and any(h.startswith(("generation ", "price day ahead"))
                                                          for h in header)


def looks_like_time_utc(text: str) -> bool:
    header = _header(text)
    return header[:1] == ["time_utc"]


def _header(text: str) -> list[str]:
    line = text.lstrip().splitlines()[0] if text.strip() else ""
    return [cell.strip().strip('"').lower() for cell in line.split(",")]


def _frame(path: str | Path) -> tuple[pd.DataFrame, SourceFile]:
    data = read_bytes(path)
    name = Path(path).name
    try:
        frame = pd.read_csv(io.StringIO(decode(data, name)), dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DataImportError(f"{name}: cannot be read as CSV ({exc})") from None
    frame.columns = [c.strip() for c in frame.columns]
    return frame, SourceFile(name, fingerprint(data), len(frame))


# ----------------------------------------------------------------------------- the Spanish energy dataset


def dataset_series(column: str) -> tuple[str, str] | None:
    """Canonical name and meaning of a dataset column (``None``: not read)."""
    if column.startswith("generation "):
        kind = column[len("generation "):]
        meaning = "actual generation, " + kind + (" (photovoltaic and concentrated solar)" if kind == "solar" else "")
        return f"actual_{slug(kind)}", meaning
    match = _FORECAST.match(column)
    if match:
        return f"forecast_{slug(match.group('type'))}", f"day-ahead forecast, {match.group('type')}"
    return {"total load forecast": ("load_forecast", "day-ahead total load forecast"),
            "total load actual": ("load_actual", "actual total load"),
            "price day ahead": ("price_da", "day-ahead marginal price, Spain")}.get(column)


def read_dataset(path: str | Path) -> Imported:
    """Read the Spanish energy dataset (or a file in its layout)."""
    frame, file = _frame(path)
    if "time" not in frame.columns:
        raise DataImportError(f'{file.name}: no "time" column')
    meanings, notes = {}, []
    for column in frame.columns[1:]:
        found = dataset_series(column)
        if found is None:
            notes.append(f"ignored column {excerpt(column)!r}"
                         + (f" ({IGNORED[column]})" if column in IGNORED else ""))
            continue
        meanings[found[0]] = found[1]
        frame = frame.rename(columns={column: found[0]})
    if not meanings:
        raise DataImportError(f"{file.name}: no column rvpp reads (generation ..., forecast ... day ahead, "
                              "total load ..., price day ahead)")
    text = frame["time"].tolist()
    stamps, swapped = _dataset_times(text, file.name)
    if swapped:
        notes.append(f"day and month were swapped on {swapped} days (dates with day <= 12 written month first, "
                     "a known error of the published dataset); corrected, the times now run in order and match "
                     f"the {TIMEZONE} clock")
    rows = Rows()
    rows.add_table(stamps, stamps + HOUR, _numbers(frame, list(meanings), file.name), _lines(file.name, len(frame)))
    return assemble(rows, source=DATASET, files=[file], timezone=TIMEZONE, zone="ES (Spain)", meanings=meanings,
                    dst=_clock_changes(stamps), notes=notes)


def _dataset_times(text: list[str], name: str) -> tuple[pd.DatetimeIndex, int]:
    """UTC starts of the rows, with the published file's day/month swap undone when present."""
    parts = []
    for i, value in enumerate(text):
        match = _OFFSET.match(value.strip())
        if not match:
            raise DataImportError(f"{name} line {i + 2}: time {excerpt(value)!r} must be like "
                                  "2015-01-01 00:00:00+01:00 "
                                  "(local time with its UTC offset)")
        check_year(int(match.group(1)), f"{name} line {i + 2}", f"time {excerpt(value.strip())!r}")
        parts.append(match.groups())
    written = _instants(parts, name, swap=False)
    swapped = _instants(parts, name, swap=True)
    if _ordered(swapped) and _offsets_match(parts, swapped) and (
            not _ordered(written) or _missing_hours(swapped) < _missing_hours(written)):
        days = {(y, d, m) for y, m, d, *_ in parts if int(d) <= 12 and d != m}
        return swapped, len(days)
    if _ordered(written):
        return written, 0
    if written is None:
        raise DataImportError(f"{name}: a time is not a valid date")
    i = int(np.flatnonzero(np.diff(written.asi8) <= 0)[0]) + 1
    raise DataImportError(f"{name} line {i + 2}: time {excerpt(text[i])!r} is not after the row before it "
                          f"({excerpt(text[i - 1])!r}); "
                          "rows must be in time order without repeats")


def _instants(parts, name: str, swap: bool) -> pd.DatetimeIndex | None:
    iso = []
    for y, m, d, hh, mm, ss, off in parts:
        if swap and int(d) <= 12 and d != m:
            m, d = d, m
        iso.append(f"{y}-{m}-{d}T{hh}:{mm}:{ss or '00'}{off}")
    try:
        return pd.DatetimeIndex(pd.to_datetime(iso, utc=True, format="ISO8601"))
    except (ValueError, TypeError):
        return None


def _ordered(stamps: pd.DatetimeIndex | None) -> bool:
    return stamps is not None and stamps.is_monotonic_increasing and not stamps.has_duplicates


def _missing_hours(stamps: pd.DatetimeIndex) -> int:
    # in whole nanoseconds: a span of centuries exceeds a pandas Timedelta
    return int((stamps[-1].value - stamps[0].value) // HOUR.value + 1 - len(stamps))


def _offsets_match(parts, instants: pd.DatetimeIndex) -> bool:
    """True if every written offset is the one Europe/Madrid has at that instant."""
    local = instants.tz_convert(TIMEZONE)
    expected = [f"{t:%z}" for t in local]
    written = [off.replace(":", "").replace("Z", "+0000") for *_, off in parts]
    return expected == written


def _clock_changes(stamps: pd.DatetimeIndex) -> list[str]:
    local = stamps.tz_convert(TIMEZONE)
    days = pd.Series(1, index=local.date).groupby(level=0).size()
    notes = []
    for day, count in days.items():
        midnight = pd.Timestamp(day).tz_localize(TIMEZONE)
        length = int(round((pd.Timestamp(day + pd.Timedelta(days=1)).tz_localize(TIMEZONE) - midnight) / HOUR))
        if length == 23:
            notes.append(f"{day}: 23-hour day (clocks go forward at 02:00); {count} rows")
        elif length == 25:
            notes.append(f"{day}: 25-hour day (clocks go back at 03:00); {count} rows, 02:00 local placed by its "
                         "written offset")
    return notes


def _numbers(frame: pd.DataFrame, columns: list[str], name: str) -> pd.DataFrame:
    """The columns as numbers; an empty cell is a missing value, any other text is refused."""
    out = {}
    for column in columns:
        text = frame[column].astype(str).str.strip()
        empty = text.isin(["", "nan", "NaN", "-"])
        values = pd.to_numeric(text.where(~empty), errors="coerce")
        bad = values.isna() & ~empty
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataImportError(f"{name} line {i + 2}: {column} value {excerpt(text[i])!r} is not a number")
        if np.isinf(values.to_numpy(float)).any():
            i = int(np.flatnonzero(np.isinf(values.to_numpy(float)))[0])
            raise DataImportError(f"{name} line {i + 2}: {column} value {excerpt(text[i])!r} is not a finite number")
        out[column] = values.to_numpy(float)
    return pd.DataFrame(out)


def _lines(name: str, count: int) -> list[str]:
    return [f"{name} line {i + 2}" for i in range(count)]


# ----------------------------------------------------------------------------- time_utc tables


def read_time_utc(path: str | Path, zone: str | None = None) -> Imported:
    """Read a ``time_utc, time_local, ...`` hourly table (OMIE hourly prices, rvpp's normalised CSV)."""
    frame, file = _frame(path)
    columns = [c for c in frame.columns if c not in ("time_utc", "time_local")]
    meanings, rename, notes, zones = {}, {}, [], set()
    prices = [c for c in columns if c in OMIE_PRICES]
    chosen = None
    if prices:
        wanted = (zone or "ES").upper()
        chosen = next((c for c in prices if OMIE_PRICES[c] == wanted), None)
        if chosen is None:
            raise DataImportError(f"{file.name}: no price column for zone {wanted} (columns: {', '.join(prices)})")
    for column in columns:
        if column in OMIE_PRICES:
            if column == chosen:
                rename[column] = "price_da"
                meanings["price_da"] = f"day-ahead marginal price, {ZONE_NAMES[OMIE_PRICES[column]]}"
                zones.add(f"{OMIE_PRICES[column]} ({ZONE_NAMES[OMIE_PRICES[column]]})")
            else:
                notes.append(f"ignored column {excerpt(column)!r} (another zone)")
        elif unit_of(column) and re.fullmatch(r"[a-z0-9_]+", column):
            meanings[column] = f"{column.replace('_', ' ')} (as written)"
        else:
            notes.append(f"ignored column {excerpt(column)!r}")
    if not meanings:
        raise DataImportError(f"{file.name}: no series rvpp reads (price_es_eur_mwh, price_da, actual_..., "
                              "forecast_..., load_...)")
    frame = frame.rename(columns=rename)
    stamps = _utc_times(frame, file.name)
    rows = Rows()
    rows.add_table(stamps, stamps + HOUR, _numbers(frame, list(meanings), file.name), _lines(file.name, len(frame)))
    return assemble(rows, source=TIME_UTC, files=[file], timezone=TIMEZONE,
                    zone=next(iter(zones)) if zones else zone, meanings=meanings, dst=_clock_changes(stamps),
                    notes=notes)


def _utc_times(frame: pd.DataFrame, name: str) -> pd.DatetimeIndex:
    text = frame["time_utc"].astype(str).str.strip()
    bad = ~text.str.match(r"^\d{4}-\d{2}-\d{2}[ T]\d{2}:\d{2}(:\d{2})?(Z|\+00:?00)$")
    if bad.any():
        i = int(np.flatnonzero(bad.to_numpy())[0])
        raise DataImportError(f"{name} line {i + 2}: time_utc {excerpt(text[i])!r} must be a UTC time such as "
                              "2018-01-01T00:00:00Z")
    years = text.str.slice(0, 4).astype(int).to_numpy()
    outside = np.flatnonzero((years < FIRST_YEAR) | (years > LAST_YEAR))
    if len(outside):
        i = int(outside[0])
        check_year(int(years[i]), f"{name} line {i + 2}", f"time_utc {excerpt(text[i])!r}")
    stamps = pd.DatetimeIndex(pd.to_datetime(text, utc=True, format="ISO8601"))
    off_hour = np.flatnonzero((stamps.minute != 0) | (stamps.second != 0))
    if len(off_hour):
        i = int(off_hour[0])
        raise DataImportError(f"{name} line {i + 2}: time_utc {excerpt(text[i])!r} is not on the hour; "
                              "the table is hourly")
    if "time_local" in frame.columns:
        local = frame["time_local"].astype(str).str.strip()
        try:
            check = pd.DatetimeIndex(pd.to_datetime(local, utc=True, format="ISO8601"))
        except (ValueError, TypeError):
            raise DataImportError(f"{name}: a time_local value cannot be read as a time with its offset") from None
        differ = np.flatnonzero(check != stamps)
        if len(differ):
            i = int(differ[0])
            raise DataImportError(f"{name} line {i + 2}: time_local {excerpt(local[i])!r} is not the instant time_utc "
                                  f"{excerpt(text[i])!r}")
    return stamps
