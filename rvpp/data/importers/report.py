"""What an importer read: the series on their timeline, and a report of everything met.

Every importer returns an :class:`Imported`: one row per market time unit (MTU) actually
read, indexed by the UTC instant the period starts, with the UTC instant it ends beside
it (so hourly and quarter-hourly periods can sit in one import), one column per series
and NaN where the file gave no value. Nothing is filled in: missing periods are listed
as gaps, missing values per series, and identical duplicates are dropped and listed;
duplicates that disagree are refused.

Series use canonical names whatever the source called them, so a case can be built from
any mix of files:

=========================  ========  =================================================
name                       unit      meaning
=========================  ========  =================================================
``price_da``               EUR/MWh   day-ahead marginal price of the zone
``actual_<type>``          MW        actual generation per production type, e.g.
                                     ``actual_wind_onshore``, ``actual_solar``
``forecast_<type>``        MW        day-ahead forecast of the same (wind and solar)
``load_actual``            MW        actual total load
``load_forecast``          MW        day-ahead total load forecast
=========================  ========  =================================================
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ...errors import DataImportError
from ..case import FIRST_DATE, LAST_DATE
from ..files import open_regular, sniff

HOUR = pd.Timedelta(hours=1)
# The years rvpp plans (the delivery dates a case may have); every reader refuses a date
# outside them before building a timestamp, which pandas cannot hold before 1677 or after 2262.
FIRST_YEAR, LAST_YEAR = FIRST_DATE.year, LAST_DATE.year
DATE_RANGE = f"dates must lie between {FIRST_YEAR} and {LAST_YEAR}"
SHOWN = 12  # gaps, duplicates and missing runs listed in full before "and N more"
UNITS = {"price": "EUR/MWh", "actual": "MW", "forecast": "MW", "load": "MW", "temperature": "°C"}


def check_year(year: int, where: str, written: str) -> None:
    """Refuse a date of ``year`` outside :data:`FIRST_YEAR` to :data:`LAST_YEAR`, e.g.
    ``prices.csv line 5: time_utc '3000-01-01T00:00:00Z' is out of range; dates must lie between
    1900 and 2199`` (``where``: file and line; ``written``: the field as the file gives it)."""
    if not FIRST_YEAR <= year <= LAST_YEAR:
        raise DataImportError(f"{where}: {written} is out of range; {DATE_RANGE}")


def unit_of(name: str) -> str:
    """Unit of a canonical series name (``price_da`` -> ``EUR/MWh``)."""
    return UNITS.get(name.split("_", 1)[0], "")


def slug(text: str) -> str:
    """``"Wind Onshore "`` -> ``wind_onshore``; ``"Hydro Run-of-river and poundage"`` ->
    ``hydro_run_of_river_and_poundage``."""
    words = "".join(c.lower() if c.isalnum() else " " for c in text).split()
    return "_".join(words)


@dataclass(frozen=True)
class SourceFile:
    """A file read: its name (without folders), content fingerprint and data lines."""

    name: str
    sha256: str
    lines: int


def fingerprint(data: bytes) -> str:
    """sha256 of a file's bytes, 16 hex digits."""
    return hashlib.sha256(data).hexdigest()[:16]


@dataclass(frozen=True)
class Span:
    """A stretch of time ``[start, end)`` in UTC and the periods it holds."""

    start: pd.Timestamp
    end: pd.Timestamp
    periods: int

    def describe(self, timezone: str) -> str:
        first, last = self.start.tz_convert(timezone), self.end.tz_convert(timezone)
        return (f"{first:%Y-%m-%d %H:%M}{_offset(first)} to {last:%Y-%m-%d %H:%M}{_offset(last)} "
                f"({self.periods} period{'s' if self.periods != 1 else ''})")


@dataclass(frozen=True)
class SeriesReport:
    """One imported series: name, unit, what it means, how many values, where it is empty."""

    name: str
    unit: str
    meaning: str
    values: int
    minimum: float | None
    maximum: float | None
    missing: tuple[Span, ...] = ()


