"""Evaluation after the fact: the recourse model (MODEL_SPEC §10; paper Case 4).

Given first-stage bids ``p_da``, ``r_sr_up``, ``r_sr_dn``, ``h_hpa`` (optionally the CSP
commitment too) and one *realization* of every uncertain series, the recourse model
re-dispatches every unit with the physics of MODEL_SPEC §7-§9 at the realized values
(no budgets) and may fall short through slacks:

====================  =====================================================  ===========
slack                 meaning                                                unit
====================  =====================================================  ===========
``s_neg``             energy deficit against ``p_da``                        [MW]
``s_pos``             energy surplus against ``p_da``                        [MW]
``q_up``, ``q_dn``    reserve band that could not be delivered               [MW]
``g``                 unserved heat                                          [MW_th]
====================  =====================================================  ===========

Settlement at realized prices: market cost ``= −(DAM revenue + SR revenue + intraday revenue)
+ HPA cost + operating cost``, the intraday revenue ``Σ_k Σt λ_k·q_k·dt`` of the trades made in
intraday sessions at their realized prices (0 without; the imbalance is then measured against the
final position ``p_da + Σ_k q_k``, MODEL_SPEC §14); penalty ``= Σt dt·[π_def·s_neg − π_sur·s_pos + m_sr·(λup·q_up + λdn·q_dn)
+ c_heat·g]`` with the imbalance prices ``π_def = λda + (m_def − 1)·|λda|`` and
``π_sur = λda − (1 − m_sur)·|λda|`` (``m_def·λda`` and ``m_sur·λda`` for ``λda ≥ 0``), or the
case's real imbalance price series; net cost = market cost + penalty, which the recourse
minimizes. Since ``π_def ≥ π_sur`` for any sign of the price, a deficit and a surplus in
one period never pay for each other, so the settlement stays bounded at zero and negative
prices too. The same builder with several realizations and free first-stage
bids is the scenario-based stochastic benchmark (expected net cost over the scenarios).
"""

from __future__ import annotations

import datetime as dt
import hashlib
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import pyomo.environ as pyo

from ..data.case import Case
from ..data.kinds import DISPATCHABLE_KINDS, KINDS, UnitKind
from ..errors import RvppError, SettlementError
from ..data.history import MAX_QUANTITY, PRICE_COLUMNS
from ..model import add_units
from ..model.market import add_market_bids, add_market_limits, add_time, net_injection, operating_cost
from ..data.scenarios import activation
from ..data.periods import delivery_periods, period_labels
from ..uncertainty.problem import Problem, Source, SourceKind, source_columns
from ..solving.highs import model_lifetime, run_highs
from .penalties import Penalties
from ..uncertainty.bands import realized_values
from ..uncertainty.forecast import band_specs

FIRST_STAGE = ("p_da", "r_sr_up", "r_sr_dn", "h_hpa")
# Settling a day: the feasibility-jump heuristic costs more than it finds (51 settlements, four
# runs each, best CPU of four: 9.68 -> 8.79 s, the same settlements; docs/performance.md).
SETTLE_OPTIONS = {"mip_heuristic_run_feasibility_jump": False}
IMBALANCE_COLUMNS = ("imbalance_short", "imbalance_long")  # realized π_def, π_sur [EUR/MWh] where the case has them


