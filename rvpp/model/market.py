"""Market bids, RVPP-level limits, system balances and the objective (MODEL_SPEC §2-§3, §7)."""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.history import PRICE_COLUMNS
from ..uncertainty.problem import Problem

SCENARIOS = ("none", "up", "dn")


def activation(s: str, up, dn):
    """Reserve deployed in activation scenario ``s``: ``+up``, ``-dn`` or 0 (paper's vectors)."""
    if s == "up":
        return up
    if s == "dn":
        return -dn
    return 0.0


def add_time(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Periods ``T = 1..NT`` and activation scenarios ``S`` (only ``none`` without the SRM)."""
    m.T = pyo.RangeSet(1, problem.nt)
    scenarios = SCENARIOS if problem.case.markets.srm else ("none",)
    m.S = pyo.Set(initialize=scenarios, ordered=True)


def capacities(problem: Problem) -> tuple[float, float, float]:
    """Generation nameplate ``ΣPmax_r + ΣPmax_θ``, demand nameplate ``ΣPmax_d`` and the
    reserve cap ``κ·max(0, generation − demand)`` [MW] (Power-Traded1..4)."""
    case = problem.case
    generation = sum(u.p_max_mw for u in case.ndres) + sum(c.p_max_mw for c in case.csp)
    demand = sum(d.p_max_mw for d in case.ed)
    return generation, demand, case.markets.kappa * max(0.0, generation - demand)


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


def add_market_limits(m: pyo.ConcreteModel, problem: Problem) -> None:
    """RVPP trading limits (Power-Traded1-2) [MW].

    ``p_da + r_sr_up ≤ ΣPmax_r + ΣPmax_θ`` and ``−ΣPmax_d ≤ p_da − r_sr_dn``.
    """
    generation, demand, _ = capacities(problem)
    m.trade_upper = pyo.Constraint(m.T, rule=lambda m, t: m.p_da[t] + m.r_sr_up[t] <= generation)
    m.trade_lower = pyo.Constraint(m.T, rule=lambda m, t: m.p_da[t] - m.r_sr_dn[t] >= -demand)


def add_electric_balance(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Electrical balance in every activation scenario (Supply-Demand1; MODEL_SPEC §7) [MW].

    ``Σr (p_r + a_s(r↑_r, r↓_r)) + Σθ e_θ,s − Σd (p_d − a_s(r↑_d, r↓_d)) = p_da + a_s(r↑_SR, r↓_SR)``
    """
    case = problem.case
    m.electric_balance = pyo.Constraint(m.S, m.T, rule=lambda m, s, t: (
        net_injection(m, case, s, t) == m.p_da[t] + activation(s, m.r_sr_up[t], m.r_sr_dn[t])))


def net_injection(m: pyo.Block, case, s: str, t: int):
    """Units' supply minus demand in scenario ``s`` (left side of Supply-Demand1) [MW].

    ``Σr (p_r + a_s(r↑_r, r↓_r)) + Σθ e_θ,s − Σd (p_d − a_s(r↑_d, r↓_d))``; ``m`` holds the
    unit blocks (the model, or one scenario block of :mod:`rvpp.settle.recourse`).
    """
    supply = sum(m.ndres[u.name].p[t] + activation(s, m.ndres[u.name].r_up[t], m.ndres[u.name].r_dn[t])
                 for u in case.ndres)
    supply += sum(m.csp[c.name].e[s, t] for c in case.csp)
    demand = sum(m.ed[d.name].p[t] - activation(s, m.ed[d.name].r_up[t], m.ed[d.name].r_dn[t])
                 for d in case.ed)
    return supply - demand


def operating_cost(m: pyo.Block, case, dt: float):
    """``Σt Σr C_r·p_r·dt + Σt Σθ C_θ·(p_θ + h_θ)·dt`` over the unit blocks of ``m`` [EUR]."""
    return sum(u.om_eur_per_mwh * m.ndres[u.name].p[t] * dt for u in case.ndres for t in m.T) + sum(
        c.om_eur_per_mwh * (m.csp[c.name].e["none", t] + m.csp[c.name].h[t]) * dt
        for c in case.csp for t in m.T)


def add_heat_balance(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Heat balance ``Σθ h_θ + h_hpa = Σk h_k`` (Supply-Demand1_Heat) [MW_th]."""
    case = problem.case
    m.heat_balance = pyo.Constraint(m.T, rule=lambda m, t: (
        sum(m.csp[c.name].h[t] for c in case.csp) + m.h_hpa[t] == sum(m.td[k.name].h[t] for k in case.td)))


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
