"""How a HiGHS run is reported: only an optimal or a limited run with an incumbent and a
finite bound carries numbers (rvpp.solving.outcome)."""

from __future__ import annotations

import math

import pyomo.environ as pyo
import pytest

from rvpp.data.case import SolverSettings
from rvpp.solving.highs import HighsModel, objective_scale, run_highs
from rvpp.solving.outcome import Outcome, SolveOutcome


def _solve(m: pyo.ConcreteModel):
    return run_highs(m, SolverSettings(rel_gap=0.0, time_limit_s=30))


def test_an_optimal_run_reports_objective_bound_and_zero_gap():
    m = pyo.ConcreteModel()
    m.x = pyo.Var(domain=pyo.NonNegativeIntegers, bounds=(0, 7.5))
    m.obj = pyo.Objective(expr=3 * m.x, sense=pyo.maximize)
    outcome = _solve(m)
    assert isinstance(outcome, SolveOutcome) and outcome.status is Outcome.OPTIMAL and outcome.usable
    assert outcome.objective == pytest.approx(21.0) and outcome.bound == pytest.approx(21.0)
    assert outcome.gap == pytest.approx(0.0, abs=1e-12)
    assert pyo.value(m.x) == pytest.approx(7.0)


def test_an_unbounded_model_is_never_usable_even_with_a_point():
    m = pyo.ConcreteModel()
    m.x = pyo.Var(domain=pyo.NonNegativeReals)
    m.y = pyo.Var(domain=pyo.Binary)
    m.c = pyo.Constraint(expr=m.x >= m.y)
    m.obj = pyo.Objective(expr=m.x + m.y, sense=pyo.maximize)
    outcome = _solve(m)
    assert outcome.status in (Outcome.UNBOUNDED, Outcome.INFEASIBLE_OR_UNBOUNDED)
    assert not outcome.usable and outcome.objective is None and outcome.gap is None
    assert "unbounded" in outcome.message
    assert m.x.value is None  # nothing was loaded into the model


def test_an_infeasible_model_is_its_own_outcome():
    m = pyo.ConcreteModel()
    m.x = pyo.Var(domain=pyo.Binary)
    m.c = pyo.Constraint(expr=m.x >= 2)
    m.obj = pyo.Objective(expr=m.x)
    outcome = _solve(m)
    assert outcome.status in (Outcome.INFEASIBLE, Outcome.INFEASIBLE_OR_UNBOUNDED)
    assert not outcome.usable and outcome.objective is None


@pytest.mark.parametrize("bound", [None, math.inf, -math.inf, math.nan])
def test_a_limit_without_a_finite_bound_carries_no_plan(bound):
    outcome = SolveOutcome.of(Outcome.TIME_LIMIT, "maxTimeLimit", 100.0, bound, 5.0)
    assert outcome.status is Outcome.NO_SOLUTION and not outcome.usable
    assert outcome.objective is None and outcome.bound is None and outcome.gap is None


def test_a_limit_with_incumbent_and_bound_is_usable_with_its_gap():
    outcome = SolveOutcome.of(Outcome.TIME_LIMIT, "maxTimeLimit", -200.0, -190.0, 5.0)
    assert outcome.usable and outcome.gap == pytest.approx(10.0 / 200.0)
    assert "time limit" in outcome.message


def test_outcomes_read_as_their_plain_value():
    assert f"{Outcome.INFEASIBLE_OR_UNBOUNDED}" == "infeasible_or_unbounded"
    assert Outcome("time_limit") is Outcome.TIME_LIMIT
    assert [o for o in Outcome if o.usable] == [Outcome.OPTIMAL, Outcome.TIME_LIMIT, Outcome.STOPPED]