@dataclass(frozen=True, eq=False)
class FirstStage:
    """Market bids per period [MW], [MW_th]; optionally the CSP commitment to keep fixed
    (``online``), the commitment of the hydro and biomass units decided with the bids
    (``committed``, 1 online / 0 offline per period, kept exactly: :func:`keep_commitment`) and the
    intraday trades: one ``(q_k, λ_k)`` pair per session, the trade [MW] (+ sell, − buy) and the
    realized intraday price it settles at [EUR/MWh] (MODEL_SPEC §14)."""

    p_da: np.ndarray
    r_sr_up: np.ndarray
    r_sr_dn: np.ndarray
    h_hpa: np.ndarray
    online: dict[str, np.ndarray] = field(default_factory=dict)
    intraday: tuple[tuple[np.ndarray, np.ndarray], ...] = ()
    committed: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def nt(self) -> int:
        return len(self.p_da)

    @property
    def traded(self) -> np.ndarray:
        """``Σ_k q_k`` per period [MW]."""
        return sum((np.asarray(q, dtype=float) for q, _ in self.intraday), np.zeros(self.nt))

    @property
    def position(self) -> np.ndarray:
        """The final position ``p_da + Σ_k q_k`` [MW] the imbalance is measured against."""
        return np.asarray(self.p_da, dtype=float) + self.traded

    def intraday_revenue(self, dt_h: float) -> float:
        """``Σ_k Σ_t λ_k·q_k·dt`` [EUR]: the intraday cash flows (+ received, − paid)."""
        return float(sum(np.dot(np.asarray(price, dtype=float), np.asarray(q, dtype=float)) * dt_h
                         for q, price in self.intraday))


def first_stage(result, fix_commitment: bool = False) -> FirstStage:
    """The bids of a solved plan with the commitment of its hydro and biomass units
    (:func:`unit_commitment`); ``fix_commitment``: also its CSP turbine schedule, see
    :func:`fix_commitment`."""
    if not result.has_plan:
        raise RvppError(f"the plan has no solution to evaluate ({result.status}: {result.message})")
    market = result.market
    online = {}
    if fix_commitment and not result.csp.empty:
        online = {name: part["online"].to_numpy(float) for name, part in result.csp.groupby("unit")}
    return FirstStage(*(market[f"{name}_mw"].to_numpy(float) for name in FIRST_STAGE), online=online,
                      committed=unit_commitment(result.dispatch))


def unit_commitment(dispatch: pd.DataFrame) -> dict[str, np.ndarray]:
    """The status (1 online, 0 offline) per period of every hydro and biomass unit of a plan's
    ``dispatch`` table (:attr:`rvpp.Result.dispatch`), by unit name."""
    if dispatch is None or dispatch.empty:
        return {}
    rows = dispatch[[UnitKind(kind) in DISPATCHABLE_KINDS for kind in dispatch["kind"]]]
    return {name: part.sort_values("t")["online"].to_numpy(float) for name, part in rows.groupby("unit")}


@dataclass(frozen=True, eq=False)
class Realization:
    """Observed values of one day per period [t = 1..NT; one column per source]."""

    day: dt.date
    values: pd.DataFrame

    @property
    def fingerprint(self) -> str:
        """sha256 of the values (sources in sorted order), 16 hex digits."""
        return values_fingerprint(self.values)


def values_fingerprint(values: pd.DataFrame) -> str:
    """Content fingerprint of a realization's values (independent of the column order)."""
    ordered = values[sorted(values.columns)]
    digest = hashlib.sha256(",".join(ordered.columns).encode())
    digest.update(np.ascontiguousarray(ordered.to_numpy(dtype=float)).tobytes())
    return digest.hexdigest()[:16]


def set_fingerprint(realizations: Sequence[Realization]) -> str:
    """Fingerprint of an ordered set of realizations (16 hex digits)."""
    digest = hashlib.sha256()
    for r in realizations:
        digest.update(f"{r.day.isoformat()}:{r.fingerprint};".encode())
    return digest.hexdigest()[:16]


def realization(case: Case, day: dt.date) -> Realization:
    """What the history observed on ``day`` for every source of ``case`` (and its real
    imbalance prices ``imbalance_short``, ``imbalance_long`` when the case names them)."""
    periods = delivery_periods(day, case.timezone, case.dt_h)
    columns = source_columns(case)
    if case.markets.imbalance_prices is not None:
        columns.update({name: (getattr(case.markets.imbalance_prices, side), 1.0)
                        for name, side in zip(IMBALANCE_COLUMNS, ("short", "long"))})
    limits = {name: (spec.low, spec.high) for name, spec in band_specs(case).items()}
    values = realized_values(case.history, day, periods, columns, case.timezone, limits)
    return Realization(day=day, values=values)


