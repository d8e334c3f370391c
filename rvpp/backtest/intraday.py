"""The intraday sessions of one backtest day: day-ahead plan → each session → final position (MODEL_SPEC §14).

:func:`trade_sessions` takes the day's day-ahead plan and its cleared bids, runs every session
of the case in gate-closure order (:mod:`rvpp.uncertainty.intraday` for what each knows,
:func:`rvpp.solving.intraday.solve_session` for its trade and re-dispatch) and returns the
bids with the trades attached, for the settlement against the final position, and one plain
record per session. A session without a usable plan trades nothing and the next session starts
from the last step that had one.

Expected imbalance (``expected_imbalance_before_mwh`` / ``_after_mwh``): by the session's
central forecast (the band's ``mid``), each uncertain electrical unit delivers its schedule
except where the forecast falls short of it: an ND-RES produces ``min(p, mid)``, an electrical
demand consumes ``max(p, mid)``; every other unit keeps its schedule. The expected imbalance is
``Σt |expected net injection − position|·dt`` over the session's window, with the schedule and
position of the step before (before) and of the session (after).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd

from ..data.case import Case
from ..data.intraday import session_times
from ..data.kinds import KINDS, Carrier, Role
from ..errors import RvppError
from ..model.session import Commitments
from ..settle.audit import audit_session
from ..settle.recourse import FirstStage, Penalties, Realization, unit_commitment
from ..solving.intraday import solve_session
from ..solving.results import Result
from ..uncertainty.intraday import realized_price, session_problem
from ..uncertainty.problem import Problem


def trade_sessions(case: Case, plan: Result, bids: FirstStage, real: Realization, penalties: Penalties,
                   audit: bool = True) -> tuple[FirstStage, list[dict[str, Any]]]:
    """Run every intraday session of ``case`` after the day-ahead ``plan``; the bids with the
    trades attached (and the hydro and biomass commitment of the last session with a plan, which
    may re-commit them in its window) and one record per session (keys of docs/intraday.md)."""
    day_ahead = plan.problem
    nt, dt_h = day_ahead.nt, case.dt_h
    times = session_times(case.intraday, case.delivery_date, day_ahead.periods, case.timezone, dt_h)
    previous, schedule, units = day_ahead, plan.schedule, plan.units
    committed = bids.committed
    traded, short = np.zeros(nt), np.zeros(nt)
    trades: list[tuple[np.ndarray, np.ndarray]] = []
    records = []
    for session in times:
        started = time.perf_counter()
        record: dict[str, Any] = {"session": session.name, "gate_closure": session.gate.isoformat(),
                                  "window_first_period": session.first}
        before = bids.p_da + traded
        price, price_origin = realized_price(case, session, day_ahead.periods, real.values["price_da"].to_numpy(float))
        try:
            problem, origin = session_problem(case, day_ahead, previous, session, real.values)
        except RvppError as exc:
            records.append({**record, "status": "error", "message": str(exc), "traded_mw": [0.0] * nt,
                            "price_eur_per_mwh": price.tolist(), "position_mw": before.tolist(),
                            "trading_revenue_eur": 0.0, "expected_imbalance_before_mwh": None,
                            "expected_imbalance_after_mwh": None, "forecast_change_mw": {},
                            "origin": {}, "solve_s": 0.0})
            continue
        commitments = Commitments(bids.p_da, bids.r_sr_up, bids.r_sr_dn, bids.h_hpa, traded.copy(), session.first,
                                  schedule, penalties.heat_price(case), short)
        result = solve_session(problem, commitments, session)
        q = result.traded_mw
        traded = traded + q
        after = bids.p_da + traded
        trades.append((q, price))
        imbalance_before = expected_imbalance(problem, units, before, session.first)
        record.update({
            "status": str(result.status), "message": result.message, "traded_mw": q.tolist(),
            "price_eur_per_mwh": price.tolist(), "position_mw": after.tolist(),
            "trading_revenue_eur": float(np.dot(price, q) * dt_h),
            "expected_imbalance_before_mwh": imbalance_before,
            "expected_imbalance_after_mwh": (expected_imbalance(problem, result.units, after, session.first)
                                             if result.has_plan else imbalance_before),
            "forecast_change_mw": forecast_change(case, problem, previous, session.first),
            "origin": {**origin, "price": price_origin}, "budgets": problem.budgets,
            "objective_eur": result.objective_eur, "mip_gap": result.mip_gap,
            "build_s": result.build_s, "solve_s": result.solve_s})
        if audit and result.has_plan:
            violations = audit_session(result, commitments, units)
            record.update(audit_violations=len(violations), audit_first=str(violations[0]) if violations else "")
        if result.has_plan:
            previous, schedule, units = problem, result.schedule, result.units
            committed = unit_commitment(result.dispatch)
            short = result.market["heat_short_mw"].to_numpy(float)
        record["wall_s"] = time.perf_counter() - started
        records.append(record)
    return replace(bids, intraday=tuple(trades), committed=committed), records


def forecast_change(case: Case, problem: Problem, previous: Problem, first: int) -> dict[str, list[float]]:
    """Per uncertain unit, the session's central forecast less the step before's [MW], [MW_th]
    (0 before the window, where nothing was forecast anew)."""
    out = {}
    for _, unit in case.uncertain_units():
        change = problem.bands[(unit.name, "mid")].to_numpy(float) - previous.bands[(unit.name, "mid")].to_numpy(float)
        change[:first] = 0.0
        out[unit.name] = change.tolist()
    return out


def expected_imbalance(problem: Problem, units: pd.DataFrame, position: np.ndarray, first: int) -> float | None:
    """``Σ_{t∈W} |expected net injection − position|·dt`` [MWh] by the central forecast of ``problem``
    for the schedule in ``units`` (see the module's docstring); ``None`` without a schedule."""
    if units is None or units.empty:
        return None
    case = problem.case
    injection = np.zeros(problem.nt)
    for kind, unit in case.units():
        info = KINDS[kind]
        if info.electric_sign == 0:  # heat only
            continue
        p = units[units["unit"] == unit.name].sort_values("t")["p_mw"].to_numpy(float)
        if info.role is not None and info.carrier is Carrier.ELECTRICITY:  # its own forecast is in MW
            mid = problem.bands[(unit.name, "mid")].to_numpy(float)
            p = np.minimum(p, mid) if info.role is Role.PRODUCTION else np.maximum(p, mid)
        injection += info.electric_sign * p
    gap = np.abs(injection - np.asarray(position, dtype=float))[first:]
    return float(gap.sum() * problem.dt_h)