def test_a_kept_model_re_solves_after_its_data_change():
    from rvpp.solving.highs import HighsModel

    m = pyo.ConcreteModel()
    m.cap = pyo.Param(mutable=True, initialize=4.0)
    m.x = pyo.Var(domain=pyo.NonNegativeIntegers)
    m.c = pyo.Constraint(expr=2 * m.x <= m.cap)
    m.obj = pyo.Objective(expr=m.x, sense=pyo.maximize)
    model = HighsModel(m)
    settings = SolverSettings(rel_gap=0.0)
    assert model.solve(settings).objective == pytest.approx(2.0)
    m.cap.set_value(9.0)
    model.refresh()
    start = model.values()  # the previous optimum x = 2 is still feasible: a valid start
    outcome = model.solve(settings, start=start)
    assert outcome.status is Outcome.OPTIMAL and outcome.objective == pytest.approx(4.0)
    assert pyo.value(m.x) == pytest.approx(4.0) and outcome.nodes is not None


def test_a_constraint_without_variables_that_fails_is_infeasible_not_an_error():
    m = pyo.ConcreteModel()
    m.x = pyo.Var(bounds=(0, 1))
    m.x.fix(1.0)
    m.c = pyo.Constraint(expr=m.x >= 2)
    m.obj = pyo.Objective(expr=m.x)
    outcome = _solve(m)
    assert outcome.status is Outcome.INFEASIBLE and not outcome.usable
    assert "c" in outcome.message


def test_a_linear_program_reports_its_objective_as_bound():
    m = pyo.ConcreteModel()
    m.x = pyo.Var(bounds=(0, 2.5))
    m.obj = pyo.Objective(expr=2 * m.x + 1, sense=pyo.maximize)
    outcome = _solve(m)
    assert outcome.status is Outcome.OPTIMAL and outcome.nodes is None
    assert outcome.objective == pytest.approx(6.0) and outcome.bound == pytest.approx(6.0)


@pytest.mark.parametrize("scale", [-12, 0, 3])
def test_a_scaled_objective_reports_in_the_models_units(scale):
    # min 3x + 2y + 7 with x + y ≥ 1.5 on integers: y = 2 gives 11 (x = y = 1 gives 12, x = 2 gives 13).
    m = pyo.ConcreteModel()
    m.x = pyo.Var(domain=pyo.NonNegativeIntegers, bounds=(0, 5))
    m.y = pyo.Var(domain=pyo.NonNegativeIntegers, bounds=(0, 5))
    m.c = pyo.Constraint(expr=m.x + m.y >= 1.5)
    m.obj = pyo.Objective(expr=3 * m.x + 2 * m.y + 7)
    outcome = HighsModel(m).solve(SolverSettings(rel_gap=0.0, time_limit_s=30), scale=scale)
    assert outcome.status is Outcome.OPTIMAL
    assert outcome.objective == pytest.approx(11.0) and outcome.bound == pytest.approx(11.0)
    assert (pyo.value(m.x), pyo.value(m.y)) == pytest.approx((0.0, 2.0))
    # The same with continuous x and y: the LP optimum y = 1.5 gives 10, its own bound.
    m.y.domain = pyo.NonNegativeReals
    m.x.domain = pyo.NonNegativeReals
    outcome = HighsModel(m).solve(SolverSettings(rel_gap=0.0, time_limit_s=30), scale=scale)
    assert outcome.objective == pytest.approx(10.0) and outcome.bound == pytest.approx(10.0)


def test_days_scale_their_objective_except_hourly_days_where_the_solver_places_budgets():
    assert objective_scale(1.0) == objective_scale(0.5) == objective_scale(0.25) < 0
    assert objective_scale(0.5, budget_choices=True) == objective_scale(0.25, budget_choices=True) < 0
    assert objective_scale(1.0, budget_choices=True) == 0


def _knapsack() -> pyo.ConcreteModel:
    """Three items of value 5, 4, 3 and weight 3, 3, 2 in a sack of 4: only the first fits with
    anything of value (optimum 5); the relaxation takes it and half of the third (6.5)."""
    m = pyo.ConcreteModel()
    m.x = pyo.Var([1, 2, 3], domain=pyo.Binary)
    m.spare = pyo.Var(bounds=(0, 4))
    m.sack = pyo.Constraint(expr=3 * m.x[1] + 3 * m.x[2] + 2 * m.x[3] + m.spare == 4)
    m.obj = pyo.Objective(expr=5 * m.x[1] + 4 * m.x[2] + 3 * m.x[3], sense=pyo.maximize)
    return m