def nominal_realization(problem: Problem) -> Realization:
    """A realization equal to the nominal values a plan was made with."""
    values = pd.DataFrame({name: src.nominal for name, src in problem.sources.items()},
                          index=pd.RangeIndex(1, problem.nt + 1, name="t"))
    return Realization(day=problem.day, values=values)


def realized_problem(case: Case, real: Realization) -> "RealizedProblem":
    """A :class:`Problem` of the delivery day of ``case`` whose sources carry the realized values.

    Budgets are 0 and deviations 0, so the unit builders see the realization as the
    nominal bound. Availabilities are clipped to ``[0, nameplate]`` (as the forecast
    bands are) and consumptions to each demand's ``[min, max]`` limits. Its ``bands`` are
    of zero width at these values (``lo = mid = hi``), so a plan solved from it (the
    perfect-information plan) is audited against them.
    """
    periods = delivery_periods(case.delivery_date, case.timezone, case.dt_h)
    if len(real.values) != len(periods):
        raise RvppError(f"the realization of {real.day} has {len(real.values)} periods but the delivery day "
                        f"{case.delivery_date} has {len(periods)}; use days of the same length")
    sources = {}
    for name in PRICE_COLUMNS:
        kind = SourceKind.PRICE_DA if name == "price_da" else SourceKind.PRICE_SR
        sources[name] = _exact(name, kind, None, real.values[name].to_numpy(float))
    for kind, unit in case.uncertain_units():
        low, high = unit.series_range
        values = np.clip(real.values[unit.name].to_numpy(float), low, high)
        sources[unit.name] = _exact(unit.name, SourceKind(KINDS[kind].role.value), kind, values)
    tariff = np.array([case.markets.hpa_tariff_eur_per_mwh[h] for h in periods.hour], dtype=float)
    bands = pd.DataFrame({(name, stat): src.nominal for name, src in sources.items() for stat in ("lo", "mid", "hi")},
                         index=pd.RangeIndex(1, len(periods) + 1, name="t"))
    bands.columns = pd.MultiIndex.from_tuples(bands.columns, names=["source", "stat"])
    imbalance = [real.values[c].to_numpy(float) if c in real.values.columns else None for c in IMBALANCE_COLUMNS]
    return RealizedProblem(case=case, day=case.delivery_date, periods=periods, bands=bands,
                           sources=sources, tariff_hpa=tariff, labels=period_labels(periods),
                           imbalance_short=imbalance[0], imbalance_long=imbalance[1])


@dataclass(frozen=True, eq=False)
class RealizedProblem(Problem):
    """A :class:`Problem` whose sources carry one realization, with the realized imbalance
    prices [EUR/MWh] where the case has real ones (``None``: from the DAM price, §10)."""

    imbalance_short: np.ndarray | None = None
    imbalance_long: np.ndarray | None = None


def _exact(name: str, kind: SourceKind, unit_kind: UnitKind | None, values: np.ndarray) -> Source:
    zero = np.zeros_like(values)
    return Source(name, kind, unit_kind, values, zero, 0,
                  deviation_up=zero if kind is SourceKind.PRICE_DA else None)


# ----------------------------------------------------------------------------- model


def build_recourse_model(problems: Sequence[Problem], penalties: Penalties,
                         bids: FirstStage | None = None) -> pyo.ConcreteModel:
    """Minimize the mean net cost over ``problems`` (one per realization) [EUR].

    With ``bids`` the first stage is fixed (the recourse model of one plan); without,
    the bids are shared decisions of every scenario (the stochastic benchmark).
    Scenario ``k`` is the block ``m.scenario[k]`` with its own periods, activation
    scenarios, unit blocks, slacks and settlement.
    """
    base = problems[0]
    m = pyo.ConcreteModel(name=f"recourse {base.case.name} {base.day}")
    add_time(m, base)
    if bids is None:
        add_market_bids(m, base)
        add_market_limits(m, base)
    else:
        add_fixed_bids(m, bids)
    m.scenario = pyo.Block(range(len(problems)))
    for k, problem in enumerate(problems):
        add_scenario(m, m.scenario[k], problem, penalties, bids)
    weight = 1.0 / len(problems)
    # The heat kept past midnight is valued as the plan valued it (0 unless the case sets
    # end_value_eur_per_mwh_th), so the settlement does not spend it for less; it is not cash
    # and stays out of net_cost.
    m.expected_net_cost = pyo.Objective(
        expr=weight * sum(m.scenario[k].net_cost - sum(m.scenario[k].csp[c.name].heat_kept_value
                                                        for c in problems[k].case.csp)
                          for k in m.scenario), sense=pyo.minimize)
    return m


