"""The scenario-based stochastic benchmark (MODEL_SPEC §10; paper Case 4, Table 14).

For every N, N whole days are sampled (seeded) from the training window, the
stochastic program maximizes expected profit over them with shared bids, and its bids
are settled on the same test realizations as the robust plans.
"""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..solving.batch import run_many
from ..data.case import Case
from ..data.variants import with_options
from ..settle.stochastic import StochasticPlan, solve_stochastic
from ..settle.recourse import set_fingerprint
from . import figures
from .evaluation import (EUR_PER_KEUR, evaluate_methods, realizations, sample_days, settlement_warning, summarize,
                         training_days)
from .out_of_sample import shared_realizations
from .runner import Progress, StudyOutput, stage
from .settings import StudySettings

TITLE = "Stochastic benchmark with N sampled days (paper Case 4, Table 14)"


def method_name(n: int) -> str:
    return f"SP N={n}"


def stochastic_task(task: tuple) -> StochasticPlan:
    """Worker entry point: ``(case, scenarios, penalties)`` -> the stochastic plan."""
    case, scenarios, penalties = task
    return solve_stochastic(case, scenarios, penalties)


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Solve the stochastic program for every N, settle its bids on the test days."""
    started = time.perf_counter()
    reals = shared_realizations(case, settings)
    pool = training_days(case)
    samples = {n: sample_days(pool, n, settings.seed) for n in settings.scenario_counts}
    sp_case = with_options(case, threads=settings.threads, time_limit_s=settings.sp_time_limit_s)
    largest_first = sorted(samples, reverse=True)
    tasks = [(sp_case, realizations(case, samples[n]), settings.penalties) for n in largest_first]
    solved = dict(zip(largest_first, run_many(stochastic_task, tasks, executor,
                                              stage(progress, "stochastic solves"))))
    plans = pd.DataFrame([{
        "method": method_name(n), "approach": "SP", "n_scenarios": n, "status": solved[n].status,
        "plan_cost_keur": None if solved[n].expected_profit_eur is None
        else -solved[n].expected_profit_eur / EUR_PER_KEUR,
        "mip_gap": solved[n].mip_gap, "solve_s": solved[n].solve_s, "time_limit_s": settings.sp_time_limit_s,
        "scenario_set": set_fingerprint(task[1]), "scenario_days": " ".join(d.isoformat() for d in samples[n]),
    } for n, task in zip(largest_first, tasks)]).sort_values("n_scenarios", ignore_index=True)
    bids = {method_name(n): solved[n].bids for n in settings.scenario_counts if solved[n].bids is not None}
    settle_case = with_options(case, threads=settings.threads)
    evaluations = evaluate_methods(settle_case, bids, reals, settings.penalties, executor,
                                   stage(progress, "stochastic settlements"))
    summary = summarize(evaluations, plans)
    out = StudyOutput("stochastic", TITLE, tables={"table14_stochastic": summary, "stochastic_days": evaluations})
    out.figures["stochastic_cost"] = figures.out_of_sample_figure(summary)
    out.warnings += [w for w in (settlement_warning(evaluations),) if w]
    out.facts.update(summary=summary, evaluations=evaluations, realization_set=set_fingerprint(reals))
    out.seconds = time.perf_counter() - started
    return out
