"""Write study outputs: tables as CSV, Markdown and one Excel workbook, figures as HTML
and PNG, and ``report.md`` with the paper's findings checked against our numbers."""

from __future__ import annotations

import io
import json
import math
import warnings
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..data.case import Case
from ..data.files import replacing
from ..solving.extract import SOLVER_ZERO
from .findings import findings
from .runner import StudyOutput
from .settings import StudySettings

EXCEL_SHEET_CHARS = 31
REPORT_TABLES = {  # the tables shown in report.md; every table is in tables/ and tables.xlsx
    "case1": ("case1_summary", "case1_flexibility"),
    "strategies": ("strategies", "flexibility"),
    "sensitivity": ("sensitivity",),
    "markets": ("table10_markets", "table11_without_csp", "table12_hpa_price"),
    "out_of_sample": ("table13_out_of_sample",),
    "stochastic": ("table14_stochastic",),
    "stress": ("stress",),
    "backtest": ("backtest_verdicts", "backtest_penalty_causes", "backtest_aggregates", "backtest_comparison",
                 "backtest_curve", "backtest_comparison_modelled_sky", "backtest_curve_modelled_sky"),
}
REPORT_COLUMNS = {  # keep report.md readable: the CSVs hold every column
    "strategies": ["strategy", "variant", "status", "cost_keur", "sold_mwh", "bought_mwh", "heat_bought_mwh",
                   "sr_up_mwh", "sr_dn_mwh", "solve_s", "audit_violations"],
    "case1_summary": ["strategy", "variant", "status", "cost_keur", "sold_mwh", "bought_mwh", "heat_bought_mwh",
                      "sr_up_mwh", "sr_dn_mwh", "solve_s", "audit_violations"],
    "sensitivity": ["sources", "gamma", "variant", "status", "cost_keur", "sold_mwh", "bought_mwh", "heat_bought_mwh",
                    "csp_up_mwh", "ed_up_mwh", "wind_dn_mwh", "pv_dn_mwh", "csp_dn_mwh", "ed_dn_mwh", "solve_s"],
    "table13_out_of_sample": ["method", "status", "avg_market_cost_keur", "avg_penalty_keur", "avg_net_cost_keur",
                              "solve_s", "settlements_optimal", "realization_set"],
    "table14_stochastic": ["method", "status", "mip_gap", "avg_market_cost_keur", "avg_penalty_keur",
                           "avg_net_cost_keur", "solve_s", "settlements_optimal", "realization_set"],
    "backtest_aggregates": ["period", "label", "days_settled", "mean_market_cost_eur", "mean_penalty_eur",
                            "mean_net_cost_eur", "median_net_cost_eur", "cvar95_net_cost_eur", "penalty_share",
                            "mean_regret_eur", "audit_violations"],
    "backtest_penalty_causes": ["case", "label", "days_settled", "mean_market_cost_eur", "mean_penalty_eur",
                                "mean_penalty_deficit_eur", "mean_penalty_surplus_eur", "mean_penalty_reserve_eur",
                                "mean_penalty_heat_eur", "mean_net_cost_eur", "cvar95_net_cost_eur",
                                "mean_regret_eur"],
    "backtest_comparison": ["variant", "train_mean_net_cost_eur", "train_cvar95_net_cost_eur",
                            "test_mean_market_cost_eur", "test_mean_penalty_eur", "test_mean_net_cost_eur",
                            "test_cvar95_net_cost_eur", "test_mean_regret_eur"],
    "backtest_comparison_modelled_sky": ["variant", "train_mean_net_cost_eur", "train_cvar95_net_cost_eur",
                                         "test_mean_market_cost_eur", "test_mean_penalty_eur",
                                         "test_mean_net_cost_eur", "test_cvar95_net_cost_eur",
                                         "test_mean_regret_eur"],
    "backtest_curve_modelled_sky": ["fraction", "period", "days_settled", "mean_market_cost_eur", "mean_penalty_eur",
                                    "mean_net_cost_eur", "cvar95_net_cost_eur"],
    "backtest_curve": ["fraction", "period", "days_settled", "mean_market_cost_eur", "mean_penalty_eur",
                       "mean_net_cost_eur", "cvar95_net_cost_eur"],
}


def markdown_table(table: pd.DataFrame, digits: int = 2) -> str:
    """A GitHub-flavoured Markdown table; floats rounded to ``digits``."""
    frame = flat(table)
    header = [str(c) for c in frame.columns]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for row in frame.itertuples(index=False):
        lines.append("| " + " | ".join(_cell(v, digits) for v in row) + " |")
    return "\n".join(lines)


