"""A Γ sweep re-solves one built model; every point equals the plan solved on its own."""

from __future__ import annotations

import pytest

from rvpp import audit_result, solve, with_options
from rvpp.errors import RvppError
from rvpp.solving.sweep import sweep_gamma

REL_GAP = 1e-4


@pytest.fixture(scope="module")
def day(paper_case):
    return with_options(paper_case, strategy="deterministic", date="2025-04-15")


def _same_optimum(point, alone):
    assert point.status == alone.status == "optimal"
    assert point.objective_eur == pytest.approx(alone.objective_eur, abs=REL_GAP * abs(alone.objective_eur) + 0.01)
    assert point.objective_eur <= alone.bound_eur + 0.01 and alone.objective_eur <= point.bound_eur + 0.01


@pytest.mark.slow
def test_every_source_swept_equals_the_plans_solved_one_by_one(day):
    gammas = [9, 0, 4]
    points = sweep_gamma(day, gammas)
    for gamma, point in zip(gammas, points):
        alone = solve(with_options(day, gammas={name: gamma for name in day.sources()}))
        _same_optimum(point, alone)
        assert point.problem.budgets == alone.problem.budgets
        assert audit_result(point) == []
        assert point.units["chi"].dropna().groupby(point.units["unit"]).sum().le(gamma).all()
    profits = [p.objective_eur for p in sorted(points, key=lambda p: p.problem.budgets["price_da"])]
    assert profits == sorted(profits, reverse=True), "profit never rises with the budget"


@pytest.mark.slow
def test_a_gamma_among_tied_deviations_swept_equals_the_plan_solved_alone(paper_case):
    # 6 April: the field of CSP1 deviates by its 300 MW_th in five hours, so Γ = 3 ties there;
    # it is solved as a part of its own, with a model of its own.
    tie_day = with_options(paper_case, date="2025-04-06")
    points = sweep_gamma(tie_day, [6, 3, 0], workers=2)
    for gamma, point in zip([6, 3, 0], points):
        alone = solve(with_options(tie_day, gammas={name: gamma for name in tie_day.sources()}))
        _same_optimum(point, alone)
        assert audit_result(point) == []
    assert [p.problem.budgets["CSP1"] for p in points] == [6, 3, 0]


def test_one_source_swept_keeps_the_other_budgets(day):
    points = sweep_gamma(with_options(day, strategy="optimistic"), [0, 24], sources=["price_da"])
    assert [p.problem.budgets["price_da"] for p in points] == [0, 24]
    assert all(p.problem.budgets["WF1"] == 3 for p in points)
    for point in points:
        alone = solve(point.problem.case)
        _same_optimum(point, alone)
    assert points[0].protection_eur["price_da"] == 0.0
    assert points[1].protection_eur["price_da"] > 0.0


def test_a_grid_outside_the_day_or_an_unknown_source_is_refused(day):
    with pytest.raises(RvppError, match="outside 0..24"):
        sweep_gamma(day, [0, 25])
    with pytest.raises(RvppError, match="unknown source 'WF9'"):
        sweep_gamma(day, [0], sources=["WF9"])
    assert sweep_gamma(day, []) == []