def add_fixed_bids(m: pyo.ConcreteModel, bids: FirstStage) -> None:
    """First-stage bids as fixed data ``p_da``, ``r_sr_up``, ``r_sr_dn`` [MW], ``h_hpa`` [MW_th]."""
    if bids.nt != len(m.T):
        raise RvppError(f"the bids have {bids.nt} periods but the day has {len(m.T)}")
    for name in FIRST_STAGE:
        values = getattr(bids, name)
        m.add_component(name, pyo.Param(m.T, initialize=lambda _, t, v=values: float(v[t - 1])))
    traded = bids.traded
    m.q_id = pyo.Param(m.T, initialize=lambda _, t: float(traded[t - 1]))
    m.intraday_cash = bids.intraday_revenue(1.0)  # [EUR/h of period]: × dt in the settlement


def add_scenario(m: pyo.ConcreteModel, b: pyo.Block, problem: Problem, penalties: Penalties,
                 bids: FirstStage | None) -> None:
    """One realization: units, slacks, balances and settlement on block ``b``."""
    add_time(b, problem)
    add_units(b, problem)
    allow_trip(b, problem.case)
    if bids is not None:
        fix_commitment(b, bids)
        keep_commitment(b, bids)
    add_slacks(m, b)
    add_recourse_electric_balance(m, b, problem)
    add_recourse_heat_balance(m, b, problem)
    add_settlement(m, b, problem, penalties)


def fix_commitment(b: pyo.Block, bids: FirstStage) -> None:
    """Keep the CSP turbine schedule of the plan (option of MODEL_SPEC §10): ``u[t] ≤ u_plan[t]``.

    The turbine never starts where the plan has it off; where the plan has it on it may
    still stop (trip), since a realized day may not bring the heat for its minimum input.
    Staying off is always possible, so the settlement never becomes infeasible.
    """
    for name, online in bids.online.items():
        for t in b.T:
            if round(float(online[t - 1])) == 0:
                b.csp[name].online[t].fix(0)


def keep_commitment(b: pyo.Block, bids: FirstStage) -> None:
    """Keep the plan's hydro and biomass commitment: ``u[t] = u_plan[t]`` (MODEL_SPEC §13).

    The units start and stop as decided the day before, with the bids; only their output and
    reserve are re-dispatched. Neither kind depends on the weather and the settlement has the
    plan's physics and initial state, so the plan's own dispatch always fits the schedule.
    """
    units = b.dispatchable
    for name, online in bids.committed.items():
        if name not in units:
            raise SettlementError(f"the plan commits unit {name!r}, which is not a hydro or biomass unit of the "
                                  "case being settled; settle a plan with the case it was made for")
        status = np.asarray(online, dtype=float)
        if status.shape != (len(b.T),) or not np.isin(status, (0.0, 1.0)).all():
            raise SettlementError(f"the commitment of {name!r} must hold one status, 0 or 1, for each of the "
                                  f"day's {len(b.T)} periods")
        for t in b.T:
            units[name].online[t].fix(int(status[t - 1]))


def allow_trip(b: pyo.Block, case: Case) -> None:
    """A turbine online at the start of the day may stop before completing a minimum up time
    begun the day before (STU12 is lifted): a trip is always possible in operation, and the
    realized day may lack the heat to keep it running. A minimum down time begun the day
    before still holds, since staying off is always possible."""
    for csp in case.csp:
        if csp.power_block.initially_on:
            b.csp[csp.name].initial_status_held.deactivate()


