"""The deterministic plan with its figures (paper Case 1, Figures 9-11)."""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..case import Case
from ..solve import solve
from .runner import Config, Progress, StudyOutput, plan_row, stage
from .settings import StudySettings

TITLE = "Deterministic plan (paper Case 1)"
FIGURES = {"case1_trades": "trades_figure", "case1_heat": "heat_figure", "case1_storage": "storage_figure",
           "case1_reserve_share": "reserve_share_figure"}


def plan_figures(result) -> dict:
    """Trades, heat supply, storage and reserve shares of a plan (:mod:`rvpp.plots`)."""
    from .. import plots

    return {name: getattr(plots, function)(result) for name, function in FIGURES.items()}


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Solve the deterministic plan; its tables and the paper's Case 1 figures."""
    started = time.perf_counter()
    config = Config.of({"strategy": "deterministic"}, strategy="deterministic")
    result = solve(config.case(case, settings))
    stage(progress, "deterministic plan")(1, 1)
    out = StudyOutput("case1", TITLE)
    out.tables = {"case1_summary": pd.DataFrame([plan_row(config, result)])}
    if result.has_plan:
        out.tables.update(case1_market=result.market, case1_units=result.units, case1_csp=result.csp,
                          case1_flexibility=result.flexibility)
        try:
            out.figures.update(plan_figures(result))
        except ImportError:
            out.notes.append("Case 1 figures need rvpp.plots (trades, heat, storage, reserve share), "
                             "which this installation does not have; the tables are complete.")
    out.facts.update(result=result)
    out.seconds = time.perf_counter() - started
    return out
