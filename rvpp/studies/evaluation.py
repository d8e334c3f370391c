"""Out-of-sample evaluation shared by the RO and SP studies (MODEL_SPEC §10; paper Case 4).

Protocol: the robust plans take their bands from the training window (the
``window_days`` before the delivery day); the stochastic benchmark samples its
scenarios from the same window; every method is then settled by the recourse model
against the *same* realizations, the observed whole days of a disjoint test window
starting on the delivery day. Days whose number of periods differs from the delivery
day's (the two clock-change days of a year) are left out of both windows.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable, Sequence
from concurrent.futures import Executor

import numpy as np
import pandas as pd

from ..solving.batch import run_many
from ..data.case import Case
from ..errors import RvppError
from ..data.periods import delivery_periods
from ..solving.outcome import Outcome
from ..settle.recourse import FirstStage, Penalties, Realization, evaluate, realization, set_fingerprint
from ..uncertainty.bands import window_days

EUR_PER_KEUR = 1000.0


def same_length_days(case: Case, days: Sequence[dt.date]) -> list[dt.date]:
    """The days that have as many periods as the delivery day."""
    length = len(delivery_periods(case.delivery_date, case.timezone, case.dt_h))
    return [d for d in days if len(delivery_periods(d, case.timezone, case.dt_h)) == length]


def evaluation_days(case: Case, n_days: int) -> list[dt.date]:
    """The first ``n_days`` whole days from the delivery day on (the test window)."""
    covered = [d for d in case.history.local_days(case.timezone) if d >= case.delivery_date]
    days = same_length_days(case, covered)[:n_days]
    if len(days) < n_days:
        raise RvppError(f"{case.history.source}: only {len(days)} whole days of the delivery day's length from "
                        f"{case.delivery_date} on; the out-of-sample test needs {n_days}. Choose an earlier "
                        "delivery date or fewer test days")
    return days


def training_days(case: Case) -> list[dt.date]:
    """The days of the window the forecast bands are drawn from (the training window)."""
    first, _ = window_days(case.delivery_date, case.uncertainty.window_days)
    covered = set(case.history.local_days(case.timezone))
    window = [first + dt.timedelta(days=k) for k in range(case.uncertainty.window_days)]
    return same_length_days(case, [d for d in window if d in covered])


def sample_days(days: Sequence[dt.date], n: int, seed: int) -> list[dt.date]:
    """The first ``n`` days of a seeded random order, so a smaller sample is part of a larger one.

    Without replacement while ``n`` does not exceed the days available.
    """
    rng = np.random.default_rng(seed)
    if n <= len(days):
        order = rng.permutation(len(days))[:n]
    else:
        order = rng.integers(0, len(days), size=n)
    return [days[i] for i in order]


def realizations(case: Case, days: Sequence[dt.date]) -> list[Realization]:
    return [realization(case, d) for d in days]


def evaluate_task(task: tuple) -> dict:
    """Worker entry point: ``(method, case, bids, realization, penalties)`` -> record."""
    method, case, bids, real, penalties = task
    return {"method": method, **evaluate(case, bids, real, penalties)}


def evaluate_methods(case: Case, methods: dict[str, FirstStage], reals: Sequence[Realization],
                     penalties: Penalties, executor: Executor | None = None,
                     progress: Callable[[int, int], None] | None = None) -> pd.DataFrame:
    """Settle every method's bids against every realization: one row per (method, day)."""
    tasks = [(name, case, bids, real, penalties) for name, bids in methods.items() for real in reals]
    records = run_many(evaluate_task, tasks, executor, progress)
    table = pd.DataFrame(records)
    if table.empty:  # no method had bids to settle
        return table
    table.insert(2, "realization_set", set_fingerprint(reals))
    return table


SETTLEMENT_MEANS = {"avg_market_cost_keur": "market_cost_eur", "avg_penalty_keur": "penalty_eur",
                    "avg_net_cost_keur": "net_cost_eur"}


def ended_optimal(statuses: pd.Series) -> pd.Series:
    """True where a settlement's solve ended :attr:`Outcome.OPTIMAL` (statuses as members or plain values)."""
    return statuses.map(lambda status: Outcome(status) is Outcome.OPTIMAL).astype(bool)


def summarize(evaluations: pd.DataFrame, plans: pd.DataFrame) -> pd.DataFrame:
    """Averages per method (paper Tables 13-14): market cost, penalty, net cost [kEUR].

    Only settlements that ended optimal enter the averages: a settlement stopped by its
    time limit (or with no solution) is counted in ``settlements_optimal`` ("29 / 30":
    optimal out of settled) and left out, so a method's averages then cover fewer days
    than ``test_days``. ``plans`` has one row per method with ``method``, ``solve_s``
    and ``status`` of the first-stage solve (and optional extra columns kept as they
    are); a method without a plan keeps its row with empty averages and ``no plan``.
    """
    if evaluations.empty:
        summary = pd.DataFrame({"method": plans["method"]})
        summary = summary.assign(**{c: float("nan") for c in SETTLEMENT_MEANS}, test_days=0,
                                 settlements_optimal="no plan", realization_set=None)
        return plans.merge(summary, on="method", how="left")
    optimal = ended_optimal(evaluations["status"])
    grouped = evaluations.groupby("method", sort=False)
    methods = list(grouped.groups)
    means = evaluations[optimal].groupby("method", sort=False)[list(SETTLEMENT_MEANS.values())].mean()
    means = means.reindex(methods) / EUR_PER_KEUR
    counts = optimal.groupby(evaluations["method"], sort=False).sum().reindex(methods)
    settled = grouped.size().reindex(methods)
    summary = pd.DataFrame({
        "method": methods,
        **{column: means[source].to_numpy(float) for column, source in SETTLEMENT_MEANS.items()},
        "test_days": settled.to_numpy(),
        "settlements_optimal": [f"{int(k)} / {int(n)}" for k, n in zip(counts, settled)],
        "realization_set": grouped["realization_set"].first().reindex(methods).to_numpy(),
    })
    merged = plans.merge(summary, on="method", how="left")
    merged["settlements_optimal"] = merged["settlements_optimal"].fillna("no plan")
    return merged


def settlement_warning(evaluations: pd.DataFrame) -> str | None:
    """One line naming the settlements that did not end optimal, or ``None`` if every one did."""
    if evaluations.empty:
        return None
    failed = evaluations[~ended_optimal(evaluations["status"])]
    if failed.empty:
        return None
    per_method = "; ".join(
        f"{method}: {', '.join(f'{row.day} {Outcome(row.status)}' for row in part.itertuples())}"
        for method, part in failed.groupby("method", sort=False))
    return (f"{len(failed)} of {len(evaluations)} settlements did not end optimal and are left out of the "
            f"averages ({per_method}).")


def realizations_used(evaluations: pd.DataFrame) -> pd.DataFrame:
    """One row per test day and realization fingerprint, with the number of methods settled on it.

    Every method met the same data when each day has a single row whose ``methods`` is
    the number of methods evaluated.
    """
    grouped = evaluations.groupby(["day", "fingerprint"], sort=True)["method"]
    return grouped.nunique().reset_index(name="methods")