def _cell(value: Any, digits: int) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if isinstance(value, (float, np.floating)):
        if abs(value) <= SOLVER_ZERO:
            return f"{0.0:.{digits}f}"
        if SOLVER_ZERO < abs(value) < 10 ** -digits:  # e.g. a MIP gap: keep it visible
            return f"{value:.1e}"
        return f"{value:,.{digits}f}"
    return str(value)


def flat(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with a named index turned into columns (how tables are written)."""
    return table.reset_index() if not isinstance(table.index, pd.RangeIndex) else table


def table_csv(table: pd.DataFrame) -> str:
    """A table as CSV text, full precision (the content of ``tables/NAME.csv``)."""
    return flat(table).to_csv(index=False, float_format="%.6f")


def tables_workbook_bytes(tables: dict[str, pd.DataFrame]) -> bytes:
    """Tables as one Excel workbook, one sheet each (the content of ``tables.xlsx``)."""
    buffer = io.BytesIO()
    with pd.ExcelWriter(buffer, engine="openpyxl") as writer:
        for name, table in tables.items():
            flat(table).to_excel(writer, sheet_name=name[:EXCEL_SHEET_CHARS], index=False)
    return buffer.getvalue()


def write_tables(outputs: Sequence[StudyOutput], folder: Path) -> list[Path]:
    """Every table as ``tables/NAME.csv`` and ``tables/NAME.md``, and all of them in ``tables.xlsx``."""
    target = folder / "tables"
    target.mkdir(parents=True, exist_ok=True)
    written = []
    tables = {name: table for out in outputs for name, table in out.tables.items()}
    for name, table in tables.items():
        _write(target / f"{name}.csv", table_csv(table))
        _write(target / f"{name}.md", markdown_table(table) + "\n")
        written += [target / f"{name}.csv", target / f"{name}.md"]
    workbook = folder / "tables.xlsx"
    _write(workbook, tables_workbook_bytes(tables))
    return written + [workbook]


def write_figures(outputs: Sequence[StudyOutput], folder: Path, png: bool) -> list[Path]:
    """Every figure as interactive ``figures/NAME.html`` and, with ``png``, ``figures/NAME.png``."""
    target = folder / "figures"
    target.mkdir(parents=True, exist_ok=True)
    figures = {name: fig for out in outputs for name, fig in out.figures.items()}
    written = []
    for name, fig in figures.items():
        with replacing(target / f"{name}.html") as path:
            fig.write_html(path, include_plotlyjs="directory")
        written.append(target / f"{name}.html")
    if png and figures:
        written += _write_png(figures, target)
    return written


def _write_png(figures: dict, target: Path) -> list[Path]:
    import kaleido  # heavy: the PNG renderer (a browser) loads only when pictures are written

    kaleido.start_sync_server()
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="The kopts argument is ignored")
            for name, fig in figures.items():
                with replacing(target / f"{name}.png") as path:
                    fig.write_image(path, width=1100, height=520)
    finally:
        kaleido.stop_sync_server()
    return [target / f"{name}.png" for name in figures]


def consistency(outputs: Sequence[StudyOutput]) -> dict[str, Any]:
    """Checks a reader can redo: net = market cost + penalty; one realization set for all methods."""
    frames = [out.facts["evaluations"] for out in outputs if "evaluations" in out.facts]
    if not frames:
        return {}
    evaluations = pd.concat(frames, ignore_index=True)
    gap = (evaluations["net_cost_eur"] - evaluations["market_cost_eur"] - evaluations["penalty_eur"]).abs()
    per_day = evaluations.groupby("day")["fingerprint"].nunique()
    return {"settlements": int(len(evaluations)),
            "max_abs_net_minus_cost_plus_penalty_eur": float(gap.max()),
            "realization_sets": sorted(evaluations["realization_set"].unique()),
            "days_with_differing_realizations": int((per_day > 1).sum()),
            "methods": list(dict.fromkeys(evaluations["method"]))}


def write_report(outputs: Sequence[StudyOutput], folder: Path, case: Case, settings: StudySettings,
                 run_info: dict[str, Any]) -> Path:
    """``report.md``: context, findings with verdicts, the main tables, consistency checks."""
    by_name = {out.name: out for out in outputs}
    checks = consistency(outputs)
    lines = [f"# Case studies of the RVPP bidding model: case `{case.name}`, delivery day {case.delivery_date}", "",
             f"History `{case.history.source}` (fingerprint `{case.history.fingerprint}`), periods of "
             f"{case.dt_h:g} h, forecast window {case.uncertainty.window_days} days. Penalties: "
             + ", ".join(f"{k} = {v:g}" for k, v in settings.penalties.describe(case).items())
             + f". Scheduler: {run_info.get('scheduler')}, wall time {run_info.get('wall_s', 0):.1f} s.", "",
             "## Findings of the paper, checked on this run", "",
             "| # | finding | paper | holds here | numbers |", "|---|---|---|---|---|"]
    for i, finding in enumerate(findings(by_name), start=1):
        lines.append(f"| {i} | {finding.claim} | {finding.paper} | {'yes' if finding.holds else 'no'} | "
                     f"{finding.evidence} |")
    for out in outputs:
        lines += ["", f"## {out.title}", ""]
        for warning in out.warnings:  # the first lines of the section
            lines += [f"**Warning: {warning}**", ""]
        lines += [f"Wall time {out.seconds:.1f} s."]
        lines += [f"> {note}" for note in out.notes]
        for name in REPORT_TABLES.get(out.name, ()):
            if name in out.tables:
                table = out.tables[name]
                columns = [c for c in REPORT_COLUMNS.get(name, list(table.columns)) if c in table.columns]
                lines += ["", f"**{name}** (`tables/{name}.csv`)", "", markdown_table(table[columns])]
        if out.figures:
            lines += ["", "Figures: " + ", ".join(f"`figures/{n}.html`" for n in out.figures)]
    if checks:
        lines += ["", "## Consistency of the out-of-sample settlements", "",
                  f"- {checks['settlements']} settlements of {len(checks['methods'])} methods "
                  f"({', '.join(checks['methods'])}).",
                  f"- Largest |net cost − (market cost + penalty)|: "
                  f"{checks['max_abs_net_minus_cost_plus_penalty_eur']:.2e} EUR.",
                  f"- Realization sets used: {', '.join(f'`{s}`' for s in checks['realization_sets'])} "
                  f"({'one set for every method' if len(checks['realization_sets']) == 1 else 'DIFFERENT sets'}); "
                  f"days whose realization differs between methods: {checks['days_with_differing_realizations']}."]
    if "backtest" in by_name:
        lines += backtest_checks(by_name["backtest"].facts)
    path = folder / "report.md"
    _write(path, "\n".join(lines) + "\n")
    return path


def backtest_checks(facts: dict[str, Any]) -> list[str]:
    """The backtest's reconciliation (and its modelled-sky counterpart's), as lines of report.md."""
    lines = ["", "## Consistency of the backtest settlements", ""]
    for checks, suffix in ((facts, ""), (facts.get("modelled_sky"), "_modelled_sky")):
        if checks:
            lines += [f"- {checks['records']} stored days (day x variant) of backtest `{checks['backtest_id']}`; "
                      f"{checks['reconcile_problems']} do not reconcile or were not settled "
                      f"(`tables/backtest_problems{suffix}.csv`).",
                      f"- Largest |net cost − (market cost + penalty)|: "
                      f"{checks['max_abs_net_minus_cost_plus_penalty_eur']:.2e} EUR.",
                      f"- Plans audited: {checks['audited']}; rules broken: {checks['audit_violations']}."]
    return lines


def write_run_info(folder: Path, case: Case, settings: StudySettings, outputs: Sequence[StudyOutput],
                   run_info: dict[str, Any]) -> Path:
    """``run.json``: settings, case, timings, fingerprints and consistency checks."""
    info = {"case": case.name, "delivery_date": case.delivery_date.isoformat(), "dt_h": case.dt_h,
            "history_fingerprint": case.history.fingerprint, "settings": asdict(settings),
            "penalties": settings.penalties.describe(case),
            "studies": {out.name: {"seconds": out.seconds, "tables": list(out.tables), "figures": list(out.figures),
                                   "notes": out.notes, "warnings": out.warnings} for out in outputs},
            "consistency": consistency(outputs),
            "findings": [asdict(f) for f in findings({out.name: out for out in outputs})], **run_info}
    info.update({"backtest": out.facts for out in outputs if out.name == "backtest"})
    path = folder / "run.json"
    _write(path, json.dumps(info, indent=2, default=str) + "\n")
    return path


def _write(path: Path, content: str | bytes) -> None:
    """Write ``content`` to ``path`` atomically (UTF-8 for text)."""
    with replacing(path) as temporary:
        temporary.write_bytes(content.encode("utf-8") if isinstance(content, str) else content)


def write_all(outputs: Sequence[StudyOutput], folder: str | Path, case: Case, settings: StudySettings,
              run_info: dict[str, Any]) -> list[Path]:
    """Write tables, figures, ``report.md`` and ``run.json`` of ``outputs`` into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = write_tables(outputs, folder) + write_figures(outputs, folder, settings.png)
    written.append(write_report(outputs, folder, case, settings, run_info))
    written.append(write_run_info(folder, case, settings, outputs, run_info))
    return written
