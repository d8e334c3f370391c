"""A case as tables: one row per unit, for table editors and Excel workbooks.

:func:`unit_table` lays the units of one kind out flat (nested CSP sections become
dotted columns such as ``storage.e_min_mwh_th``; the power-block breakpoints have their
own :func:`breakpoint_table`). :func:`with_unit_table` reads such a table back through
the case model, so an invalid value raises :class:`~rvpp.errors.CaseError` naming the
unit, the field, the value and the rule.

The case workbook follows the layout of the plan export (``plan.xlsx``): a ``case``
sheet of ``field``/``value`` rows, then one sheet per table with one header row:

=============  ==================================================================
sheet          content
=============  ==================================================================
``case``       name, description, delivery date, time zone, period length and the
               ``markets.``, ``uncertainty.``, ``budgets.`` and ``solver.`` settings
               (not ``solver.mip_start``, a start from an earlier plan)
``hpa_tariff`` ``hour`` 0..23, ``tariff_eur_per_mwh``
``budgets``    ``source``, ``gamma`` [periods]: per-source overrides of the strategy
``wind`` ...   one sheet per unit kind (``wind``, ``pv``, ``csp``, ``ed``, ``td``, ``battery``,
               ``hydro``, ``biomass``)
``breakpoints`` ``unit``, ``input_mw_th``, ``efficiency`` of every CSP power block
``history``    ``timestamp`` (ISO 8601 with UTC offset) and one column per series
=============  ==================================================================
"""

from __future__ import annotations

import datetime as dt
import io
import math
import zipfile
from xml.etree import ElementTree
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

import openpyxl

from ..data.case import Case, ElectricalDemand, PowerBlock, ThermalStorage, parse_case
from ..data.kinds import KINDS, PAPER_KINDS, UNIT_KINDS, UnitKind
from ..data.edits import flatten
from ..data.files import UploadBudget, UploadLimits, excerpt, open_zip, read_file, unzip
from ..data.history import History
from ..errors import CaseError, CaseFileError, UploadLimitError

BREAKPOINTS = "power_block.breakpoints"
BREAKPOINT_COLUMNS = ("input_mw_th", "efficiency")
SERIES_FIELDS = {kind: info.series_field for kind, info in KINDS.items()}
NAME_PREFIXES = {kind: info.prefix for kind, info in KINDS.items()}
SETTING_SECTIONS = ("markets", "uncertainty", "budgets", "solver")
TOP_SETTINGS = ("name", "description", "delivery_date", "timezone", "dt_h")
# Sections of the ``case`` sheet, each given as dotted rows (one field of each as an example).
SECTION_EXAMPLES = {"markets": "markets.kappa", "uncertainty": "uncertainty.window_days",
                    "budgets": "budgets.strategy", "solver": "solver.time_limit_s",
                    "provenance": "provenance.price_da.origin"}
# Parts of a case read from sheets of their own: a row of the ``case`` sheet would be overwritten.
# (Not budgets.overrides: the writer puts them in both places, and the budgets sheet wins.)
OWN_SHEETS = {"units": f"the sheets {', '.join(UNIT_KINDS[:-1])} and {UNIT_KINDS[-1]}",
              "markets.hpa_tariff_eur_per_mwh": "the sheet 'hpa_tariff'"}
HOURS_PER_DAY = 24
SHEET_WIDTH = (10, 40)  # [characters] narrowest and widest column of a written sheet

