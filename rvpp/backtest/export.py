"""A backtest's records and the exact inputs it used, as files others can reproduce it from.

``export(store, ident, folder)`` writes (CSV for spreadsheets, Parquet for programs):

* ``records.csv`` / ``.parquet``: one row per day and variant, every number of the day
  (budgets as ``gamma_<source>``, start and end state as ``start_<csp>_<field>``, ...);
* ``bids.csv`` / ``.parquet``: the first-stage bids, one row per day, variant and period;
* ``dispatch.csv`` / ``.parquet``: the settled dispatch, one row per day, variant, unit and
  period: a CSP's turbine status and storage energy, a battery's charge, discharge and energy, a
  hydro or biomass unit's status and output;
* ``aggregates.csv`` / ``.parquet`` and ``monthly.csv`` / ``.parquet`` (:mod:`.metrics`);
* ``case/``: ``case.yaml`` and ``history.csv`` (full precision) exactly as stored with the
  backtest: ``rvpp.load_case`` on it gives the same history fingerprint;
* ``manifest.json``: backtest id, settings, data fingerprints, rvpp version, git commit
  (when the code runs from a git checkout) and the time of the export.

The folder appears complete or not at all: everything is written into a temporary
sibling folder that replaces ``folder`` in one rename. Since it replaces ``folder`` as a
whole, ``folder`` may only be missing, an empty folder or an earlier export holding nothing
else (:func:`check_replaceable_export`): a folder of your own or a file is never replaced.
"""

from __future__ import annotations

import datetime as dt
import errno
import io
import json
import os
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from pathlib import Path
from typing import Any

import pandas as pd

from ..data.case_yaml import save_case
from ..data.files import excerpt_names
from ..store import BacktestStore
from . import metrics
from .engine import BIDS
from .settings import BacktestError
from .. import __version__

ROOT = Path(__file__).resolve().parents[2]
NESTED = ("budgets", "start_state", "end_state", "bids", "settled_csp", "settled_units", "plan_integer_ones")
# The settled dispatch: the columns of the CSPs first, as exported before batteries, hydro and biomass units
DISPATCH_COLUMNS = ["day", "strategy", "gamma", "unit", "t", "online", "e_mwh_th", "kind", "p_mw", "charge_mw",
                    "discharge_mw", "e_mwh"]
MANIFEST = "manifest.json"
MANIFEST_MAX_BYTES = 1024 ** 2  # an export's manifest holds settings and notes: a few kB; larger is not one


def records_table(records: pd.DataFrame) -> pd.DataFrame:
    """The records with nested values spread into flat columns (bids go to :func:`bids_table`)."""
    rows = []
    for record in records.to_dict("records"):
        row = {k: v for k, v in record.items() if k not in NESTED}
        for source, gamma in (record.get("budgets") or {}).items():
            row[f"gamma_{source}"] = gamma
        for when in ("start", "end"):
            for unit, state in (record.get(f"{when}_state") or {}).items():
                for field, value in state.items():
                    row[f"{when}_{unit}_{field}"] = value
        rows.append(row)
    return pd.DataFrame(rows)


def bids_table(records: pd.DataFrame) -> pd.DataFrame:
    """First-stage bids, one row per day, variant and period ``t`` [MW], [MW_th]."""
    frames = []
    for record in records.to_dict("records"):
        bids = record.get("bids")
        if not isinstance(bids, dict):
            continue
        frame = pd.DataFrame({name: bids[name] for name in BIDS})
        frame.insert(0, "t", range(1, len(frame) + 1))
        for position, key in enumerate(("day", "strategy", "gamma")):
            frame.insert(position, key, record[key])
        frames.append(frame)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["day", "strategy", "gamma", "t",
                                                                                       *BIDS])


def dispatch_table(records: pd.DataFrame) -> pd.DataFrame:
    """The settled dispatch, one row per day, variant, unit and period: a CSP's turbine status and
    storage energy, a battery's charge, discharge and energy, a hydro or biomass unit's status and
    output (:data:`DISPATCH_COLUMNS`; a column that does not apply to a unit's kind is empty)."""
    frames = []
    for record in records.to_dict("records"):
        csps, others = (value if isinstance(value, dict) else {}  # a day without a settlement has none
                        for value in (record.get("settled_csp"), record.get("settled_units")))
        units = [(unit, {"kind": "csp", **values}) for unit, values in csps.items()] + list(others.items())
        for unit, settled in units:
            values = {key: value for key, value in settled.items() if key != "kind"}
            periods = len(next(iter(values.values())))
            frame = pd.DataFrame({"t": range(1, periods + 1), **values})
            for position, (key, value) in enumerate((("day", record["day"]), ("strategy", record["strategy"]),
                                                     ("gamma", record["gamma"]), ("unit", unit))):
                frame.insert(position, key, value)
            frame["kind"] = settled["kind"]
            frames.append(frame)
    if not frames:
        return pd.DataFrame(columns=DISPATCH_COLUMNS)
    return pd.concat(frames, ignore_index=True).reindex(columns=DISPATCH_COLUMNS)


