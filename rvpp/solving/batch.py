"""Solve many cases, serially or through any ``concurrent.futures.Executor``.

Workers build and solve in their own process and return plain results; HiGHS gets
one thread per solve when solves run side by side, so workers do not oversubscribe
the cores. :func:`run_many` is the general form (any picklable function applied to a
list of tasks) that the studies of :mod:`rvpp.studies` use for recourse evaluations.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed
from typing import Any, TypeVar

from ..data.case import Case
from .results import Result
from .plan import solve

Progress = Callable[[int, int], None]
Task = TypeVar("Task")


def solve_many(cases: Sequence[Case], executor: Executor | None = None,
               progress: Progress | None = None) -> list[Result]:
    """Results in the order of ``cases``; ``progress(done, total)`` before the first solve and after each."""
    if executor is not None:
        cases = [case.replace(solver={"threads": 1}) if case.solver.threads != 1 else case for case in cases]
    return run_many(solve, cases, executor, progress)


def run_many(function: Callable[[Task], Any], tasks: Sequence[Task], executor: Executor | None = None,
             progress: Progress | None = None) -> list[Any]:
    """``function(task)`` for every task, in the order of ``tasks``.

    Serial without an executor; otherwise every task is submitted at once.
    ``progress(done, total)`` is called once with ``done=0`` before the first task (so a
    long first task already shows its stage) and then as results arrive.
    ``function`` must be a module-level function so it can be sent to worker processes.
    """
    total = len(tasks)
    report = progress or (lambda _done, _total: None)
    report(0, total)
    if executor is None:
        results = []
        for i, task in enumerate(tasks, start=1):
            results.append(function(task))
            report(i, total)
        return results
    futures = {executor.submit(function, task): i for i, task in enumerate(tasks)}
    results: list[Any] = [None] * total
    for done, future in enumerate(as_completed(futures), start=1):
        results[futures[future]] = future.result()
        report(done, total)
    return results
