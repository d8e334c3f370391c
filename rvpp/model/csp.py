"""Concentrated solar power plant (MODEL_SPEC §8; paper STU, STU_SOS, TS, Appendix A).

One block per CSP on the shared periods. Thermal flows are in [MW_th], stored energy
in [MWh_th], electrical output in [MW]. The electrical output ``e[s,t]`` exists for
every activation scenario ``s``; ``p_θ = e[none]``, ``r↑_θ = e[up] − e[none]`` and
``r↓_θ = e[none] − e[dn]``.
"""

from __future__ import annotations

import numpy as np
import pyomo.environ as pyo

from ..data.case import CSP
from ..uncertainty.problem import Problem
from .robust import surely_deviating
from ..data.scenarios import Scenario, activation
from .curve import on_curve
from .piecewise import add_convex_combination, add_incremental
from .units import reserve_cap

NONE, UP, DN = Scenario.NONE, Scenario.UP, Scenario.DN


def add_csp_solar_field(m: pyo.ConcreteModel, csp: CSP, problem: Problem) -> None:
    """Solar-field thermal power ``0 ≤ p_sf ≤ P̂sf − y`` (STU1, MILP-STU1) [MW_th]."""
    b = m.csp[csp.name]
    nominal = problem.sources[csp.name].nominal
    b.p_sf = pyo.Var(m.T, bounds=(0.0, csp.solar_field.p_max_mw_th))
    b.bound = pyo.Expression(m.T, rule=lambda b, t: float(nominal[t - 1]))
    b.sf_available = pyo.Constraint(m.T, rule=lambda b, t: b.p_sf[t] <= b.bound[t])


