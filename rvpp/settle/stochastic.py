"""The stochastic benchmark (MODEL_SPEC §10; the paper's comparison with its reference [2]).

Expected profit over Monte Carlo scenarios of whole days, one recourse copy
(:mod:`rvpp.settle.recourse`) per scenario sharing the first-stage bids, solved from a chain
of MIP starts.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyomo.environ as pyo
from pyomo.common.collections import ComponentMap

from ..data.case import Case
from ..errors import RvppError
from ..solving.highs import HighsModel
from ..solving.outcome import Outcome
from ..uncertainty.problem import Problem
from .recourse import (FIRST_STAGE, SETTLE_OPTIONS, FirstStage, Penalties, Realization, build_recourse_model,
                       realized_problem)

START_STEP = 5  # the stochastic benchmark starts from the bids of its solve over this many scenarios fewer
START_GAP = 1e-3  # smallest relative gap of the solves that build that MIP start
MIN_SOLVE_S = 1.0  # the last solve of the stochastic benchmark runs at least this long [s]
# With a start close to the optimum, HiGHS's neighbourhood searches around it (RINS, RENS; off
# for the single-day plans, where they cost more than they find) improve it quickly.
IMPROVE_START = {"mip_heuristic_run_rins": True, "mip_heuristic_run_rens": True}


@dataclass(frozen=True, eq=False)
class StochasticPlan:
    """First-stage bids of the scenario-based benchmark and how the solve ended."""

    bids: FirstStage | None
    status: Outcome
    expected_profit_eur: float | None
    bound_eur: float | None
    mip_gap: float | None
    solve_s: float
    build_s: float
    n_scenarios: int
    message: str = ""
    nodes: int | None = None
    lp_iterations: int | None = None
    start_s: float = 0.0


def solve_stochastic(case: Case, scenarios: Sequence[Realization],
                     penalties: Penalties = Penalties()) -> StochasticPlan:
    """Maximize expected profit over equally likely ``scenarios`` with shared bids.

    The stochastic benchmark of MODEL_SPEC §10 (the paper's comparison with its
    reference [2]): one recourse copy per scenario, the same first-stage variables.
    Solved with the case's solver settings (time limit, gap); the status and gap
    are reported as HiGHS ends.

    With more than :data:`START_STEP` scenarios, HiGHS starts from a complete
    incumbent: the bids of the same benchmark over all but the last :data:`START_STEP`
    scenarios (solved first, the same way, to a gap of at least :data:`START_GAP`) and
    every new scenario's best recourse to them (one single-day solve each; the others keep
    their recourse from that solve). For 25
    scenarios that is a chain 5 → 10 → 15 → 20 → 25, each solve starting from the bids
    of the one before, so the search only has to improve on a near-optimal plan and
    close the bound instead of looking for a first plan in the whole tree; HiGHS's
    neighbourhood searches (:data:`IMPROVE_START`) improve it. The chain
    takes at most half of the time left under the case's time limit at each step, so
    the whole call stays within that limit.
    """
    if not scenarios:
        raise RvppError("the stochastic benchmark needs at least one scenario")
    return _solve_chain(case, scenarios, penalties, case.solver.time_limit_s)[0]


def _solve_chain(case: Case, scenarios: Sequence[Realization], penalties: Penalties,
                 limit: float) -> tuple[StochasticPlan, pyo.ConcreteModel]:
    """:func:`solve_stochastic` within ``limit`` seconds, with its solved model."""
    started = time.perf_counter()
    problems = [realized_problem(case, real) for real in scenarios]
    m = build_recourse_model(problems, penalties)
    build_s = time.perf_counter() - started
    start = ComponentMap()
    if len(scenarios) > START_STEP:
        quick = case.model_copy(update={"solver": case.solver.model_copy(
            update={"rel_gap": max(case.solver.rel_gap, START_GAP)})})
        share = (limit - (time.perf_counter() - started)) / 2
        first, solved = _solve_chain(quick, scenarios[:len(scenarios) - START_STEP], penalties, share)
        if first.bids is not None:
            start = recourse_start(m, case, problems, penalties, first.bids, solved)
    start_s = time.perf_counter() - started - build_s
    left = max(limit - (time.perf_counter() - started), MIN_SOLVE_S)
    outcome = HighsModel(m).solve(case.solver.model_copy(update={"time_limit_s": left}), start=start,
                                  options=IMPROVE_START)
    bids = None
    if outcome.usable:
        bids = FirstStage(*(np.array([float(pyo.value(getattr(m, name)[t])) for t in m.T]) for name in FIRST_STAGE))
    flip = (lambda v: None if v is None else -v)
    plan = StochasticPlan(bids=bids, status=outcome.status, expected_profit_eur=flip(outcome.objective),
                          bound_eur=flip(outcome.bound), mip_gap=outcome.gap, solve_s=outcome.seconds,
                          build_s=build_s, n_scenarios=len(scenarios), message=outcome.message,
                          nodes=outcome.nodes, lp_iterations=outcome.lp_iterations, start_s=start_s)
    return plan, m


def recourse_start(m: pyo.ConcreteModel, case: Case, problems: Sequence[Problem], penalties: Penalties,
                   bids: FirstStage, solved: pyo.ConcreteModel | None = None) -> ComponentMap:
    """A complete MIP start for the stochastic model ``m``: ``bids`` and each scenario's best
    recourse to them (the recourse has slacks, so any bids fit every scenario).

    ``solved`` is a stochastic model over the first scenarios of ``m`` whose solution holds
    ``bids``: its scenarios keep the recourse found there, only the others are solved.
    """
    settings = case.solver.model_copy(update={"rel_gap": max(case.solver.rel_gap, START_GAP)})
    start = ComponentMap()
    for name in FIRST_STAGE:
        for t in m.T:
            start[getattr(m, name)[t]] = float(getattr(bids, name)[t - 1])
    known = len(solved.scenario) if solved is not None else 0
    for k, problem in enumerate(problems):
        if k < known:
            block = solved.scenario[k]
            source = ComponentMap((theirs, theirs.value) for theirs in _block_vars(block))
        else:
            single = build_recourse_model([problem], penalties, bids)
            block = single.scenario[0]
            recourse = HighsModel(single)
            if not recourse.solve(settings, load=False, options=SETTLE_OPTIONS).usable:
                return ComponentMap()
            source = recourse.values()
        # Every scenario block comes from add_scenario, so their variables are created in the same order.
        for mine, theirs in zip(_block_vars(m.scenario[k]), _block_vars(block)):
            value = source[theirs] if theirs in source else None
            if value is not None:
                start[mine] = value
    return start


def _block_vars(b: pyo.Block) -> list:
    return list(b.component_data_objects(pyo.Var, descend_into=True, sort=False))
