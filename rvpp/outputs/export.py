"""Write a plan to disk: ``summary.json``, CSV tables and ``plan.xlsx`` (docs/exports.md).

Writes are atomic: a file appears complete or not at all, and a plan folder holds the
files of one run only (:func:`write_plan`).
"""

from __future__ import annotations

import errno
import io
import json
import math
import os
import shutil
from pathlib import Path

import pandas as pd

from ..data.files import sibling
from ..errors import require
from ..solving.results import Result

TABLES = ("market", "units", "csp", "dispatch", "flexibility")
SUMMARY = "summary.json"
PLAN_FILES = (*(f"{name}.csv" for name in TABLES), "plan.xlsx", SUMMARY)  # what rvpp owns in a plan folder


def write_plan(result: Result, folder: str | Path) -> list[Path]:
    """Write every export of ``result`` into ``folder``; return the paths written.

    The files are written into a temporary folder beside ``folder`` and moved into place
    only when all are complete, ``summary.json`` last. A run without a plan writes only
    ``summary.json`` and removes the plan files of an earlier run, so the folder never
    shows a stale plan beside a new summary. Other files in ``folder`` (notes of your
    own) are never touched; a failure part-way leaves the earlier run's files as they were.
    """
    require(result, Result, "rvpp.write_plan: result", "from rvpp.solve")
    folder = check_plan_folder(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = sibling(folder, "tmp")
    staging.mkdir()
    try:
        names = _write_exports(result, staging)
        if not folder.exists():
            staging.rename(folder)
            return [folder / name for name in names]
        for name in names[:-1]:
            os.replace(staging / name, folder / name)
        for stale in set(PLAN_FILES) - set(names):
            (folder / stale).unlink(missing_ok=True)
        os.replace(staging / SUMMARY, folder / SUMMARY)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [folder / name for name in names]


def check_plan_folder(folder: str | Path) -> Path:
    """``folder`` as an absolute path, once it is known to be able to take a plan's exports (a
    folder or nothing yet, not the root folder); else :class:`OSError` naming ``folder`` as given.
    ``.`` is the current folder: the exports are written beside it first, so they need its name."""
    path = Path(os.path.abspath(folder))
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "it is a file, not a folder", str(folder))
    if path.parent == path:
        raise IsADirectoryError(errno.EISDIR, "the root folder cannot take the exports; give a folder inside it",
                                str(folder))
    return path


def _write_exports(result: Result, folder: Path) -> list[str]:
    """Write the exports into an empty ``folder``; their names, ``summary.json`` last."""
    names = []
    if result.has_plan:
        for name in TABLES:
            getattr(result, name).to_csv(folder / f"{name}.csv", index=False, float_format="%.6f")
            names.append(f"{name}.csv")
        write_workbook(result, folder / "plan.xlsx")
        names.append("plan.xlsx")
    (folder / SUMMARY).write_text(json.dumps(_clean(result.summary()), indent=2) + "\n", encoding="utf-8")
    return [*names, SUMMARY]


def write_workbook(result: Result, target: str | Path | io.BytesIO) -> str | Path | io.BytesIO:
    """The same tables as sheets of one Excel workbook, plus a summary sheet."""
    summary = _flatten(result.summary())
    with pd.ExcelWriter(target, engine="openpyxl") as writer:
        pd.DataFrame({"field": list(summary), "value": list(summary.values())}).to_excel(
            writer, sheet_name="summary", index=False)
        for name in TABLES:
            getattr(result, name).to_excel(writer, sheet_name=name, index=False)
        for sheet in writer.sheets.values():
            sheet.freeze_panes = "A2"
            for column in sheet.columns:
                width = max(len(str(c.value)) if c.value is not None else 0 for c in column[:50])
                sheet.column_dimensions[column[0].column_letter].width = min(max(10, width + 2), 40)
    return target


def plan_workbook_bytes(result: Result) -> bytes:
    """``plan.xlsx`` as bytes (for downloads)."""
    buffer = io.BytesIO()
    write_workbook(result, buffer)
    return buffer.getvalue()


def _flatten(summary: dict, prefix: str = "") -> dict:
    flat = {}
    for key, value in summary.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, f"{prefix}{key}."))
        elif isinstance(value, list):
            flat[f"{prefix}{key}"] = ", ".join(map(str, value))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _clean(value):
    """JSON-safe: NaN and infinities become null."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
