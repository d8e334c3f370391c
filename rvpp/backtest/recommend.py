"""The recommended Γ: chosen on a training period, judged on a later test period.

One backtest runs every Γ fraction of the grid (Γ = ⌊f·NT + ½⌋ periods for every
source), the four presets and the perfect-information plan over the training and the
test period (one chain each, so the test period starts from the state the training
period left). The fraction that minimises the criterion (mean daily net cost, or CVaR
95 % of it) on the training days is the recommendation; its test-period figures are
then set against the presets', whichever way that falls. Nothing of the test period
enters the choice: this is a walk-forward check of a single choice, not a search on the
test days. The fraction 0 is the deterministic plan (all budgets 0) and reuses its
records.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

import pandas as pd

from ..data.case import STRATEGIES, Case
from ..outputs.money import IN_EUR, MoneyUnit
from ..store import BacktestStore
from . import metrics
from .engine import Progress, run_backtest
from .settings import FRACTION, PERFECT, PRESET, BacktestError, BacktestSettings, BacktestVariant, variants_of
from .export import export

CRITERIA = {"mean": "mean_net_cost_eur", "cvar95": "cvar95_net_cost_eur"}
# The least evidence a recommendation is offered on. Two training weeks hold every weekday twice (demand
# and prices follow the week) and one test week holds each once; a choice on fewer days follows the
# weather of a few days more than Γ.
MIN_TRAIN_DAYS = 14
MIN_TEST_DAYS = 7
CVAR_DAYS = 20  # under 20 days the CVaR 95 % is the single worst day
CRITERION_NAMES = {"mean": "mean daily net cost", "cvar95": "CVaR 95 % of the daily net cost"}


@dataclass(frozen=True, eq=False)
class Recommendation:
    """The recommended fraction, the price-of-robustness curve and the test-period comparison.

    ``curve``: one row per fraction and period (``train``/``test``) with the mean market
    cost, penalty and net cost, the median and the CVaR 95 % [EUR/day]. ``comparison``: the
    test period's figures of the recommendation, the presets and the perfect-information
    plan, with each one's difference to the recommendation on the criterion.
    """

    backtest_id: str
    criterion: str
    train: tuple[dt.date, dt.date]
    test: tuple[dt.date, dt.date]
    fraction: float
    curve: pd.DataFrame
    comparison: pd.DataFrame
    verdict: str
    outcome: Verdict

    @property
    def variant(self) -> BacktestVariant:
        """The recommendation as a variant a solve can use (``with_options(gamma_fraction=...)``)."""
        return BacktestVariant.of_fraction(self.fraction)


def recommend(case: Case, train: tuple[dt.date, dt.date], test: tuple[dt.date, dt.date],
              fractions: Sequence[float], criterion: str = "mean", presets: Sequence[str] = STRATEGIES,
              template: BacktestSettings | None = None, store: BacktestStore | None = None,
              executor: Executor | None = None, progress: Progress | None = None, label: str = "") -> Recommendation:
    """Backtest the grid and the presets over both periods, then :func:`recommendation_from`.

    ``template``: settings whose penalties, storage rule and switches are kept (days and
    variants are set here). Resumes like any backtest.
    """
    check_periods(train, test)
    if criterion not in CRITERIA:
        raise BacktestError(f"--criterion {criterion!r} must be one of {', '.join(CRITERIA)}")
    grid = sorted(set(float(f) for f in fractions))
    if not grid:
        raise BacktestError("--fractions is empty; give the Γ grid, e.g. 0,0.125,0.25,0.375")
    presets = list(dict.fromkeys([*presets, "deterministic"] if 0.0 in grid else presets))
    run_fractions = [f for f in grid if f > 0.0]
    perfect = template.perfect if template is not None else True
    variants = variants_of(presets, run_fractions, perfect)
    settings = (template or BacktestSettings(train[0], test[1], variants)).with_changes(
        first_day=train[0], last_day=test[1], variants=variants)
    store = store or BacktestStore()
    ident = run_backtest(case, settings, store, executor, progress,
                         label=label or f"{case.name}: Γ on {train[0]}..{train[1]}, test {test[0]}..{test[1]}")
    return recommendation_from(store.records(ident), train, test, grid, criterion, ident)


def recommendation_from(records: pd.DataFrame, train: tuple[dt.date, dt.date], test: tuple[dt.date, dt.date],
                        fractions: Sequence[float], criterion: str, backtest_id: str = "") -> Recommendation:
    """The recommendation from a backtest's records (pure: no solve)."""
    check_periods(train, test)
    table = metrics.daily(records)
    column = CRITERIA[criterion]
    periods = {"train": train, "test": test}
    rows = []
    for fraction in sorted(set(float(f) for f in fractions)):
        part = _fraction_rows(table, fraction)
        for period, (first, last) in periods.items():
            rows.append({"fraction": fraction, "period": period,
                         **_stats(part[(part["day"] >= first) & (part["day"] <= last)])})
    curve = pd.DataFrame(rows)
    trained = curve[curve["period"] == "train"].dropna(subset=[column])
    if trained.empty:
        raise BacktestError("no fraction of the grid has settled training days; the recommendation needs them")
    best = trained.sort_values([column, "fraction"]).iloc[0]
    fraction = float(best["fraction"])
    comparison = _comparison(table, fraction, periods, column)
    outcome, verdict = _verdict(comparison, fraction, criterion, test)
    return Recommendation(backtest_id, criterion, train, test, fraction, curve, comparison, verdict, outcome)


