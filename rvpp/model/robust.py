"""Robust counterpart with temporal uncertainty budgets.

Bertsimas, D. and Sim, M. (2004), "The Price of Robustness", Operations Research
52(1):35-53, Proposition 1: for fixed decisions, the worst case of ``Σt λneg_t·x_t``
over at most Γ deviating periods equals ``min Γ·φ + Σt ζ_t`` subject to
``φ + ζ_t ≥ λneg_t·|x_t|``, ``φ, ζ ≥ 0``. This module takes the nominal model built
by :mod:`rvpp.model`, the deviations and budgets of each :class:`~rvpp.uncertainty.problem.Source`
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
  fixed to the Γ largest deviations in advance (:func:`top_gamma_choice`); only when
  tied deviations straddle the Γ boundary do binaries choose among the tied periods,
  so the optimum is the same;
* planner-chosen hours: the formulation as printed (``y ≤ M·χ``), under which the
  maximizing operator picks the Γ periods where a deviation hurts least. For teaching.
"""

from __future__ import annotations

import math

import numpy as np
import pyomo.environ as pyo

from ..errors import RvppError
from ..uncertainty.problem import Problem, Source, SourceKind, budget_split
from .blocks import unit_block

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
            sign = -1.0 if source.kind is SourceKind.PRODUCTION else 1.0
            y = add_budgeted_deviation(block, source, problem)
            for t in m.T:
                target[t].set_value(float(source.nominal[t - 1]) + sign * y[t])


def _bound_target(m: pyo.ConcreteModel, source: Source):
    """The robust bound Expression of the unit the source belongs to."""
    return unit_block(m, source.unit_kind, source.name).bound


def _price_exposure(m, block, source: Source, problem: Problem) -> dict:
    """Loss per period if the price moves adversely by its full deviation [EUR]."""
    dt = problem.dt_h
    if source.name == "price_da":
        # In an intraday session the price is the session's and the energy exposed to it is the
        # trade q_k (MODEL_SPEC §14); otherwise the day-ahead bid.
        energy = m.q_id if hasattr(m, "q_id") else m.p_da
        # w_t = λneg_t·y_t of (MILP-asymetric1): the larger of the selling loss
        # λneg·p·dt and the buying loss λpos·(−p)·dt; written without the ratio
        # λneg/λpos so a zero deviation on either side is well defined.
        block.w = pyo.Var(m.T, domain=pyo.NonNegativeReals)
        neg, pos = source.deviation, source.deviation_up
        block.w_sell = pyo.Constraint(m.T, rule=lambda b, t: b.w[t] >= float(neg[t - 1]) * energy[t] * dt)
        block.w_buy = pyo.Constraint(m.T, rule=lambda b, t: b.w[t] >= -float(pos[t - 1]) * energy[t] * dt)
        return {t: block.w[t] for t in m.T}
    band = m.r_sr_up if source.name == "price_sr_up" else m.r_sr_dn
    return {t: float(source.deviation[t - 1]) * band[t] * dt for t in m.T}


def add_price_protection(block, exposure: dict, gamma: int):
    """Worst-case loss of Γ periods: ``Γ·φ + Σt ζ_t`` with ``φ + ζ_t ≥ exposure_t`` [EUR].

    Dual of the inner maximisation (paper Protection_obj), equation (MILP-DAMprice).
    Γ is the mutable parameter ``block.gamma``; the same rows hold for every Γ from 0
    (``φ`` covers every exposure, no loss) to the number of periods (``φ = 0``, every
    exposure counts), so a model can be re-solved for another Γ without rebuilding.
    """
    periods = list(exposure)
    block.gamma = pyo.Param(mutable=True, initialize=int(gamma), within=pyo.NonNegativeIntegers)
    block.phi = pyo.Var(domain=pyo.NonNegativeReals)
    block.zeta = pyo.Var(periods, domain=pyo.NonNegativeReals)
    block.dual = pyo.Constraint(periods, rule=lambda b, t: b.phi + b.zeta[t] >= exposure[t])
    return block.gamma * block.phi + sum(block.zeta[t] for t in periods)


