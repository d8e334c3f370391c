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
name other periods. With ``RVPP_BACKTEST_MODELLED_CASE`` naming its counterpart on the
modelled sky (``data build-case --sky modelled --demands modelled`` on the same files and
days), the same recommendation runs on that case too, and the report sets the two side by
side: per case, the four presets and the perfect-information plan with the penalty split
by cause, and each case's recommended Γ with its verdict. The records go to the store of
the environment (``RVPP_STORE_URL`` / ``RVPP_DATA_DIR``), so a rerun resumes.
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
from ..backtest.recommend import CRITERION_NAMES, Recommendation, recommend
from ..backtest.settings import PERFECT, PRESET, BacktestSettings, variants_of
from ..data.case import Case, STRATEGIES
from ..data.case_yaml import load_case
from ..errors import RvppError
from ..store import BacktestStore
from .runner import Progress, StudyOutput
from .settings import StudySettings

TITLE = "Rolling backtest and the recommended Γ (beyond the paper)"
REAL_CASE_VARIABLE = "RVPP_BACKTEST_CASE"
MODELLED_CASE_VARIABLE = "RVPP_BACKTEST_MODELLED_CASE"
REAL_SKY, MODELLED_SKY = "real sky", "modelled sky"
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


def modelled_sky_case() -> Case | None:
    """The real case's counterpart on the modelled sky, when :data:`MODELLED_CASE_VARIABLE` names one."""
    folder = os.environ.get(MODELLED_CASE_VARIABLE, "").strip()
    if not folder:
        return None
    if not os.environ.get(REAL_CASE_VARIABLE, "").strip():
        raise RvppError(f"{MODELLED_CASE_VARIABLE} names the modelled-sky counterpart of a real case; set "
                        f"{REAL_CASE_VARIABLE} to that real case too")
    return load_case(Path(folder))


def penalty_causes(records: pd.DataFrame) -> pd.DataFrame:
    """The four presets and the perfect-information plan over the settled days of ``records``:
    mean daily market cost, penalty and its parts by cause (deficit, surplus, reserve
    shortfall, unserved heat), net cost, its CVaR 95 % and the mean regret [EUR/day], presets
    in the order of :data:`~rvpp.data.case.STRATEGIES`, the perfect plan last."""
    table = metrics.aggregates(records)
    table = table[(table["gamma"] == PRESET) | (table["strategy"] == PERFECT)]
    rank = table["strategy"].map({name: i for i, name in enumerate((*STRATEGIES, PERFECT))})
    table = table.iloc[rank.to_numpy().argsort(kind="stable")].reset_index(drop=True)
    out = table[["label", "days_settled", "mean_market_cost_eur", "mean_penalty_eur"]].copy()
    for part in metrics.PENALTY_PARTS:
        out[f"mean_{part}"] = table[f"total_{part}"] / table["days_settled"]
    for column in ("mean_net_cost_eur", "cvar95_net_cost_eur", "mean_regret_eur", "audit_violations"):
        out[column] = table[column]
    return out


def _recommend(case: Case, train, test, settings: StudySettings, store: BacktestStore, executor, progress,
               stage: str) -> tuple[Recommendation, pd.DataFrame]:
    template = BacktestSettings(train[0], test[1], variants_of(STRATEGIES), penalties=settings.penalties,
                                fix_commitment=settings.fix_commitment)
    report = (lambda done, total, _eta: progress(stage, done, total)) if progress else None
    result = recommend(case, train, test, settings.backtest_fractions, settings.backtest_criterion,
                       template=template, store=store, executor=executor, progress=report)
    return result, store.records(result.backtest_id)


def _checks(result: Recommendation, records: pd.DataFrame, problems: pd.DataFrame) -> dict:
    """What report.md's consistency section says of one backtest."""
    gap = (records["net_cost_eur"] - records["market_cost_eur"] - records["penalty_eur"]).abs().max()
    return {"backtest_id": result.backtest_id, "recommended_fraction": result.fraction, "verdict": result.verdict,
            "records": len(records), "reconcile_problems": len(problems),
            "audited": int(records["audit_violations"].notna().sum()),
            "audit_violations": int(records["audit_violations"].fillna(0).sum()),
            "max_abs_net_minus_cost_plus_penalty_eur": float(gap)}


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Backtest the presets and the Γ grid, recommend Γ on the training days, judge it on the test days
    (on the modelled-sky counterpart too, when one is given)."""
    started = time.perf_counter()
    modelled = modelled_sky_case()
    case, source, train, test = study_case(case)
    train = settings.backtest_train or train
    test = settings.backtest_test or test
    store = BacktestStore()
    result, records = _recommend(case, train, test, settings, store, executor, progress, "backtest days")
    period = records["day"].map(lambda d: "train" if d <= train[1].isoformat() else "test")
    aggregates = [metrics.aggregates(records[period == name]).assign(period=name) for name in ("train", "test")]
    table = pd.concat(aggregates, ignore_index=True)
    problems = metrics.reconcile(records)
    sky = REAL_SKY if modelled is not None else case.name
    causes = penalty_causes(records).assign(case=sky)
    verdicts = [{"case": sky, "fraction": result.fraction, "outcome": str(result.outcome), "verdict": result.verdict}]
    out = StudyOutput("backtest", TITLE, tables={
        "backtest_aggregates": table, "backtest_curve": result.curve, "backtest_comparison": result.comparison,
        "backtest_monthly": metrics.monthly(records), "backtest_problems": problems})
    out.notes.append(f"{source}; training {train[0]}..{train[1]}, test {test[0]}..{test[1]}; Γ grid "
                     f"{', '.join(f'{f:g}' for f in settings.backtest_fractions)} (fractions of the day); "
                     f"criterion: {CRITERION_NAMES[settings.backtest_criterion]}; backtest `{result.backtest_id}`.")
    out.notes.append(result.verdict)
    if modelled is not None:
        other, other_records = _recommend(modelled, train, test, settings, store, executor, progress,
                                          "backtest days, modelled sky")
        other_problems = metrics.reconcile(other_records)
        causes = pd.concat([causes, penalty_causes(other_records).assign(case=MODELLED_SKY)], ignore_index=True)
        verdicts.append({"case": MODELLED_SKY, "fraction": other.fraction, "outcome": str(other.outcome),
                         "verdict": other.verdict})
        out.tables.update(backtest_comparison_modelled_sky=other.comparison, backtest_curve_modelled_sky=other.curve,
                          backtest_problems_modelled_sky=other_problems)
        out.facts["modelled_sky"] = {**_checks(other, other_records, other_problems), "case": modelled.name}
        out.notes.append(f"Modelled sky: case `{modelled.name}` from {MODELLED_CASE_VARIABLE}, the same days, "
                         f"grid and criterion; backtest `{other.backtest_id}`.")
        out.notes.append(other.verdict)
    out.tables["backtest_penalty_causes"] = causes[["case", *[c for c in causes.columns if c != "case"]]]
    out.tables["backtest_verdicts"] = pd.DataFrame(verdicts)
    out.figures["backtest_price_of_robustness"] = robustness_figure(result.curve, result.fraction, "train")
    out.figures["backtest_price_of_robustness_test"] = robustness_figure(result.curve, result.fraction, "test")
    out.figures["backtest_cumulative_cost"] = cumulative_figure(records)
    out.facts.update(**_checks(result, records, problems), source=source, train=[d.isoformat() for d in train],
                     test=[d.isoformat() for d in test])
    out.seconds = time.perf_counter() - started
    return out