# A typical unit of each kind, from the paper's case (MODEL_SPEC §12, paper Tables 3-6):
# the values a new row starts from.
UNIT_TEMPLATES: dict[str, dict[str, Any]] = {
    "wind": {"p_max_mw": 50.0, "p_min_mw": 0.0, "om_eur_per_mwh": 15.0, "ramp_up_mw_per_min": 15.0,
             "ramp_dn_mw_per_min": 25.0, "reserve_share": 0.1, "series_scale": 1.0},
    "pv": {"p_max_mw": 50.0, "p_min_mw": 0.0, "om_eur_per_mwh": 7.5, "ramp_up_mw_per_min": 10.0,
           "ramp_dn_mw_per_min": 25.0, "reserve_share": 0.1, "series_scale": 1.0},
    "csp": {"om_eur_per_mwh": 25.0, "heat_efficiency": 0.9, "ramp_mw_per_min": 25.0, "reserve_share": 0.5,
            "solar_field": {"p_max_mw_th": 300.0, "series_scale": 1.0},
            "storage": {"e_min_mwh_th": 110.0, "e_max_mwh_th": 1100.0, "p_ch_max_mw_th": 140.0,
                        "p_ch_min_mw_th": 0.0, "p_dis_max_mw_th": 115.0, "p_dis_min_mw_th": 0.0,
                        "eta_ch": 0.95, "eta_dis": 0.95},
            "power_block": {"p_in_max_mw_th": 140.0, "p_in_min_mw_th": 19.0, "p_el_max_mw": 55.0,
                            "breakpoints": [[0.0, 0.0], [18.99, 0.0], [19.0, 0.27], [40.0, 0.34],
                                            [70.0, 0.38], [140.0, 0.395]],
                            "min_up_h": 6.0, "min_down_h": 6.0, "startup_fraction": 1.0,
                            "startup_duration_h": 1.0, "initially_on": False}},
    "ed": {"p_min_mw": 5.0, "p_max_mw": 60.0, "e_min_mwh": 600.0, "ramp_up_mw_per_min": 10.0,
           "ramp_dn_mw_per_min": 10.0, "flex_up": 0.1, "flex_dn": 0.1, "series_scale": 1.0},
    "td": {"h_min_mw_th": 5.0, "h_max_mw_th": 70.0, "q_min_mwh_th": 700.0, "series_scale": 1.0},
    # Beyond the paper (MODEL_SPEC §13): a two-hour battery, a small hydro and a biomass plant.
    "battery": {"enabled": True, "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 20.0, "p_dis_max_mw": 20.0,
                "eta_ch": 0.95, "eta_dis": 0.95, "self_discharge_per_h": 0.0, "degradation_eur_per_mwh": 5.0,
                "ramp_mw_per_min": 20.0, "reserve_share": 1.0},
    "hydro": {"enabled": True, "p_min_mw": 5.0, "p_max_mw": 30.0, "marginal_cost_eur_per_mwh": 5.0,
              "startup_cost_eur": 100.0, "shutdown_cost_eur": 0.0, "ramp_up_mw_per_h": 30.0, "ramp_dn_mw_per_h": 30.0,
              "min_up_h": 2.0, "min_down_h": 2.0, "initial_online": False, "energy_max_mwh": 300.0,
              "ramp_mw_per_min": 10.0, "reserve_share": 0.5},
    "biomass": {"enabled": True, "p_min_mw": 5.0, "p_max_mw": 15.0, "marginal_cost_eur_per_mwh": 60.0,
                "startup_cost_eur": 500.0, "shutdown_cost_eur": 0.0, "ramp_up_mw_per_h": 5.0, "ramp_dn_mw_per_h": 5.0,
                "min_up_h": 4.0, "min_down_h": 4.0, "initial_online": False, "ramp_mw_per_min": 1.0,
                "reserve_share": 0.2},
}
_DISPATCHABLE_OPTIONAL = ["startup_ramp_mw_per_h", "shutdown_ramp_mw_per_h", "initial_hours_in_status", "p_init_mw"]
# The authors' tool's conventions (docs/gams-tool.md): last columns of their kind's table, each cell
# showing its default where the case leaves the option out (case.yaml writes them only when set).
TOOL_OPTIONS: dict[str, dict[str, Any]] = {
    "ed": dict(ElectricalDemand.TOOL_DEFAULTS),
    "csp": {**{f"storage.{k}": v for k, v in ThermalStorage.TOOL_DEFAULTS.items()},
            **{f"power_block.{k}": v for k, v in PowerBlock.TOOL_DEFAULTS.items()}},
}


# ----------------------------------------------------------------------------- unit tables


