"""Laws of the robust layer that hold for all inputs (MODEL_SPEC §4-§5)."""

from __future__ import annotations

import numpy as np
import pyomo.environ as pyo
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rvpp import solve_problem
from rvpp.settle.audit import audit_day, audit_result, audit_tables, protection_exact
from rvpp.data.case import SolverSettings
from rvpp.model import build_model
from rvpp.uncertainty.problem import tied_budgets
from rvpp.model.robust import add_price_protection, budget_choices
from rvpp.solving.highs import run_highs
from rvpp.solving.sweep import sweep_parts
from rvpp.solving.outcome import Outcome

from tests.factories import demand, heat, tiny_case, tiny_problem, wind

NT = 24
FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
series = st.lists(st.floats(0.0, 50.0, allow_nan=False, width=32), min_size=NT, max_size=NT).map(np.array)
gammas = st.integers(0, NT)


@FAST
@given(exposure=st.lists(st.floats(0.0, 1e4, allow_nan=False), min_size=1, max_size=30), data=st.data())
def test_protection_dual_equals_the_sum_of_the_largest_exposures(exposure, data):
    gamma = data.draw(st.integers(0, len(exposure)))
    m = pyo.ConcreteModel()
    m.b = pyo.Block()
    periods = list(range(1, len(exposure) + 1))
    protection = add_price_protection(m.b, {t: exposure[t - 1] for t in periods}, gamma)
    if not hasattr(m.b, "phi"):  # Γ = 0 or Γ ≥ NT need no dual variables
        value = float(pyo.value(protection))
    else:
        m.obj = pyo.Objective(expr=protection, sense=pyo.minimize)
        outcome = run_highs(m, SolverSettings(rel_gap=0.0))
        assert outcome.status is Outcome.OPTIMAL
        value = outcome.objective
    assert value == pytest.approx(protection_exact(np.array(exposure), gamma), rel=1e-9, abs=1e-6)


@FAST
@given(w=series, d=series, mid=st.floats(20, 100), neg_share=series, pos=series, gamma=gammas)
def test_dam_protection_of_a_fixed_plan_is_the_sum_of_the_gamma_largest_losses(w, d, mid, neg_share, pos, gamma):
    # Wind at zero cost sells all it has, the demand buys exactly its forecast, so the
    # plan p_da = w − d is fixed; deviations below the price keep it optimal.
    neg = mid * 0.9 * neg_share / 50.0
    case = tiny_case([wind(om=0)], ed_units=[demand(p_min=0, p_max=100)], overrides={"price_da": gamma})
    result = solve_problem(tiny_problem(case, W=(w, w, w), D=(d, d, d), price_da=(mid - neg, mid, mid + pos)))
    assert result.status == "optimal"
    p = w - d
    assert np.allclose(result.market["p_da_mw"], p, atol=1e-6)
    losses = np.maximum(neg * p, -pos * p)
    assert result.protection_eur["price_da"] == pytest.approx(protection_exact(losses, gamma), rel=1e-7, abs=1e-5)


def _small_case(budgets, encoding="top_gamma", mode="paper"):
    return tiny_case([wind("W", om=12)], pv_units=[wind("P", om=5)],
                     ed_units=[demand("D", p_min=0, p_max=120, e_min=600, flex=0.1)],
                     td_units=[heat("H", h_max=80, q_min=300)], srm=True, hpa=True,
                     tariff=[60] * 6 + [100] * 18, overrides=budgets, encoding=encoding, mode=mode)


def _small_bands(w_dev, p_dev, d_dev, h_dev):
    hours = np.arange(NT)
    sun = np.clip(np.sin((hours - 6) / 12 * np.pi), 0, None) * 45
    return dict(W=(30 - w_dev * 0.5, 30, 30), P=(np.clip(sun - p_dev, 0, None), sun, sun),
                D=(20, 22, 20 + d_dev * 0.3), H=(15, 16, 15 + h_dev * 0.2),
                price_da=(40, 60 + 20 * np.cos(hours / 4), 75), price_sr_up=(5, 12, 15),
                price_sr_dn=(2, 6, 9))


tied = st.lists(st.sampled_from([0.0, 4.0, 10.0]), min_size=NT, max_size=NT).map(np.array)