def add_slacks(m: pyo.ConcreteModel, b: pyo.Block) -> None:
    """Deficit ``s_neg``, surplus ``s_pos`` [MW], reserve shortfall ``q_up ≤ r_sr_up``,
    ``q_dn ≤ r_sr_dn`` [MW] and unserved heat ``g`` [MW_th] (MODEL_SPEC §10)."""
    b.s_neg = pyo.Var(b.T, domain=pyo.NonNegativeReals)
    b.s_pos = pyo.Var(b.T, domain=pyo.NonNegativeReals)
    b.q_up = pyo.Var(b.T, domain=pyo.NonNegativeReals)
    b.q_dn = pyo.Var(b.T, domain=pyo.NonNegativeReals)
    b.g = pyo.Var(b.T, domain=pyo.NonNegativeReals)
    b.q_up_cap = pyo.Constraint(b.T, rule=lambda b, t: b.q_up[t] <= m.r_sr_up[t])
    b.q_dn_cap = pyo.Constraint(b.T, rule=lambda b, t: b.q_dn[t] <= m.r_sr_dn[t])


def add_recourse_electric_balance(m: pyo.ConcreteModel, b: pyo.Block, problem: Problem) -> None:
    """Supply-Demand1 with slacks in every activation scenario ``s`` [MW]:

    ``net_injection_s = p_da + Σ_k q_k − s_neg + s_pos + a_s(r_sr↑ − q↑, r_sr↓ − q↓)``: the
    imbalance is measured against the final position (the intraday trades ``Σ_k q_k`` are 0
    without intraday sessions; MODEL_SPEC §14).
    """
    case = problem.case
    traded = m.q_id if hasattr(m, "q_id") else {t: 0.0 for t in b.T}
    b.electric_balance = pyo.Constraint(b.S, b.T, rule=lambda b, s, t: (
        net_injection(b, case, s, t) == m.p_da[t] + traded[t] - b.s_neg[t] + b.s_pos[t]
        + activation(s, m.r_sr_up[t] - b.q_up[t], m.r_sr_dn[t] - b.q_dn[t])))


def add_recourse_heat_balance(m: pyo.ConcreteModel, b: pyo.Block, problem: Problem) -> None:
    """Heat balance with unserved heat: ``Σθ h_θ + h_hpa + g = Σk h_k`` [MW_th]."""
    case = problem.case
    b.heat_balance = pyo.Constraint(b.T, rule=lambda b, t: (
        sum(b.csp[c.name].h[t] for c in case.csp) + m.h_hpa[t] + b.g[t]
        == sum(b.td[k.name].h[t] for k in case.td)))


def add_settlement(m: pyo.ConcreteModel, b: pyo.Block, problem: Problem, penalties: Penalties) -> None:
    """Market cost, penalty and net cost at realized prices [EUR] (MODEL_SPEC §10)."""
    case, dt_h = problem.case, problem.dt_h
    da, up, dn = (problem.sources[n].nominal for n in PRICE_COLUMNS)
    hpa, c_heat = problem.tariff_hpa, penalties.heat_price(case)

    def total(term):
        return sum(term(t, t - 1) * dt_h for t in b.T)

    b.revenue_dam = pyo.Expression(expr=total(lambda t, i: float(da[i]) * m.p_da[t]))
    b.revenue_sr = pyo.Expression(expr=total(lambda t, i: float(up[i]) * m.r_sr_up[t] + float(dn[i]) * m.r_sr_dn[t]))
    b.cost_hpa = pyo.Expression(expr=total(lambda t, i: float(hpa[i]) * m.h_hpa[t]))
    b.cost_opex = pyo.Expression(expr=operating_cost(b, case, dt_h))
    b.revenue_intraday = pyo.Expression(expr=getattr(m, "intraday_cash", 0.0) * dt_h)
    b.market_cost = pyo.Expression(expr=-(b.revenue_dam + b.revenue_sr + b.revenue_intraday) + b.cost_hpa
                                   + b.cost_opex)
    # A realized problem may carry real imbalance prices; otherwise they follow the DAM price.
    short, long = penalties.imbalance_prices(da, getattr(problem, "imbalance_short", None),
                                             getattr(problem, "imbalance_long", None),
                                             [f"{problem.day} {label}" for label in problem.labels])
    b.penalty_deficit = pyo.Expression(expr=total(lambda t, i: float(short[i]) * b.s_neg[t]))
    b.penalty_surplus = pyo.Expression(expr=total(lambda t, i: -float(long[i]) * b.s_pos[t]))
    b.penalty_reserve = pyo.Expression(expr=total(lambda t, i: penalties.m_sr * (
        float(up[i]) * b.q_up[t] + float(dn[i]) * b.q_dn[t])))
    b.penalty_heat = pyo.Expression(expr=total(lambda t, i: c_heat * b.g[t]))
    b.penalty = pyo.Expression(expr=b.penalty_deficit + b.penalty_surplus + b.penalty_reserve + b.penalty_heat)
    b.net_cost = pyo.Expression(expr=b.market_cost + b.penalty)