def unit_table(case: Case, kind: str) -> pd.DataFrame:
    """The units of ``kind`` as one flat row each.

    The series column shows the history column that backs each unit (its own name
    unless the unit names another series).
    """
    _check_kind(kind)
    rows = []
    for unit, data in zip(getattr(case, kind), case.to_data()["units"].get(kind, [])):
        row = {**TOOL_OPTIONS.get(kind, {}), **flatten(data)}
        row.pop(BREAKPOINTS, None)
        if KINDS[UnitKind(kind)].role is not None:
            row[SERIES_FIELDS[kind]] = unit.column
        rows.append(row)
    table = pd.DataFrame(rows, columns=unit_columns(kind))
    template = flatten(UNIT_TEMPLATES[kind])
    empty = [c for c in table.columns if c != "name" and table[c].isna().all()]
    return table.astype({c: bool if isinstance(template.get(c), bool) else float for c in empty})


def unit_columns(kind: str) -> list[str]:
    """Column names of :func:`unit_table` for ``kind`` (template order, then optional fields)."""
    _check_kind(kind)
    columns = ["name", *(c for c in flatten(UNIT_TEMPLATES[kind]) if c != BREAKPOINTS)]
    optional = {"wind": ["forecast_series"], "pv": ["forecast_series"],
                "csp": ["storage.e_init_mwh_th", "storage.e_end_min_mwh_th", "storage.end_value_eur_per_mwh_th",
                        "power_block.initial_status_h", "solar_field.forecast_series"],
                "ed": ["p_init_mw", "forecast_series"], "td": ["h_init_mw_th", "forecast_series"],
                "battery": ["e_init_mwh", "e_end_min_mwh"], "hydro": _DISPATCHABLE_OPTIONAL,
                "biomass": _DISPATCHABLE_OPTIONAL + ["energy_max_mwh"]}
    tool = list(TOOL_OPTIONS.get(kind, {}))
    if KINDS[UnitKind(kind)].role is None:  # no series to follow
        return columns + optional[kind] + tool
    series = SERIES_FIELDS[kind]
    scale_at = columns.index(series.replace("series", "series_scale"))
    columns.insert(scale_at, series)
    return columns + optional[kind] + tool


def new_unit_row(case: Case, kind: str) -> dict[str, Any]:
    """Values a new unit of ``kind`` starts from: a free name, the template and the series
    of the first unit of that kind (or its own name when there is none)."""
    row = {**flatten(UNIT_TEMPLATES[kind]), **TOOL_OPTIONS.get(kind, {})}
    row.pop(BREAKPOINTS, None)
    existing = [u for k, u in case.units() if k == kind]
    row["name"] = next_unit_name(case, kind)
    if KINDS[UnitKind(kind)].role is not None:
        row[SERIES_FIELDS[kind]] = existing[0].column if existing else row["name"]
    return row


def next_unit_name(case: Case, kind: str) -> str:
    """The first free name ``<prefix><n>`` for a new unit of ``kind`` (e.g. ``WF3``)."""
    taken = set(case.unit_names())
    n = 1
    while f"{NAME_PREFIXES[kind]}{n}" in taken:
        n += 1
    return f"{NAME_PREFIXES[kind]}{n}"


def with_unit_table(case: Case, kind: str, table: pd.DataFrame,
                    breakpoints: Mapping[str, Any] | None = None) -> Case:
    """``case`` with its units of ``kind`` replaced by the rows of ``table``.

    Empty cells fall back to the model's defaults (or are reported as required). A CSP
    keeps the breakpoints of the CSP of the same name, else those in ``breakpoints``
    (name → list of ``(input, efficiency)``), else the template's. A unit's Γ override
    and band method (``budgets.overrides``, ``uncertainty.bands``) follow it when its row
    is renamed (:func:`_renamed`) and leave with it when its row is removed.
    Raises :class:`CaseError` when a value breaks a rule.
    """
    _check_kind(kind)
    units = _units_from_table(kind, table)
    if kind == UnitKind.CSP:
        known = {c.name: [list(p) for p in c.power_block.breakpoints] for c in case.csp}
        known.update({name: [list(p) for p in points] for name, points in (breakpoints or {}).items()})
        for unit in units:
            block = unit.setdefault("power_block", {})
            block.setdefault("breakpoints", known.get(unit.get("name"),
                                                      UNIT_TEMPLATES["csp"]["power_block"]["breakpoints"]))
    data = case.to_data()
    data["units"][kind] = units
    renamed = _renamed([u.name for u in getattr(case, kind)], table)
    removed = {u.name for u in getattr(case, kind)} - {u.get("name") for u in units} - set(renamed)
    for section, field in (("budgets", "overrides"), ("uncertainty", "bands")):
        data[section][field] = {renamed.get(k, k): v for k, v in data[section][field].items() if k not in removed}
    return parse_case(data, case.history)


