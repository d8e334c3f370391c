"""The RVPP bidding model in Pyomo (MODEL_SPEC §2-§9).

:func:`build_model` reads like the paper: one call per constraint family, one block
per asset on the shared periods, system balances and market coupling at the top, then
the robust layer (:mod:`rvpp.model.robust`) and the objective.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pyomo.environ as pyo

from ..uncertainty.problem import Problem
from .robust import add_robustness
from .csp import (add_csp_commitment, add_csp_power_block, add_csp_reserves, add_csp_solar_field,
                  add_csp_storage, add_csp_symmetry)
from ..data.scenarios import SCENARIOS, Scenario, activation
from .market import (add_electric_balance, add_heat_balance, add_market_bids,
                     add_market_limits, add_objective, add_time)
from .units import add_electrical_demand, add_ndres, add_thermal_demand
from .storage import add_battery
from .dispatchable import add_dispatchable
from ..data.case import CSP
from ..data.kinds import UnitKind
from .blocks import UNIT_BLOCKS, unit_block

__all__ = ["build_model", "add_units", "unit_block", "UNIT_BUILDERS", "SCENARIOS", "Scenario", "activation"]


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


def add_csp(m: pyo.Block, csp: CSP, problem: Problem) -> None:
    """One CSP: solar field, thermal storage, turbine commitment, power block, reserves (MODEL_SPEC §8)."""
    add_csp_solar_field(m, csp, problem)
    add_csp_storage(m, csp, problem)
    add_csp_commitment(m, csp, problem)
    add_csp_power_block(m, csp, problem)
    add_csp_reserves(m, csp, problem)


# The model's part of a unit kind (rvpp.data.kinds.KINDS holds its other facts, rvpp.model.blocks
# where its block sits): a new kind adds its builder, build(m, unit, problem), here.
UNIT_BUILDERS: dict[UnitKind, Callable[[pyo.Block, Any, Problem], None]] = {
    UnitKind.WIND: add_ndres,
    UnitKind.PV: add_ndres,
    UnitKind.CSP: add_csp,
    UnitKind.ED: add_electrical_demand,
    UnitKind.TD: add_thermal_demand,
    UnitKind.BATTERY: add_battery,
    UnitKind.HYDRO: add_dispatchable,
    UnitKind.BIOMASS: add_dispatchable,
}


def add_units(m: pyo.Block, problem: Problem) -> None:
    """One block per unit on the periods ``m.T`` and scenarios ``m.S`` of ``m`` (MODEL_SPEC §8-§9).

    ``m`` is the model itself or any block carrying its own ``T`` and ``S``, such as
    one scenario of the stochastic benchmark (:mod:`rvpp.settle.stochastic`).
    """
    case = problem.case
    names: dict[str, list[str]] = {block: [] for block in UNIT_BLOCKS.values()}
    for kind, unit in case.units():
        names[UNIT_BLOCKS[kind]].append(unit.name)
    for block, members in names.items():
        m.add_component(block, pyo.Block(members))
    for kind, unit in case.units():
        UNIT_BUILDERS[kind](m, unit, problem)
