"""Out-of-sample evaluation of the robust strategies (paper Case 4, Table 13).

Each strategy's plan (bands from the training window) is settled by the recourse
model against every realization of the test window (:mod:`.evaluation`).
"""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..data.case import Case
from ..data.variants import with_options
from ..data.variants import describe
from ..settle.recourse import first_stage, set_fingerprint
from . import figures
from .evaluation import evaluate_methods, evaluation_days, realizations, settlement_warning, summarize
from .runner import Config, Progress, StudyOutput, solve_configs, stage
from .settings import StudySettings

TITLE = "Out-of-sample evaluation of the robust strategies (paper Case 4, Table 13)"


def shared_realizations(case: Case, settings: StudySettings):
    """The realizations every method is settled against."""
    return realizations(case, evaluation_days(case, settings.test_days))


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Plan every strategy once, settle each plan on every test day, average per strategy."""
    started = time.perf_counter()
    reals = shared_realizations(case, settings)
    configs = [Config.of({"method": s}, strategy=s) for s in settings.strategies]
    results = solve_configs(case, configs, settings, executor, progress, "robust plans")
    plans = pd.DataFrame([{"method": dict(c.labels)["method"], "approach": "RO", "variant": describe(r.case),
                           "status": r.status, "plan_cost_keur": r.cost_keur, "mip_gap": r.mip_gap,
                           "solve_s": r.solve_s}
                          for c, r in zip(configs, results)])
    bids = {dict(c.labels)["method"]: first_stage(r, settings.fix_commitment)
            for c, r in zip(configs, results) if r.has_plan}
    settle_case = with_options(case, threads=settings.threads)
    evaluations = evaluate_methods(settle_case, bids, reals, settings.penalties, executor,
                                   stage(progress, "out-of-sample settlements"))
    summary = summarize(evaluations, plans)
    out = StudyOutput("out_of_sample", TITLE, tables={"table13_out_of_sample": summary,
                                                      "out_of_sample_days": evaluations})
    out.figures["out_of_sample_cost"] = figures.out_of_sample_figure(summary)
    out.warnings += [w for w in (settlement_warning(evaluations),) if w]
    out.facts.update(summary=summary, evaluations=evaluations, realization_set=set_fingerprint(reals),
                     days=[r.day.isoformat() for r in reals])
    out.seconds = time.perf_counter() - started
    return out
