"""Solve many cases, serially or through any ``concurrent.futures.Executor``.

Workers build and solve in their own process and return plain results; HiGHS gets
one thread per solve when solves run side by side, so workers do not oversubscribe
the cores.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed

from .case import Case
from .results import Result
from .solving import solve

Progress = Callable[[int, int], None]


def solve_many(cases: Sequence[Case], executor: Executor | None = None,
               progress: Progress | None = None) -> list[Result]:
    """Results in the order of ``cases``; ``progress(done, total)`` after each solve."""
    total = len(cases)
    report = progress or (lambda _done, _total: None)
    if executor is None:
        results = []
        for i, case in enumerate(cases, start=1):
            results.append(solve(case))
            report(i, total)
        return results
    single = [case.replace(solver={"threads": 1}) if case.solver.threads != 1 else case for case in cases]
    futures = {executor.submit(solve, case): i for i, case in enumerate(single)}
    results: list[Result | None] = [None] * total
    for done, future in enumerate(as_completed(futures), start=1):
        results[futures[future]] = future.result()
        report(done, total)
    return results  # type: ignore[return-value]