def add_csp_storage(m: pyo.ConcreteModel, csp: CSP, problem: Problem) -> None:
    """Two-tank thermal storage with reserve margins (TS1-TS11; MODEL_SPEC §8).

    Mode binary ``charging`` (1 = charging). Power limits with reserves (TS1-TS4):
    ``P̲ch·u ≤ p_ch − r_ch↑``, ``p_ch + r_ch↓ ≤ P̄ch·u``, ``p_dis + r_dis↑ ≤ P̄dis·(1−u)``,
    ``P̲dis·(1−u) ≤ p_dis − r_dis↓``; ``r_ts↑ = r_ch↑ + r_dis↑``, ``r_ts↓ = r_ch↓ + r_dis↓``
    (TS5-TS6). Energy ``e[t] = e[t−1] + η_ch·p_ch·dt − p_dis·dt/η_dis`` for every ``t``
    with ``e[0] ≡ e[NT]`` (cyclic day; MODEL_SPEC corrects TS7-TS8), or from a fixed
    ``e_init`` with ``e[NT] ≥ min(e_end_min, e_init)`` (``e[NT] ≥ e_init`` without an end
    target ``e_end_min``). Reserve energy shares (TS9-TS10)
    ``Σ r_ts↑·dt/η_dis ≤ σ↑·ΔE``, ``Σ r_ts↓·η_ch·dt ≤ σ↓·ΔE`` and margins (TS11, corrected)
    ``Emin + σ↑·ΔE ≤ e ≤ Emax − σ↓·ΔE``, ``ΔE = Emax − Emin``. The authors' tool's conventions
    (off by default): each band ``≤ reserve_band_max_mw_th``; ``Σ r·dt/η ≤ k·σ·ΔE`` with
    ``k = reserve_energy_factor``; ``σ ≤ reserve_share_max``. From a fixed ``e_init`` the
    heat kept past midnight is worth ``heat_kept_value = v_end·(e[NT] − e_init)`` [EUR], with
    ``v_end`` = ``end_value_eur_per_mwh_th`` (0 by default, the paper's day).

    Valid tightening: the storage charges only from the solar field (while charging
    it does not discharge and the power block takes no negative input), so
    ``p_ch ≤ min(P̄ch, P̂sf)·u``, where ``P̂sf`` is the field's highest robust
    availability (the nominal value, less the deviation in the periods that surely
    deviate). In periods without sun charging mode can only idle, so the mode is fixed
    to discharging there whenever discharging mode can idle too (``P̲dis = 0``) or
    charging mode cannot (``P̲ch > 0``).

    From a fixed initial level the reserve shares are bounded by what the first period
    can reach (:func:`reserve_share_limits`); a tank that starts empty can hold no up
    reserve (``σ↑ = 0``), so its reserve variables are bounded to zero.
    """
    b = m.csp[csp.name]
    ts, dt = csp.storage, problem.dt_h
    srm = problem.case.markets.srm
    span = ts.e_max_mwh_th - ts.e_min_mwh_th
    b.charging = pyo.Var(m.T, domain=pyo.Binary)
    b.p_ch = pyo.Var(m.T, bounds=(0.0, ts.p_ch_max_mw_th))
    b.p_dis = pyo.Var(m.T, bounds=(0.0, ts.p_dis_max_mw_th))
    b.e_ts = pyo.Var(m.T, bounds=(ts.e_min_mwh_th, ts.e_max_mwh_th))
    band = float("inf") if ts.reserve_band_max_mw_th is None else ts.reserve_band_max_mw_th
    ch_band, dis_band = (min(cap, band) if srm else 0.0 for cap in (ts.p_ch_max_mw_th, ts.p_dis_max_mw_th))
    b.r_ch_up = pyo.Var(m.T, bounds=(0.0, ch_band))
    b.r_ch_dn = pyo.Var(m.T, bounds=(0.0, ch_band))
    b.r_dis_up = pyo.Var(m.T, bounds=(0.0, dis_band))
    b.r_dis_dn = pyo.Var(m.T, bounds=(0.0, dis_band))
    source = problem.sources[csp.name]
    field = np.maximum(source.nominal - np.where(surely_deviating(problem, csp.name), source.deviation, 0.0), 0.0)
    sigma_up_max, sigma_dn_max = (min(limit, ts.reserve_share_max)
                                  for limit in reserve_share_limits(ts, float(field[0]), dt))
    b.sigma_up = pyo.Var(bounds=(0.0, sigma_up_max))
    b.sigma_dn = pyo.Var(bounds=(0.0, sigma_dn_max))
    for t in m.T:
        if sigma_up_max == 0.0:
            b.r_ch_up[t].setub(0.0)
            b.r_dis_up[t].setub(0.0)
        if sigma_dn_max == 0.0:
            b.r_ch_dn[t].setub(0.0)
            b.r_dis_dn[t].setub(0.0)
    idle_when_discharging = ts.p_dis_min_mw_th == 0.0 or ts.p_ch_min_mw_th > 0.0
    for t in m.T:
        if field[t - 1] <= 0.0 and idle_when_discharging:
            b.charging[t].fix(0)
    b.charge_from_field = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_ch[t] <= min(ts.p_ch_max_mw_th, float(field[t - 1])) * b.charging[t]))
    b.charge_floor = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_ch[t] - b.r_ch_up[t] >= ts.p_ch_min_mw_th * b.charging[t]))
    b.charge_ceiling = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_ch[t] + b.r_ch_dn[t] <= ts.p_ch_max_mw_th * b.charging[t]))
    b.discharge_ceiling = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_dis[t] + b.r_dis_up[t] <= ts.p_dis_max_mw_th * (1 - b.charging[t])))
    b.discharge_floor = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_dis[t] - b.r_dis_dn[t] >= ts.p_dis_min_mw_th * (1 - b.charging[t])))
    b.r_ts_up = pyo.Expression(m.T, rule=lambda b, t: b.r_ch_up[t] + b.r_dis_up[t])
    b.r_ts_dn = pyo.Expression(m.T, rule=lambda b, t: b.r_ch_dn[t] + b.r_dis_dn[t])

    def previous_energy(b, t):
        if not ts.cyclic and t == m.T.first():
            return ts.e_init_mwh_th
        return b.e_ts[m.T.prevw(t)]

    b.energy_balance = pyo.Constraint(m.T, rule=lambda b, t: (
        b.e_ts[t] == previous_energy(b, t) + ts.eta_ch * b.p_ch[t] * dt - b.p_dis[t] * dt / ts.eta_dis))
    if not ts.cyclic:
        b.energy_end = pyo.Constraint(expr=b.e_ts[m.T.last()] >= ts.end_floor_mwh_th)
    kept = not ts.cyclic and ts.end_value_eur_per_mwh_th > 0.0
    b.heat_kept_value = pyo.Expression(
        expr=ts.end_value_eur_per_mwh_th * (b.e_ts[m.T.last()] - ts.e_init_mwh_th) if kept else 0.0)
    held = ts.reserve_energy_factor * span  # the energy behind the bands per unit of σ [MWh_th]
    b.reserve_energy_up = pyo.Constraint(expr=sum(b.r_ts_up[t] * dt / ts.eta_dis for t in m.T)
                                         <= b.sigma_up * held)
    b.reserve_energy_dn = pyo.Constraint(expr=sum(b.r_ts_dn[t] * ts.eta_ch * dt for t in m.T)
                                         <= b.sigma_dn * held)
    b.margin_low = pyo.Constraint(m.T, rule=lambda b, t: b.e_ts[t] >= ts.e_min_mwh_th + b.sigma_up * span)
    b.margin_high = pyo.Constraint(m.T, rule=lambda b, t: b.e_ts[t] <= ts.e_max_mwh_th - b.sigma_dn * span)