def shortfalls(rec: Recommendation) -> list[str]:
    """Why ``rec`` rests on too little evidence to be followed, in words (empty when it does not):
    fewer settled training or test days than :data:`MIN_TRAIN_DAYS` / :data:`MIN_TEST_DAYS`, and
    a CVaR 95 % that is only the worst day."""
    mine = rec.comparison.iloc[0]
    train, test = int(mine["train_days_settled"]), int(mine["test_days_settled"])
    found = []
    if train < MIN_TRAIN_DAYS:
        found.append(f"{train} settled training day{'s' * (train != 1)}, fewer than the {MIN_TRAIN_DAYS} a "
                     "choice needs (every weekday twice)")
    if test < MIN_TEST_DAYS:
        found.append(f"{test} settled test day{'s' * (test != 1)}, fewer than the {MIN_TEST_DAYS} a check needs "
                     "(every weekday once)")
    if rec.criterion == "cvar95" and train < CVAR_DAYS:
        found.append(f"under {CVAR_DAYS} training days the CVaR 95 % is the single worst day")
    return found


def beats_presets_on_training(rec: Recommendation) -> bool:
    """Whether the recommendation's criterion on the training days is strictly lower (less cost)
    than every preset's: otherwise a preset does as well and there is nothing to recommend."""
    column = f"train_{CRITERIA[rec.criterion]}"
    presets = rec.comparison[rec.comparison["variant"].isin(STRATEGIES)][column].dropna()
    mine = rec.comparison.iloc[0][column]
    return bool(pd.notna(mine) and (presets.empty or mine < presets.min()))


def check_periods(train, test) -> None:
    """Refuse a training and a test period out of order, in the words of `backtest recommend`."""
    if train[1] < train[0] or test[1] < test[0]:
        raise BacktestError("--train and --test must each run from their first to their last day")
    if test[0] <= train[1]:
        raise BacktestError(f"--test must start after --train ends ({train[1]}); got {test[0]}: the choice may "
                            "only use days before the test period")


def _fraction_rows(table: pd.DataFrame, fraction: float) -> pd.DataFrame:
    rows = table[(table["strategy"] == FRACTION) & (table["gamma"] == f"{fraction:g}")]
    if rows.empty and fraction == 0.0:
        rows = table[(table["strategy"] == "deterministic") & (table["gamma"] == PRESET)]
    return rows