def test_a_start_sets_the_named_integer_variables_to_one_and_every_other_to_zero():
    m = _knapsack()
    start = HighsModel(m).start_at_ones(["x[3]", "x[9]", "spare", "csp[CSP1].online[1]"])
    assert {v.name: value for v, value in start.items()} == {"x[1]": 0.0, "x[2]": 0.0, "x[3]": 1.0}
    assert len(HighsModel(m).start_at_ones(())) == 0, "no names is no start, not every variable at zero"


def test_the_integer_variables_at_one_are_named_after_a_solve_and_none_before():
    m = _knapsack()
    highs = HighsModel(m)
    assert highs.integer_ones() == ()
    outcome = highs.solve(SolverSettings(rel_gap=0.0, time_limit_s=30))
    assert outcome.objective == pytest.approx(5.0)
    assert highs.integer_ones() == ("x[1]",)


def test_a_start_reaches_highs_as_a_full_integer_point(monkeypatch):
    import highspy

    passed = []

    class Spy(highspy.Highs):
        def setSolution(self, *args):
            passed.append([list(map(float, a)) if hasattr(a, "__len__") else a for a in args])
            return super().setSolution(*args)

    monkeypatch.setattr(highspy, "Highs", Spy)
    m = _knapsack()
    highs = HighsModel(m)
    outcome = highs.solve(SolverSettings(rel_gap=0.0, time_limit_s=30), start=highs.start_at_ones(["x[2]"]))
    assert outcome.objective == pytest.approx(5.0), "a start that is not optimal must not change the optimum"
    (count, index, value), = passed
    columns = [highs.compiled.columns[int(j)].name for j in index]
    assert count == 3 and dict(zip(columns, value)) == {"x[1]": 0.0, "x[2]": 1.0, "x[3]": 0.0}


# A day whose search is long and finds plans early: 6 April, 15 minutes, balanced (tied deviations; HiGHS's
# first plan within a second lies 16 % below its bound, the proven optimum takes 15-30 s).
SLOW_DAY = {"date": "2025-04-06", "strategy": "balanced", "dt_h": 0.25}


def test_a_watch_asked_before_the_first_plan_stops_the_search_at_it(paper_case):
    import rvpp
    from rvpp.settle.audit import audit_result

    seen = []

    def watch(search) -> bool:
        seen.append(search)
        return True  # from the first look on, before HiGHS has any plan

    result = rvpp.solve(rvpp.with_options(paper_case, **SLOW_DAY), watch=watch)
    assert result.status is Outcome.STOPPED and result.has_plan, result.message
    assert "stopped on request" in result.message
    assert seen and seen[0].objective is None  # the first look came before any plan
    # Not proven optimal: the profit (maximized) lies below the bound by more than the case's gap.
    assert result.objective_eur < result.bound_eur
    assert result.mip_gap == pytest.approx(abs(result.bound_eur - result.objective_eur) / abs(result.objective_eur))
    assert result.mip_gap > paper_case.solver.rel_gap
    assert audit_result(result) == []  # the plan kept is feasible
    times = [s.seconds for s in seen]
    assert times == sorted(times)
    for search in seen:
        if search.objective is not None and search.bound is not None:
            assert search.objective <= search.bound + 1e-6 * abs(search.bound)


def test_a_watch_that_never_stops_leaves_the_solve_as_it_is(paper_solve, paper_case):
    import rvpp

    seen = []
    result = rvpp.solve(rvpp.with_options(paper_case, strategy="pessimistic"),
                        watch=lambda search: seen.append(search) is not None)  # always False
    expected = paper_solve(strategy="pessimistic")
    assert seen and result.status is Outcome.OPTIMAL
    assert result.objective_eur == pytest.approx(expected.objective_eur,
                                                 abs=paper_case.solver.rel_gap * abs(expected.objective_eur))


@pytest.mark.parametrize("error", [ValueError("the watch broke"), KeyboardInterrupt()])
def test_an_error_in_the_watch_reaches_the_caller(paper_case, error):
    import rvpp

    def watch(search):
        raise error

    with pytest.raises(type(error)):
        rvpp.solve(rvpp.with_options(paper_case, **SLOW_DAY), watch=watch)