def reserve_share_limits(ts, field_first_mw_th: float, dt_h: float) -> tuple[float, float]:
    """Upper bounds of the reserve shares ``(σ↑, σ↓)`` implied by a fixed initial level [-].

    After the first period the level lies within ``e_init − P̄dis·dt/η_dis ≤ e[1] ≤
    e_init + η_ch·min(P̄ch, P̂sf[1])·dt`` (the tank charges only from the field), and
    the margins (TS11) ``Emin + σ↑·ΔE ≤ e[1] ≤ Emax − σ↓·ΔE`` then give
    ``σ↑ ≤ (e_init + η_ch·min(P̄ch, P̂sf[1])·dt − Emin)/ΔE`` and
    ``σ↓ ≤ (Emax − e_init + P̄dis·dt/η_dis)/ΔE``, clipped to [0, 1]. ``P̂sf[1]`` is the
    field's highest robust availability in the first period [MW_th]. A cyclic day has
    no fixed level: (1, 1).
    """
    if ts.cyclic:
        return 1.0, 1.0
    span = ts.e_max_mwh_th - ts.e_min_mwh_th
    highest = ts.e_init_mwh_th + ts.eta_ch * min(ts.p_ch_max_mw_th, field_first_mw_th) * dt_h
    lowest = ts.e_init_mwh_th - ts.p_dis_max_mw_th * dt_h / ts.eta_dis
    return (min(1.0, max(0.0, (highest - ts.e_min_mwh_th) / span)),
            min(1.0, max(0.0, (ts.e_max_mwh_th - lowest) / span)))


def add_csp_commitment(m: pyo.ConcreteModel, csp: CSP, problem: Problem) -> None:
    """Turbine commitment with minimum up and down times (Appendix A, STU10-STU17): :func:`add_commitment`."""
    pb = csp.power_block
    add_commitment(m, m.csp[csp.name], pb.min_up_h, pb.min_down_h, pb.initially_on,
                   pb.initial_periods(problem.dt_h), problem)


