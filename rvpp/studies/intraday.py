"""With and without intraday sessions: the same backtest run twice, compared per strategy (MODEL_SPEC §14).

:func:`compare_intraday` runs (or resumes) the backtest of the given days and strategies once on
the day-ahead bids alone and once with the case's intraday sessions between the plan and the
settlement, both in the same store, and returns one row per strategy and run: the mean daily
net cost, penalty, market cost (the trading cost: the day-ahead, reserve and intraday cash
flows with the HPA and operating costs) and intraday revenue [EUR/day], the imbalance energies
[MWh/day], and the days that reconcile (``net = market + penalty`` to the cent). ``python -m rvpp
backtest intraday-compare`` writes it as CSV and Markdown (docs/intraday.md shows the numbers).
"""

from __future__ import annotations

import dataclasses
from concurrent.futures import Executor

import pandas as pd

from ..backtest.engine import run_backtest
from ..backtest.settings import BacktestSettings
from ..data.case import Case
from ..store import BacktestStore

COLUMNS = {"net_cost_eur": "mean_net_cost_eur", "penalty_eur": "mean_penalty_eur",
           "market_cost_eur": "mean_market_cost_eur", "revenue_intraday_eur": "mean_intraday_revenue_eur",
           "deficit_mwh": "mean_deficit_mwh", "surplus_mwh": "mean_surplus_mwh",
           "unserved_heat_mwh": "mean_unserved_heat_mwh"}
CENT = 0.01


def compare_intraday(case: Case, settings: BacktestSettings, store: BacktestStore, executor: Executor | None = None,
                     progress=None) -> pd.DataFrame:
    """Mean daily figures per strategy without and with intraday sessions (see the module's docstring)."""
    case = case.replace(intraday={"enabled": False}) if case.intraday.enabled else case
    rows = []
    for intraday in (False, True):
        run = dataclasses.replace(settings, intraday=intraday)
        ident = run_backtest(case, run, store, executor, progress,
                             label=f"intraday comparison, {'with' if intraday else 'without'} sessions")
        records = store.records(ident)
        for label, part in records.groupby("label", sort=False):
            settled = part[part["net_cost_eur"].notna()]
            row = {"strategy": label, "intraday": intraday, "days": len(part), "days_settled": len(settled)}
            row.update({name: float(settled[column].mean()) for column, name in COLUMNS.items()})
            gap = (settled["net_cost_eur"] - settled["market_cost_eur"] - settled["penalty_eur"]).abs()
            row["days_reconciled"] = int((gap <= CENT).sum())
            if intraday:
                sessions = [s for day in settled.get("intraday", pd.Series(dtype=object)).dropna() for s in day]
                row["sessions"] = len(sessions)
                row["sessions_without_plan"] = sum(s.get("status") not in ("optimal", "time_limit") for s in sessions)
            rows.append(row)
    return pd.DataFrame(rows)
