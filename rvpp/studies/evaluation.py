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
    table.insert(2, "realization_set", set_fingerprint(reals))
    return table


def summarize(evaluations: pd.DataFrame, plans: pd.DataFrame) -> pd.DataFrame:
    """Averages per method (paper Tables 13-14): market cost, penalty, net cost [kEUR].

    ``plans`` has one row per method with ``method``, ``solve_s`` and ``status`` of
    the first-stage solve (and optional extra columns kept as they are); a method
    without a plan keeps its row with empty averages.
    """
    grouped = evaluations.groupby("method", sort=False)
    summary = pd.DataFrame({
        "method": list(grouped.groups),
        "avg_market_cost_keur": grouped["market_cost_eur"].mean().to_numpy() / EUR_PER_KEUR,
        "avg_penalty_keur": grouped["penalty_eur"].mean().to_numpy() / EUR_PER_KEUR,
        "avg_net_cost_keur": grouped["net_cost_eur"].mean().to_numpy() / EUR_PER_KEUR,
        "test_days": grouped.size().to_numpy(),
        "evaluations_optimal": grouped["status"].apply(lambda s: int((s == "optimal").sum())).to_numpy(),
        "realization_set": grouped["realization_set"].first().to_numpy(),
    })
    return plans.merge(summary, on="method", how="left")


def realizations_used(evaluations: pd.DataFrame) -> pd.DataFrame:
    """One row per test day and realization fingerprint, with the number of methods settled on it.

    Every method met the same data when each day has a single row whose ``methods`` is
    the number of methods evaluated.
    """
    grouped = evaluations.groupby(["day", "fingerprint"], sort=True)["method"]
    return grouped.nunique().reset_index(name="methods")