@dataclass(frozen=True)
class ImportReport:
    """Everything an importer read, in the words a user checks a download with."""

    source: str
    files: tuple[SourceFile, ...]
    timezone: str
    zone: str | None
    start: pd.Timestamp
    end: pd.Timestamp
    resolutions: tuple[tuple[int, int], ...]
    gaps: tuple[Span, ...]
    duplicates: tuple[str, ...]
    dst: tuple[str, ...]
    notes: tuple[str, ...]
    series: tuple[SeriesReport, ...]

    @property
    def periods(self) -> int:
        return sum(count for _, count in self.resolutions)

    def lines(self) -> list[str]:
        """The report as text, one fact per line."""
        tz = self.timezone
        first, last = self.start.tz_convert(tz), self.end.tz_convert(tz)
        files = self.files[0].name if len(self.files) == 1 else f"{len(self.files)} files"
        out = [f"{self.source}: {files}"]
        if self.zone:
            out.append(f"  zone: {self.zone}")
        out.append(f"  span: {first:%Y-%m-%d %H:%M}{_offset(first)} to {last:%Y-%m-%d %H:%M}{_offset(last)} "
                   f"local ({tz}); {self.start:%Y-%m-%dT%H:%MZ} to {self.end:%Y-%m-%dT%H:%MZ} UTC")
        out.append(f"  periods: {self.periods} ("
                   + ", ".join(f"{count} of {minutes} min" for minutes, count in self.resolutions) + ")")
        out += _listed("gaps (no row)", [g.describe(tz) for g in self.gaps])
        out += _listed("duplicates", list(self.duplicates))
        out += _listed("clock changes", list(self.dst))
        out += [f"  note: {n}" for n in self.notes]
        for s in self.series:
            span = "no values" if s.values == 0 else f"{s.values} values, {s.minimum:.6g} to {s.maximum:.6g}"
            out.append(f"  series {s.name} [{s.unit}]: {s.meaning}; {span}")
            out += _listed("empty", [m.describe(tz) for m in s.missing], indent="    ")
        return out

    def __str__(self) -> str:
        return "\n".join(self.lines())


def _listed(title: str, items: list[str], indent: str = "  ") -> list[str]:
    if not items:
        return [f"{indent}{title}: none"]
    shown = [f"{indent}{title}: {len(items)}"] + [f"{indent}  - {item}" for item in items[:SHOWN]]
    if len(items) > SHOWN:
        shown.append(f"{indent}  - and {len(items) - SHOWN} more")
    return shown


def _offset(stamp: pd.Timestamp) -> str:
    text = stamp.strftime("%z")
    return f"{text[:3]}:{text[3:]}" if text else ""


@dataclass(frozen=True, eq=False)
class Imported:
    """Series read from one source: values per period and the report.

    ``values`` is indexed by the UTC start of each period (``start``) and has one column
    per canonical series; ``ends`` holds the UTC end of each period.
    """

    values: pd.DataFrame
    ends: pd.DatetimeIndex
    report: ImportReport

    @property
    def series(self) -> tuple[str, ...]:
        return tuple(self.values.columns)


@dataclass
class Rows:
    """Periods as an importer reads them, before they are checked and ordered."""

    starts: list[pd.Timestamp] = field(default_factory=list)
    ends: list[pd.Timestamp] = field(default_factory=list)
    values: list[dict[str, float]] = field(default_factory=list)
    where: list[str] = field(default_factory=list)  # "file line n", for messages
    tables: list[tuple[pd.DatetimeIndex, pd.DatetimeIndex, pd.DataFrame, list[str]]] = field(default_factory=list)

    def add(self, start: pd.Timestamp, end: pd.Timestamp, values: dict[str, float], where: str) -> None:
        self.starts.append(start)
        self.ends.append(end)
        self.values.append(values)
        self.where.append(where)

    def add_table(self, starts: pd.DatetimeIndex, ends: pd.DatetimeIndex, values: pd.DataFrame,
                  where: list[str]) -> None:
        """Many periods at once (``values``: one row per period, one column per series)."""
        self.tables.append((starts, ends, values.reset_index(drop=True), where))

    def collected(self, names: list[str]) -> tuple[pd.DatetimeIndex, pd.DatetimeIndex, pd.DataFrame, list[str]]:
        parts = [(pd.DatetimeIndex(self.starts), pd.DatetimeIndex(self.ends),
                  pd.DataFrame([[r.get(n, np.nan) for n in names] for r in self.values], columns=names,
                               dtype=float), self.where)] if self.starts else []
        parts += [(s, e, v.reindex(columns=names).astype(float), w) for s, e, v, w in self.tables]
        if not parts:
            return pd.DatetimeIndex([], tz="UTC"), pd.DatetimeIndex([], tz="UTC"), pd.DataFrame(columns=names), []
        where = [w for p in parts for w in p[3]]
        starts = _utc_index([p[0] for p in parts], where)
        ends = _utc_index([p[1] for p in parts], where)
        table = pd.concat([p[2] for p in parts], ignore_index=True)
        return starts, ends, table, where


