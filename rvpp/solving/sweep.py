"""A delivery day re-solved for a grid of budgets Γ without rebuilding the model.

The model of the day is built once, at the smallest Γ of the grid, and kept in a
:class:`~rvpp.solving.persistent.DayModel`: every further Γ only changes the mutable
budgets and the fixed χ of the robust layer, recompiles the matrix and re-solves,
starting HiGHS from the commitment, storage modes and curve segments of the
neighbouring Γ. Each
point is the same plain :class:`~rvpp.solving.results.Result` that
``rvpp.solve(with_options(case, gammas=...))`` returns for it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Sequence

from ..data.case import Case, with_options
from ..errors import RvppError
from .persistent import DayModel
from .problem import Problem, prepare, strategy_budgets
from .results import Result

Progress = Callable[[int, int], None]


def sweep_gamma(case: Case, gammas: Iterable[int], sources: Sequence[str] | None = None,
                progress: Progress | None = None) -> list[Result]:
    """Plans of ``case`` with Γ = g for every source in ``sources`` (default: all), for each g.

    Results come in the order of ``gammas``; sources not named keep the case's budgets.
    ``progress(done, total)`` is called before the first solve and after each.
    """
    grid = [int(g) for g in gammas]
    if not grid:
        return []
    names = list(sources) if sources else case.sources()
    unknown = [n for n in names if n not in case.sources()]
    if unknown:
        raise RvppError(f"sources: unknown source {unknown[0]!r}; choose from {', '.join(case.sources())}")
    base = prepare(with_options(case, gammas={name: min(grid) for name in names}))
    outside = [g for g in grid if not 0 <= g <= base.nt]
    if outside:
        raise RvppError(f"Γ grid: {outside[0]} is outside 0..{base.nt}, the periods of {case.delivery_date}")
    report = progress or (lambda _done, _total: None)
    order = sorted(set(grid))
    report(0, len(order))
    day = DayModel()
    solved: dict[int, Result] = {}
    for done, gamma in enumerate(order, start=1):
        solved[gamma] = day.solve(with_budgets(base, with_options(case, gammas={name: gamma for name in names})))
        report(done, len(order))
    return [solved[g] for g in grid]


def with_budgets(problem: Problem, case: Case) -> Problem:
    """``problem`` (same day, same bands) with the budgets of ``case``."""
    budgets = strategy_budgets(case, problem.nt)
    sources = {name: dataclasses.replace(source, gamma=budgets[name]) for name, source in problem.sources.items()}
    return dataclasses.replace(problem, case=case, sources=sources)
