"""The RVPP bidding model in Pyomo (MODEL_SPEC §2-§9).

:func:`build_model` reads like the paper: one call per constraint family, one block
per asset on the shared periods, system balances and market coupling at the top, then
the robust layer (:mod:`rvpp.model.robust`) and the objective.
"""

from __future__ import annotations

import pyomo.environ as pyo

from ..uncertainty.problem import Problem
from .robust import add_robustness
from .csp import (add_csp_commitment, add_csp_power_block, add_csp_reserves, add_csp_solar_field,
                  add_csp_storage, add_csp_symmetry)
from .market import (SCENARIOS, activation, add_electric_balance, add_heat_balance, add_market_bids,
                     add_market_limits, add_objective, add_time)
from .units import add_electrical_demand, add_ndres, add_thermal_demand

__all__ = ["build_model", "add_units", "SCENARIOS", "activation"]


def build_model(problem: Problem) -> pyo.ConcreteModel:
    """The robust bidding MILP of one delivery day."""
    case = problem.case
    m = pyo.ConcreteModel(name=f"rvpp {case.name} {problem.day}")
    add_time(m, problem)
    add_market_bids(m, problem)
    add_units(m, problem)
    add_csp_symmetry(m, problem)
    add_market_limits(m, problem)
    add_electric_balance(m, problem)
    add_heat_balance(m, problem)
    add_robustness(m, problem)
    add_objective(m, problem)
    return m


def add_units(m: pyo.Block, problem: Problem) -> None:
    """One block per unit on the periods ``m.T`` and scenarios ``m.S`` of ``m`` (MODEL_SPEC §8-§9).

    ``m`` is the model itself or any block carrying its own ``T`` and ``S``, such as
    one scenario of the stochastic benchmark (:mod:`rvpp.settle.recourse`).
    """
    case = problem.case
    m.ndres = pyo.Block([u.name for u in case.ndres])
    for unit in case.ndres:
        add_ndres(m, unit, problem)

    m.csp = pyo.Block([c.name for c in case.csp])
    for csp in case.csp:
        add_csp_solar_field(m, csp, problem)
        add_csp_storage(m, csp, problem)
        add_csp_commitment(m, csp, problem)
        add_csp_power_block(m, csp, problem)
        add_csp_reserves(m, csp, problem)

    m.ed = pyo.Block([d.name for d in case.ed])
    for ed in case.ed:
        add_electrical_demand(m, ed, problem)
    m.td = pyo.Block([k.name for k in case.td])
    for td in case.td:
        add_thermal_demand(m, td, problem)