def _renamed(names: list[str], table: pd.DataFrame) -> dict[str, str]:
    """Old name → new name of the units whose row of :func:`unit_table` got another name.

    A row is known by its index label, the unit's position in ``names`` (a table editor
    keeps the labels of edited rows when others are deleted or added). It is a rename only
    when the old name has left the table and the new name was no unit's, so a table
    indexed afresh never moves a setting to another unit.
    """
    given = {label: _plain(name) for label, name in table["name"].items()}
    return {names[label]: name for label, name in given.items()
            if isinstance(label, (int, np.integer)) and 0 <= label < len(names) and isinstance(name, str)
            and name not in names and names[label] not in given.values()}


def breakpoint_table(case: Case, csp: str) -> pd.DataFrame:
    """The power-block curve of CSP ``csp``: thermal input [MW_th] and efficiency [-] per point."""
    unit = _csp(case, csp)
    return pd.DataFrame(list(unit.power_block.breakpoints), columns=list(BREAKPOINT_COLUMNS))


def with_breakpoints(case: Case, csp: str, table: pd.DataFrame) -> Case:
    """``case`` with the power-block curve of ``csp`` replaced by the rows of ``table``."""
    _csp(case, csp)
    points = [[_number(row[c]) for c in BREAKPOINT_COLUMNS] for row in table.to_dict(orient="records")
              if not all(_is_empty(row[c]) for c in BREAKPOINT_COLUMNS)]
    missing = [i for i, p in enumerate(points, start=1) if any(v is None for v in p)]
    if missing:
        raise CaseError(f'csp "{csp}": power_block.breakpoints point {missing[0]} needs both an input and '
                        "an efficiency")
    data = case.to_data()
    for unit in data["units"][UnitKind.CSP]:
        if unit["name"] == csp:
            unit["power_block"]["breakpoints"] = points
    return parse_case(data, case.history)


# ----------------------------------------------------------------------------- workbook


def write_case_workbook(case: Case, target: str | Path | io.BytesIO) -> str | Path | io.BytesIO:
    """Write ``case`` (settings, units, curves, history) as an Excel workbook."""
    data = case.to_data()
    settings = {key: data[key] for key in TOP_SETTINGS}
    settings["delivery_date"] = case.delivery_date.isoformat()
    for section in SETTING_SECTIONS:
        for key, value in data[section].items():
            if isinstance(value, Mapping):  # band methods, imbalance price columns
                settings.update(flatten(value, f"{section}.{key}."))
            elif key not in ("hpa_tariff_eur_per_mwh", "overrides", "dam", "mip_start") and value is not None:
                settings[f"{section}.{key}"] = value
    settings.update(flatten({"provenance": data["provenance"]}))
    tariff = pd.DataFrame({"hour": range(HOURS_PER_DAY),
                           "tariff_eur_per_mwh": list(case.markets.hpa_tariff_eur_per_mwh)})
    budgets = pd.DataFrame(list(case.budgets.overrides), columns=["source", "gamma"])
    curves = pd.DataFrame([(c.name, p, eta) for c in case.csp for p, eta in c.power_block.breakpoints],
                          columns=["unit", *BREAKPOINT_COLUMNS])
    history = case.history.frame
    history.insert(0, "timestamp", [t.isoformat() for t in history.index.tz_convert(case.timezone)])
    with pd.ExcelWriter(target, engine="openpyxl") as writer:
        pd.DataFrame({"field": list(settings), "value": list(settings.values())}).to_excel(
            writer, sheet_name="case", index=False)
        tariff.to_excel(writer, sheet_name="hpa_tariff", index=False)
        budgets.to_excel(writer, sheet_name="budgets", index=False)
        for kind in UNIT_KINDS:
            if kind in PAPER_KINDS or getattr(case, kind):  # a kind beyond the paper's only when it has units
                unit_table(case, kind).to_excel(writer, sheet_name=kind, index=False)
        curves.to_excel(writer, sheet_name="breakpoints", index=False)
        history.to_excel(writer, sheet_name="history", index=False)
        for sheet in writer.sheets.values():
            sheet.freeze_panes = "A2"
            for column in sheet.columns:
                width = max(len(str(c.value)) if c.value is not None else 0 for c in column[:50])
                sheet.column_dimensions[column[0].column_letter].width = min(max(SHEET_WIDTH[0], width + 2),
                                                                             SHEET_WIDTH[1])
    return target


