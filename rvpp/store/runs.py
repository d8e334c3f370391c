"""The run library: solved plans saved with their case, settings and tables, to reopen later.

A saved run keeps the case as edited (every unit and setting, and its history), the run
switches the case does not hold (``settings``), the solve's outcome and objective parts,
and the plan's tables. Reopening a run prepares its case again (periods, bands) and
returns a :class:`~rvpp.solving.results.Result` equal to the one saved, without solving.

Labels are unique and editable: saving under a taken label adds `` (2)``, `` (3)``, ...;
renaming onto a taken label is refused.

Run switches are settings the case does not hold: ``settings["csp"] = False`` says the
plan was solved without the CSP plants (``rvpp.with_options(case, csp=False)``) while
the case keeps their parameters. The saved result belongs to the case with its run
switches applied (:func:`solved_case`).
"""

from __future__ import annotations

import io
import json
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
import sqlalchemy as sa

from ..data.case import Case, parse_case
from ..data.case_yaml import save_case
from ..data.variants import with_options
from ..data.files import BIDI_CONTROLS, CONTROL_CHARACTERS, excerpt, refused_character
from ..solving.outcome import Outcome
from ..solving.results import Result
from .codec import case_data, history_bytes, history_from, jsonable
from ..data.edits import LABEL_LENGTH
from .engine import (StoreError, connect, decoding, drop_unused_blobs, get_blob, now, put_blob,
                     runs)
from ..outputs.export import write_plan
from ..uncertainty.problem import prepare

TABLES = ("market", "units", "csp", "dispatch", "flexibility")
SAVE_ATTEMPTS = 5  # a save retries when a concurrent save took the same label
# A label is one line shown in tables, messages and exported files: control characters (as in a case's
# names) and the bidirectional overrides and isolates (which make "abc" read "cba") are refused;
# zero-width spaces and joiners may be part of a label but do not make one.
_ZERO_WIDTH = dict.fromkeys(map(ord, "\u200b\u200c\u200d\ufeff"))
_REFUSED = ((CONTROL_CHARACTERS, "control characters"), (BIDI_CONTROLS, "bidirectional override characters"))
LISTED = ("id", "label", "created_at", "updated_at", "case_name", "delivery_date", "strategy", "markets",
          "status", "objective_eur")


@dataclass(frozen=True)
class RunInfo:
    """One line of the library: what a run is, without its tables."""

    id: str
    label: str
    created_at: str
    updated_at: str
    case_name: str
    delivery_date: str
    strategy: str
    markets: str
    status: str
    objective_eur: float | None


@dataclass(frozen=True, eq=False)
class SavedRun:
    """A run as reopened: its line in the library, its case, its settings and its plan."""

    info: RunInfo
    case: Case
    settings: dict[str, Any] = field(default_factory=dict)
    result: Result | None = None


