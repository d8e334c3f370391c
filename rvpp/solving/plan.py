"""Solve a case: prepare the day, build the MILP, run HiGHS, extract the plan.

:func:`solve` is a pure function of its :class:`~rvpp.data.case.Case` and returns plain data
(a :class:`~rvpp.solving.results.Result`), never a Pyomo model, so callers can cache it.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from collections.abc import Callable

from ..data.case import Case
from ..errors import require
from .diagnose import explain_infeasibility
from .highs import HighsModel, model_lifetime, objective_scale
from .outcome import Outcome, SolveOutcome, Watch
from ..model import build_model
from ..model.session import schedule_of
from ..uncertainty.problem import Problem, infeasibility_reasons, prepare
from ..model.robust import budget_choices
from .extract import extract
from .results import Result
from ..data.files import replacing

Progress = Callable[[str], None]


def solve(case: Case, progress: Progress | None = None, watch: Watch | None = None,
          keep_schedule: bool = False) -> Result:
    """Compute the robust day-ahead plan of ``case`` for its delivery date.

    ``watch`` is shown the solver's search as it goes (:class:`~rvpp.solving.outcome.Search`:
    the best plan's objective, the bound, their gap) and may end it early, keeping the best
    plan found so far: the result's status is then ``stopped``, with its gap. ``keep_schedule``: the
    result carries every unit variable's value (:attr:`Result.schedule`, for intraday sessions).
    """
    require(case, Case, "rvpp.solve: case", "from rvpp.load_case")
    say = progress or (lambda _msg: None)
    started = time.perf_counter()
    say("preparing forecast bands")
    problem = prepare(case)
    return solve_problem(problem, progress=say, started=started, watch=watch, keep_schedule=keep_schedule)


def solve_problem(problem: Problem, progress: Progress | None = None, started: float | None = None,
                  watch: Watch | None = None, keep_schedule: bool = False) -> Result:
    """Solve an already prepared :class:`Problem` (``watch``: as for :func:`solve`).

    The Pyomo model lives inside :func:`~rvpp.solving.highs.model_lifetime` (the cyclic
    collector paused, the model collected young).
    """
    with model_lifetime():
        return _solve_problem(problem, progress, started, watch, keep_schedule)


def _solve_problem(problem: Problem, progress: Progress | None, started: float | None,
                   watch: Watch | None = None, keep_schedule: bool = False) -> Result:
    say = progress or (lambda _msg: None)
    started = time.perf_counter() if started is None else started
    reasons = infeasibility_reasons(problem)
    if reasons:
        return not_solved(problem, reasons, time.perf_counter() - started)
    say(f"building the model ({problem.nt} periods)")
    m = build_model(problem)
    build_s = time.perf_counter() - started
    say("solving with HiGHS")
    highs = HighsModel(m)
    outcome = highs.solve(problem.case.solver, start=highs.start_at_ones(problem.case.solver.mip_start),
                          scale=day_scale(problem, m), watch=watch)
    result = plan_result(problem, m, outcome, build_s, say, highs.integer_ones())
    if keep_schedule and result.has_plan:
        result = dataclasses.replace(result, schedule=schedule_of(m, problem))
    return result


def day_scale(problem: Problem, m) -> int:
    """The objective scale HiGHS solves ``m``, the model of ``problem``, with
    (:func:`~rvpp.solving.highs.objective_scale`)."""
    return objective_scale(problem.dt_h, budget_choices(m))


def not_solved(problem: Problem, reasons: list[str], build_s: float) -> Result:
    """The result of a day whose infeasibility is named before solving."""
    return Result(problem=problem, status=Outcome.INFEASIBLE, termination="not solved",
                  message="; ".join(reasons), build_s=build_s)


def plan_result(problem: Problem, m, outcome: SolveOutcome, build_s: float, progress: Progress | None = None,
                integer_ones: tuple[str, ...] = ()) -> Result:
    """Plain tables of a solved model, or the explanation of an infeasible day (``integer_ones``: see
    :attr:`Result.integer_ones`)."""
    say = progress or (lambda _msg: None)
    tables, extract_s, message = {}, 0.0, outcome.message
    if outcome.usable:
        t0 = time.perf_counter()
        tables = extract(m, problem)
        extract_s = time.perf_counter() - t0
    elif outcome.status in (Outcome.INFEASIBLE, Outcome.INFEASIBLE_OR_UNBOUNDED):
        say("explaining the infeasibility")
        why = explain_infeasibility(problem)
        if why:
            message = "no feasible plan: " + why
        elif outcome.status is Outcome.INFEASIBLE:
            message = "no feasible plan: the units' limits cannot all be met"
    say("done")
    return Result(problem=problem, status=outcome.status, termination=outcome.termination, message=message,
                  objective_eur=outcome.objective, bound_eur=outcome.bound, mip_gap=outcome.gap, build_s=build_s,
                  solve_s=outcome.seconds, extract_s=extract_s, nodes=outcome.nodes,
                  lp_iterations=outcome.lp_iterations, integer_ones=integer_ones, **tables)


MPS_HEADERS = (b"*", b"NAME")  # how an MPS file begins: comment lines, then its NAME


def write_mps(case: Case, path) -> None:
    """Write the MILP of ``case`` as an MPS file (readable names) for other solvers.

    The file is written beside ``path`` and renamed into place, so ``path`` is never seen
    half-written.
    """

    problem = prepare(case)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    model = build_model(problem)
    with replacing(path) as temporary:
        model.write(str(temporary), format="mps", io_options={"symbolic_solver_labels": True})