def git_commit() -> str | None:
    """The commit of the code when it runs from a git checkout (``None`` otherwise)."""
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def export(store: BacktestStore, ident: str, folder: str | Path, extra: dict[str, pd.DataFrame] | None = None,
           notes: dict[str, Any] | None = None) -> Path:
    """Write the backtest ``ident`` into ``folder`` (replaced as a whole); return the folder.

    ``folder`` must be missing, empty or an earlier export (:func:`check_replaceable_export`,
    checked before anything is written and again just before the swap). ``extra`` tables are
    written beside the others (CSV and Parquet); ``notes`` go into the manifest.
    """

    folder = Path(folder)
    check_replaceable_export(folder)
    place = folder.resolve()  # "." or "/" has no name to give the staging folder beside it
    case, settings = store.load(ident)
    records = store.records(ident)
    if records.empty:
        raise BacktestError(f"backtest {ident} has no day recorded yet: nothing to export (see backtest list)")
    place.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{place.name}.", dir=place.parent))
    try:
        tables = {"records": records_table(records), "bids": bids_table(records), "dispatch": dispatch_table(records),
                  "aggregates": metrics.aggregates(records), "monthly": metrics.monthly(records), **(extra or {})}
        for name, table in tables.items():
            # UTF-8 with a byte-order mark: Excel then reads labels such as "Γ 0.25 of the day" right
            table.to_csv(staging / f"{name}.csv", index=False, float_format="%.6f", encoding="utf-8-sig")
            _plain_for_parquet(table).to_parquet(staging / f"{name}.parquet", index=False)
        save_case(case, staging / "case")
        _exact_history(case, staging / "case" / "history.csv")
        manifest = {"backtest_id": ident, "settings": settings, "case": case.name,
                    "history_fingerprint": case.history.fingerprint, "records": len(records),
                    "rvpp_version": __version__, "git_commit": git_commit(),
                    "exported_at": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
                    **(notes or {}),
                    "files": sorted(p.name for p in staging.iterdir())}
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=2, default=str) + "\n", encoding="utf-8")
        _replace(staging, place)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return folder


def export_zip(store: BacktestStore, ident: str) -> bytes:
    """The files of :func:`export` as one zip archive (e.g. for a download), same layout."""
    with tempfile.TemporaryDirectory(prefix="rvpp-backtest-") as tmp:
        folder = export(store, ident, Path(tmp) / "backtest")
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(p for p in folder.rglob("*") if p.is_file()):
                archive.write(path, arcname=str(path.relative_to(folder)))
    return buffer.getvalue()


def _exact_history(case, path: Path) -> None:
    """The history CSV at full precision, so the exported case has the backtest's fingerprint."""
    frame = case.history.frame
    frame.insert(0, "timestamp", [t.isoformat() for t in frame.index.tz_convert(case.timezone)])
    frame.to_csv(path, index=False)


def _plain_for_parquet(table: pd.DataFrame) -> pd.DataFrame:
    """Columns Parquet can hold: dates and mixed objects as text."""
    out = table.copy()
    for column in out.columns:
        if out[column].dtype == object:
            values = out[column].dropna()
            if not values.map(lambda v: isinstance(v, str)).all():
                out[column] = out[column].map(lambda v: None if v is None or v != v else _text(v))
    return out


def _text(value: Any) -> str:
    return value.isoformat() if isinstance(value, (dt.date, dt.datetime)) else str(value)


def check_replaceable_export(folder: str | Path) -> None:
    """Refuse to replace ``folder`` with an export unless it is missing, an empty folder or an
    earlier export of :func:`export` holding nothing else.

    An earlier export is recognised by its ``manifest.json``: a JSON object with a
    ``backtest_id`` and the ``files`` written beside it, and no other file in the folder.
    Anything else (a folder of your own, a file, a link to nothing) raises
    :class:`FileExistsError` naming ``folder`` and the reason, as
    :func:`rvpp.outputs.export.check_replaceable` does for single files, so a mistyped
    folder cannot destroy unrelated work.
    """
    folder = Path(folder)
    if not os.path.lexists(folder):
        return
    if not folder.is_dir():
        what = "a file of that name exists" if folder.is_file() else "it exists and is not a folder"
        raise FileExistsError(errno.EEXIST, f"{what}; choose a new folder", str(folder))
    entries = {p.name for p in folder.iterdir()}
    if not entries:
        return
    exported = _exported_files(folder / MANIFEST)
    if exported is None:
        raise FileExistsError(errno.EEXIST, "the folder exists and is not a backtest export; choose a new folder "
                              "or remove it", str(folder))
    others = sorted(entries - exported - {MANIFEST})
    if others:
        raise FileExistsError(errno.EEXIST, f"the folder is an earlier backtest export but also holds "
                              f"{excerpt_names(others)}, which the export did not write; move them out or choose "
                              "a new folder", str(folder))


def _exported_files(manifest: Path) -> set[str] | None:
    """The files an earlier export lists in its ``manifest`` (``None``: not an export's manifest)."""
    if not manifest.is_file():
        return None
    with manifest.open("rb") as handle:
        data = handle.read(MANIFEST_MAX_BYTES + 1)
    try:
        content = json.loads(data) if len(data) <= MANIFEST_MAX_BYTES else None
    except (ValueError, RecursionError):  # not JSON or not text; nested deeper than Python's parser goes
        return None
    if not (isinstance(content, dict) and isinstance(content.get("backtest_id"), str)
            and isinstance(content.get("files"), list) and all(isinstance(f, str) for f in content["files"])):
        return None
    return set(content["files"])


def _replace(staging: Path, folder: Path) -> None:
    """Move ``staging`` to ``folder`` in one rename, the old folder (an earlier export, or empty)
    set aside first; ``folder`` is checked once more, in case something was put there meanwhile."""
    check_replaceable_export(folder)
    old = None
    if folder.exists():
        old = folder.with_name(f".{folder.name}.old-{uuid.uuid4().hex[:8]}")
        folder.rename(old)
    staging.rename(folder)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
