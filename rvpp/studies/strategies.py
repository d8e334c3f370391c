"""The four strategies and the flexibility they leave (paper Case 2, Table 9)."""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..data.case import Case
from ..solving.results import Result
from . import figures
from .runner import Config, Progress, StudyOutput, plan_table, solve_configs
from .settings import StudySettings

TITLE = "Strategies and flexibility (paper Case 2, Table 9)"


def flexibility_rows(configs: list[Config], results: list[Result]) -> pd.DataFrame:
    """Table 9 layout: per strategy and unit kind, ``Σ r·dt`` [MWh] and the same per MW installed [h]."""
    frames = []
    for config, result in zip(configs, results):
        if result.has_plan:
            frames.append(result.flexibility.assign(**dict(config.labels)))
    table = pd.concat(frames, ignore_index=True)
    labels = [name for name, _ in configs[0].labels]
    return table[labels + ["kind", "r_up_mwh", "r_dn_mwh", "capacity_mw", "r_up_h", "r_dn_h"]]


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Solve every strategy of ``settings``; plans and flexibility tables."""
    started = time.perf_counter()
    configs = [Config.of({"strategy": s}, strategy=s) for s in settings.strategies]
    results = solve_configs(case, configs, settings, executor, progress, "strategies")
    plans = plan_table(configs, results)
    flexibility = flexibility_rows(configs, results)
    out = StudyOutput("strategies", TITLE, tables={"strategies": plans, "flexibility": flexibility})
    out.figures["strategies_reserve"] = figures.reserve_by_kind_figure(flexibility)
    out.facts.update(plans=plans, flexibility=flexibility)
    out.seconds = time.perf_counter() - started
    return out
