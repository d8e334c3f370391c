"""Run HiGHS through Pyomo's solver interface and report the outcome as plain data."""

from __future__ import annotations

import threading
import time

import pyomo.environ as pyo
from pyomo.contrib.solver.common.factory import SolverFactory
from pyomo.contrib.solver.common.results import SolutionStatus, TerminationCondition

# HiGHS options that are not exposed as settings. The RINS and RENS sub-MIP
# heuristics spend most of the time on these small, tight models (measured: the
# paper case solves in about half the CPU time without them, to the same optima).
HIGHS_OPTIONS = {"mip_heuristic_run_rins": False, "mip_heuristic_run_rens": False}

# Pyomo's HiGHS interface redirects the process's output streams while it solves, so
# two solves in threads of one process would interfere; they take turns instead.
_solver_lock = threading.Lock()

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

    Safe to call from several threads: solves in one process take turns (use
    processes, e.g. :func:`rvpp.solving.batch.solve_many` with a process pool, to run in parallel).

    Returns ``status`` (optimal|time_limit|infeasible|error), ``termination``,
    ``objective``, ``bound``, ``gap``, ``seconds``, ``has_solution`` and ``message``.
    """
    threads, note = _thread_option(settings.threads)
    options = {"time_limit": settings.time_limit_s, "rel_gap": settings.rel_gap, **threads}
    try:
        with _solver_lock:
            t0 = time.perf_counter()
            res = SolverFactory("highs").solve(m, load_solutions=False, raise_exception_on_nonoptimal_result=False,
                                               solver_options=dict(HIGHS_OPTIONS), **options)
    except Exception as exc:  # the solver library failed; report, do not crash the caller
        return {"status": "error", "termination": type(exc).__name__, "objective": None, "bound": None,
                "gap": None, "seconds": 0.0, "has_solution": False,
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
