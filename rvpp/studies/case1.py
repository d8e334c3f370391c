"""The deterministic plan with its figures (paper Case 1, Figures 9-11)."""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..outputs import plots
from ..data.case import Case
from ..solving.plan import solve
from .runner import Config, Progress, StudyOutput, plan_row, stage
from .settings import StudySettings

TITLE = "Deterministic plan (paper Case 1)"
FIGURES = {  # paper Figure 9 (trades and units), Figure 10 (heat supply), reserve shares by unit kind
    "case1_trades": plots.trades_figure, "case1_dispatch": plots.dispatch_figure, "case1_heat": plots.heat_figure,
    "case1_reserve_share": plots.reserve_share_figure,
}


def storage_figures(result) -> dict:
    """Paper Figure 11: the thermal storage of every CSP of the plan."""
    return {f"case1_storage_{c.name}": plots.storage_figure(result, c.name) for c in result.case.csp}


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
        out.figures.update({name: draw(result) for name, draw in FIGURES.items()})
        out.figures.update(storage_figures(result))
    out.facts.update(result=result)
    out.seconds = time.perf_counter() - started
    return out
