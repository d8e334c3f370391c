"""Non-dispatchable renewables and demands (MODEL_SPEC §9; paper NDRES, Demand).

Each unit is a Pyomo block on the shared periods ``m.T`` with an Expression ``bound[t]``:
the available power of an ND-RES or the required consumption of a demand. It starts
at the nominal forecast; :mod:`rvpp.model.robust` moves it by the budgeted deviation.

Every unit block states what it adds to the system (docs/architecture.md): ``injection[s, t]``
[MW] into the electrical balance in activation scenario ``s``, ``heat_supply[t]`` or
``heat_use[t]`` [MW_th] in the heat balance, and ``cost`` [EUR] in the objective; a block
without one of them adds nothing there.
"""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.case import ElectricalDemand, NdresUnit, ThermalDemand
from ..uncertainty.problem import Problem
from ..data.scenarios import activation


def reserve_cap(problem: Problem, ramp_mw_per_min: float, share_cap_mw: float = float("inf")) -> float:
    """Largest reserve band a unit may offer [MW]: ``min(T_sr·ramp, share·Pmax)``; 0 without SRM."""
    markets = problem.case.markets
    if not markets.srm:
        return 0.0
    return min(markets.reserve_duration_min * ramp_mw_per_min, share_cap_mw)


def add_ndres(m: pyo.ConcreteModel, unit: NdresUnit, problem: Problem) -> None:
    """Wind farm or PV plant (NDRES1-4, MILP-NDRES1) [MW].

    ``p + r↑ ≤ P̂ − y`` (available power), ``Pmin ≤ p − r↓``,
    ``r↑ ≤ min(T_sr·R↑, share·Pmax)``, ``r↓ ≤ min(T_sr·R↓, share·Pmax)``.
    """
    b = m.ndres[unit.name]
    nominal = problem.sources[unit.name].nominal
    share = unit.reserve_share * unit.p_max_mw
    b.p = pyo.Var(m.T, bounds=(0.0, unit.p_max_mw))
    b.r_up = pyo.Var(m.T, bounds=(0.0, reserve_cap(problem, unit.ramp_up_mw_per_min, share)))
    b.r_dn = pyo.Var(m.T, bounds=(0.0, reserve_cap(problem, unit.ramp_dn_mw_per_min, share)))
    b.bound = pyo.Expression(m.T, rule=lambda b, t: float(nominal[t - 1]))
    b.available = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] + b.r_up[t] <= b.bound[t])
    b.minimum = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] - b.r_dn[t] >= unit.p_min_mw)
    b.injection = pyo.Expression(m.S, m.T, rule=lambda b, s, t: b.p[t] + activation(s, b.r_up[t], b.r_dn[t]))
    b.cost = pyo.Expression(expr=sum(unit.om_eur_per_mwh * b.p[t] * problem.dt_h for t in m.T))


