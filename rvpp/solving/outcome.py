"""How a solve ended, as a type: an enum of outcomes and a small frozen record.

A plan (or a settlement) is *usable* only when the solver proved optimality within
the gap, or stopped on a limit with a feasible incumbent and a finite bound. Every
other ending carries no numbers: an unbounded model, an "infeasible or unbounded"
answer from presolve, a limit reached before any feasible point, a solver error.
Callers branch on :attr:`SolveOutcome.usable` or on the :class:`Outcome` member,
never on strings. :class:`Outcome` is a ``StrEnum``, so tables, CSV and JSON show its
plain value (``optimal``, ``time_limit``, ...).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum


class Outcome(StrEnum):
    """How HiGHS ended a solve."""

    OPTIMAL = "optimal"                  # proven optimal within the relative gap
    TIME_LIMIT = "time_limit"            # stopped on a limit with a feasible incumbent and a finite bound
    STOPPED = "stopped"                  # stopped on request (a watch of the search) with a feasible incumbent
    NO_SOLUTION = "no_solution"          # stopped on a limit before any usable incumbent
    INFEASIBLE = "infeasible"            # proven infeasible
    UNBOUNDED = "unbounded"              # proven unbounded
    INFEASIBLE_OR_UNBOUNDED = "infeasible_or_unbounded"  # presolve could not tell which
    ERROR = "error"                      # the solver failed or ended for another reason

    @property
    def usable(self) -> bool:
        """True when the incumbent may be read as a plan or a settlement."""
        return self in (Outcome.OPTIMAL, Outcome.TIME_LIMIT, Outcome.STOPPED)


MESSAGES = {
    Outcome.OPTIMAL: "",
    Outcome.TIME_LIMIT: "stopped on its time limit with a feasible plan that may not be optimal",
    Outcome.STOPPED: "stopped on request with the best plan found so far, which may not be optimal",
    Outcome.NO_SOLUTION: "time limit reached before any feasible plan was found",
    Outcome.INFEASIBLE: "no feasible plan",
    Outcome.UNBOUNDED: ("the model is unbounded: some decision can grow without limit and improve the "
                        "objective forever, which points to a missing limit or a price of the wrong sign"),
    Outcome.INFEASIBLE_OR_UNBOUNDED: ("HiGHS found the model infeasible or unbounded without telling "
                                      "which; no plan"),
    Outcome.ERROR: "the solver failed",
}


@dataclass(frozen=True)
class SolveOutcome:
    """One solver run: outcome, incumbent objective and bound, relative gap, wall time [s],
    and the search's size (branch-and-bound nodes, simplex iterations) where HiGHS reports it.

    ``objective`` is ``None`` unless the outcome is usable; ``bound`` is ``None`` unless it
    is finite; ``termination`` keeps the solver interface's own name for the ending.
    """

    status: Outcome
    termination: str
    objective: float | None = None
    bound: float | None = None
    gap: float | None = None
    seconds: float = 0.0
    message: str = ""
    nodes: int | None = None
    lp_iterations: int | None = None

    @property
    def usable(self) -> bool:
        return self.status.usable

    @classmethod
    def of(cls, status: Outcome, termination: str, objective: float | None, bound: float | None,
           seconds: float, note: str = "", nodes: int | None = None,
           lp_iterations: int | None = None) -> "SolveOutcome":
        """Build a consistent record: numbers only where usable, the gap from objective and bound."""
        bound = bound if bound is not None and math.isfinite(bound) else None
        if status in (Outcome.TIME_LIMIT, Outcome.STOPPED) and (objective is None or bound is None):
            status = Outcome.NO_SOLUTION
        if not status.usable:
            objective = None
        gap = relative_gap(objective, bound)
        message = "; ".join(part for part in (MESSAGES[status], note) if part)
        return cls(status, termination, objective, bound, gap, seconds, message, nodes, lp_iterations)


def relative_gap(objective: float | None, bound: float | None) -> float | None:
    """How far the optimum may lie from a plan's ``objective``, given the ``bound`` on it, relative
    to the objective; ``None`` without both."""
    if objective is None or bound is None:
        return None
    return abs(bound - objective) / max(abs(objective), 1e-9)


@dataclass(frozen=True)
class Search:
    """A MIP search under way: seconds since HiGHS started, the best plan's objective and the
    bound on the optimum (the model's units, ``None`` until HiGHS has them), their relative
    gap (``None`` without a plan), and the branch-and-bound nodes explored. Plain data, so a
    solver process can send it to a process that never imports the solver."""

    seconds: float
    objective: float | None
    bound: float | None
    gap: float | None
    nodes: int


# Shown the search every quarter second (rvpp.solving.highs.WATCH_S); returns True to end it with
# the best plan found so far. Asked before there is a plan, the search ends once it has one.
Watch = Callable[[Search], bool]