# ----------------------------------------------------------------------------- evaluation


SETTLEMENT = ("market_cost", "penalty", "net_cost", "revenue_dam", "revenue_sr", "revenue_intraday", "cost_hpa",
              "cost_opex",
              "penalty_deficit", "penalty_surplus", "penalty_reserve", "penalty_heat")
SLACKS = {"deficit_mwh": "s_neg", "surplus_mwh": "s_pos", "reserve_up_short_mwh": "q_up",
          "reserve_dn_short_mwh": "q_dn", "unserved_heat_mwh": "g"}


def evaluate(case: Case, bids: FirstStage, real: Realization, penalties: Penalties = Penalties(),
             with_end_state: bool = False) -> dict:
    """Settle fixed ``bids`` against one realization: a plain record of the outcome.

    Keys: ``day``, ``fingerprint``, ``status``, ``solve_s``, the settlement in [EUR]
    (``market_cost_eur``, ``penalty_eur``, ``net_cost_eur`` and their parts), the
    slack energies [MWh] (``deficit_mwh``, ...) and, ``with_end_state``, the state at the
    end of the day (``end_state``, see :func:`end_state`), the settled turbine status and
    storage energy (``settled_csp``, see :func:`csp_dispatch`) and the settled dispatch of batteries,
    hydro and biomass units (``settled_units``, see :func:`unit_dispatch`). Values are ``None`` without a
    solution.
    """
    problem = realized_problem(case, real)
    with model_lifetime():
        m = build_recourse_model([problem], penalties, bids)
        outcome = run_highs(m, case.solver, options=SETTLE_OPTIONS)
        record = {"day": real.day.isoformat(), "fingerprint": real.fingerprint, "status": outcome.status,
                  "solve_s": outcome.seconds, "mip_gap": outcome.gap}
        record.update(scenario_record(m.scenario[0], problem.dt_h, outcome.usable))
        if with_end_state:
            record["end_state"] = end_state(m.scenario[0], case, problem.dt_h) if outcome.usable else None
            record["settled_csp"] = csp_dispatch(m.scenario[0], case) if outcome.usable else None
            record["settled_units"] = unit_dispatch(m.scenario[0], case) if outcome.usable else None
        del m  # garbage from here: collected young as the block ends
    return record


def csp_dispatch(b: pyo.Block, case: Case) -> dict[str, dict[str, list]]:
    """Per CSP, the settled turbine status and storage energy of every period [-], [MWh_th]."""
    return {csp.name: {"online": [round(float(pyo.value(b.csp[csp.name].online[t]))) for t in b.T],
                       "e_mwh_th": [float(pyo.value(b.csp[csp.name].e_ts[t])) for t in b.T]} for csp in case.csp}