def _utc_index(pieces: list[pd.DatetimeIndex], where: list[str]) -> pd.DatetimeIndex:
    """The instants of ``pieces`` as one UTC index; the last guard against a reader that let
    a year outside :data:`FIRST_YEAR` to :data:`LAST_YEAR` through (``where``: each row's place)."""
    utc = [p.tz_convert("UTC") for p in pieces]
    years = np.concatenate([p.year.to_numpy() for p in utc])
    # a year of margin each side: local midnight of 1 January 1900 is still 1899 in UTC, and the
    # last period of 2199 ends in 2200
    outside = np.flatnonzero((years < FIRST_YEAR - 1) | (years > LAST_YEAR + 1))
    if len(outside):
        i = int(outside[0])
        offsets = np.cumsum([0] + [len(p) for p in utc])
        piece = int(np.searchsorted(offsets, i, side="right")) - 1
        stamp = utc[piece][i - int(offsets[piece])]
        raise DataImportError(f"{where[i]}: the period at {stamp:%Y-%m-%dT%H:%MZ} is out of range; {DATE_RANGE}")
    nanoseconds = np.concatenate([p.as_unit("ns").asi8 for p in utc])
    return pd.DatetimeIndex(nanoseconds.astype("datetime64[ns]")).tz_localize("UTC")


