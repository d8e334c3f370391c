"""Rolling backtest and the recommended Γ over a documented period (beyond the paper).

The study runs :func:`rvpp.backtest.recommend` on the case: every preset, a Γ grid and
the perfect-information plan over a training and a test period, each day settled on its
own realized day with the storage and turbine state carried over. It reports the
aggregates per variant over both periods, the price-of-robustness curve, the test-period
comparison with the presets and the verdict, and checks that every stored day reconciles.

Periods: on the bundled synthetic case, April 2025 trains and May 2025 tests (the
settings' ``backtest_train`` / ``backtest_test`` change them). **Real data hook:** with
``RVPP_BACKTEST_CASE`` naming a case folder built from real data (e.g. by the real-data
importers from ``shared/data/spain``), the study runs on that case instead, over
:data:`REAL_TRAIN` / :data:`REAL_TEST` (the first quarter of 2018) unless the settings
name other periods. The records go to the store of the environment
(``RVPP_STORE_URL`` / ``RVPP_DATA_DIR``), so a rerun resumes.
"""

from __future__ import annotations

import datetime as dt
import os
import time
from concurrent.futures import Executor
from pathlib import Path

import pandas as pd

from ..backtest import metrics
from ..backtest.figures import cumulative_figure, robustness_figure
from ..backtest.recommend import CRITERION_NAMES, recommend
from ..backtest.settings import BacktestSettings, variants_of
from ..data.case import Case, STRATEGIES
from ..data.case_yaml import load_case
from ..store import BacktestStore
from .runner import Progress, StudyOutput
from .settings import StudySettings

TITLE = "Rolling backtest and the recommended Γ (beyond the paper)"
REAL_CASE_VARIABLE = "RVPP_BACKTEST_CASE"
SYNTHETIC_TRAIN = (dt.date(2025, 4, 1), dt.date(2025, 4, 30))
SYNTHETIC_TEST = (dt.date(2025, 5, 1), dt.date(2025, 5, 31))
REAL_TRAIN = (dt.date(2018, 1, 1), dt.date(2018, 2, 28))
REAL_TEST = (dt.date(2018, 3, 1), dt.date(2018, 3, 31))


def study_case(case: Case) -> tuple[Case, str, tuple, tuple]:
    """The case the study backtests, where it comes from, and its default training and test periods."""
    folder = os.environ.get(REAL_CASE_VARIABLE, "").strip()
    if folder:
        real = load_case(Path(folder))
        return real, f"case `{real.name}` from {REAL_CASE_VARIABLE}", REAL_TRAIN, REAL_TEST
    return case, f"case `{case.name}` (synthetic history)", SYNTHETIC_TRAIN, SYNTHETIC_TEST


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Backtest the presets and the Γ grid, recommend Γ on the training days, judge it on the test days."""
    started = time.perf_counter()
    case, source, train, test = study_case(case)
    train = settings.backtest_train or train
    test = settings.backtest_test or test
    template = BacktestSettings(train[0], test[1], variants_of(STRATEGIES), penalties=settings.penalties,
                                fix_commitment=settings.fix_commitment)
    report = (lambda done, total, _eta: progress("backtest days", done, total)) if progress else None
    store = BacktestStore()
    result = recommend(case, train, test, settings.backtest_fractions, settings.backtest_criterion,
                       template=template, store=store, executor=executor, progress=report)
    records = store.records(result.backtest_id)
    period = records["day"].map(lambda d: "train" if d <= train[1].isoformat() else "test")
    aggregates = [metrics.aggregates(records[period == name]).assign(period=name) for name in ("train", "test")]
    table = pd.concat(aggregates, ignore_index=True)
    problems = metrics.reconcile(records)
    out = StudyOutput("backtest", TITLE, tables={
        "backtest_aggregates": table, "backtest_curve": result.curve, "backtest_comparison": result.comparison,
        "backtest_monthly": metrics.monthly(records), "backtest_problems": problems})
    out.figures["backtest_price_of_robustness"] = robustness_figure(result.curve, result.fraction, "train")
    out.figures["backtest_price_of_robustness_test"] = robustness_figure(result.curve, result.fraction, "test")
    out.figures["backtest_cumulative_cost"] = cumulative_figure(records)
    out.notes.append(f"{source}; training {train[0]}..{train[1]}, test {test[0]}..{test[1]}; Γ grid "
                     f"{', '.join(f'{f:g}' for f in settings.backtest_fractions)} (fractions of the day); "
                     f"criterion: {CRITERION_NAMES[settings.backtest_criterion]}; backtest `{result.backtest_id}`.")
    out.notes.append(result.verdict)
    out.facts.update(backtest_id=result.backtest_id, recommended_fraction=result.fraction, verdict=result.verdict,
                     records=len(records), reconcile_problems=len(problems),
                     audited=int(records["audit_violations"].notna().sum()),
                     audit_violations=int(records["audit_violations"].fillna(0).sum()),
                     max_abs_net_minus_cost_plus_penalty_eur=float(
                         (records["net_cost_eur"] - records["market_cost_eur"] - records["penalty_eur"]).abs().max()),
                     source=source, train=[d.isoformat() for d in train], test=[d.isoformat() for d in test])
    out.seconds = time.perf_counter() - started
    return out
