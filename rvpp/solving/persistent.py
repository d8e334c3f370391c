"""A day model kept between solves, for sweeps and backtests.

:class:`DayModel` solves a sequence of :class:`~rvpp.uncertainty.problem.Problem` objects:

* when only the budgets Γ change (same case, day and bands), the built Pyomo model is
  kept: the mutable budgets and the fixed χ are updated in place
  (:func:`rvpp.model.robust.set_budgets`) and the matrix is recompiled, with no
  rebuild;
* when anything else changes (another day, other bands or bounds, the storage's initial
  energy ``e_init_mwh_th``, the turbine's ``initially_on``), the model is rebuilt for
  the new data;

and every solve starts HiGHS from the integer part of the previous plan (commitment,
storage modes, curve segments), the neighbouring Γ of a sweep; the first from the solver
settings' ``mip_start`` when the case has one. HiGHS checks the start and ignores it when
it does not fit the new data, so a start never changes the optimum, only the time to
reach it.
"""

from __future__ import annotations

import threading
import time

from pyomo.common.collections import ComponentMap

from ..model import build_model
from ..model.csp import identical_csp_pairs
from .highs import HighsModel
from .plan import day_scale, not_solved, plan_result
from ..uncertainty.problem import Problem, infeasibility_reasons
from .results import Result
from ..model.robust import set_budgets

# Model building and extraction are Python work and Pyomo keeps some shared state; only
# HiGHS runs of day models in different threads go side by side.
_PYOMO = threading.Lock()


class DayModel:
    """Solve problems one after another, rebuilding the model only when its data change."""

    def __init__(self) -> None:
        self.problem: Problem | None = None
        self.model = None
        self.highs: HighsModel | None = None
        self.rebuilds = 0
        self._start = ComponentMap()

    def solve(self, problem: Problem) -> Result:
        """The plan of ``problem``, as :func:`rvpp.solve_problem` returns it."""
        started = time.perf_counter()
        reasons = infeasibility_reasons(problem)
        if reasons:
            return not_solved(problem, reasons, time.perf_counter() - started)
        with _PYOMO:
            if self._budgets_only(problem):
                set_budgets(self.model, problem)
                self.highs.refresh()
            else:
                # The start's variables belong to the model being replaced and are found again by
                # their names; that model is cyclic garbage once replaced, and a collection would
                # detach its variables from their names, so it is kept until they are read.
                previous = self.model
                self.model = build_model(problem)
                self.highs = HighsModel(self.model)
                self.rebuilds += 1
                self._start = self._by_name(self._start)
                del previous
        self.problem = problem
        build_s = time.perf_counter() - started
        start = self._start or self.highs.start_at_ones(problem.case.solver.mip_start)
        outcome = self.highs.solve(problem.case.solver, start=start, scale=day_scale(problem, self.model))
        if outcome.usable:
            self._start = self.highs.values(integer_only=True)
        with _PYOMO:
            return plan_result(problem, self.model, outcome, build_s, integer_ones=self.highs.integer_ones())

    def _budgets_only(self, problem: Problem) -> bool:
        """True when ``problem`` differs from the built one in its budgets alone, and no solar
        field's budget falls below the one the model was built with (see ``set_budgets``)."""
        built = self.problem
        if built is None or self.model is None:
            return False
        if built.day != problem.day or built.case.history is not problem.case.history:
            return False
        if not built.bands.equals(problem.bands):
            return False
        if any(problem.sources[c.name].gamma < self.model.robust[c.name].built_gamma for c in problem.case.csp):
            return False
        if identical_csp_pairs(problem) != identical_csp_pairs(built):
            return False  # the order of interchangeable CSPs holds only among equal budgets
        strip = lambda case: {k: v for k, v in case.to_data().items() if k != "budgets"}  # noqa: E731
        same_variant = (built.case.budgets.mode, built.case.budgets.ties) == \
            (problem.case.budgets.mode, problem.case.budgets.ties)
        return strip(built.case) == strip(problem.case) and same_variant

    def _by_name(self, values: ComponentMap) -> ComponentMap:
        """Values of another model's variables moved to the current model's variables of the same name."""
        start = ComponentMap()
        for old, value in values.items():
            var = self.model.find_component(old.name)
            if var is not None and not var.fixed:
                start[var] = value
        return start
