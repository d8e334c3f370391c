"""Recourse model and stochastic benchmark (MODEL_SPEC §10), checked against hand computations."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

import rvpp
from rvpp.errors import RvppError
from rvpp.settle.recourse import (Penalties, Realization, evaluate, first_stage, nominal_realization, realization,
                           realized_problem, set_fingerprint, solve_stochastic, values_fingerprint)
from rvpp.solving.plan import solve_problem

CASE_DIR = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
REL = 1e-6  # relative tolerance on EUR figures of LP-sized recourse problems


@pytest.fixture(scope="module")
def paper():
    return rvpp.with_options(rvpp.load_case(CASE_DIR), strategy="deterministic", threads=1)


def _small(paper, **changes):
    """A deterministic portfolio small enough to settle by hand."""
    return paper.replace(budgets={"strategy": "deterministic", "overrides": {}}, **changes)


def _wind_portfolio(paper, srm: bool):
    wind = [u.model_copy(update={}) for u in paper.wind]
    ed = paper.ed[2].model_copy(update={"e_min_mwh": 0.0, "flex_up": 0.0, "flex_dn": 0.0})
    return _small(paper, wind=wind, pv=[], csp=[], ed=[ed], td=[], markets={"srm": srm, "hpa": False})


def _with_value(real: Realization, source: str, t: int, value: float) -> Realization:
    values = real.values.copy()
    values.loc[t, source] = value
    return Realization(day=real.day, values=values)


def test_deterministic_plan_settled_at_its_own_nominal_values_has_zero_penalty(paper):
    plan = rvpp.solve(paper)
    assert plan.status == "optimal"
    record = evaluate(paper, first_stage(plan), nominal_realization(plan.problem))
    assert record["status"] == "optimal"
    assert record["penalty_eur"] == pytest.approx(0.0, abs=1e-6)
    for slack in ("deficit_mwh", "surplus_mwh", "reserve_up_short_mwh", "reserve_dn_short_mwh", "unserved_heat_mwh"):
        assert record[slack] == pytest.approx(0.0, abs=1e-6)
    # Market cost at the nominal prices is the plan's own cost: −objective (within the MIP gap).
    assert record["market_cost_eur"] == pytest.approx(-plan.objective_eur, rel=1e-3)
    assert record["net_cost_eur"] == pytest.approx(record["market_cost_eur"] + record["penalty_eur"], rel=REL)


def test_lower_availability_in_one_period_gives_the_hand_computed_deficit(paper):
    case = _wind_portfolio(paper, srm=False)
    plan = rvpp.solve(case)
    assert plan.status == "optimal"
    nominal = nominal_realization(plan.problem)
    units = plan.units.set_index(["unit", "t"])
    t = int(nominal.values["WF1"].idxmax())
    produced = units.loc[("WF1", t), "p_mw"]
    assert produced == pytest.approx(nominal.values.loc[t, "WF1"])  # every wind MWh is sold in the plan
    shortfall = produced / 2
    penalties = Penalties(m_def=3.0)
    base = evaluate(case, first_stage(plan), nominal, penalties)
    low = evaluate(case, first_stage(plan), _with_value(nominal, "WF1", t, produced - shortfall), penalties)
    assert low["status"] == base["status"] == "optimal"
    price = nominal.values.loc[t, "price_da"]
    om = case.wind[0].om_eur_per_mwh
    assert low["deficit_mwh"] == pytest.approx(shortfall, rel=REL)
    assert low["penalty_eur"] == pytest.approx(3.0 * price * shortfall, rel=REL)
    assert low["market_cost_eur"] == pytest.approx(base["market_cost_eur"] - om * shortfall, rel=REL)
    assert low["net_cost_eur"] == pytest.approx(base["net_cost_eur"] + (3.0 * price - om) * shortfall, rel=REL)


def test_lost_wind_in_one_period_costs_deficit_and_reserve_shortfall(paper):
    case = _wind_portfolio(paper, srm=True)
    plan = rvpp.solve(case)
    assert plan.status == "optimal"
    nominal = nominal_realization(plan.problem)
    market = plan.market.set_index("t")
    t = int(market["r_sr_dn_mw"].idxmax())
    assert market.loc[t, "r_sr_dn_mw"] > 0
    calm = _with_value(_with_value(nominal, "WF1", t, 0.0), "WF2", t, 0.0)
    record = evaluate(case, first_stage(plan), calm)
    assert record["status"] == "optimal"
    units = plan.units.set_index(["unit", "t"])
    wind = units.loc[("WF1", t), "p_mw"] + units.loc[("WF2", t), "p_mw"]
    prices = nominal.values.loc[t]
    expected = (2.0 * prices["price_da"] * wind + 2.0 * (prices["price_sr_up"] * market.loc[t, "r_sr_up_mw"]
                                                         + prices["price_sr_dn"] * market.loc[t, "r_sr_dn_mw"]))
    assert record["deficit_mwh"] == pytest.approx(wind, rel=REL)
    assert record["reserve_up_short_mwh"] == pytest.approx(market.loc[t, "r_sr_up_mw"], abs=1e-6)
    assert record["reserve_dn_short_mwh"] == pytest.approx(market.loc[t, "r_sr_dn_mw"], rel=REL)
    assert record["penalty_eur"] == pytest.approx(expected, rel=REL)


@pytest.mark.parametrize("c_heat, expected_price", [(333.0, 333.0), (None, 240.0)])
def test_unserved_heat_is_priced_as_set(paper, c_heat, expected_price):
    td = paper.td[0].model_copy(update={"q_min_mwh_th": 0.0})
    case = _small(paper, wind=[], pv=[], csp=[], ed=[], td=[td], markets={"srm": False, "hpa": True})
    plan = rvpp.solve(case)
    assert plan.status == "optimal"
    nominal = nominal_realization(plan.problem)
    t, extra = 8, 7.5
    colder = _with_value(nominal, td.name, t, nominal.values.loc[t, td.name] + extra)
    record = evaluate(case, first_stage(plan), colder, Penalties(c_heat_eur_per_mwh=c_heat))
    assert record["status"] == "optimal"
    assert Penalties(c_heat_eur_per_mwh=c_heat).heat_price(case) == expected_price  # 2 x 120 by default
    assert record["unserved_heat_mwh"] == pytest.approx(extra, rel=REL)
    assert record["penalty_heat_eur"] == pytest.approx(expected_price * extra, rel=REL)
    assert record["penalty_eur"] == pytest.approx(expected_price * extra, rel=REL)


def test_stochastic_model_with_one_scenario_equals_the_deterministic_plan_of_its_data(paper):
    real = realization(paper, paper.delivery_date - dt.timedelta(days=3))
    deterministic = solve_problem(realized_problem(paper, real))
    stochastic = solve_stochastic(paper, [real])
    assert deterministic.status == stochastic.status == "optimal"
    assert stochastic.expected_profit_eur == pytest.approx(deterministic.objective_eur, rel=2e-4)
    # Settled against its own scenario, the stochastic plan pays no penalty (the bids
    # themselves need not be equal: heat can move between hours of equal tariff).
    record = evaluate(paper, stochastic.bids, real)
    assert record["penalty_eur"] == pytest.approx(0.0, abs=1e-3)
    assert -record["net_cost_eur"] == pytest.approx(stochastic.expected_profit_eur, rel=2e-4)


def test_fixing_the_csp_commitment_never_lowers_the_net_cost(paper):
    plan = rvpp.solve(rvpp.with_options(paper, strategy="balanced"))
    real = realization(paper, paper.delivery_date + dt.timedelta(days=2))
    free = evaluate(plan.case, first_stage(plan), real)
    fixed = evaluate(plan.case, first_stage(plan, fix_commitment=True), real)
    assert free["status"] == fixed["status"] == "optimal"
    assert fixed["net_cost_eur"] >= free["net_cost_eur"] - 1e-6 * abs(free["net_cost_eur"])


def test_realized_values_are_clipped_to_unit_limits(paper):
    real = realization(paper, paper.delivery_date)
    real = _with_value(_with_value(real, "WF1", 5, 80.0), "ED_industry", 5, 500.0)
    problem = realized_problem(paper, real)
    assert problem.sources["WF1"].nominal[4] == 50.0
    assert problem.sources["ED_industry"].nominal[4] == 70.0
    assert problem.sources["price_da"].gamma == 0 and not problem.sources["WF1"].deviation.any()


def test_fingerprints_follow_values_not_column_order(paper):
    real = realization(paper, paper.delivery_date)
    shuffled = real.values[list(reversed(real.values.columns))]
    assert values_fingerprint(shuffled) == real.fingerprint
    assert _with_value(real, "PV1", 12, 1.0).fingerprint != real.fingerprint
    other = realization(paper, paper.delivery_date + dt.timedelta(days=1))
    assert set_fingerprint([real, other]) != set_fingerprint([other, real])


def test_realization_of_a_day_of_another_length_is_refused(paper):
    spring = realization(paper, dt.date(2025, 3, 30))
    assert len(spring.values) == 23
    with pytest.raises(RvppError, match="23 periods"):
        realized_problem(paper, spring)


def test_penalty_settings_are_validated():
    with pytest.raises(RvppError, match="m_def"):
        Penalties(m_def=-1.0)


def test_kept_commitment_settles_a_day_without_sun(paper):
    plan = rvpp.solve(paper)
    assert plan.csp["online"].sum() > 0  # the deterministic plan runs the turbine
    dark = nominal_realization(plan.problem)
    dark.values["CSP1"] = 0.0
    record = evaluate(paper, first_stage(plan, fix_commitment=True), dark)
    assert record["status"] == "optimal"
    assert record["deficit_mwh"] > 0
