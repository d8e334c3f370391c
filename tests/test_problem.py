"""The delivery-day problem: budgets in periods and the checks made before any solve."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rvpp.model import build_model
from rvpp.solving.highs import run_highs
from rvpp.solving.outcome import Outcome
from rvpp.solving.plan import solve_problem
from rvpp.uncertainty.problem import budget_split, infeasibility_reasons

from tests.factories import demand, heat, tiny_case, tiny_problem, wind

HOURS = 24
CHECKS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
levels = st.lists(st.sampled_from([10.0, 20.0, 30.0]), min_size=HOURS, max_size=HOURS).map(np.array)
spreads = st.lists(st.sampled_from([0.0, 5.0, 10.0]), min_size=HOURS, max_size=HOURS).map(np.array)


@pytest.mark.slow
@CHECKS
@given(per_hour=st.sampled_from([1, 4]), wind_top=levels, wind_dev=spreads, need=levels, need_dev=spreads,
       heat_need=levels, heat_dev=spreads, p_min=st.sampled_from([0.0, 5.0, 10.0]),
       caps=st.tuples(st.sampled_from([25.0, 35.0]), st.sampled_from([25.0, 35.0])),
       budgets=st.tuples(st.integers(0, 30), st.integers(0, 30), st.integers(0, 30)))
@example(per_hour=4, wind_top=np.full(HOURS, 10.0), wind_dev=np.full(HOURS, 5.0), need=np.full(HOURS, 10.0),
         need_dev=np.zeros(HOURS), heat_need=np.full(HOURS, 10.0), heat_dev=np.zeros(HOURS), p_min=6.0,
         caps=(35.0, 35.0), budgets=(2, 0, 0)).via("every choice of 2 among 96 tied periods breaks p_min")
def test_a_case_refused_before_solving_is_infeasible_for_the_solver(per_hour, wind_top, wind_dev, need, need_dev,
                                                                    heat_need, heat_dev, p_min, caps, budgets):
    # Every hour's band repeats in its quarter-hours, so at 15 minutes deviations tie in
    # fours and Γ often splits a tie: the model may then deviate in any of the tied periods.
    nt = HOURS * per_hour
    spread = {name: np.repeat(values, per_hour) for name, values in
              dict(wt=wind_top, wd=wind_dev, n=need, nd=need_dev, h=heat_need, hd=heat_dev).items()}
    overrides = {name: min(gamma, nt) for name, gamma in zip(("W", "D", "H"), budgets)}
    case = tiny_case([wind(p_min_mw=p_min)], ed_units=[demand(p_max=caps[0])], td_units=[heat(h_max=caps[1])],
                     hpa=True, overrides=overrides, encoding="binary", dt_h=1.0 / per_hour)
    problem = tiny_problem(case, W=(spread["wt"] - spread["wd"], spread["wt"], spread["wt"]),
                           D=(spread["n"], spread["n"], spread["n"] + spread["nd"]),
                           H=(spread["h"], spread["h"], spread["h"] + spread["hd"]), price_da=(40, 50, 60))
    if not infeasibility_reasons(problem):
        return
    outcome = run_highs(build_model(problem), case.solver, load=False)
    assert outcome.status in (Outcome.INFEASIBLE, Outcome.INFEASIBLE_OR_UNBOUNDED), infeasibility_reasons(problem)


def quarter_hour_wind(top_first_hour: float, p_min: float, gamma: int, encoding: str = "binary",
                      ties: str = "choose"):
    """Wind whose band repeats in the quarter-hours of each hour: 96 periods tied at a deviation of 5 MW."""
    top = np.repeat(np.r_[top_first_hour, np.full(HOURS - 1, 20.0)], 4)
    case = tiny_case([wind(p_min_mw=p_min)], ed_units=[demand(p_max=50)], overrides={"W": gamma},
                     encoding=encoding, dt_h=0.25).replace(budgets={"ties": ties})
    return tiny_problem(case, W=(top - 5.0, top, top), D=(10, 10, 10), price_da=(40, 50, 60))


@pytest.mark.parametrize("encoding", ["binary", "top_gamma"])
def test_gamma_splitting_a_tie_is_not_refused_when_some_choice_is_feasible(encoding):
    # The earliest two tied periods (00:00, 00:15) would leave 10 − 5 = 5 MW < p_min = 6;
    # any two periods from 01:00 on leave 15 MW.
    problem = quarter_hour_wind(top_first_hour=10.0, p_min=6.0, gamma=2, encoding=encoding)
    assert infeasibility_reasons(problem) == []
    result = solve_problem(problem)
    assert result.status is Outcome.OPTIMAL, result.message
    chi = result.units.query("unit == 'W'")["chi"].to_numpy()
    assert chi.sum() == 2 and not chi[:4].any()


def test_under_earliest_ties_the_earliest_tied_periods_decide_feasibility():
    # The same day as above: the earliest two tied periods, which this rule makes deviate,
    # leave 10 − 5 = 5 MW < p_min = 6, so it is refused before solving, and the solver agrees.
    problem = quarter_hour_wind(top_first_hour=10.0, p_min=6.0, gamma=2, encoding="top_gamma", ties="earliest")
    assert infeasibility_reasons(problem) == ['wind "W": available power 5.00 MW at 00:00 is below p_min_mw=6']
    outcome = run_highs(build_model(problem), problem.case.solver, load=False)
    assert outcome.status in (Outcome.INFEASIBLE, Outcome.INFEASIBLE_OR_UNBOUNDED)


def test_a_tie_broken_in_every_choice_is_refused_and_explained():
    problem = quarter_hour_wind(top_first_hour=20.0, p_min=16.0, gamma=2)
    assert infeasibility_reasons(problem) == [
        'wind "W": available power 15.00 MW at 00:00 is below p_min_mw=16 in every choice of the 2 deviating '
        "periods among the 96 tied at a deviation of 5.00"]
    outcome = run_highs(build_model(problem), problem.case.solver, load=False)
    assert outcome.status is Outcome.INFEASIBLE


def test_budget_split_names_sure_and_tied_periods():
    sure, tied, count = budget_split(np.array([9.0, 7.0, 7.0, 7.0, 2.0, 0.0]), 3)
    assert list(sure) == [True, False, False, False, False, False]
    assert list(tied) == [False, True, True, True, False, False] and count == 2
    sure, tied, count = budget_split(np.array([3.0, 0.0, 0.0]), 2)  # a zero deviation changes nothing
    assert list(sure) == [True, False, False] and not tied.any() and count == 0
    assert budget_split(np.array([1.0, 2.0]), 0)[0].sum() == 0
    assert list(budget_split(np.array([1.0, 0.0]), 5)[0]) == [True, False]


def test_budget_split_under_earliest_ties_makes_the_earliest_tied_periods_sure():
    sure, tied, count = budget_split(np.array([9.0, 7.0, 7.0, 7.0, 2.0, 0.0]), 3, "earliest")
    assert list(sure) == [True, True, True, False, False, False] and not tied.any() and count == 0
    sure, tied, count = budget_split(np.array([7.0, 9.0, 7.0, 7.0]), 2, "earliest")
    assert list(sure) == [True, True, False, False] and count == 0
