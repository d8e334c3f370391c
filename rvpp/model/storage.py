"""Electrical storage: a battery (MODEL_SPEC §13).

One block per battery on the shared periods. Power in [MW], energy in [MWh]. The battery
offers up and down reserve from both modes, and the energy behind the reserve is held
back as the CSP's thermal storage does (σ-shares, MODEL_SPEC §8 TS9-TS11).
"""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.case import Battery
from ..uncertainty.problem import Problem
from ..data.scenarios import activation
from .units import reserve_cap


def add_battery(m: pyo.ConcreteModel, bat: Battery, problem: Problem) -> None:
    """A battery with mode exclusivity, self-discharge, reserve and a throughput cost (MODEL_SPEC §13).

    Mode binary ``charging`` (1 = charging): ``p_ch + r_ch↓ ≤ P̄ch·u``, ``r_ch↑ ≤ p_ch``,
    ``p_dis + r_dis↑ ≤ P̄dis·(1−u)``, ``r_dis↓ ≤ p_dis`` [MW]; ``r↑ = r_ch↑ + r_dis↑``,
    ``r↓ = r_ch↓ + r_dis↓``, each ``≤ min(T_sr·ramp, share·max(P̄ch, P̄dis))``.
    Energy [MWh] ``e[t] = (1 − ς·dt)·e[t−1] + η_ch·p_ch·dt − p_dis·dt/η_dis`` with
    ``e[0] ≡ e[NT]`` (cyclic day) or ``e[0] = e_init`` and ``e[NT] ≥ min(e_end_min, e_init)``
    (``e[NT] ≥ e_init`` without an end target ``e_end_min``, as the tank's, MODEL_SPEC §8).
    Reserve energy (TS9-TS11 form): ``Σ r↑·dt/η_dis ≤ σ↑·ΔE``, ``Σ r↓·η_ch·dt ≤ σ↓·ΔE``,
    ``Emin + σ↑·ΔE ≤ e ≤ Emax − σ↓·ΔE``, ``ΔE = Emax − Emin``. The mode binary stays: at a
    negative price a battery would otherwise charge and discharge at once to burn energy.
    Injection ``p_dis − p_ch + a_s(r↑, r↓)``; cost ``c_deg·Σ p_dis·dt`` [EUR].
    """
    b = m.battery[bat.name]
    dt = problem.dt_h
    srm = problem.case.markets.srm
    span = bat.e_max_mwh - bat.e_min_mwh
    cap = reserve_cap(problem, bat.ramp_mw_per_min, bat.reserve_share * max(bat.p_ch_max_mw, bat.p_dis_max_mw))
    keep = 1.0 - bat.self_discharge_per_h * dt
    b.charging = pyo.Var(m.T, domain=pyo.Binary)
    b.p_ch = pyo.Var(m.T, bounds=(0.0, bat.p_ch_max_mw))
    b.p_dis = pyo.Var(m.T, bounds=(0.0, bat.p_dis_max_mw))
    b.e = pyo.Var(m.T, bounds=(bat.e_min_mwh, bat.e_max_mwh))
    b.r_ch_up = pyo.Var(m.T, bounds=(0.0, bat.p_ch_max_mw if srm else 0.0))
    b.r_ch_dn = pyo.Var(m.T, bounds=(0.0, bat.p_ch_max_mw if srm else 0.0))
    b.r_dis_up = pyo.Var(m.T, bounds=(0.0, bat.p_dis_max_mw if srm else 0.0))
    b.r_dis_dn = pyo.Var(m.T, bounds=(0.0, bat.p_dis_max_mw if srm else 0.0))
    b.sigma_up = pyo.Var(bounds=(0.0, 1.0))
    b.sigma_dn = pyo.Var(bounds=(0.0, 1.0))
    b.charge_ceiling = pyo.Constraint(m.T, rule=lambda b, t: b.p_ch[t] + b.r_ch_dn[t] <= bat.p_ch_max_mw * b.charging[t])
    b.charge_up = pyo.Constraint(m.T, rule=lambda b, t: b.r_ch_up[t] <= b.p_ch[t])
    b.discharge_ceiling = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_dis[t] + b.r_dis_up[t] <= bat.p_dis_max_mw * (1 - b.charging[t])))
    b.discharge_dn = pyo.Constraint(m.T, rule=lambda b, t: b.r_dis_dn[t] <= b.p_dis[t])
    b.r_up = pyo.Expression(m.T, rule=lambda b, t: b.r_ch_up[t] + b.r_dis_up[t])
    b.r_dn = pyo.Expression(m.T, rule=lambda b, t: b.r_ch_dn[t] + b.r_dis_dn[t])
    b.reserve_up_cap = pyo.Constraint(m.T, rule=lambda b, t: b.r_up[t] <= cap)
    b.reserve_dn_cap = pyo.Constraint(m.T, rule=lambda b, t: b.r_dn[t] <= cap)

    def previous_energy(b, t):
        if not bat.cyclic and t == m.T.first():
            return bat.e_init_mwh
        return b.e[m.T.prevw(t)]

    b.energy_balance = pyo.Constraint(m.T, rule=lambda b, t: (
        b.e[t] == keep * previous_energy(b, t) + bat.eta_ch * b.p_ch[t] * dt - b.p_dis[t] * dt / bat.eta_dis))
    if not bat.cyclic:
        b.energy_end = pyo.Constraint(expr=b.e[m.T.last()] >= bat.end_floor_mwh)
    b.reserve_energy_up = pyo.Constraint(expr=sum(b.r_up[t] * dt / bat.eta_dis for t in m.T) <= b.sigma_up * span)
    b.reserve_energy_dn = pyo.Constraint(expr=sum(b.r_dn[t] * bat.eta_ch * dt for t in m.T) <= b.sigma_dn * span)
    b.margin_low = pyo.Constraint(m.T, rule=lambda b, t: b.e[t] >= bat.e_min_mwh + b.sigma_up * span)
    b.margin_high = pyo.Constraint(m.T, rule=lambda b, t: b.e[t] <= bat.e_max_mwh - b.sigma_dn * span)
    b.injection = pyo.Expression(m.S, m.T, rule=lambda b, s, t: (
        b.p_dis[t] - b.p_ch[t] + activation(s, b.r_up[t], b.r_dn[t])))
    b.cost = pyo.Expression(expr=sum(bat.degradation_eur_per_mwh * b.p_dis[t] * dt for t in m.T))