def unit_dispatch(b: pyo.Block, case: Case) -> dict[str, dict[str, list]]:
    """Per battery, hydro and biomass unit, its ``kind`` and the settled dispatch of every period
    (MODEL_SPEC §13): a battery's ``charge_mw``, ``discharge_mw`` [MW] and ``e_mwh`` [MWh] at the
    period's end; a hydro or biomass unit's ``online`` [-] and ``p_mw`` [MW]."""

    def values(var) -> list[float]:
        return [float(pyo.value(var[t])) for t in b.T]

    settled = {}
    for kind, unit in case.units():
        if kind == UnitKind.BATTERY:
            bat = b.battery[unit.name]
            settled[unit.name] = {"kind": kind.value, "charge_mw": values(bat.p_ch), "discharge_mw": values(bat.p_dis),
                                  "e_mwh": values(bat.e)}
        elif kind in DISPATCHABLE_KINDS:
            unit_block = b.dispatchable[unit.name]
            settled[unit.name] = {"kind": kind.value,
                                  "online": [round(value) for value in values(unit_block.online)],
                                  "p_mw": values(unit_block.p)}
    return settled


def end_state(b: pyo.Block, case: Case, dt_h: float) -> dict[str, dict]:
    """The state a settled day hands to the next, per CSP, battery, hydro and biomass unit (the
    next day's initial conditions). A battery hands ``e_mwh`` [MWh]; a hydro or biomass unit
    ``online``, ``status_h`` as a turbine's, and ``p_mw`` [MW], its output in the last period.

    ``e_mwh_th``: storage energy at the last period [MWh_th] (solver round-off clipped to
    the storage limits); ``online``: the turbine's status in the last period; ``status_h``:
    hours in that status at the end of the day [h], counting into the day before when the
    turbine never switched (``initial_status_h`` of the case added; ``None`` if that was unset,
    i.e. long enough that no minimum time binds).
    """
    state = {}
    for csp in case.csp:
        c, ts, pb = b.csp[csp.name], csp.storage, csp.power_block
        online = [round(float(pyo.value(c.online[t]))) for t in b.T]
        last = online[-1]
        run = next((k for k, value in enumerate(reversed(online)) if value != last), len(online))
        hours: float | None = run * dt_h
        if run == len(online) and bool(last) == pb.initially_on:
            hours = None if pb.initial_status_h is None else pb.initial_status_h + hours
        energy = float(pyo.value(c.e_ts[b.T.last()]))
        state[csp.name] = {"e_mwh_th": min(max(energy, ts.e_min_mwh_th), ts.e_max_mwh_th),
                           "online": bool(last), "status_h": hours}
    for kind, unit in case.units():  # MODEL_SPEC §13: a battery's energy, a hydro or biomass unit's status
        if kind == UnitKind.BATTERY:
            energy = float(pyo.value(b.battery[unit.name].e[b.T.last()]))
            state[unit.name] = {"e_mwh": min(max(energy, unit.e_min_mwh), unit.e_max_mwh)}
        elif kind in (UnitKind.HYDRO, UnitKind.BIOMASS):
            g = b.dispatchable[unit.name]
            online = [round(float(pyo.value(g.online[t]))) for t in b.T]
            last = online[-1]
            run = next((k for k, value in enumerate(reversed(online)) if value != last), len(online))
            hours = run * dt_h
            if run == len(online) and bool(last) == unit.initial_online:
                hours = None if unit.initial_hours_in_status is None else unit.initial_hours_in_status + hours
            output = float(pyo.value(g.p[b.T.last()])) if last else 0.0
            state[unit.name] = {"online": bool(last), "status_h": hours,
                                "p_mw": min(max(output, unit.p_min_mw), unit.p_max_mw) if last else 0.0}
    return state


def scenario_record(b: pyo.Block, dt_h: float, solved: bool) -> dict:
    """Settlement [EUR] and slack energies [MWh] of one solved scenario block (``None`` unless ``solved``
    is true, i.e. the solve ended usable)."""
    if not solved:
        return {**{f"{k}_eur": None for k in SETTLEMENT}, **{k: None for k in SLACKS}}
    record = {f"{k}_eur": float(pyo.value(getattr(b, k))) for k in SETTLEMENT}
    record.update({k: float(sum(pyo.value(getattr(b, v)[t]) for t in b.T) * dt_h) for k, v in SLACKS.items()})
    return record
