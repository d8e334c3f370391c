"""Run HiGHS through Pyomo's solver interface and report the outcome as a :class:`SolveOutcome`."""

from __future__ import annotations

import threading
import time

import pyomo.environ as pyo
from pyomo.contrib.solver.common.factory import SolverFactory
from pyomo.contrib.solver.common.results import SolutionStatus, TerminationCondition

from .outcome import Outcome, SolveOutcome

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


def run_highs(m: pyo.ConcreteModel, settings, *, load: bool = True) -> SolveOutcome:
    """Run HiGHS on ``m`` with a fresh solver object; load the incumbent if it is usable.

    Safe to call from several threads: solves in one process take turns (use
    processes, e.g. :func:`rvpp.solving.batch.solve_many` with a process pool, to run in parallel).
    A point HiGHS returns with any ending other than optimal, or a limit with a finite
    bound, is not loaded (see :mod:`rvpp.solving.outcome`).
    """
    threads, note = _thread_option(settings.threads)
    options = {"time_limit": settings.time_limit_s, "rel_gap": settings.rel_gap, **threads}
    try:
        with _solver_lock:
            t0 = time.perf_counter()
            res = SolverFactory("highs").solve(m, load_solutions=False, raise_exception_on_nonoptimal_result=False,
                                               solver_options=dict(HIGHS_OPTIONS), **options)
    except Exception as exc:  # the solver library failed; report, do not crash the caller
        return SolveOutcome.of(Outcome.ERROR, type(exc).__name__, None, None, 0.0, f"HiGHS failed: {exc}")
    seconds = time.perf_counter() - t0
    tc = res.termination_condition
    has_point = res.solution_status in (SolutionStatus.optimal, SolutionStatus.feasible)
    status = _OUTCOMES.get(tc, Outcome.ERROR)
    if status is Outcome.OPTIMAL and not has_point:
        status = Outcome.ERROR
    if status is Outcome.ERROR:
        note = "; ".join(part for part in (f"HiGHS stopped: {tc.name}", note) if part)
    outcome = SolveOutcome.of(status, tc.name, res.incumbent_objective if has_point else None,
                              res.objective_bound, seconds, note)
    if outcome.usable and load:
        res.solution_loader.load_vars()
    return outcome


_OUTCOMES = {
    TerminationCondition.convergenceCriteriaSatisfied: Outcome.OPTIMAL,
    TerminationCondition.maxTimeLimit: Outcome.TIME_LIMIT,
    TerminationCondition.iterationLimit: Outcome.TIME_LIMIT,
    TerminationCondition.interrupted: Outcome.TIME_LIMIT,
    TerminationCondition.objectiveLimit: Outcome.TIME_LIMIT,
    TerminationCondition.provenInfeasible: Outcome.INFEASIBLE,
    TerminationCondition.locallyInfeasible: Outcome.INFEASIBLE,
    TerminationCondition.unbounded: Outcome.UNBOUNDED,
    TerminationCondition.infeasibleOrUnbounded: Outcome.INFEASIBLE_OR_UNBOUNDED,
}