def case_workbook_bytes(case: Case) -> bytes:
    """The case workbook as bytes (for downloads)."""
    buffer = io.BytesIO()
    write_case_workbook(case, buffer)
    return buffer.getvalue()


def read_case_workbook(source: str | Path | io.BytesIO | bytes, label: str = "workbook",
                       budget: UploadBudget | None = None) -> Case:
    """Read a case workbook written by :func:`write_case_workbook` (or filled in by hand).

    The workbook is read as an upload: within ``budget`` (by default the limits of
    :class:`~rvpp.data.files.UploadLimits`), its zip inflated and counted before the
    sheets are parsed, the sheets streamed row by row.
    """
    budget = budget or UploadBudget(UploadLimits())
    if isinstance(source, (str, Path)):
        source = read_file(Path(source), label, max_bytes=budget.limits.upload_bytes)
    elif isinstance(source, io.BytesIO):
        source = source.getvalue()
    sheets = _read_sheets(source, label, budget)
    for name, columns in (("case", ("field", "value")), ("budgets", ("source", "gamma")),
                          ("breakpoints", ("unit", *BREAKPOINT_COLUMNS)), ("history", ("timestamp",))):
        if name in sheets:
            _require_columns(sheets[name], name, columns, label)
    data = _settings(sheets["case"], label)
    data.setdefault("markets", {})["hpa_tariff_eur_per_mwh"] = _tariff(sheets["hpa_tariff"], label)
    budgets = sheets.get("budgets", pd.DataFrame(columns=["source", "gamma"]))
    data.setdefault("budgets", {})["overrides"] = {
        str(row["source"]): _plain(row["gamma"]) for row in budgets.to_dict(orient="records")
        if not _is_empty(row.get("source"))}
    curves = sheets.get("breakpoints", pd.DataFrame(columns=["unit", *BREAKPOINT_COLUMNS]))
    points: dict[str, list] = {}
    for row in curves.to_dict(orient="records"):
        points.setdefault(str(row["unit"]), []).append([_plain(row[c]) for c in BREAKPOINT_COLUMNS])
    data["units"] = {}
    for kind in UNIT_KINDS:
        for unit in _units_from_table(kind, sheets.get(kind, pd.DataFrame(columns=["name"]))):
            if kind == UnitKind.CSP:
                unit.setdefault("power_block", {})["breakpoints"] = points.get(unit.get("name"), [])
            data["units"].setdefault(kind, []).append(unit)
    history = sheets["history"]
    history["timestamp"] = [None if _is_empty(t) else str(t) for t in history["timestamp"]]
    case = parse_case(data, History(history, source=f"{label}, sheet history"))
    budget.check_time(f"checking {label}")
    return case


REQUIRED_SHEETS = ("case", "hpa_tariff", "history")
AUTHORS_TOOL_SHEET = "Global_params"  # the first sheet of the seed paper's authors' tool workbook (RVPP_data.xlsx)
AUTHORS_TOOL_HINT = ("; this is the workbook of the authors' RVPP tool, not a case workbook: turn it into a case "
                     "folder with `python -m rvpp data import-workbook RVPP_data.xlsx --out FOLDER --date YYYY-MM-DD` "
                     "(docs/gams-tool.md), then load that folder or upload it as a zip")


