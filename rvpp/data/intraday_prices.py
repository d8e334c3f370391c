"""Real intraday auction prices added to a case's history (MODEL_SPEC §14).

:func:`add_intraday_prices` reads OMIE's intraday price files
(:mod:`rvpp.data.importers.omie_intraday`) for the days of a case's history and writes one
column per session into it, ``price_<session>`` [EUR/MWh] (``price_ida1``, ``price_ida2``,
``price_ida3``), hourly like every column of the history (quarter-hours averaged to hours,
as for the day-ahead price).

A history has a value in every hour, but a session trades only in its window (IDA3 from
12:00). The hours before the window hold the day-ahead price of the same hour: the session
trades nothing there, so the value is never used, and the provenance says so. Inside the
window every hour of every day of the history needs a price; a missing one is refused with
the first hour it concerns, never filled.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

import pandas as pd

from ..errors import DataImportError, RvppError
from .case import CASE_FILE, Case, parse_case
from .case_yaml import load_case, save_case
from .importers import HourlyTable, ImportReport, hourly_table, omie_intraday
from .importers.omie_intraday import DEFAULT_PRESET, TIMEZONE, in_window, sessions_of

SHOWN_HOURS = 3  # missing hours named in a refusal before "and N more"


@dataclass(frozen=True, eq=False)
class AddedPrices:
    """A case whose history received intraday prices, with what went into them."""

    folder: Path
    case: Case
    reports: tuple[ImportReport, ...]
    columns: tuple[str, ...]
    table: HourlyTable  # the prices as read, on their hours (empty outside each window)

    def lines(self) -> list[str]:
        days = self.case.history.local_days(TIMEZONE)
        out = [f"added {', '.join(self.columns)} to the history of case {self.case.name!r} in {self.folder}",
               f"  days: {days[0]} to {days[-1]} ({len(days)} days)"]
        for column in self.columns:
            origin = self.case.provenance_map[column]
            out.append(f"  {column}: {origin.origin}, {origin.source} ({origin.note})")
        return out


def add_intraday_prices(sources: list[str | Path], folder: str | Path, *, preset: str = DEFAULT_PRESET,
                        zone: str = "ES", overwrite: bool = False) -> AddedPrices:
    """Read intraday price files and write their sessions' prices into the history of the case in
    ``folder`` (``case.yaml`` and its history CSV, replaced atomically); ``overwrite`` allows
    replacing intraday price columns the history already holds."""
    folder = Path(folder)
    sessions = sessions_of(preset)
    case = load_case(folder)
    history = case.history.frame
    days = sorted(set(history.index.tz_convert(TIMEZONE).date))
    imports = omie_intraday.read(list(sources), preset, zone, days=(days[0], days[-1]))
    table = hourly_table(imports)
    held = [c for c in table.frame.columns if c in history.columns]
    if held and not overwrite:
        raise RvppError(f"the history of {folder} already holds {', '.join(held)}; replace them (--force) or "
                        "choose another case")
    columns, provenance = {}, {}
    for session in sessions:
        if session.column not in table.frame.columns:
            continue
        values = table.frame[session.column].reindex(history.index)
        inside = in_window(history.index, session)
        missing = history.index[(inside & values.isna()).to_numpy()]
        if len(missing):
            raise DataImportError(_missing_message(session.name, session.column, missing, days))
        columns[session.column] = values.where(inside, history["price_da"]).to_numpy(float)
        provenance[session.column] = {
            "origin": "real", "source": _source(session.column, table.origins[session.column]),
            "note": f"as published, averaged to hours; before {session.first_hour:02d}:00 local, outside "
                    f"{session.name}'s window, the day-ahead price of the hour (the session trades nothing there)"}
    data = case.to_data()
    data["provenance"] = {**data["provenance"], **provenance}
    added = parse_case(data, case.history.with_columns(columns))
    _write(added, folder, PurePosixPath(case.history.source))
    return AddedPrices(folder=folder, case=added, reports=tuple(i.report for i in imports), columns=tuple(columns),
                        table=table)


def _missing_message(name: str, column: str, missing: pd.DatetimeIndex, days: list[dt.date]) -> str:
    local = [f"{t.tz_convert(TIMEZONE):%Y-%m-%d %H:%M}" for t in missing[:SHOWN_HOURS]]
    more = f" and {len(missing) - SHOWN_HOURS} more" if len(missing) > SHOWN_HOURS else ""
    return (f"{column}: no {name} price for {len(missing)} hour(s) of its window ({', '.join(local)}{more}, local "
            f"time); give the {name} file of every day of the history ({days[0]} to {days[-1]})")


def _source(column: str, reports: tuple[ImportReport, ...]) -> str:
    names = sorted({f.name for r in reports for f in r.files})
    digest = hashlib.sha256("".join(sorted(f.sha256 for r in reports for f in r.files)).encode()).hexdigest()[:16]
    files = names[0] if len(names) == 1 else f"{len(names)} files, {names[0]} to {names[-1]}"
    return f"{omie_intraday.SOURCE}: {column}, zone {reports[0].zone}; {files}, sha256 {digest}"


def _write(case: Case, folder: Path, history_file: PurePosixPath) -> None:
    """Write the case into a temporary folder beside ``folder``, then move its history and its
    ``case.yaml`` into place (each replaced whole, never seen half-written)."""
    temp = Path(tempfile.mkdtemp(dir=folder.resolve().parent, prefix=f".{folder.name}.", suffix=".tmp"))
    try:
        (temp / history_file).parent.mkdir(parents=True, exist_ok=True)
        save_case(case, temp, str(history_file))
        os.replace(temp / history_file, folder / history_file)
        os.replace(temp / CASE_FILE, folder / CASE_FILE)
    finally:
        shutil.rmtree(temp, ignore_errors=True)

