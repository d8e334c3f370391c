"""Write a plan to disk: ``summary.json``, CSV tables and ``plan.xlsx`` (docs/exports.md)."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import pandas as pd

from ..solving.results import Result

TABLES = ("market", "units", "csp", "flexibility")


def write_plan(result: Result, folder: str | Path) -> list[Path]:
    """Write every export of ``result`` into ``folder``; return the paths written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = [folder / "summary.json"]
    written[0].write_text(json.dumps(_clean(result.summary()), indent=2) + "\n", encoding="utf-8")
    if not result.has_plan:
        return written
    for name in TABLES:
        path = folder / f"{name}.csv"
        getattr(result, name).to_csv(path, index=False, float_format="%.6f")
        written.append(path)
    written.append(write_workbook(result, folder / "plan.xlsx"))
    return written


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