def add_budgeted_deviation(block, source: Source, problem: Problem) -> dict:
    """The deviation ``y_t`` [MW] applied to the source's bound, by budget variant.

    Always creates ``block.chi[t]`` (1 in the periods that deviate) and the mutable
    budget ``block.gamma``, and returns ``y_t`` as an expression per period.
    """
    periods = range(1, problem.nt + 1)
    dev = np.asarray(source.deviation, dtype=float)
    block.chi = pyo.Var(periods, domain=pyo.Binary)
    block.gamma = pyo.Param(mutable=True, initialize=int(source.gamma), within=pyo.NonNegativeIntegers)
    block.built_gamma = int(source.gamma)
    mode = problem.case.budgets.mode
    encoding = problem.case.solver.budget_encoding
    if dev.max() <= 0.0:  # nothing deviates, whatever the budget
        _fix_chi(block, top_gamma_choice(dev, int(source.gamma)))
        return {t: 0.0 for t in periods}
    block.budget = pyo.Constraint(expr=sum(block.chi[t] for t in periods) == block.gamma)
    if mode == "planner_chosen":
        return {t: float(dev[t - 1]) * block.chi[t] for t in periods}
    if encoding == "binary":
        return _paper_binary(block, dev, periods)
    _fix_chi(block, top_gamma_choice(dev, int(source.gamma), problem.case.budgets.ties))
    return {t: float(dev[t - 1]) * block.chi[t] for t in periods}


def set_budgets(m: pyo.ConcreteModel, problem: Problem) -> None:
    """Give a model built by :func:`add_robustness` the budgets of ``problem``.

    ``problem`` must describe the same case and day as the model, with other Γ values:
    the mutable budgets change and, under the top-Γ encoding, χ is fixed anew, so the
    model is re-solved without being rebuilt. A solar field's budget may not fall below
    the one the model was built with: the storage's charging limit was tightened with
    the periods that surely deviate then (:func:`surely_deviating`), and those periods
    only grow with Γ.
    """
    for csp in problem.case.csp:
        if problem.sources[csp.name].gamma < m.robust[csp.name].built_gamma:
            raise RvppError(f"Γ of {csp.name!r} below the {m.robust[csp.name].built_gamma} the model was built "
                             "with; build the model with the smallest budget first")
    top_gamma = problem.case.budgets.mode == "paper" and problem.case.solver.budget_encoding == "top_gamma"
    for name, source in problem.sources.items():
        block = m.robust[name]
        block.gamma.set_value(int(source.gamma))
        if not source.is_price and (top_gamma or not hasattr(block, "budget")):
            _fix_chi(block, top_gamma_choice(source.deviation, int(source.gamma), problem.case.budgets.ties))


def budget_choices(m: pyo.ConcreteModel) -> bool:
    """True when the solver places some budgeted deviation of ``m`` itself: a χ left free (tied
    deviations at the Γ boundary under the top-Γ encoding, or every χ of the other variants)."""
    return any(not v.fixed for block in m.robust.values() if hasattr(block, "chi") for v in block.chi.values())


def _fix_chi(block, chi: np.ndarray) -> None:
    """Fix χ where the data decide it; leave it free (NaN) among ties at the Γ boundary."""
    for var, value in zip(block.chi.values(), chi.tolist()):
        if math.isnan(value):
            var.unfix()
        else:
            var.fix(int(value), skip_validation=True)  # 0 or 1 by construction


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


def top_gamma_choice(dev: np.ndarray, gamma: int, ties: str = "choose") -> np.ndarray:
    """Paper-mode χ decided by the data: 1 on the Γ largest deviations, 0 elsewhere, NaN where
    tied deviations straddle the Γ boundary (the solver chooses among them) unless ``ties`` is
    ``"earliest"`` (``budgets.ties``: the earliest of them deviate).

    The periods come from :func:`~rvpp.uncertainty.problem.budget_split`; where fewer than Γ
    periods have a positive deviation, χ is completed with the earliest remaining
    periods (their deviation is 0, so they change no bound) to keep ``Σχ = Γ``.
    """
    dev = np.asarray(dev, dtype=float)
    sure, tied, count = budget_split(dev, gamma, ties)
    chi = sure.astype(float)
    if count and int(tied.sum()) > count:
        chi[tied] = np.nan
    else:
        chi[tied] = 1.0
    missing = max(0, gamma - int(np.nansum(chi)) - int(np.isnan(chi).any()) * count)
    chi[np.flatnonzero(chi == 0.0)[:missing]] = 1.0
    return chi


def surely_deviating(problem: Problem, name: str) -> np.ndarray:
    """Periods where source ``name`` sits at its bad bound whatever the solver chooses.

    In paper mode with the top-Γ encoding these are the Γ largest deviations outside a
    tie; under the other variants the solver places χ, so no period is sure.
    """
    source = problem.sources[name]
    if problem.case.budgets.mode != "paper" or problem.case.solver.budget_encoding != "top_gamma":
        return np.zeros(problem.nt, dtype=bool)
    return top_gamma_choice(source.deviation, int(source.gamma), problem.case.budgets.ties) == 1.0
