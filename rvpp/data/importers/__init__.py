"""Importers for the public files a user downloads: OMIE, ENTSO-E and hourly tables.

:func:`import_files` recognises each file by its content, reads files of one kind
together (OMIE's daily files make one price series) and returns one
:class:`~rvpp.data.importers.report.Imported` per source, each with its report.
:func:`hourly_table` puts the series of several imports on one UTC hour grid, refusing
series that two files give with different values; :func:`write_table` writes that grid
as rvpp's normalised CSV, which the importers read back.

The ENTSO-E platform's XML web API is not read: its parsers in entsoe-py come with the
package's network client and fill gaps silently, so rvpp reads the platform's CSV
exports instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ...errors import DataImportError
from . import entsoe, omie, omie_intraday, tables
from .report import Imported, ImportReport, decode, hourly, read_bytes
from ..files import replacing

__all__ = ["Imported", "ImportReport", "HourlyTable", "detect", "fill_gaps", "import_files", "hourly_table",
           "write_table"]

FORMATS = ("omie", "entsoe", "dataset", "time_utc")
FORMAT_NAMES = {"omie": omie.SOURCE, "entsoe": entsoe.SOURCE, "dataset": tables.DATASET, "time_utc": tables.TIME_UTC}
AGREE_EUR_OR_MW = 0.005  # two files agree on a value when they differ by less (prices carry 2 decimals)


def detect(path: str | Path) -> str:
    """The format of a file: ``omie``, ``entsoe``, ``dataset`` or ``time_utc``."""
    path = Path(path)
    data = read_bytes(path)
    if omie.is_archive(path, data):
        return "omie"
    text = decode(data[:65536], path.name)
    if omie_intraday.looks_like(text):
        raise DataImportError(f'"{path.name}" is an OMIE intraday auction price file (marginalpibc); read it with '
                              '"rvpp data import-omie-intraday", which knows its sessions')
    for name, test in (("omie", omie.looks_like), ("time_utc", tables.looks_like_time_utc),
                       ("dataset", tables.looks_like_dataset), ("entsoe", entsoe.looks_like)):
        if test(text):
            return name
    raise DataImportError(
        f'"{path.name}": format not recognised; rvpp reads OMIE marginalpdbc files (or their zip archives), '
        "ENTSO-E Transparency Platform CSV exports, the hourly Spanish energy dataset and time_utc tables")


def import_files(paths: list[str | Path], zone: str | None = None) -> list[Imported]:
    """Read every file; ``zone`` chooses the OMIE price column (``ES`` default, ``PT``) or an
    ENTSO-E area when an export holds several."""
    if not paths:
        raise DataImportError("no file given")
    groups: dict[str, list[Path]] = {}
    for path in paths:
        groups.setdefault(detect(path), []).append(Path(path))
    out: list[Imported] = []
    for kind in FORMATS:
        files = groups.get(kind, [])
        if not files:
            continue
        if kind == "omie":
            out.append(omie.read(files, zone or "ES"))
        elif kind == "entsoe":
            out += entsoe.read(files, zone)
        elif kind == "dataset":
            out += [tables.read_dataset(f) for f in files]
        else:
            out += [tables.read_time_utc(f, zone) for f in files]
    return out


@dataclass(frozen=True, eq=False)
class HourlyTable:
    """Series of several imports on one UTC hour grid, with the import each series came from.

    ``frame`` is indexed by UTC hour-beginning instants (NaN where no file gives a value);
    ``origins`` maps each series to the reports of the imports that gave it; ``notes``
    lists hours an average could not fill.
    """

    frame: pd.DataFrame
    origins: dict[str, tuple[ImportReport, ...]]
    notes: tuple[str, ...]


def hourly_table(imports: list[Imported]) -> HourlyTable:
    """Combine imports hour by hour (sub-hourly periods averaged, see :func:`report.hourly`).

    Where two imports give one series for the same hour, their values must agree within
    0.005 (EUR/MWh or MW); otherwise the hour and both files are named.
    """
    frame = pd.DataFrame()
    origins: dict[str, tuple[ImportReport, ...]] = {}
    notes: list[str] = []
    for item in imports:
        table, partial = hourly(item)
        notes += partial
        grid = frame.index.union(table.index) if len(frame) else table.index
        frame = frame.reindex(grid)
        table = table.reindex(grid)
        for column in table.columns:
            if column not in frame.columns:
                frame[column] = table[column]
                origins[column] = (item.report,)
                continue
            both = frame[column].notna() & table[column].notna()
            differ = both & ((frame[column] - table[column]).abs() >= AGREE_EUR_OR_MW)
            if differ.any():
                hour = frame.index[differ.to_numpy()][0]
                first = ", ".join(f.name for r in origins[column] for f in r.files[:1])
                raise DataImportError(
                    f"{column} at {hour:%Y-%m-%dT%H:%MZ}: {item.report.files[0].name} gives "
                    f"{table.at[hour, column]:.6g} but {first} gives {frame.at[hour, column]:.6g}; "
                    "give only one source of this series for that period")
            frame[column] = frame[column].fillna(table[column])
            origins[column] = origins[column] + (item.report,)
    frame.index = pd.DatetimeIndex(frame.index, name="timestamp")
    return HourlyTable(frame=frame, origins=origins, notes=tuple(notes))


def fill_gaps(table: pd.DataFrame, max_hours: int) -> tuple[pd.DataFrame, list[str]]:
    """Interpolate linearly across empty runs of at most ``max_hours`` hours inside each column.

    Only on request (``--fill-gaps``): returns the table and one line per run filled, so the
    filling is reported; a longer run, or one at either end of the table, is refused.
    """
    out = table.copy()
    filled = []
    for column in table.columns:
        empty = table[column].isna().to_numpy()
        if not empty.any():
            continue
        runs = np.split(np.flatnonzero(empty), np.flatnonzero(np.diff(np.flatnonzero(empty)) != 1) + 1)
        for run in runs:
            first, last = table.index[run[0]], table.index[run[-1]]
            if run[0] == 0 or run[-1] == len(table) - 1:
                raise DataImportError(f"{column} has no value at {first:%Y-%m-%dT%H:%MZ}, at the edge of the data; "
                                      "choose a span that starts and ends with values")
            if len(run) > max_hours:
                raise DataImportError(f"{column} has no value for {len(run)} hours from {first:%Y-%m-%dT%H:%MZ}; "
                                      f"at most {max_hours} hours are interpolated (--fill-gaps)")
            filled.append(f"{column}: {len(run)} hour(s) from {first:%Y-%m-%dT%H:%MZ} to {last:%Y-%m-%dT%H:%MZ} "
                          "interpolated linearly")
        out[column] = table[column].interpolate(method="linear", limit_area="inside")
    return out, filled


TABLE_HEADER = b"time_utc,time_local"  # how the normalised CSV of write_table begins


def write_table(table: pd.DataFrame, path: str | Path, timezone: str = "Europe/Madrid") -> Path:
    """Write an hourly table as rvpp's normalised CSV (``time_utc, time_local, series...``),
    atomically (a temporary file renamed into place)."""

    path = Path(path)
    out = table.copy()
    out.insert(0, "time_local", [t.isoformat() for t in table.index.tz_convert(timezone)])
    out.insert(0, "time_utc", [f"{t:%Y-%m-%dT%H:%M:%SZ}" for t in table.index])
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as temporary:
        out.to_csv(temporary, index=False, float_format="%.6g", na_rep="")
    return path