def assemble(rows: Rows, *, source: str, files: list[SourceFile], timezone: str, zone: str | None,
             meanings: dict[str, str], dst: list[str] = (), notes: list[str] = ()) -> Imported:
    """Order the periods read, drop identical duplicates, refuse conflicting ones and overlaps,
    and describe the result. ``meanings`` gives each series its description (and its column order)."""
    names = list(meanings)
    starts, ends, table, where = rows.collected(names)
    if not len(starts):
        raise DataImportError(f"{', '.join(f.name for f in files)}: no data rows found")
    order = np.lexsort((np.arange(len(starts)), starts.asi8))
    starts, ends, table = starts[order], ends[order], table.iloc[order].reset_index(drop=True)
    where = [where[i] for i in order]

    keep = np.ones(len(starts), dtype=bool)
    duplicates = []
    for i in np.flatnonzero(starts.asi8[1:] == starts.asi8[:-1]) + 1:
        j = i - 1
        while not keep[j]:
            j -= 1
        same = ends[i] == ends[j] and np.array_equal(table.iloc[i].to_numpy(), table.iloc[j].to_numpy(),
                                                     equal_nan=True)
        if not same:
            raise DataImportError(
                f"{where[i]}: the period starting {_utc(starts[i])} is also given by {where[j]} with other "
                "values; remove one of the two files or rows")
        keep[i] = False
        duplicates.append(f"{_utc(starts[i])} given twice with the same values ({where[j]}; {where[i]}): "
                          "one kept")
    starts, ends, table = starts[keep], ends[keep], table[keep].reset_index(drop=True)
    where = [w for w, k in zip(where, keep) if k]

    durations = ends - starts
    if (durations <= pd.Timedelta(0)).any():
        i = int(np.flatnonzero(durations <= pd.Timedelta(0))[0])
        raise DataImportError(f"{where[i]}: the period ends before it starts")
    overlap = np.flatnonzero(starts[1:] < ends[:-1])
    if len(overlap):
        i = int(overlap[0]) + 1
        raise DataImportError(f"{where[i]}: the period starting {_utc(starts[i])} overlaps the one before it "
                              f"({where[i - 1]}, ending {_utc(ends[i - 1])})")
    gaps = [Span(ends[i], starts[i + 1], _count(ends[i], starts[i + 1], durations[i]))
            for i in np.flatnonzero(starts[1:] > ends[:-1])]
    minutes = pd.Series(durations.total_seconds() // 60).astype(int).value_counts().sort_index()
    table.index = pd.DatetimeIndex(starts, name="start")
    series = tuple(_series_report(name, meanings[name], table[name], ends) for name in names)
    report = ImportReport(
        source=source, files=tuple(files), timezone=timezone, zone=zone, start=starts[0], end=ends[-1],
        resolutions=tuple((int(m), int(c)) for m, c in minutes.items()), gaps=tuple(gaps),
        duplicates=tuple(duplicates), dst=tuple(dst), notes=tuple(notes), series=series)
    return Imported(values=table, ends=pd.DatetimeIndex(ends), report=report)


def _count(start: pd.Timestamp, end: pd.Timestamp, step: pd.Timedelta) -> int:
    # in whole nanoseconds: a gap of centuries (files of 1900 and 2199) exceeds a pandas Timedelta
    return max(1, int(round((end.value - start.value) / step.value)))


def _utc(stamp: pd.Timestamp) -> str:
    return f"{stamp:%Y-%m-%dT%H:%MZ}"


def _series_report(name: str, meaning: str, column: pd.Series, ends: pd.DatetimeIndex) -> SeriesReport:
    values = column.to_numpy(float)
    present = ~np.isnan(values)
    missing = []
    empty = np.flatnonzero(~present)
    if len(empty):
        # a run continues while the next empty period starts where the previous one ends
        breaks = np.flatnonzero((np.diff(empty) != 1)
                                | (column.index[empty[1:]] != ends[empty[:-1]])) + 1
        for run in np.split(empty, breaks):
            missing.append(Span(column.index[run[0]], ends[run[-1]], len(run)))
    finite = values[present]
    return SeriesReport(name=name, unit=unit_of(name), meaning=meaning, values=int(present.sum()),
                        minimum=float(finite.min()) if len(finite) else None,
                        maximum=float(finite.max()) if len(finite) else None, missing=tuple(missing))


# ----------------------------------------------------------------------------- to hours


def hourly(imported: Imported) -> tuple[pd.DataFrame, list[str]]:
    """The series on a contiguous UTC hour grid [hour-beginning index; NaN where unknown].

    Hourly periods are taken as they are. Shorter periods (15 or 30 minutes) are averaged
    over the hour they fall in, which for a price is the price of a flat one-hour block
    (each quarter delivers a quarter of the energy) and for a power the hourly mean power;
    an hour is averaged only when all of its periods have a value, otherwise it stays
    empty. Periods longer than an hour, or not aligned to the hour grid, are refused.
    Returns the table and one note per hour left empty by an incomplete average.
    """
    values, ends = imported.values, imported.ends
    starts = values.index
    durations = ends - starts
    name = imported.report.files[0].name if imported.report.files else imported.report.source
    if (durations > HOUR).any():
        raise DataImportError(f"{name}: periods longer than one hour cannot be placed on an hourly history")
    hours = starts.floor("h")
    misaligned = ((HOUR % durations) != pd.Timedelta(0)) | ((starts - hours) % durations != pd.Timedelta(0))
    if misaligned.any():
        raise DataImportError(f"{name}: some periods do not divide the clock hour evenly; "
                              "only 15, 30 and 60-minute periods aligned to the hour are supported")
    share = (durations / HOUR).to_numpy(float)
    weighted = values.mul(share, axis=0)
    complete = values.notna().mul(share, axis=0)
    by_hour = weighted.groupby(hours).sum(min_count=1)
    covered = complete.groupby(hours).sum()
    full = covered.sub(1.0).abs() < 1e-9
    notes = []
    partial = (~full & (covered > 0)).any(axis=1)
    for hour in by_hour.index[partial.to_numpy()]:
        short = [c for c in by_hour.columns if not full.loc[hour, c] and covered.loc[hour, c] > 0]
        notes.append(f"{_utc(hour)}: {', '.join(short)} not averaged (some quarter-hours of the hour have no value)")
    table = by_hour.where(full)
    grid = pd.date_range(hours.min(), ends.max().ceil("h"), freq="h", inclusive="left", name="timestamp")
    return table.reindex(grid), notes


# ----------------------------------------------------------------------------- files


def read_bytes(path: str | Path, limit_mb: float = 512.0) -> bytes:
    """A file's bytes, refusing folders, named pipes and devices (before opening them, see
    :func:`rvpp.data.files.open_regular`), missing or unreadable files and files above ``limit_mb``."""
    path = Path(path)
    limit = int(limit_mb * 1e6)
    try:
        with open_regular(path, f'"{path.name}"', DataImportError) as handle:
            size = os.fstat(handle.fileno()).st_size
            data = handle.read(limit + 1) if size <= limit else b""  # read no more than the limit, even if it grows
    except FileNotFoundError:
        raise DataImportError(f'"{path.name}" does not exist') from None
    except OSError as exc:
        raise DataImportError(f'"{path.name}" cannot be read ({exc.strerror or exc})') from None
    size = max(size, len(data))
    if size > limit:
        raise DataImportError(f'"{path.name}" is {size / 1e6:.0f} MB; files above {limit_mb:g} MB are refused')
    return data


def decode(data: bytes, name: str) -> str:
    """Text of a download: UTF-8 (with or without byte-order mark), else Latin-1, as
    spreadsheet programs on Windows save a CSV. Anything that is not text is refused,
    naming what it seems to be (:func:`rvpp.data.files.sniff`)."""
    kind = sniff(data)
    if kind is not None:
        raise DataImportError(f'"{name}" is {kind}, not a text file')
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")