class RunLibrary:
    """Saved runs in the store at ``url`` (default: the environment's, see :mod:`rvpp.store.engine`)."""

    def __init__(self, url: str | None = None, engine: sa.Engine | None = None):
        self.engine = engine or connect(url)

    def save(self, label: str, case: Case, result: Result | None = None,
             settings: Mapping[str, Any] | None = None) -> RunInfo:
        """Save one run in one transaction; the label gets a suffix if it is taken."""
        label = _clean_label(label)
        if result is not None and result.case != solved_case(case, settings or {}):
            raise StoreError(f'could not save "{label}": its plan was solved for another case than the one '
                             "given (with the run switches of its settings applied)")
        history = history_bytes(case.history)
        tables = _tables_bytes(result) if result is not None and result.has_plan else None
        stamp = now()
        row = {
            "id": uuid.uuid4().hex, "created_at": stamp, "updated_at": stamp,
            "case_name": case.name, "delivery_date": case.delivery_date.isoformat(),
            "strategy": case.budgets.strategy, "markets": case.markets.label,
            "status": str(result.status) if result is not None else "not solved",
            "objective_eur": result.objective_eur if result is not None else None,
            "case": case_data(case), "settings": jsonable(dict(settings or {})),
            "result": _result_data(result),
        }
        for attempt in range(1, SAVE_ATTEMPTS + 1):
            try:
                with self.engine.begin() as connection:
                    row["history_digest"] = put_blob(connection, "history.parquet", history)
                    row["tables_digest"] = put_blob(connection, "tables.zip", tables) if tables else None
                    similar = sa.select(runs.c.label).where(runs.c.label.startswith(label, autoescape=True))
                    row["label"] = _free_label(label, set(connection.execute(similar).scalars()))
                    connection.execute(runs.insert().values(**row))
                return RunInfo(**{k: row[k] for k in LISTED})
            except sa.exc.IntegrityError:  # another session took the same label meanwhile: pick again
                if attempt == SAVE_ATTEMPTS:
                    raise StoreError(f'could not save "{label}": the store kept refusing the label') from None

    def list(self) -> list[RunInfo]:
        """Every run, newest first."""
        query = sa.select(*(runs.c[k] for k in LISTED)).order_by(runs.c.created_at.desc())
        with self.engine.connect() as connection:
            return [RunInfo(**row._asdict()) for row in connection.execute(query)]

    def info(self, run_id: str) -> RunInfo:
        query = sa.select(*(runs.c[k] for k in LISTED)).where(runs.c.id == run_id)
        with self.engine.connect() as connection:
            row = connection.execute(query).first()
        if row is None:
            raise _no_run(run_id)
        return RunInfo(**row._asdict())

    def load(self, run_id: str) -> SavedRun:
        """Reopen a run: its case (with history), settings and plan."""
        with self.engine.connect() as connection:
            row = connection.execute(sa.select(runs).where(runs.c.id == run_id)).first()
            if row is None:
                raise _no_run(run_id)
            history = get_blob(connection, row.history_digest)
            tables = get_blob(connection, row.tables_digest) if row.tables_digest else None
        with decoding(f"the saved run {excerpt(run_id)!r}", "; delete it"):
            info = RunInfo(**{k: getattr(row, k) for k in LISTED})
            case = parse_case(row.case, history_from(history, row.settings.get("history_source", "history")))
            result = _result_from(solved_case(case, row.settings), row.result, tables) if row.result else None
            return SavedRun(info=info, case=case, settings=dict(row.settings), result=result)

    def rename(self, run_id: str, label: str) -> RunInfo:
        """Give a run a new label; refused if another run has it."""
        label = _clean_label(label)
        taken = StoreError(f'the label "{label}" is already used by another saved run; choose another')
        try:
            with self.engine.begin() as connection:
                other = connection.execute(sa.select(runs.c.id).where(runs.c.label == label)).scalar_one_or_none()
                if other is not None and other != run_id:
                    raise taken
                done = connection.execute(runs.update().where(runs.c.id == run_id)
                                          .values(label=label, updated_at=now())).rowcount
        except sa.exc.IntegrityError:  # another session gave a run the same label meanwhile
            raise taken from None
        if not done:
            raise _no_run(run_id)
        return self.info(run_id)

    def delete(self, run_id: str) -> None:
        """Delete a run, and its stored history and tables once no other run or backtest shares them."""
        with self.engine.begin() as connection:
            done = connection.execute(runs.delete().where(runs.c.id == run_id)).rowcount
            drop_unused_blobs(connection)
        if not done:
            raise _no_run(run_id)

    def export_zip(self, run_id: str) -> bytes:
        """The run as a zip: its case folder (``case/``) and its plan exports (``plan/``)."""

        saved = self.load(run_id)
        buffer = io.BytesIO()
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            save_case(saved.case, folder / "case")
            if saved.result is not None:
                write_plan(saved.result, folder / "plan")
            (folder / "run.json").write_text(json.dumps({
                "label": saved.info.label, "id": saved.info.id, "created_at": saved.info.created_at,
                "settings": saved.settings}, indent=2) + "\n", encoding="utf-8")
            with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
                for path in sorted(p for p in folder.rglob("*") if p.is_file()):
                    archive.write(path, arcname=str(path.relative_to(folder)))
        return buffer.getvalue()


def solved_case(case: Case, settings: Mapping[str, Any]) -> Case:
    """The case a saved plan was solved for: ``case`` with the run switches of ``settings``."""
    return with_options(case, csp=False) if settings.get("csp") is False and case.csp else case


# ----------------------------------------------------------------------------- encoding


def _clean_label(label: str) -> str:
    if refused := refused_character(str(label), _REFUSED):
        raise StoreError(f"the label must not contain {refused}")
    text = " ".join(str(label).split())
    if not text.translate(_ZERO_WIDTH).strip():
        raise StoreError("a saved run needs a label; the label is empty")
    if len(text) > LABEL_LENGTH - 8:
        raise StoreError(f"the label has {len(text)} characters; at most {LABEL_LENGTH - 8} are allowed")
    return text


def _no_run(run_id: str) -> StoreError:
    return StoreError(f"no saved run has the id {excerpt(run_id)!r}; it may have been deleted")


def _free_label(label: str, taken: set[str]) -> str:
    if label not in taken:
        return label
    n = 2
    while f"{label} ({n})" in taken:
        n += 1
    return f"{label} ({n})"


def _tables_bytes(result: Result) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as archive:
        for name in TABLES:
            table = io.BytesIO()
            getattr(result, name).to_parquet(table, index=False)
            archive.writestr(f"{name}.parquet", table.getvalue())
    return buffer.getvalue()


def _result_data(result: Result | None) -> dict[str, Any]:
    if result is None:
        return {}
    return jsonable({
        "status": str(result.status), "termination": result.termination, "message": result.message,
        "objective_eur": result.objective_eur, "bound_eur": result.bound_eur, "mip_gap": result.mip_gap,
        "build_s": result.build_s, "solve_s": result.solve_s, "extract_s": result.extract_s,
        "parts": result.parts, "protection_eur": result.protection_eur,
    })


def _result_from(case: Case, data: Mapping[str, Any], tables: bytes | None) -> Result:

    frames = {}
    if tables:
        with zipfile.ZipFile(io.BytesIO(tables)) as archive:
            stored = set(archive.namelist())  # a run saved before a table existed has none of it
            frames = {name: pd.read_parquet(io.BytesIO(archive.read(f"{name}.parquet"))) for name in TABLES
                      if f"{name}.parquet" in stored}
    fields = {k: data[k] for k in ("termination", "message", "objective_eur", "bound_eur", "mip_gap", "build_s",
                                   "solve_s", "extract_s", "parts", "protection_eur")}
    return Result(problem=prepare(case), status=Outcome(data["status"]), **fields, **frames)
