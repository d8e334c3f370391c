"""Robust counterpart with temporal uncertainty budgets.

Bertsimas, D. and Sim, M. (2004), "The Price of Robustness", Operations Research
52(1):35-53, Proposition 1: for fixed decisions, the worst case of ``Σt λneg_t·x_t``
over at most Γ deviating periods equals ``min Γ·φ + Σt ζ_t`` subject to
``φ + ζ_t ≥ λneg_t·|x_t|``, ``φ, ζ ≥ 0``. This module takes the nominal model built
by :mod:`rvpp.model`, the deviations and budgets of each :class:`~rvpp.solving.problem.Source`
and adds

* the price protection of the objective for the DAM, SR-up and SR-down prices
  (MILP-asymetric1, MILP-DAMprice, MILP-upSRMprice, MILP-downSRMprice);
* the budgeted deviation ``y_t`` of every uncertain availability and consumption
  (MILP-STU1..4, MILP-NDRES1..4, MILP-Demand1..Demand_Heat4; MODEL_SPEC §5).

Three variants of the constraint budgets exist (``Budgets.mode`` and
``SolverSettings.budget_encoding``):

* paper mode, binary encoding: MODEL_SPEC §5 verbatim, with the bounds
  ``y ≤ dev·χ`` and ``ζ ≤ M·χ`` of the authors' implementation, which make χ land on
  the Γ largest deviations;
* paper mode, top-Γ encoding (default): since χ is then determined by the data, it is
  fixed to the Γ largest deviations in advance; only when tied deviations straddle
  the Γ boundary do binaries choose among the tied periods, so the optimum is the same;
* planner-chosen hours: the formulation as printed (``y ≤ M·χ``), under which the
  maximizing operator picks the Γ periods where a deviation hurts least. For teaching.
"""

from __future__ import annotations

import numpy as np
import pyomo.environ as pyo

from .problem import Problem, Source

PRICE_EXPOSURES = ("price_da", "price_sr_up", "price_sr_dn")