def _read_sheets(data: bytes, label: str, budget: UploadBudget) -> dict[str, pd.DataFrame]:
    """Every sheet of the workbook as a table of cell values (first row: the column names); a workbook
    without the sheets every case workbook has is refused first, by the first one missing.

    The zip is inflated once and counted before openpyxl parses it (its headers are not
    trusted); rows are streamed, so a sheet larger than the limits is refused early.
    """
    limits = budget.limits
    with open_zip(data, label, limits, expected="an Excel workbook (.xlsx)") as archive:
        for member in archive.infolist():
            unzip(archive, member, label, budget, keep=False)
    try:
        book = openpyxl.load_workbook(io.BytesIO(data), read_only=True, data_only=True, keep_links=False)
    except Exception as exc:  # openpyxl raises many types for a zip that is not a workbook
        raise CaseFileError(f"{label}: cannot be read as an Excel workbook ({excerpt(exc, 120)})") from None
    missing = [name for name in REQUIRED_SHEETS if name not in book.sheetnames]
    if missing:  # before any sheet is read: a workbook of another kind is named as such, not by its contents
        tool = AUTHORS_TOOL_SHEET in book.sheetnames
        book.close()
        raise CaseError(f"{label}: sheet {missing[0]!r} is missing (a case workbook has the sheets case, "
                        f"hpa_tariff, budgets, {', '.join(UNIT_KINDS)}, breakpoints and history)"
                        + (AUTHORS_TOOL_HINT if tool else ""))
    sheets = {}
    try:
        for sheet in book.worksheets:
            sheet.reset_dimensions()  # the recorded size may lie: read the rows that are there
            rows = []
            for row in sheet.iter_rows(values_only=True):
                if len(rows) > limits.history_rows:
                    raise UploadLimitError(f"{label}: sheet {excerpt(sheet.title)!r} has more than "
                                           f"{limits.history_rows:,} rows; an upload may have at most "
                                           f"{limits.history_rows:,}")
                if len(row) > limits.history_columns:
                    raise UploadLimitError(f"{label}: sheet {excerpt(sheet.title)!r} row {len(rows) + 1} reaches "
                                           f"column {len(row):,}; an upload may have at most "
                                           f"{limits.history_columns:,} columns")
                if len(rows) % 1000 == 0:
                    budget.check_time(f"reading sheet {excerpt(sheet.title)!r} of {label}")
                rows.append(row)
            sheets[sheet.title] = _table(rows, sheet.title, label)
    except (KeyError, ValueError, TypeError, OSError, zipfile.BadZipFile, ElementTree.ParseError) as exc:
        raise CaseFileError(f"{label}: cannot be read as an Excel workbook ({excerpt(exc, 120)})") from None
    finally:
        book.close()
    return sheets


def _table(rows: list[tuple], sheet: str, label: str) -> pd.DataFrame:
    """Cell values under their header row; empty trailing rows and columns left out."""
    while rows and all(_is_empty(v) for v in rows[-1]):
        rows.pop()
    if not rows:
        return pd.DataFrame()
    width = max(_width(row) for row in rows)
    header = [f"Unnamed: {i}" if _is_empty(v) else str(v).strip() for i, v in enumerate(rows[0][:width])]
    header += [f"Unnamed: {i}" for i in range(len(header), width)]
    seen: dict[str, int] = {}
    for i, name in enumerate(header):
        if name in seen:
            raise CaseError(f"{label}: sheet {excerpt(sheet)!r} has the column {excerpt(name)!r} twice "
                            f"(columns {seen[name] + 1} and {i + 1})")
        seen[name] = i
    body = [tuple(row[:width]) + (None,) * (width - len(row[:width])) for row in rows[1:]]
    return pd.DataFrame(body, columns=header, dtype=object)


def _width(row: tuple) -> int:
    """Cells up to the last one that holds a value."""
    width = len(row)
    while width and _is_empty(row[width - 1]):
        width -= 1
    return width


def _require_columns(sheet: pd.DataFrame, name: str, columns: tuple[str, ...], label: str) -> None:
    missing = [c for c in columns if c not in sheet.columns]
    if missing:
        raise CaseError(f"{label}: sheet {name!r} needs the columns {', '.join(columns)} in its first row "
                        f"(missing: {', '.join(missing)})")


# ----------------------------------------------------------------------------- helpers


def _check_kind(kind: str) -> None:
    if kind not in UNIT_KINDS:
        raise ValueError(f"unknown unit kind {kind!r}; kinds are {', '.join(UNIT_KINDS)}")


def _csp(case: Case, name: str):
    for unit in case.csp:
        if unit.name == name:
            return unit
    raise CaseError(f"no CSP named {name!r} (the case has {', '.join(c.name for c in case.csp) or 'none'})")


