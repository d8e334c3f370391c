"""Sensitivity of the plan to the uncertainty budget Γ (paper Case 2, Figures 15-16).

Γ runs over a grid (default: every hour from 0 to the length of the day) for every
source at once, or for named sources one at a time (a unit kind such as ``pv`` or
``price`` names all of its sources). The sources not swept keep Γ = 0.
"""

from __future__ import annotations

import time
from concurrent.futures import Executor

from ..data.case import Case
from ..data.kinds import UNIT_KINDS
from ..errors import RvppError
from ..data.history import PRICE_COLUMNS
from ..data.periods import delivery_periods
from ..solving.sweep import check_gamma_grid
from . import figures
from .runner import Config, Progress, StudyOutput, plan_table, solve_configs
from .settings import StudySettings

TITLE = "Sensitivity to the uncertainty budget (paper Figures 15-16)"
ALL = "all"


def gamma_grid(case: Case, settings: StudySettings) -> list[int]:
    """Γ values [periods]: the settings' grid, or 0..NT in steps of one hour."""
    if settings.gammas is not None:
        check_gamma_grid(settings.gammas, case)
        return sorted(set(settings.gammas))
    nt = len(delivery_periods(case.delivery_date, case.timezone, case.dt_h))
    return list(range(0, nt + 1, int(round(1.0 / case.dt_h))))


def kind_sources(case: Case) -> dict[str, list[str]]:
    """``{kind: sources}`` for every kind the case has (``price``: the three prices)."""
    kinds = {kind: [u.name for k, u in case.units() if k == kind] for kind in UNIT_KINDS}
    kinds["price"] = list(PRICE_COLUMNS)
    return {kind: sources for kind, sources in kinds.items() if sources}


def sweep_choices(case: Case) -> list[str]:
    """What can be swept one at a time: every kind the case has, then every source."""
    return list(kind_sources(case)) + case.sources()


def source_groups(case: Case, names: tuple[str, ...]) -> dict[str, list[str]]:
    """``{label: sources}``: every source at once, or each named source / kind on its own."""
    if not names:
        return {ALL: case.sources()}
    kinds = kind_sources(case)
    groups = {}
    for name in names:
        if name in kinds:
            groups[name] = kinds[name]
        elif name in case.sources():
            groups[name] = [name]
        else:
            raise RvppError(f"sources: unknown source {name!r}; choose from {', '.join(case.sources())} "
                            f"or a kind ({', '.join(kinds)})")
    return groups


def configurations(case: Case, settings: StudySettings) -> list[Config]:
    return [Config.of({"sources": label, "gamma": gamma}, strategy="deterministic",
                      gammas={source: gamma for source in sources})
            for label, sources in source_groups(case, settings.sources).items()
            for gamma in gamma_grid(case, settings)]


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Solve the plan at every Γ of the grid; cost, trades and reserves per Γ."""
    started = time.perf_counter()
    configs = configurations(case, settings)
    results = solve_configs(case, configs, settings, executor, progress, "sensitivity")
    table = plan_table(configs, results)
    out = StudyOutput("sensitivity", TITLE, tables={"sensitivity": table})
    out.figures["sensitivity_trades"] = figures.sensitivity_trade_figure(table)
    out.figures["sensitivity_reserve"] = figures.sensitivity_reserve_figure(table)
    out.facts["sensitivity"] = table
    out.seconds = time.perf_counter() - started
    return out