def add_commitment(m: pyo.ConcreteModel, b: pyo.Block, min_up_h: float, min_down_h: float, initially_on: bool,
                   initial_periods: tuple[int, int], problem: Problem, continuous_transitions: bool = False) -> None:
    """Binaries ``online``, ``startup``, ``shutdown`` on block ``b`` with minimum up and down times
    (Appendix A, STU10-STU17; also the hydro and biomass units of MODEL_SPEC §13).

    ``u[t] − u[t−1] = v_su[t] − v_sd[t]``, ``v_su + v_sd ≤ 1``, and in the equivalent
    tight form of Rajan and Takriti (2005): ``Σ_{τ=t−UT+1..t} v_su[τ] ≤ u[t]``,
    ``Σ_{τ=t−DT+1..t} v_sd[τ] ≤ 1 − u[t]``. ``u[0]`` is the initial status. A minimum
    time begun before the day carries over (STU12, STU15): ``u[t] = u[0]`` for the first
    ``initial_periods = (N_on, N_off)`` periods that complete it.

    ``continuous_transitions``: ``v_su, v_sd ∈ [0, 1]`` continuous, with windows of at least one
    period (``UT, DT ≥ 1``, the same limit) and without ``v_su + v_sd ≤ 1``. Both are whole
    wherever ``u`` is: with ``u[t] = u[t−1]`` the windows give ``v_su[t] ≤ u[t]`` and
    ``v_sd[t] ≤ 1 − u[t]``, one of them 0, so the transition row makes both 0; with
    ``u[t] ≠ u[t−1]`` the transition row and the bounds leave ``v_su = 1, v_sd = 0`` for a
    start and the reverse for a stop. The optimum is that of the binary form, with fewer binaries to search.
    """
    up_periods = problem.periods_for_hours(min_up_h)
    down_periods = problem.periods_for_hours(min_down_h)
    if continuous_transitions:
        up_periods, down_periods = max(1, up_periods), max(1, down_periods)
    initial = 1.0 if initially_on else 0.0
    b.online = pyo.Var(m.T, domain=pyo.Binary)
    transition = pyo.UnitInterval if continuous_transitions else pyo.Binary
    b.startup = pyo.Var(m.T, domain=transition)
    b.shutdown = pyo.Var(m.T, domain=transition)

    def previous(b, t):
        return initial if t == m.T.first() else b.online[m.T.prev(t)]

    b.transition = pyo.Constraint(m.T, rule=lambda b, t: (
        b.online[t] - previous(b, t) == b.startup[t] - b.shutdown[t]))
    if not continuous_transitions:
        b.one_transition = pyo.Constraint(m.T, rule=lambda b, t: b.startup[t] + b.shutdown[t] <= 1)
    b.min_up = pyo.Constraint(m.T, rule=lambda b, t: (
        sum(b.startup[k] for k in _window(m, t, up_periods)) <= b.online[t]))
    b.min_down = pyo.Constraint(m.T, rule=lambda b, t: (
        sum(b.shutdown[k] for k in _window(m, t, down_periods)) <= 1 - b.online[t]))
    n_on, n_off = initial_periods
    held = list(m.T)[:n_on + n_off]
    b.initial_status_held = pyo.Constraint(held, rule=lambda b, t: b.online[t] == initial)


def _window(m: pyo.ConcreteModel, t: int, length: int) -> list[int]:
    """The ``length`` periods ending at ``t`` that lie inside the day."""
    return [k for k in range(max(m.T.first(), t - length + 1), t + 1)]


