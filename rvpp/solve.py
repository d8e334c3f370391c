"""Solve a case: prepare the day, build the MILP, run HiGHS, extract the plan.

:func:`solve` is a pure function of its :class:`~rvpp.case.Case` and returns plain data
(a :class:`~rvpp.results.Result`), never a Pyomo model, so callers can cache it.
"""

from __future__ import annotations

import time
from pathlib import Path
from collections.abc import Callable

import pyomo.environ as pyo
from pyomo.contrib.solver.common.factory import SolverFactory
from pyomo.contrib.solver.common.results import SolutionStatus, TerminationCondition

from .case import Case
from .model import build_model
from .problem import Problem, infeasibility_reasons, prepare
from .results import Result, extract

Progress = Callable[[str], None]


def solve(case: Case, progress: Progress | None = None) -> Result:
    """Compute the robust day-ahead plan of ``case`` for its delivery date."""
    say = progress or (lambda _msg: None)
    started = time.perf_counter()
    say("preparing forecast bands")
    problem = prepare(case)
    return solve_problem(problem, progress=say, started=started)


def solve_problem(problem: Problem, progress: Progress | None = None, started: float | None = None) -> Result:
    """Solve an already prepared :class:`Problem`."""
    say = progress or (lambda _msg: None)
    started = time.perf_counter() if started is None else started
    reasons = infeasibility_reasons(problem)
    if reasons:
        return Result(problem=problem, status="infeasible", termination="not solved",
                      message="; ".join(reasons), build_s=time.perf_counter() - started)
    say(f"building the model ({problem.nt} periods)")
    m = build_model(problem)
    build_s = time.perf_counter() - started
    say("solving with HiGHS")
    outcome = run_highs(m, problem.case.solver)
    if outcome["status"] in ("optimal", "time_limit") and outcome["has_solution"]:
        t0 = time.perf_counter()
        tables = extract(m, problem)
        extract_s = time.perf_counter() - t0
    else:
        tables, extract_s = {}, 0.0
        if outcome["status"] == "time_limit":
            outcome["message"] = "time limit reached before any feasible plan was found"
        if outcome["status"] == "infeasible" and not outcome["message"]:
            outcome["message"] = ("the model is infeasible: the demands cannot be met within the units' "
                                  "limits under the chosen budgets")
    say("done")
    return Result(problem=problem, status=outcome["status"], termination=outcome["termination"],
                  message=outcome["message"], objective_eur=outcome["objective"], bound_eur=outcome["bound"],
                  mip_gap=outcome["gap"], build_s=build_s, solve_s=outcome["seconds"], extract_s=extract_s,
                  **tables)


# HiGHS options that are not exposed as settings. The RINS and RENS sub-MIP
# heuristics spend most of the time on these small, tight models (measured: the
# paper case solves in about half the CPU time without them, to the same optima).
HIGHS_OPTIONS = {"mip_heuristic_run_rins": False, "mip_heuristic_run_rens": False}

# HiGHS sizes one thread pool per process at its first solve and refuses a
# different "threads" value afterwards; the first explicit value is kept here.
_pool_threads: list[int] = []


def _thread_option(requested: int) -> tuple[dict, str]:
    if not requested:
        return {}, ""
    if not _pool_threads:
        _pool_threads.append(requested)
    if requested == _pool_threads[0]:
        return {"threads": requested}, ""
    return {}, (f"threads={requested} ignored: HiGHS already runs this process with "
                f"{_pool_threads[0]} thread(s)")


def run_highs(m: pyo.ConcreteModel, settings, *, load: bool = True) -> dict:
    """Run HiGHS on ``m`` with a fresh solver object; load the incumbent if there is one.

    Returns ``status`` (optimal|time_limit|infeasible|error), ``termination``,
    ``objective``, ``bound``, ``gap``, ``seconds``, ``has_solution`` and ``message``.
    """
    threads, note = _thread_option(settings.threads)
    options = {"time_limit": settings.time_limit_s, "rel_gap": settings.rel_gap, **threads}
    t0 = time.perf_counter()
    try:
        res = SolverFactory("highs").solve(m, load_solutions=False, raise_exception_on_nonoptimal_result=False,
                                           solver_options=dict(HIGHS_OPTIONS), **options)
    except Exception as exc:  # the solver library failed; report, do not crash the caller
        return {"status": "error", "termination": type(exc).__name__, "objective": None, "bound": None,
                "gap": None, "seconds": time.perf_counter() - t0, "has_solution": False,
                "message": f"HiGHS failed: {exc}"}
    seconds = time.perf_counter() - t0
    tc = res.termination_condition
    has_solution = res.solution_status in (SolutionStatus.optimal, SolutionStatus.feasible)
    if tc == TerminationCondition.convergenceCriteriaSatisfied and has_solution:
        status = "optimal"
    elif tc in (TerminationCondition.maxTimeLimit, TerminationCondition.iterationLimit,
                TerminationCondition.interrupted):
        status = "time_limit"
    elif tc in (TerminationCondition.provenInfeasible, TerminationCondition.locallyInfeasible,
                TerminationCondition.infeasibleOrUnbounded):
        status = "infeasible"
    else:
        status = "error"
    objective = res.incumbent_objective if has_solution else None
    bound = res.objective_bound
    bound = None if bound is None or abs(bound) == float("inf") else float(bound)
    gap = None
    if objective is not None and bound is not None:
        gap = abs(bound - objective) / max(abs(objective), 1e-9)
    if has_solution and load:
        res.solution_loader.load_vars()
    message = "" if status in ("optimal", "infeasible") else f"HiGHS stopped: {tc.name}"
    message = "; ".join(part for part in (message, note) if part)
    return {"status": status, "termination": tc.name, "objective": objective, "bound": bound, "gap": gap,
            "seconds": seconds, "has_solution": has_solution, "message": message}


def write_mps(case: Case, path) -> None:
    """Write the MILP of ``case`` as an MPS file (readable names) for other solvers."""
    problem = prepare(case)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    build_model(problem).write(str(path), format="mps", io_options={"symbolic_solver_labels": True})