def _unflatten(flat: Mapping[str, Any]) -> dict[str, Any]:
    """``{"storage.e_min_mwh_th": 110}`` -> ``{"storage": {"e_min_mwh_th": 110}}``.

    A name that is both a value and a section (``storage`` and ``storage.eta_ch``)
    raises :class:`CaseError`.
    """
    nested: dict[str, Any] = {}
    for key, value in flat.items():
        *parents, leaf = key.split(".")
        node = nested
        for depth, part in enumerate(parents, start=1):
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise CaseError(f"{excerpt(key)!r}: {'.'.join(parents[:depth])!r} is given both as a value and as a "
                                "section of fields")
        if isinstance(node.get(leaf), dict):
            raise CaseError(f"{excerpt(key)!r} is given both as a value and as a section of fields")
        node[leaf] = value
    return nested


def _is_empty(value: Any) -> bool:
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    if isinstance(value, float) and math.isnan(value):
        return True
    return isinstance(value, str) and not value.strip()


def _plain(value: Any) -> Any:
    """Python scalars from numpy/pandas cells; empty cells become ``None``."""
    if _is_empty(value):
        return None
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, pd.Timestamp):
        value = value.to_pydatetime()
    if isinstance(value, dt.datetime):
        return value.date() if value.time() == dt.time(0) else value
    return value.strip() if isinstance(value, str) else value


def _number(value: Any) -> Any:
    value = _plain(value)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _units_from_table(kind: str, table: pd.DataFrame) -> list[dict[str, Any]]:
    """Nested unit data from table rows; empty cells are left out so model defaults apply,
    and a series equal to the unit's own name is left implicit."""
    units = []
    for row in table.to_dict(orient="records"):
        unit = _unflatten({key: _plain(value) for key, value in row.items() if not _is_empty(value)})
        if not unit:
            continue
        if KINDS[UnitKind(kind)].role is None:  # no series to follow
            units.append(unit)
            continue
        node = unit
        for part in SERIES_FIELDS[kind].split(".")[:-1]:
            node = node.setdefault(part, {})
        if node.get("series") is not None and node["series"] == unit.get("name"):
            node["series"] = None
        units.append(unit)
    return units


def _settings(sheet: pd.DataFrame, label: str) -> dict[str, Any]:
    flat: dict[str, Any] = {}
    rows: dict[str, int] = {}
    for row_number, row in enumerate(sheet.to_dict(orient="records"), start=2):
        if _is_empty(row["field"]):
            continue
        field = str(row["field"]).strip()
        if field in rows:
            raise CaseError(f"{label}: sheet 'case' gives the field {excerpt(field)!r} twice (rows {rows[field]} "
                            f"and {row_number}); keep one")
        rows[field] = row_number
        flat[field] = _plain(row["value"])
    flat = {key: value for key, value in flat.items() if value is not None or key == "description"}
    for field in flat:
        if field in SECTION_EXAMPLES:
            raise CaseError(f"{label}: sheet 'case': {field} must be a section of fields ({SECTION_EXAMPLES[field]}, "
                            f"...), not a value (row {rows[field]})")
        part = next((part for part in OWN_SHEETS if field == part or field.startswith(part + ".")), None)
        if part is not None:
            raise CaseError(f"{label}: sheet 'case': {excerpt(field)} is read from {OWN_SHEETS[part]}, not from a "
                            f"row of this sheet (row {rows[field]}); remove the row")
    if isinstance(flat.get("delivery_date"), dt.date):
        flat["delivery_date"] = flat["delivery_date"].isoformat()
    if flat.get("description") is None:
        flat["description"] = ""
    try:
        return _unflatten(flat)
    except CaseError as err:
        raise CaseError(f"{label}: sheet 'case': {err}") from None


def _tariff(sheet: pd.DataFrame, label: str) -> list[Any]:
    if "tariff_eur_per_mwh" not in sheet.columns:
        raise CaseError(f"{label}: sheet 'hpa_tariff' needs a column tariff_eur_per_mwh (one row per hour 0..23)")
    return [_number(v) for v in sheet["tariff_eur_per_mwh"].tolist()]