def add_csp_power_block(m: pyo.ConcreteModel, csp: CSP, problem: Problem) -> None:
    """Power-block heat balance, limits and conversion curve (STU2-STU5, STU_SOS).

    Thermal input (STU2) ``p_pb = p_sf − h/η_heat + p_dis − p_ch − K_su·P̄pb·Σ v_su``
    where a start draws ``K_su·P̄pb`` in its start-up period (or for ``startup_duration_h``);
    limits (STU3-STU4) ``p_pb + r_ts↑ ≤ P̄pb·u``, ``P̲pb·u ≤ p_pb − r_ts↓``; in every scenario
    the input ``x_s = p_pb + a_s(r_ts↑, r_ts↓)`` gives output ``e_s = f(x_s)`` on the
    breakpoint curve, capped by the turbine nameplate ``e_s ≤ Pmax_θ·u`` (with ``output_capped:
    false``, the authors' tool's convention, by the curve's own highest output).
    """
    b = m.csp[csp.name]
    pb = csp.power_block
    startup_periods = pb.startup_periods(problem.dt_h)
    startup_heat = pb.startup_fraction * pb.p_in_max_mw_th
    b.h = pyo.Var(m.T, domain=pyo.NonNegativeReals)
    b.p_pb = pyo.Var(m.T, bounds=(0.0, pb.p_in_max_mw_th))
    curve = on_curve(pb)
    top = pb.p_el_max_mw if pb.output_capped else float(curve.outputs.max())  # the turbine's or the curve's
    b.e = pyo.Var(m.S, m.T, bounds=(0.0, top))

    b.heat_split = pyo.Constraint(m.T, rule=lambda b, t: b.p_pb[t] == (
        b.p_sf[t] - b.h[t] / csp.heat_efficiency + b.p_dis[t] - b.p_ch[t]
        - startup_heat * sum(b.startup[k] for k in _window(m, t, startup_periods))))
    b.input_ceiling = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_pb[t] + b.r_ts_up[t] <= pb.p_in_max_mw_th * b.online[t]))
    b.input_floor = pyo.Constraint(m.T, rule=lambda b, t: (
        b.p_pb[t] - b.r_ts_dn[t] >= pb.p_in_min_mw_th * b.online[t]))
    b.x = pyo.Expression(m.S, m.T, rule=lambda b, s, t: b.p_pb[t] + activation(s, b.r_ts_up[t], b.r_ts_dn[t]))
    b.injection = pyo.Expression(m.S, m.T, rule=lambda b, s, t: b.e[s, t])
    b.heat_supply = pyo.Expression(m.T, rule=lambda b, t: b.h[t])
    b.cost = pyo.Expression(expr=sum(csp.om_eur_per_mwh * (b.e[NONE, t] + b.h[t]) * problem.dt_h for t in m.T))
    b.turbine_cap = pyo.Constraint(m.S, m.T, rule=lambda b, s, t: b.e[s, t] <= top * b.online[t])

    index = [(s, t) for s in m.S for t in m.T]
    if problem.case.solver.pwl_encoding == "incremental":
        add_incremental(b, "pb", index, b.x, b.e, b.online, curve)
        if len(m.S) > 1:
            _order_fill(m, b, len(curve.lengths) - 1)
    else:
        add_convex_combination(b, "pb", index, b.x, b.e, b.online, curve)
    if len(m.S) > 1:
        _reserve_slopes(m, b, curve)


def _order_fill(m: pyo.ConcreteModel, b, n_fill: int) -> None:
    """Valid inequalities: inputs are ordered ``x_dn ≤ x_none ≤ x_up``, so are the fill binaries.

    Where the storage can hold no reserve in one direction (its share is bounded to 0,
    :func:`reserve_share_limits`), that scenario's input equals the nominal one and its
    fill binaries are taken equal to the nominal ones (at a knot either value fits).
    """
    fills = range(n_fill)
    fixed_up, fixed_dn = b.sigma_up.ub == 0.0, b.sigma_dn.ub == 0.0
    b.pb_fill_order_up = pyo.Constraint(m.T, fills, rule=lambda b, t, k: (
        b.pb_fill[NONE, t, k] == b.pb_fill[UP, t, k] if fixed_up
        else b.pb_fill[NONE, t, k] <= b.pb_fill[UP, t, k]))
    b.pb_fill_order_dn = pyo.Constraint(m.T, fills, rule=lambda b, t, k: (
        b.pb_fill[DN, t, k] == b.pb_fill[NONE, t, k] if fixed_dn
        else b.pb_fill[DN, t, k] <= b.pb_fill[NONE, t, k]))


