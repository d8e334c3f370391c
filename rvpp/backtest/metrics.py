"""Aggregates of a backtest's records: what each variant cost, how badly, when and why.

Every function takes the records (one row per day and variant, as
:meth:`rvpp.store.BacktestStore.records` returns them) and returns a DataFrame.
Costs are in EUR, positive = the plant pays (a day that earns money has a negative net
cost). Definitions (docs/backtest.md):

* **CVaR 95 %** of the daily net cost: the mean of the ``k = ⌈0.05·n⌉`` largest daily net
  costs among the ``n`` settled days (for ``n < 20`` this is the worst day);
* **penalty share**: total penalty / total net cost over the days (reported only when the
  total net cost is positive, where the ratio reads as a share);
* **regret** of a day: its net cost minus the perfect-information plan's net cost on the
  same day (the perfect plan runs as its own chain, from its own carried state).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..settle.recourse import SETTLEMENT, SLACKS
from ..solving.outcome import Outcome
from .settings import PERFECT

GROUP = ["strategy", "gamma", "label"]
PENALTY_PARTS = ("penalty_deficit_eur", "penalty_surplus_eur", "penalty_reserve_eur", "penalty_heat_eur")
CVAR_LEVEL = 0.95
RECONCILE_TOLERANCE_EUR = 0.01  # one cent, on |net − (market cost + penalty)|
USABLE = tuple(str(o) for o in Outcome if o.usable)  # a plan or settlement with numbers


def cvar(costs: Sequence[float], level: float = CVAR_LEVEL) -> float:
    """Mean of the ``⌈(1 − level)·n⌉`` largest costs (the worst tail); NaN without costs."""
    values = np.sort(np.asarray(costs, dtype=float))[::-1]
    if len(values) == 0:
        return math.nan
    k = max(1, math.ceil(round((1.0 - level) * len(values), 9)))
    return float(values[:k].mean())


def daily(records: pd.DataFrame) -> pd.DataFrame:
    """One flat row per day and variant: settlement, plan numbers, audit and regret [EUR].

    ``regret_eur`` is filled where the perfect-information chain settled the same day.
    """
    if records.empty:
        return pd.DataFrame(columns=["day", *GROUP])
    table = records.copy()
    table["day"] = pd.to_datetime(table["day"]).dt.date
    table["month"] = pd.to_datetime(table["day"]).dt.strftime("%Y-%m")
    table["settled"] = table["status"].isin(USABLE)
    table["planned"] = table["plan_status"].isin(USABLE)
    for column in [f"{k}_eur" for k in SETTLEMENT] + list(SLACKS):
        if column not in table:
            table[column] = np.nan
        table[column] = pd.to_numeric(table[column], errors="coerce")
    table["audit_violations"] = pd.to_numeric(table.get("audit_violations", np.nan), errors="coerce")
    perfect = table[(table["strategy"] == PERFECT) & table["settled"]].set_index("day")["net_cost_eur"]
    table["perfect_net_cost_eur"] = table["day"].map(perfect)
    table["regret_eur"] = table["net_cost_eur"] - table["perfect_net_cost_eur"]
    return table.sort_values(["day", "strategy", "gamma"]).reset_index(drop=True)


def aggregates(records: pd.DataFrame) -> pd.DataFrame:
    """Per variant: days, failures, mean / median / CVaR 95 % / total net cost, market cost,
    penalty and its parts by cause, penalty share, regret, audit findings and timings."""
    table = daily(records)
    rows = []
    for (strategy, gamma, label), part in table.groupby(GROUP, sort=False):
        settled = part[part["settled"]]
        net = settled["net_cost_eur"]
        penalty = settled["penalty_eur"].sum()
        row = {"strategy": strategy, "gamma": gamma, "label": label, "days": len(part),
               "days_settled": len(settled), "days_without_plan": int((~part["planned"]).sum()),
               "mean_net_cost_eur": net.mean(), "median_net_cost_eur": net.median(),
               "cvar95_net_cost_eur": cvar(net), "total_net_cost_eur": net.sum(),
               "mean_market_cost_eur": settled["market_cost_eur"].mean(),
               "mean_penalty_eur": settled["penalty_eur"].mean(),
               "penalty_share": penalty / net.sum() if net.sum() > 0 else None}
        for name in PENALTY_PARTS:
            row[f"total_{name}"] = settled[name].sum()
        regret = settled["regret_eur"].dropna()
        row.update({"days_with_regret": len(regret), "mean_regret_eur": regret.mean() if len(regret) else None,
                    "total_regret_eur": regret.sum() if len(regret) else None,
                    "audit_violations": int(part["audit_violations"].fillna(0).sum()),
                    "mean_plan_solve_s": part["plan_solve_s"].mean() if "plan_solve_s" in part else None,
                    "mean_wall_s": part["wall_s"].mean() if "wall_s" in part else None})
        rows.append(row)
    return pd.DataFrame(rows)


def monthly(records: pd.DataFrame) -> pd.DataFrame:
    """Per variant and month: settled days and the sums of market cost, penalty and net cost [EUR]."""
    table = daily(records)
    settled = table[table["settled"]]
    grouped = settled.groupby([*GROUP, "month"], sort=True)
    out = grouped.agg(days=("day", "size"), market_cost_eur=("market_cost_eur", "sum"),
                      penalty_eur=("penalty_eur", "sum"), net_cost_eur=("net_cost_eur", "sum"),
                      mean_net_cost_eur=("net_cost_eur", "mean"), regret_eur=("regret_eur", "sum"))
    return out.reset_index()


def worst_days(records: pd.DataFrame, strategy: str, gamma: str, n: int = 10) -> pd.DataFrame:
    """The ``n`` costliest settled days of one variant, with what is needed to reopen their plan:
    the day, its start state, its budgets, its bids and key numbers of the plan and settlement."""
    table = daily(records)
    part = table[(table["strategy"] == strategy) & (table["gamma"] == gamma) & table["settled"]]
    columns = ["day", "strategy", "gamma", "net_cost_eur", "market_cost_eur", "penalty_eur", *PENALTY_PARTS,
               "regret_eur", "plan_status", "plan_objective_eur", "sold_mwh", "bought_mwh", "heat_bought_mwh",
               "deficit_mwh", "surplus_mwh", "unserved_heat_mwh", "start_state", "budgets", "bids"]
    return part.nlargest(n, "net_cost_eur")[[c for c in columns if c in part]].reset_index(drop=True)


def reconcile(records: pd.DataFrame) -> pd.DataFrame:
    """Every stored day checked: settled, net = market cost + penalty (to a cent), penalty parts
    adding up to the penalty, the plan audited without violation. One row per problem found."""
    problems = []
    table = daily(records)
    for row in table.itertuples(index=False):
        where = {"day": row.day, "strategy": row.strategy, "gamma": row.gamma}
        if not row.settled:
            problems.append({**where, "check": "settled", "detail": f"settlement {row.status}"})
            continue
        gap = row.net_cost_eur - (row.market_cost_eur + row.penalty_eur)
        if not abs(gap) <= RECONCILE_TOLERANCE_EUR:
            problems.append({**where, "check": "net = market cost + penalty", "detail": f"off by {gap:.6g} EUR"})
        parts = sum(getattr(row, name) for name in PENALTY_PARTS)
        if not abs(parts - row.penalty_eur) <= RECONCILE_TOLERANCE_EUR:
            problems.append({**where, "check": "penalty = sum of its parts",
                             "detail": f"off by {parts - row.penalty_eur:.6g} EUR"})
        if row.planned and math.isnan(row.audit_violations):
            problems.append({**where, "check": "plan audit", "detail": "the plan was not audited"})
        elif row.planned and row.audit_violations > 0:
            problems.append({**where, "check": "plan audit", "detail": f"{row.audit_violations:g} violation(s)"})
    return pd.DataFrame(problems, columns=["day", "strategy", "gamma", "check", "detail"])