def add_electrical_demand(m: pyo.ConcreteModel, ed: ElectricalDemand, problem: Problem) -> None:
    """Flexible electrical demand (Demand1-Demand8, MILP-Demand1) [MW], [MWh].

    ``p ≥ P̌ + y`` (required consumption), ``Pmin ≤ p − r↑``, ``p + r↓ ≤ Pmax``,
    ``r↑ ≤ β↑·p``, ``r↓ ≤ β↓·p``, ``r ≤ T_sr·ramp``, ``Emin ≤ Σt (p − r↑)·dt``.
    Up reserve is a consumption decrease.

    The authors' tool's conventions, each off by default (docs/gams-tool.md D23-D26):
    ``profile_window``: ``(1 − β↑)·P̌ + y ≤ p − r↑`` and ``p + r↓ ≤ (1 + β↓)·P̌ + y`` in place of
    ``p ≥ P̌ + y``, and ``r↑ ≤ β↑·P̌``, ``r↓ ≤ β↓·P̌`` (``P̌`` the nominal profile);
    ``ramp_up/dn_mw_per_h``: ``(p_t + r↓_t) − (p_t−1 − r↑_t−1) ≤ RU·dt`` and
    ``(p_t−1 + r↓_t−1) − (p_t − r↑_t) ≤ RD·dt``, the first period from ``p_init_mw`` (no bands
    before the day; no limit on it without ``p_init_mw``);
    ``energy_net_of_up_band: false``: ``Emin ≤ Σt p·dt``.
    """
    b = m.ed[ed.name]
    dt = problem.dt_h
    nominal = problem.sources[ed.name].nominal
    b.p = pyo.Var(m.T, bounds=(ed.p_min_mw, ed.p_max_mw))
    b.r_up = pyo.Var(m.T, bounds=(0.0, reserve_cap(problem, ed.ramp_up_mw_per_min)))
    b.r_dn = pyo.Var(m.T, bounds=(0.0, reserve_cap(problem, ed.ramp_dn_mw_per_min)))
    b.bound = pyo.Expression(m.T, rule=lambda b, t: float(nominal[t - 1]))
    # in the order they always had: a case without the options gives the solver the same model
    if ed.profile_window:  # bound = P̌ + y
        room_up, room_dn = ed.flex_up * nominal, ed.flex_dn * nominal
        b.window_low = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] - b.r_up[t] >= b.bound[t] - float(room_up[t - 1]))
        b.window_high = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] + b.r_dn[t] <= b.bound[t] + float(room_dn[t - 1]))
    else:
        b.required = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] >= b.bound[t])
    b.floor = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] - b.r_up[t] >= ed.p_min_mw)
    b.ceiling = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] + b.r_dn[t] <= ed.p_max_mw)
    if ed.profile_window:
        b.flex_up = pyo.Constraint(m.T, rule=lambda b, t: b.r_up[t] <= float(room_up[t - 1]))
        b.flex_dn = pyo.Constraint(m.T, rule=lambda b, t: b.r_dn[t] <= float(room_dn[t - 1]))
    else:
        b.flex_up = pyo.Constraint(m.T, rule=lambda b, t: b.r_up[t] <= ed.flex_up * b.p[t])
        b.flex_dn = pyo.Constraint(m.T, rule=lambda b, t: b.r_dn[t] <= ed.flex_dn * b.p[t])
    _add_demand_ramps(m, b, ed, dt)
    net = ed.energy_net_of_up_band
    b.energy = pyo.Constraint(expr=sum((b.p[t] - (b.r_up[t] if net else 0.0)) * dt for t in m.T) >= ed.e_min_mwh)
    b.injection = pyo.Expression(m.S, m.T, rule=lambda b, s, t: -(b.p[t] - activation(s, b.r_up[t], b.r_dn[t])))


def _add_demand_ramps(m: pyo.ConcreteModel, b: pyo.Block, ed: ElectricalDemand, dt: float) -> None:
    """The tool's ramps between periods (eDem_ramp_up, eDem_ramp_down): the highest consumption of a
    period against the lowest of the one before, and the reverse; the first from ``p_init_mw``."""
    first = m.T.first()

    def highest_before(b, t):
        return ed.p_init_mw if t == first else b.p[t - 1] + b.r_dn[t - 1]

    def lowest_before(b, t):
        return ed.p_init_mw if t == first else b.p[t - 1] - b.r_up[t - 1]

    def step(limit, rise):
        def rule(b, t):
            if t == first and ed.p_init_mw is None:
                return pyo.Constraint.Skip
            return rise(b, t) <= limit * dt
        return rule

    if ed.ramp_up_mw_per_h is not None:
        b.ramp_up = pyo.Constraint(m.T, rule=step(ed.ramp_up_mw_per_h,
                                                  lambda b, t: b.p[t] + b.r_dn[t] - lowest_before(b, t)))
    if ed.ramp_dn_mw_per_h is not None:
        b.ramp_dn = pyo.Constraint(m.T, rule=step(ed.ramp_dn_mw_per_h,
                                                  lambda b, t: highest_before(b, t) - (b.p[t] - b.r_up[t])))


def add_thermal_demand(m: pyo.ConcreteModel, td: ThermalDemand, problem: Problem) -> None:
    """Thermal demand (Demand_Heat1-3, MILP-Demand_Heat1) [MW_th], [MWh_th].

    ``h ≥ Ȟ + y`` (required heat), ``Hmin ≤ h ≤ Hmax``, ``Qmin ≤ Σt h·dt``.
    """
    b = m.td[td.name]
    dt = problem.dt_h
    nominal = problem.sources[td.name].nominal
    b.h = pyo.Var(m.T, bounds=(td.h_min_mw_th, td.h_max_mw_th))
    b.bound = pyo.Expression(m.T, rule=lambda b, t: float(nominal[t - 1]))
    b.required = pyo.Constraint(m.T, rule=lambda b, t: b.h[t] >= b.bound[t])
    b.energy = pyo.Constraint(expr=sum(b.h[t] * dt for t in m.T) >= td.q_min_mwh_th)
    b.heat_use = pyo.Expression(m.T, rule=lambda b, t: b.h[t])