@FAST
@given(w=tied, p=tied, d=tied, h=tied, g=st.tuples(gammas, gammas, gammas, gammas))
def test_top_gamma_fast_path_equals_the_binary_formulation(w, p, d, h, g):
    budgets = dict(zip(("W", "P", "D", "H"), g))
    bands = _small_bands(w, p, d, h)
    fast = solve_problem(tiny_problem(_small_case(budgets, "top_gamma"), **bands))
    exact = solve_problem(tiny_problem(_small_case(budgets, "binary"), **bands))
    assert fast.status == exact.status == "optimal"
    assert fast.objective_eur == pytest.approx(exact.objective_eur, rel=1e-7, abs=1e-4)
    given = exact.problem.bands
    assert audit_result(exact, bands=given) == [] and audit_result(fast, bands=given) == []


@FAST
@given(w=series, p=series, d=series, h=series, g=st.tuples(gammas, gammas, gammas, gammas),
       which=st.integers(0, 3), step=st.integers(1, 6))
def test_profit_never_increases_when_a_budget_increases(w, p, d, h, g, which, step):
    names = ("W", "P", "D", "H")
    budgets = dict(zip(names, g))
    bigger = {**budgets, names[which]: min(NT, budgets[names[which]] + step)}
    bands = _small_bands(w, p, d, h)
    base = solve_problem(tiny_problem(_small_case(budgets), **bands))
    safer = solve_problem(tiny_problem(_small_case(bigger), **bands))
    assert base.status == safer.status == "optimal"
    assert safer.objective_eur <= base.objective_eur + 1e-6 * max(1.0, abs(base.objective_eur))


@FAST
@given(w=series, d=series, g=st.tuples(gammas, gammas))
def test_planner_chosen_hours_are_never_worse_than_paper_mode(w, d, g):
    # The planner-chosen variant lets the maximiser pick the Γ hours, so it is an
    # optimistic relaxation of paper mode.
    budgets = dict(zip(("W", "D"), g))
    bands = _small_bands(w, np.zeros(NT), d, np.zeros(NT))
    paper = solve_problem(tiny_problem(_small_case(budgets), **bands))
    planner = solve_problem(tiny_problem(_small_case(budgets, mode="planner_chosen"), **bands))
    assert paper.status == planner.status == "optimal"
    assert planner.objective_eur >= paper.objective_eur - 1e-6 * max(1.0, abs(paper.objective_eur))


def test_binary_encoding_puts_chi_on_the_largest_deviations():
    dev = np.array([3, 9, 1, 7, 7, 2, 0, 5, 8, 6, 4, 2, 1, 3, 9, 0, 2, 2, 5, 6, 1, 0, 4, 3], float)
    bands = _small_bands(dev, np.zeros(NT), np.zeros(NT), np.zeros(NT))
    result = solve_problem(tiny_problem(_small_case({"W": 4}, "binary"), **bands))
    assert result.status == "optimal"
    chi = result.units.query("unit == 'W'")["chi"].to_numpy()
    chosen = set(np.flatnonzero(chi) + 1)
    # Deviations 9 (t=2, 15) and 8 (t=9), then one of the two tied 7s (t=4, 5).
    assert chi.sum() == 4 and {2, 9, 15} <= chosen and len(chosen & {4, 5}) == 1


def test_earliest_ties_put_chi_on_the_earlier_of_two_tied_deviations_and_the_audit_checks_it():
    dev = np.array([3, 9, 1, 7, 7, 2, 0, 5, 8, 6, 4, 2, 1, 3, 9, 0, 2, 2, 5, 6, 1, 0, 4, 3], float)
    bands = _small_bands(dev, np.zeros(NT), np.zeros(NT), np.zeros(NT))
    case = _small_case({"W": 4}).replace(budgets={"ties": "earliest"})
    problem = tiny_problem(case, **bands)
    assert not budget_choices(build_model(problem))
    result = solve_problem(problem)
    assert result.status == "optimal"
    rows = result.units.query("unit == 'W'")
    # Deviations 9 (t=2, 15) and 8 (t=9), then the earlier of the two tied 7s: t=4, not t=5.
    assert set(rows.loc[rows["chi"] == 1, "t"]) == {2, 4, 9, 15}
    assert audit_result(result, bands=problem.bands) == []
    units = result.units.copy()
    units.loc[(units["unit"] == "W") & (units["t"] == 4), "chi"] = 0
    units.loc[(units["unit"] == "W") & (units["t"] == 5), "chi"] = 1
    units.loc[(units["unit"] == "W") & (units["t"].isin([4, 5])), "bound_mw"] = [30.0, 30.0 - 3.5]
    day = audit_day(result.case, bands=problem.bands)
    later = {v.check for v in audit_tables(day, result.market, units, result.csp, result.summary())}
    assert "budget.earliest_ties" in later
    chosen = audit_day(result.case.replace(budgets={"ties": "choose"}), bands=problem.bands)
    assert "budget.earliest_ties" not in {v.check for v in audit_tables(chosen, result.market, units, result.csp,
                                                                          result.summary())}


