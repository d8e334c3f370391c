"""A kept day model: budgets change in place, other data rebuild it, the plans stay the same."""

from __future__ import annotations

import gc

import pytest

from rvpp import audit_result, prepare, solve_problem, with_options
from rvpp.solving.persistent import DayModel
from rvpp.solving.sweep import with_budgets


def _with_initial_state(case, energy_mwh_th: float, on: bool):
    csp = case.csp[0]
    csp = csp.model_copy(update={
        "storage": csp.storage.model_copy(update={"e_init_mwh_th": energy_mwh_th}),
        "power_block": csp.power_block.model_copy(update={"initially_on": on})})
    return case.replace(csp=[csp])


@pytest.mark.slow
def test_budgets_re_solve_in_place_and_new_data_rebuild(paper_case):
    day = with_options(paper_case, strategy="deterministic", date="2025-04-15")
    first = prepare(day)
    problems = [
        first,
        with_budgets(first, with_options(day, strategy="balanced")),        # budgets only: kept
        prepare(_with_initial_state(day, 400.0, True)),                    # initial state: rebuilt
        prepare(with_options(day, date="2025-04-16", strategy="balanced")),  # next day: rebuilt
    ]
    kept = DayModel()
    rebuilds = []
    for problem in problems:
        result = kept.solve(problem)
        rebuilds.append(kept.rebuilds)
        alone = solve_problem(problem)
        assert result.status == alone.status == "optimal"
        assert result.objective_eur == pytest.approx(alone.objective_eur, abs=1e-4 * abs(alone.objective_eur) + 0.01)
        assert result.problem is problem and audit_result(result) == []
    assert rebuilds == [1, 1, 2, 3]
    assert problems[2].case.csp[0].storage.e_init_mwh_th == 400.0


def test_a_rebuild_moves_the_start_even_when_the_old_model_is_collected_meanwhile(paper_case, monkeypatch):
    """The start of a rebuilt model comes from the old model's variables, read by name; a garbage
    collection just before must not detach them (it once could, at random)."""
    kept = DayModel()
    kept.solve(prepare(with_options(paper_case, strategy="deterministic", date="2025-04-15")))
    moved = DayModel._by_name

    def collected_first(self, values):
        gc.collect()
        return moved(self, values)

    monkeypatch.setattr(DayModel, "_by_name", collected_first)
    next_day = prepare(with_options(paper_case, strategy="deterministic", date="2025-04-16"))
    result = kept.solve(next_day)
    assert kept.rebuilds == 2 and result.status == "optimal" and audit_result(result) == []
    assert len(kept._start) > 0, "the previous plan's integer values start the next solve"


@pytest.mark.slow
def test_another_tie_rule_rebuilds_the_model(paper_case):
    """Under ``ties: earliest`` the storage's charging limit is tightened in the earliest tied periods,
    which the other rule may leave at their nominal field: a kept model must not be re-solved
    across the two rules."""
    chosen = prepare(with_options(paper_case, strategy="balanced", date="2025-04-06"))
    earliest = prepare(with_options(chosen.case, ties="earliest"))
    kept = DayModel()
    results = [kept.solve(problem) for problem in (chosen, earliest, chosen)]
    assert kept.rebuilds == 3
    for result, problem in zip(results, (chosen, earliest, chosen)):
        alone = solve_problem(problem)
        assert result.status == alone.status == "optimal" and audit_result(result) == []
        assert result.objective_eur == pytest.approx(alone.objective_eur, abs=1e-4 * abs(alone.objective_eur) + 0.01)
    assert results[1].objective_eur < results[0].objective_eur - 1e-3 * abs(results[0].objective_eur)


@pytest.mark.slow
def test_a_budget_that_parts_identical_csps_rebuilds_without_their_order(paper_case):
    """Two interchangeable CSPs are ordered by hours online (rvpp.model.csp.add_csp_symmetry);
    giving one of them its own budget makes them different plants, so the order must go:
    the model is rebuilt rather than re-solved in place, and the plan is a fresh solve's."""
    day = with_options(paper_case, strategy="balanced", date="2025-04-15")
    csp = day.csp[0]
    twin = csp.model_copy(update={"name": f"{csp.name}_2", "solar_field": csp.solar_field.model_copy(
        update={"series": csp.column})})
    twins = day.replace(csp=[csp, twin])
    first = prepare(twins)
    parted = with_budgets(first, with_options(twins, gammas={twin.name: 0}))
    kept = DayModel()
    kept.solve(first)
    assert hasattr(kept.model, "csp_order")
    result = kept.solve(parted)
    assert kept.rebuilds == 2 and not hasattr(kept.model, "csp_order")
    alone = solve_problem(parted)
    assert result.status == alone.status == "optimal"
    assert result.objective_eur == pytest.approx(alone.objective_eur, abs=1e-4 * abs(alone.objective_eur) + 0.01)