def _stats(part: pd.DataFrame) -> dict:
    settled = part[part["settled"]]
    net = settled["net_cost_eur"]
    return {"days": len(part), "days_settled": len(settled),
            "mean_market_cost_eur": settled["market_cost_eur"].mean(),
            "mean_penalty_eur": settled["penalty_eur"].mean(), "mean_net_cost_eur": net.mean(),
            "median_net_cost_eur": net.median(), "cvar95_net_cost_eur": metrics.cvar(net),
            "mean_regret_eur": settled["regret_eur"].mean()}


def _comparison(table: pd.DataFrame, fraction: float, periods: dict, column: str) -> pd.DataFrame:
    candidates = [(f"recommended: Γ {fraction:g} of the day", _fraction_rows(table, fraction))]
    candidates += [(name, table[(table["strategy"] == name) & (table["gamma"] == PRESET)]) for name in STRATEGIES]
    candidates.append(("perfect information", table[table["strategy"] == PERFECT]))
    rows = []
    for name, part in candidates:
        if part.empty:
            continue
        row = {"variant": name}
        for period, (first, last) in periods.items():
            stats = _stats(part[(part["day"] >= first) & (part["day"] <= last)])
            row.update({f"{period}_{k}": v for k, v in stats.items() if k != "days"})
        rows.append(row)
    out = pd.DataFrame(rows)
    reference = out.loc[0, f"test_{column}"]
    out[f"test_{column}_minus_recommended"] = out[f"test_{column}"] - reference
    return out


class Verdict(StrEnum):
    """How the recommended Γ fared on the test days against the presets: no preset did better
    (``holds``), or at least one did (``loses``: the choice did not carry over)."""

    HOLDS = "holds"
    LOSES = "loses"


def verdict_words(result: Recommendation, money: MoneyUnit) -> str:
    """The verdict of ``result`` with its amounts written in ``money`` (``result.verdict``, kept with
    the backtest and exported, writes them in EUR)."""
    return _verdict(result.comparison, result.fraction, result.criterion, result.test, money)[1]


def _verdict(comparison: pd.DataFrame, fraction: float, criterion: str, test,
             money: MoneyUnit = IN_EUR) -> tuple[Verdict, str]:
    column = f"test_{CRITERIA[criterion]}"
    name = CRITERION_NAMES[criterion]
    contenders = comparison[comparison["variant"] != "perfect information"]
    mine = contenders.iloc[0][column]
    presets = contenders.iloc[1:]
    better = presets[presets[column] < mine]
    head = (f"Recommended Γ = {fraction:g} of the day (chosen on the training days by the {name}). "
            f"On the test days {test[0]}..{test[1]} its {name} is {money.words(mine)}")
    if better.empty:
        runner = presets.nsmallest(1, column)
        gap = f"; the best preset, {runner.iloc[0]['variant']}, has {money.words(runner.iloc[0][column])}" \
            if len(runner) else ""
        return Verdict.HOLDS, head + f": no preset does better{gap}."
    listing = ", ".join(f"{r['variant']} ({money.words(r[column])})" for _, r in better.sort_values(column).iterrows())
    return Verdict.LOSES, (head + f", and it LOSES to {listing} on the test days: the choice made on the training "
                           "days did not carry over to the test period.")


def write_recommendation(result: Recommendation, store: BacktestStore, folder: str | Path) -> Path:
    """The backtest's export (:func:`.export.export`) plus ``curve``, ``comparison`` and the verdict."""

    notes = {"recommendation": {"fraction": result.fraction, "criterion": result.criterion,
                                "train": [d.isoformat() for d in result.train],
                                "test": [d.isoformat() for d in result.test], "verdict": result.verdict}}
    return export(store, result.backtest_id, folder, extra={"curve": result.curve, "comparison": result.comparison},
                  notes=notes)