def test_tied_budgets_name_the_source_the_count_and_the_tied_deviation():
    # W deviates by half the given values: 4.5 at t=2 and 15, 4 at t=9, 3.5 at t=4 and 5.
    dev = np.array([3, 9, 1, 7, 7, 2, 0, 5, 8, 6, 4, 2, 1, 3, 9, 0, 2, 2, 5, 6, 1, 0, 4, 3], float)
    bands = _small_bands(dev, np.zeros(NT), np.zeros(NT), np.zeros(NT))
    assert tied_budgets(tiny_problem(_small_case({"W": 4}), **bands)) == [
        "W: 1 of the 2 periods tied at a deviation of 3.5 MW"]
    assert tied_budgets(tiny_problem(_small_case({"W": 3}), **bands)) == []
    assert tied_budgets(tiny_problem(_small_case({"W": 4}).replace(budgets={"ties": "earliest"}), **bands)) == []
    # One Γ for W instead of its own: Γ = 1 takes one of the two 4.5s, Γ = 2 and Γ = 5 whole groups.
    three = tiny_problem(_small_case({"W": 3}), **bands)
    assert tied_budgets(three, gamma=4) == ["W: 1 of the 2 periods tied at a deviation of 3.5 MW"]
    assert tied_budgets(three, gamma=1) == ["W: 1 of the 2 periods tied at a deviation of 4.5 MW"]
    assert tied_budgets(three, gamma=2) == tied_budgets(three, gamma=5) == []


def test_a_sweep_solves_each_gamma_with_tied_deviations_as_a_part_of_its_own():
    # W deviates by 4.5 twice, 4, 3.5 twice, 3 twice: Γ = 1, 4 and 6 fall among equal deviations.
    dev = np.array([3, 9, 1, 7, 7, 2, 0, 5, 8, 6, 4, 2, 1, 3, 9, 0, 2, 2, 5, 6, 1, 0, 4, 3], float)
    bands = _small_bands(dev, np.zeros(NT), np.zeros(NT), np.zeros(NT))
    problems = {g: tiny_problem(_small_case({"W": g}), **bands) for g in range(8)}
    assert sweep_parts(problems, 2) == [[1], [4], [6], [0, 2, 3], [5, 7]]
    assert sweep_parts(problems, 1) == [list(range(8))]
    earliest = {g: tiny_problem(_small_case({"W": g}).replace(budgets={"ties": "earliest"}), **bands)
                for g in range(8)}
    assert sweep_parts(earliest, 2) == [[0, 1, 2, 3], [4, 5, 6, 7]]


def test_budget_choices_are_the_tied_deviations_at_the_gamma_boundary_and_the_variants_without_the_fast_path():
    # Γ = 4 on deviations 9, 9, 8, then 7 twice: the fourth largest is one of the two 7s, so the
    # solver places that one; with Γ = 3 or 5 the data decide every period.
    dev = np.array([3, 9, 1, 7, 7, 2, 0, 5, 8, 6, 4, 2, 1, 3, 9, 0, 2, 2, 5, 6, 1, 0, 4, 3], float)
    bands = _small_bands(dev, np.zeros(NT), np.zeros(NT), np.zeros(NT))

    def choices(gamma, encoding="top_gamma", mode="paper"):
        return budget_choices(build_model(tiny_problem(_small_case({"W": gamma}, encoding, mode), **bands)))

    assert choices(4) and not choices(3) and not choices(5)
    assert choices(3, encoding="binary") and choices(3, mode="planner_chosen")