def _reserve_slopes(m: pyo.ConcreteModel, b, curve) -> None:
    """Valid inequalities: between two inputs on the curve the output changes at a rate
    between the curve's smallest and largest slope [MW per MW_th], so
    ``s̲·r_ts↑ ≤ e_up − e_none ≤ s̄·r_ts↑`` and ``s̲·r_ts↓ ≤ e_none − e_dn ≤ s̄·r_ts↓``
    (off, every term is zero). They tie the reserve scenarios to the nominal output."""
    low, high = float(curve.slopes.min()), float(curve.slopes.max())
    b.pb_slope_up_low = pyo.Constraint(m.T, rule=lambda b, t: b.e[UP, t] - b.e[NONE, t] >= low * b.r_ts_up[t])
    b.pb_slope_up_high = pyo.Constraint(m.T, rule=lambda b, t: b.e[UP, t] - b.e[NONE, t] <= high * b.r_ts_up[t])
    b.pb_slope_dn_low = pyo.Constraint(m.T, rule=lambda b, t: b.e[NONE, t] - b.e[DN, t] >= low * b.r_ts_dn[t])
    b.pb_slope_dn_high = pyo.Constraint(m.T, rule=lambda b, t: b.e[NONE, t] - b.e[DN, t] <= high * b.r_ts_dn[t])


def add_csp_reserves(m: pyo.ConcreteModel, csp: CSP, problem: Problem) -> None:
    """Electrical reserves of the CSP (STU6-STU7) [MW].

    ``r↑_θ = e_up − e_none``, ``r↓_θ = e_none − e_dn``, each ``≤ min(T_sr·R_θ, share·Pmax_θ)``.
    """
    b = m.csp[csp.name]
    cap = reserve_cap(problem, csp.ramp_mw_per_min, csp.reserve_share * csp.p_max_mw)
    if UP not in m.S:
        b.r_up = pyo.Expression(m.T, rule=lambda b, t: 0.0)
        b.r_dn = pyo.Expression(m.T, rule=lambda b, t: 0.0)
        return
    b.r_up = pyo.Expression(m.T, rule=lambda b, t: b.e[UP, t] - b.e[NONE, t])
    b.r_dn = pyo.Expression(m.T, rule=lambda b, t: b.e[NONE, t] - b.e[DN, t])
    b.reserve_up_cap = pyo.Constraint(m.T, rule=lambda b, t: b.r_up[t] <= cap)
    b.reserve_dn_cap = pyo.Constraint(m.T, rule=lambda b, t: b.r_dn[t] <= cap)



def identical_csp_pairs(problem: Problem) -> list[tuple[str, str]]:
    """Consecutive CSPs of ``problem`` that are interchangeable: equal parameters and initial
    state, equal solar-field band and budget."""
    groups: dict[tuple, list[str]] = {}
    for csp in problem.case.csp:
        src = problem.sources[csp.name]
        key = (csp.model_dump_json(exclude={"name": True, "solar_field": {"series"}}), csp.column,
               src.nominal.tobytes(), src.deviation.tobytes(), src.gamma)
        groups.setdefault(key, []).append(csp.name)
    return [(a, b) for names in groups.values() for a, b in zip(names, names[1:])]


def add_csp_symmetry(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Valid inequalities for interchangeable CSPs (:func:`identical_csp_pairs`):
    ``Σt u_a[t] ≥ Σt u_b[t]``.

    Exchanging two such plants' whole schedules turns a plan into another of the same
    cost, so some optimum has them ordered by hours online; the search then need not
    visit both orders. Not for settlements, where each plant keeps its own schedule.
    """
    pairs = identical_csp_pairs(problem)
    if pairs:
        m.csp_order = pyo.Constraint(range(len(pairs)), rule=lambda m, i: (
            sum(m.csp[pairs[i][0]].online[t] for t in m.T) >= sum(m.csp[pairs[i][1]].online[t] for t in m.T)))
