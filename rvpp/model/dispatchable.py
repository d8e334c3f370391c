"""Dispatchable renewable units: hydro and biomass plants (MODEL_SPEC §13).

One block per unit on the shared periods, with commitment as the CSP turbine's (§8):
binary ``online``, ``startup`` and ``shutdown`` (continuous, whole wherever ``online`` is:
:func:`~rvpp.model.csp.add_commitment`), minimum up and down times carried over from the
day before. Power in [MW], energy in [MWh], costs in [EUR].
"""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.case import DispatchableUnit
from ..uncertainty.problem import Problem
from .csp import add_commitment
from ..data.scenarios import activation
from .units import reserve_cap


def add_dispatchable(m: pyo.ConcreteModel, unit: DispatchableUnit, problem: Problem) -> None:
    """A hydro or biomass unit (MODEL_SPEC §13).

    ``Pmin·u ≤ p − r↓``, ``p + r↑ ≤ Pmax·u``, ``r↑, r↓ ≤ min(T_sr·ramp, share·Pmax)``.
    Ramps hold in every activation scenario, so against the worst pair of neighbours:
    ``(p[t] + r↑[t]) − (p[t−1] − r↓[t−1]) ≤ RU·dt·u[t−1] + SU·dt·v_su[t]`` and
    ``(p[t−1] + r↑[t−1]) − (p[t] − r↓[t]) ≤ RD·dt·u[t] + SD·dt·v_sd[t]`` (an unset ramp is
    ``Pmax`` per period); the first period ramps from ``p_init`` when it is given.
    The day's water or fuel holds even if all up reserve is called: ``Σ (p + r↑)·dt ≤ Emax``.
    Injection ``p + a_s(r↑, r↓)``; cost ``c·Σ p·dt + c_su·Σ v_su + c_sd·Σ v_sd``.
    """
    b = getattr(m, "dispatchable")[unit.name]
    dt = problem.dt_h
    cap = reserve_cap(problem, unit.ramp_mw_per_min, unit.reserve_share * unit.p_max_mw)
    add_commitment(m, b, unit.min_up_h, unit.min_down_h, unit.initial_online, unit.initial_periods(dt), problem,
                   continuous_transitions=True)
    b.p = pyo.Var(m.T, bounds=(0.0, unit.p_max_mw))
    b.r_up = pyo.Var(m.T, bounds=(0.0, cap))
    b.r_dn = pyo.Var(m.T, bounds=(0.0, cap))
    b.floor = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] - b.r_dn[t] >= unit.p_min_mw * b.online[t])
    b.ceiling = pyo.Constraint(m.T, rule=lambda b, t: b.p[t] + b.r_up[t] <= unit.p_max_mw * b.online[t])

    def per_period(ramp: float | None) -> float:
        return unit.p_max_mw if ramp is None else min(ramp * dt, unit.p_max_mw)

    ru, rd = per_period(unit.ramp_up_mw_per_h), per_period(unit.ramp_dn_mw_per_h)
    su, sd = per_period(unit.startup_ramp_mw_per_h), per_period(unit.shutdown_ramp_mw_per_h)
    first = m.T.first()
    initial = 1.0 if unit.initial_online else 0.0
    ramped = [t for t in m.T if t != first or unit.p_init_mw is not None]

    def before(b, t):
        """Output low and high, and status, in the period before ``t``."""
        if t == first:
            return unit.p_init_mw, unit.p_init_mw, initial
        k = m.T.prev(t)
        return b.p[k] - b.r_dn[k], b.p[k] + b.r_up[k], b.online[k]

    b.ramp_up = pyo.Constraint(ramped, rule=lambda b, t: (
        b.p[t] + b.r_up[t] - before(b, t)[0] <= ru * before(b, t)[2] + su * b.startup[t]))
    b.ramp_dn = pyo.Constraint(ramped, rule=lambda b, t: (
        before(b, t)[1] - (b.p[t] - b.r_dn[t]) <= rd * b.online[t] + sd * b.shutdown[t]))
    if unit.energy_max_mwh is not None:
        b.energy = pyo.Constraint(expr=sum((b.p[t] + b.r_up[t]) * dt for t in m.T) <= unit.energy_max_mwh)
    b.injection = pyo.Expression(m.S, m.T, rule=lambda b, s, t: b.p[t] + activation(s, b.r_up[t], b.r_dn[t]))
    b.cost = pyo.Expression(expr=sum(unit.marginal_cost_eur_per_mwh * b.p[t] * dt
                                     + unit.startup_cost_eur * b.startup[t] + unit.shutdown_cost_eur * b.shutdown[t]
                                     for t in m.T))
