"""A delivery day re-solved for a grid of budgets Γ without rebuilding the model.

The grid is sorted and each part of it walked by a
:class:`~rvpp.solving.persistent.DayModel`: the model is built once, at the part's
smallest Γ, and every further Γ only changes the mutable budgets and the fixed χ of
the robust layer, recompiles the matrix and re-solves, starting HiGHS from the
commitment, storage modes and curve segments of the neighbouring Γ. On two cores two
threads take the parts in turn (HiGHS runs side by side): each Γ at which the solver
must choose among tied deviations is a part of its own (such a plan takes many times
longer than the others and gains nothing measurable from its neighbour's start), and
the other Γ are cut into one contiguous part per thread (:func:`sweep_parts`). Every
part has its own model, so a plan does not depend on which thread solved it. Each point
is the same plain :class:`~rvpp.solving.results.Result` that
``rvpp.solve(with_options(case, gammas=...))`` returns for it.
"""

from __future__ import annotations

import dataclasses
import os
import queue
import threading
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..data.case import Case
from ..data.variants import with_options
from ..data.periods import delivery_periods
from ..errors import RvppError
from .persistent import DayModel
from ..uncertainty.problem import Problem, prepare, strategy_budgets, tied_budgets
from .results import Result

Progress = Callable[[int, int], None]


def check_gamma_grid(grid: Iterable[float], case: Case) -> None:
    """Refuse a Γ outside 0..NT, the periods of the case's delivery day, by value."""
    nt = len(delivery_periods(case.delivery_date, case.timezone, case.dt_h))
    outside = [g for g in grid if not 0 <= g <= nt]
    if outside:
        raise RvppError(f"Γ grid: {outside[0]:g} is outside 0..{nt}, the periods of {case.delivery_date}")


def sweep_gamma(case: Case, gammas: Iterable[int], sources: Sequence[str] | None = None,
                progress: Progress | None = None, workers: int | None = None) -> list[Result]:
    """Plans of ``case`` with Γ = g for every source in ``sources`` (default: all), for each g.

    Results come in the order of ``gammas``; sources not named keep the case's budgets.
    ``progress(done, total)`` is called before the first solve and after each.
    ``workers`` threads take the parts of the sorted grid (:func:`sweep_parts`) in turn, each
    part walked with a model of its own (default: two on a machine with two cores or more,
    one when the case's solver is limited to one thread, as in a process pool).
    """
    grid = [int(g) for g in gammas]
    if not grid:
        return []
    names = list(sources) if sources else case.sources()
    unknown = [n for n in names if n not in case.sources()]
    if unknown:
        raise RvppError(f"sources: unknown source {unknown[0]!r}; choose from {', '.join(case.sources())}")
    check_gamma_grid(grid, case)
    base = prepare(with_options(case, gammas={name: min(grid) for name in names}))
    problems = {g: with_budgets(base, with_options(case, gammas={name: g for name in names}))
                for g in sorted(set(grid))}
    if workers is None:
        workers = 1 if case.solver.threads == 1 else min(2, os.cpu_count() or 1)
    parts = queue.SimpleQueue()
    for part in sweep_parts(problems, workers):
        parts.put(part)
    report = progress or (lambda _done, _total: None)
    report(0, len(problems))
    solved: dict[int, Result] = {}
    lock = threading.Lock()

    def walk() -> None:
        while True:
            try:
                part = parts.get_nowait()
            except queue.Empty:
                return
            day = DayModel()
            for gamma in part:
                result = day.solve(problems[gamma])
                with lock:
                    solved[gamma] = result
                    report(len(solved), len(problems))

    threads = max(1, min(workers, parts.qsize()))
    if threads == 1:
        walk()
    else:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            for future in [pool.submit(walk) for _ in range(threads)]:
                future.result()
    return [solved[g] for g in grid]


def sweep_parts(problems: dict[int, Problem], workers: int) -> list[list[int]]:
    """The sorted Γ of ``problems`` cut into the parts that ``workers`` threads walk, in the order
    they are taken: each Γ at which the solver must choose among tied deviations
    (:func:`~rvpp.uncertainty.problem.tied_budgets`) alone, then the other Γ in ``workers``
    contiguous parts; one part when there is one worker."""
    order = sorted(problems)
    if workers <= 1:
        return [order]
    tied = [g for g in order if tied_budgets(problems[g])]
    rest = [g for g in order if g not in tied]
    runs = np.array_split(np.array(rest, dtype=int), min(workers, len(rest))) if rest else []
    return [[g] for g in tied] + [run.tolist() for run in runs]


def with_budgets(problem: Problem, case: Case) -> Problem:
    """``problem`` (same day, same bands) with the budgets of ``case``."""
    budgets = strategy_budgets(case, problem.nt)
    sources = {name: dataclasses.replace(source, gamma=budgets[name]) for name, source in problem.sources.items()}
    return dataclasses.replace(problem, case=case, sources=sources)
