"""The model of one intraday session (MODEL_SPEC §14).

:func:`build_session_model` reads like :func:`rvpp.model.build_model`, with the same
builders: the day-ahead bids ``p_da``, ``r_sr_up``, ``r_sr_dn`` and ``h_hpa`` are fixed at
their cleared values, the session trades ``q_k[t]`` [MW] (+ sell, − buy) in the periods of
its window, the electrical balance and the trading limits of §7 hold on the total position
``p_da + Σ_{j<k} q_j + q_k``, every unit is re-dispatched in the window and keeps the schedule
of the step before in the periods before it. The robust layer (:mod:`rvpp.model.robust`)
applies the session's bands and budgets and protects the trade against the intraday price
as it protects the day-ahead bid against the DAM price. Objective [EUR]:

    ``max Σt λ~_k·q_k·dt − protection_k − Σ operating cost − c_heat·Σt heat_short·dt
    + value of the heat kept``

(the day-ahead revenue, the reserve revenue and the HPA cost are fixed, so they are left out;
the operating cost of the units less its value in the step before is the ``Δ operating cost``
of §14).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyomo.environ as pyo
from pyomo.core.expr.visitor import identify_variables

from ..errors import RvppError
from ..uncertainty.problem import Problem
from . import add_units
from .blocks import unit_block
from .csp import add_csp_symmetry
from .market import (add_electric_balance, add_heat_balance, add_market_bids, add_market_limits, add_time,
                     capacities, operating_cost)
from .robust import add_robustness

FIXED_BIDS = ("p_da", "r_sr_up", "r_sr_dn", "h_hpa")


@dataclass(frozen=True, eq=False)
class Commitments:
    """What a session may not change: the day-ahead bids [MW], [MW_th], the trades of earlier
    sessions summed per period [MW], the first period of the window (0-based), the schedule
    of the step before (every unit variable's value by its name in the model), the price of
    heat the units cannot supply in the window [EUR/MWh_th] (the settlement's unserved heat) and
    the heat the step before planned short [MW_th] (``None``: none)."""

    p_da: np.ndarray
    r_sr_up: np.ndarray
    r_sr_dn: np.ndarray
    h_hpa: np.ndarray
    traded: np.ndarray
    first: int
    schedule: dict[str, float] = field(default_factory=dict)
    heat_short_eur_per_mwh: float = 0.0
    heat_short: np.ndarray | None = None

    @property
    def position(self) -> np.ndarray:
        """The position before the session: ``p_da + Σ_{j<k} q_j`` [MW]."""
        return self.p_da + self.traded


def build_session_model(problem: Problem, commitments: Commitments) -> pyo.ConcreteModel:
    """The robust re-dispatch MILP of one intraday session."""
    m = pyo.ConcreteModel(name=f"rvpp {problem.case.name} {problem.day} intraday")
    add_time(m, problem)
    add_market_bids(m, problem)
    fix_bids(m, commitments)
    add_intraday_trade(m, problem, commitments)
    add_heat_shortfall(m, commitments)
    add_units(m, problem)
    add_csp_symmetry(m, problem)
    add_market_limits(m, problem)
    add_electric_balance(m, problem)
    add_heat_balance(m, problem)
    add_robustness(m, problem)
    keep_schedule_before(m, problem, commitments)
    add_session_objective(m, problem, commitments)
    return m


def fix_bids(m: pyo.ConcreteModel, commitments: Commitments) -> None:
    """``p_da``, ``r_sr_up``, ``r_sr_dn``, ``h_hpa`` fixed at the cleared day-ahead values."""
    for name in FIXED_BIDS:
        values = getattr(commitments, name)
        if len(values) != len(m.T):
            raise RvppError(f"the day-ahead {name} has {len(values)} periods but the day has {len(m.T)}")
        var = getattr(m, name)
        for t in m.T:
            var[t].fix(float(values[t - 1]), skip_validation=True)


def add_intraday_trade(m: pyo.ConcreteModel, problem: Problem, commitments: Commitments) -> None:
    """The trade ``q_id[t]`` [MW] (+ sell, − buy), 0 before the window, and the total position
    ``position[t] = p_da + Σ_{j<k} q_j + q_id`` [MW] on which §7 holds (MODEL_SPEC §14).

    The trade's own bounds leave the position within ``[−ΣPmax_d, ΣPmax_r + ΣPmax_θ]``, the
    widest the trading limits of :func:`~rvpp.model.market.add_market_limits` allow.
    """
    generation, demand, _ = capacities(problem)
    before = commitments.position
    m.q_id = pyo.Var(m.T, bounds=lambda _, t: (-demand - float(before[t - 1]), generation - float(before[t - 1])))
    for t in m.T:
        if t <= commitments.first:
            m.q_id[t].fix(0.0)
    m.position = pyo.Expression(m.T, rule=lambda m, t: m.p_da[t] + float(commitments.traded[t - 1]) + m.q_id[t])


def add_heat_shortfall(m: pyo.ConcreteModel, commitments: Commitments) -> None:
    """``heat_short[t]`` [MW_th] ≥ 0: heat the units cannot supply in the window under the session's
    bands. The HPA purchase is fixed, so a heat demand forecast higher than at the day-ahead may
    not be met; the session then plans it short, at the price the settlement charges for unserved
    heat, instead of having no plan at all. Before the window, what the step before planned short."""
    m.heat_short = pyo.Var(m.T, domain=pyo.NonNegativeReals)
    before = np.zeros(len(m.T)) if commitments.heat_short is None else commitments.heat_short
    for t in m.T:
        if t <= commitments.first:
            m.heat_short[t].fix(max(0.0, float(before[t - 1])))


def schedule_of(m: pyo.ConcreteModel, problem: Problem) -> dict[str, float]:
    """Every unit variable's value by its name: the schedule a later session keeps before its window."""
    return {var.name: float(var.value) for block in _unit_blocks(m, problem)
            for var in block.component_data_objects(pyo.Var, descend_into=True) if var.value is not None}


def keep_schedule_before(m: pyo.ConcreteModel, problem: Problem, commitments: Commitments) -> None:
    """Periods before the window keep the step before's schedule: every unit variable of those
    periods is fixed at its value there (integers rounded, values held within their bounds), and a
    constraint left without a free variable is dropped (it held in the step before; solver
    round-off could otherwise make it fail as written)."""
    if commitments.first == 0:
        return
    for block in _unit_blocks(m, problem):
        for component in block.component_objects(pyo.Var, descend_into=True):
            at = _time_position(component, m)
            if at is None:
                continue
            for index, var in component.items():
                t = index[at] if isinstance(index, tuple) else index
                if t > commitments.first:
                    continue
                if var.name not in commitments.schedule:
                    raise RvppError(f"the schedule of the step before has no value for {var.name}")
                value = commitments.schedule[var.name]
                if var.is_integer():
                    value = round(value)
                low, high = var.bounds
                value = min(max(value, -np.inf if low is None else low), np.inf if high is None else high)
                var.fix(value, skip_validation=True)
    for con in m.component_data_objects(pyo.Constraint, active=True, descend_into=True):
        if all(v.fixed for v in identify_variables(con.body, include_fixed=True)):
            con.deactivate()


def _unit_blocks(m: pyo.ConcreteModel, problem: Problem) -> list[pyo.Block]:
    return [unit_block(m, kind, unit.name) for kind, unit in problem.case.units()]


def _time_position(component, m: pyo.ConcreteModel) -> int | None:
    """Where the period sits in the index of a unit variable: the position of ``m.T`` among its
    index sets, or the second place of an ``(s, t)`` pair set (the piecewise curves); ``None`` for a
    variable of the whole day."""
    if not component.is_indexed():
        return None
    parts = list(component.index_set().subsets(expand_all_set_operators=True))
    position = 0
    for part in parts:
        if part is m.T:
            return position
        dimen = part.dimen if isinstance(part.dimen, int) else 1
        if dimen == 2 and len(part) and all(isinstance(x, tuple) and x[0] in m.S and x[1] in m.T for x in part):
            return position + 1
        position += dimen
    return None


def add_session_objective(m: pyo.ConcreteModel, problem: Problem, commitments: Commitments) -> None:
    """Maximise ``Σt λ~_k·q_k·dt − protection_k − operating cost − c_heat·Σt heat_short·dt + value of
    the heat kept`` [EUR]."""
    case, dt = problem.case, problem.dt_h
    price = problem.sources["price_da"].nominal
    m.revenue_intraday = pyo.Expression(expr=sum(float(price[t - 1]) * m.q_id[t] * dt for t in m.T))
    m.cost_opex = pyo.Expression(expr=operating_cost(m, case, dt))
    m.value_heat_kept = pyo.Expression(expr=sum(m.csp[c.name].heat_kept_value for c in case.csp))
    m.cost_heat_short = pyo.Expression(expr=sum(commitments.heat_short_eur_per_mwh * m.heat_short[t] * dt for t in m.T))
    m.profit = pyo.Objective(expr=m.revenue_intraday - m.protection["price_da"] - m.cost_opex - m.cost_heat_short
                             + m.value_heat_kept, sense=pyo.maximize)