def add_robustness(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Add price protection and budgeted deviations for every source of ``problem``."""
    m.robust = pyo.Block(list(problem.sources))
    for name, source in problem.sources.items():
        block = m.robust[name]
        if source.is_price:
            exposure = _price_exposure(m, block, source, problem)
            protection = add_price_protection(block, exposure, source.gamma)
            m.protection[name].set_value(protection)
        else:
            target = _bound_target(m, source)
            sign = -1.0 if source.kind == "production" else 1.0
            y = add_budgeted_deviation(block, source, problem)
            for t in m.T:
                target[t].set_value(float(source.nominal[t - 1]) + sign * y[t])


def _bound_target(m: pyo.ConcreteModel, source: Source):
    """The robust bound Expression of the unit the source belongs to."""
    container = {"wind": m.ndres, "pv": m.ndres, "csp": m.csp, "ed": m.ed, "td": m.td}[source.unit_kind]
    return container[source.name].bound


def _price_exposure(m, block, source: Source, problem: Problem) -> dict:
    """Loss per period if the price moves adversely by its full deviation [EUR]."""
    dt = problem.dt_h
    if source.name == "price_da":
        # w_t = λneg_t·y_t of (MILP-asymetric1): the larger of the selling loss
        # λneg·p·dt and the buying loss λpos·(−p)·dt; written without the ratio
        # λneg/λpos so a zero deviation on either side is well defined.
        block.w = pyo.Var(m.T, domain=pyo.NonNegativeReals)
        neg, pos = source.deviation, source.deviation_up
        block.w_sell = pyo.Constraint(m.T, rule=lambda b, t: b.w[t] >= float(neg[t - 1]) * m.p_da[t] * dt)
        block.w_buy = pyo.Constraint(m.T, rule=lambda b, t: b.w[t] >= -float(pos[t - 1]) * m.p_da[t] * dt)
        return {t: block.w[t] for t in m.T}
    band = m.r_sr_up if source.name == "price_sr_up" else m.r_sr_dn
    return {t: float(source.deviation[t - 1]) * band[t] * dt for t in m.T}


def add_price_protection(block, exposure: dict, gamma: int):
    """Worst-case loss of Γ periods: ``Γ·φ + Σt ζ_t`` with ``φ + ζ_t ≥ exposure_t`` [EUR].

    Dual of the inner maximisation (paper Protection_obj), equation (MILP-DAMprice).
    """
    periods = list(exposure)
    if gamma <= 0:
        return 0.0
    if gamma >= len(periods):
        return sum(exposure[t] for t in periods)
    block.phi = pyo.Var(domain=pyo.NonNegativeReals)
    block.zeta = pyo.Var(periods, domain=pyo.NonNegativeReals)
    block.dual = pyo.Constraint(periods, rule=lambda b, t: b.phi + b.zeta[t] >= exposure[t])
    return gamma * block.phi + sum(block.zeta[t] for t in periods)


def add_budgeted_deviation(block, source: Source, problem: Problem) -> dict:
    """The deviation ``y_t`` [MW] applied to the source's bound, by budget variant.

    Always creates ``block.chi[t]`` (1 in the periods that deviate) and returns
    ``y_t`` as an expression per period.
    """
    periods = range(1, problem.nt + 1)
    dev = np.asarray(source.deviation, dtype=float)
    gamma = int(source.gamma)
    block.chi = pyo.Var(periods, domain=pyo.Binary)
    mode = problem.case.budgets.mode
    encoding = problem.case.solver.budget_encoding
    if gamma == 0 or dev.max() <= 0.0:
        for i, t in enumerate(periods):
            block.chi[t].fix(1 if i < gamma else 0)
        return {t: 0.0 for t in periods}
    block.budget = pyo.Constraint(expr=sum(block.chi[t] for t in periods) == gamma)
    if mode == "planner_chosen":
        return {t: float(dev[t - 1]) * block.chi[t] for t in periods}
    if encoding == "binary":
        return _paper_binary(block, dev, periods)
    return _paper_top_gamma(block, dev, gamma, periods)


def _paper_binary(block, dev: np.ndarray, periods) -> dict:
    """MODEL_SPEC §5 with the bounds of the authors' implementation (MILP-STU1..4)."""
    big_m = float(dev.max())
    block.phi = pyo.Var(domain=pyo.NonNegativeReals, bounds=(0.0, big_m))
    block.zeta = pyo.Var(periods, domain=pyo.NonNegativeReals, bounds=(0.0, big_m))
    block.y = pyo.Var(periods, domain=pyo.NonNegativeReals, bounds=(0.0, big_m))
    block.dual = pyo.Constraint(periods, rule=lambda b, t: b.phi + b.zeta[t] >= float(dev[t - 1]))
    block.y_lower = pyo.Constraint(
        periods, rule=lambda b, t: b.y[t] >= b.phi + b.zeta[t] - big_m * (1 - b.chi[t]))
    block.y_upper = pyo.Constraint(periods, rule=lambda b, t: b.y[t] <= float(dev[t - 1]) * b.chi[t])
    block.zeta_upper = pyo.Constraint(periods, rule=lambda b, t: b.zeta[t] <= big_m * b.chi[t])
    return {t: block.y[t] for t in periods}


def _paper_top_gamma(block, dev: np.ndarray, gamma: int, periods) -> dict:
    """χ fixed on the Γ largest deviations; binaries only among ties at the boundary."""
    order = np.argsort(-dev, kind="stable")
    threshold = dev[order[gamma - 1]]
    above = dev > threshold
    tied = dev == threshold
    needed = gamma - int(above.sum())
    ambiguous = threshold > 0.0 and int(tied.sum()) > needed
    for t in periods:
        i = t - 1
        if above[i]:
            block.chi[t].fix(1)
        elif tied[i] and ambiguous:
            continue
        elif tied[i] and needed > 0:
            block.chi[t].fix(1)
            needed -= 1
        else:
            block.chi[t].fix(0)
    if not ambiguous:
        block.del_component(block.budget)
    return {t: float(dev[t - 1]) * block.chi[t] for t in periods}
