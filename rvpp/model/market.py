"""Market bids, RVPP-level limits, system balances and the objective (MODEL_SPEC §2-§3, §7)."""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.history import PRICE_COLUMNS
from ..uncertainty.problem import Problem
from .blocks import unit_block
from ..data.scenarios import SCENARIOS, Scenario, activation

def add_time(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Periods ``T = 1..NT`` and activation scenarios ``S`` (only ``none`` without the SRM)."""
    m.T = pyo.RangeSet(1, problem.nt)
    scenarios = SCENARIOS if problem.case.markets.srm else (Scenario.NONE,)
    m.S = pyo.Set(initialize=[s.value for s in scenarios], ordered=True)  # plain text inside Pyomo


def capacities(problem: Problem) -> tuple[float, float, float]:
    """Generation nameplate ``ΣPmax_r + ΣPmax_θ`` (batteries' discharge and dispatchable units
    included), demand nameplate ``ΣPmax_d`` (batteries' charge included) and the reserve cap
    ``κ·max(0, generation − demand)`` (``markets.reserve_base`` net, the paper) or ``κ·generation``
    (installed, the authors' tool) [MW] (Power-Traded1..4; MODEL_SPEC §7, §13)."""
    case = problem.case
    generation = sum(unit.supply_mw for _, unit in case.units())
    demand = sum(unit.demand_mw for _, unit in case.units())
    base = generation if case.markets.reserve_base == "installed" else max(0.0, generation - demand)
    return generation, demand, case.markets.kappa * base


def add_market_bids(m: pyo.ConcreteModel, problem: Problem) -> None:
    """First-stage decisions (MODEL_SPEC §2) with the reserve cap (Power-Traded3-4).

    ``p_da`` [MW] day-ahead energy (+ sell, − buy); ``r_sr_up``, ``r_sr_dn`` [MW] secondary
    reserve bands, each ``≤ κ·max(0, ΣPmax_r + ΣPmax_θ − ΣPmax_d)``; ``h_hpa`` [MW_th] heat
    bought through the HPA. A market switched off fixes its decisions to zero.
    ``protection[price]`` [EUR] holds the price protection that :mod:`rvpp.model.robust` adds.
    """
    markets = problem.case.markets
    reserve_cap = capacities(problem)[2] if markets.srm else 0.0
    m.p_da = pyo.Var(m.T, domain=pyo.Reals)
    m.r_sr_up = pyo.Var(m.T, domain=pyo.NonNegativeReals, bounds=(0.0, reserve_cap))
    m.r_sr_dn = pyo.Var(m.T, domain=pyo.NonNegativeReals, bounds=(0.0, reserve_cap))
    m.h_hpa = pyo.Var(m.T, domain=pyo.NonNegativeReals, bounds=(0.0, None) if markets.hpa else (0.0, 0.0))
    m.protection = pyo.Expression(list(PRICE_COLUMNS), initialize=0.0)


def position(m: pyo.ConcreteModel):
    """The energy position the units must deliver [MW]: ``p_da``, or in an intraday session
    (:mod:`rvpp.model.session`) the total position ``p_da + Σ_{j≤k} q_j`` (MODEL_SPEC §14)."""
    return m.position if hasattr(m, "position") else m.p_da


def add_market_limits(m: pyo.ConcreteModel, problem: Problem) -> None:
    """RVPP trading limits (Power-Traded1-2) [MW].

    ``p_da + r_sr_up ≤ ΣPmax_r + ΣPmax_θ`` and ``−ΣPmax_d ≤ p_da − r_sr_dn``, with the total
    position in place of ``p_da`` in an intraday session (MODEL_SPEC §14).
    """
    generation, demand, _ = capacities(problem)
    p = position(m)
    m.trade_upper = pyo.Constraint(m.T, rule=lambda m, t: p[t] + m.r_sr_up[t] <= generation)
    m.trade_lower = pyo.Constraint(m.T, rule=lambda m, t: p[t] - m.r_sr_dn[t] >= -demand)


def add_electric_balance(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Electrical balance in every activation scenario (Supply-Demand1; MODEL_SPEC §7) [MW].

    ``Σr (p_r + a_s(r↑_r, r↓_r)) + Σθ e_θ,s − Σd (p_d − a_s(r↑_d, r↓_d)) = p_da + a_s(r↑_SR, r↓_SR)``,
    with the total position in place of ``p_da`` in an intraday session (MODEL_SPEC §14).
    """
    case = problem.case
    p = position(m)
    m.electric_balance = pyo.Constraint(m.S, m.T, rule=lambda m, s, t: (
        net_injection(m, case, s, t) == p[t] + activation(s, m.r_sr_up[t], m.r_sr_dn[t])))


def net_injection(m: pyo.Block, case, s: str, t: int):
    """Units' supply minus demand in scenario ``s`` (left side of Supply-Demand1) [MW].

    ``Σr (p_r + a_s(r↑_r, r↓_r)) + Σθ e_θ,s − Σd (p_d − a_s(r↑_d, r↓_d))``; ``m`` holds the
    unit blocks (the model, or one scenario block of :mod:`rvpp.settle.recourse`).
    """
    return sum(block.injection[s, t] for block in _unit_blocks(m, case, "injection"))


def _unit_blocks(m: pyo.Block, case, term: str) -> list[pyo.Block]:
    """The blocks of ``m``'s units that add ``term`` (``injection``, ``heat_supply``, ...) to the system."""
    blocks = (unit_block(m, kind, unit.name) for kind, unit in case.units())
    return [block for block in blocks if hasattr(block, term)]


def operating_cost(m: pyo.Block, case, dt: float):
    """``Σt Σr C_r·p_r·dt + Σt Σθ C_θ·(p_θ + h_θ)·dt`` over the unit blocks of ``m`` [EUR]."""
    return sum(block.cost for block in _unit_blocks(m, case, "cost"))


def add_heat_balance(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Heat balance ``Σθ h_θ + h_hpa = Σk h_k`` (Supply-Demand1_Heat) [MW_th]; in an intraday
    session, whose HPA purchase is fixed, the heat its units cannot supply, ``heat_short``, is
    added to the left (:mod:`rvpp.model.session`)."""
    case = problem.case
    supply, use = _unit_blocks(m, case, "heat_supply"), _unit_blocks(m, case, "heat_use")
    short = m.heat_short if hasattr(m, "heat_short") else {t: 0.0 for t in m.T}
    m.heat_balance = pyo.Constraint(m.T, rule=lambda m, t: (
        sum(b.heat_supply[t] for b in supply) + m.h_hpa[t] + short[t] == sum(b.heat_use[t] for b in use)))


def add_objective(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Maximise robust profit [EUR] (MILP-Obj; MODEL_SPEC §3).

    ``Σt [λda~·p_da + λup^·r_sr_up + λdn^·r_sr_dn]·dt − Σt λhpa·h_hpa·dt
    − Σt Σr C_r·p_r·dt − Σt Σθ C_θ·(p_θ + h_θ)·dt − protection_DA − protection_SRup − protection_SRdn
    + Σθ v_end,θ·(e_θ[NT] − e_init,θ)``; the last term, the value of the heat kept past
    midnight, is 0 unless the case gives its storage an ``end_value_eur_per_mwh_th``.
    """
    case, dt = problem.case, problem.dt_h
    da, up, dn = (problem.sources[n].nominal for n in PRICE_COLUMNS)
    hpa = problem.tariff_hpa
    m.revenue_dam = pyo.Expression(expr=sum(float(da[t - 1]) * m.p_da[t] * dt for t in m.T))
    m.revenue_sr = pyo.Expression(expr=sum(
        (float(up[t - 1]) * m.r_sr_up[t] + float(dn[t - 1]) * m.r_sr_dn[t]) * dt for t in m.T))
    m.cost_hpa = pyo.Expression(expr=sum(float(hpa[t - 1]) * m.h_hpa[t] * dt for t in m.T))
    m.cost_opex = pyo.Expression(expr=operating_cost(m, case, dt))
    m.value_heat_kept = pyo.Expression(expr=sum(m.csp[c.name].heat_kept_value for c in case.csp))
    m.profit = pyo.Objective(
        expr=m.revenue_dam + m.revenue_sr - m.cost_hpa - m.cost_opex - sum(m.protection[n] for n in PRICE_COLUMNS)
        + m.value_heat_kept,
        sense=pyo.maximize)
