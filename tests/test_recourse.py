"""Recourse model and stochastic benchmark (MODEL_SPEC §10), checked against hand computations."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.errors import RvppError
from rvpp.settle.recourse import (FirstStage, Penalties, Realization, evaluate, first_stage, nominal_realization,
                                  realization, realized_problem, set_fingerprint, values_fingerprint)
from rvpp.settle.stochastic import solve_stochastic
from rvpp.solving.plan import solve_problem

from tests.factories import heat, tiny_case, wind

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
    with pytest.raises(RvppError, match=r"m_def=1e\+308 must be <= 1e\+06"):
        Penalties(m_def=1e308)
    with pytest.raises(RvppError, match=r"c_heat_eur_per_mwh=1e\+07 must be <= 1e\+06"):
        Penalties(c_heat_eur_per_mwh=1e7)


def test_kept_commitment_settles_a_day_without_sun(paper):
    plan = rvpp.solve(paper)
    assert plan.csp["online"].sum() > 0  # the deterministic plan runs the turbine
    dark = nominal_realization(plan.problem)
    dark.values["CSP1"] = 0.0
    record = evaluate(paper, first_stage(plan, fix_commitment=True), dark)
    assert record["status"] == "optimal"
    assert record["deficit_mwh"] > 0


# ----------------------------------------------------------------------------- hand-built settlements

HOURS = np.arange(1, 25)


def settle(case, bids: dict, values: dict, penalties=Penalties()):
    """Settle hand-given bids (MW per hour) against hand-given realized values (per hour) of ``case``."""
    per_hour = round(1 / case.dt_h)
    nt = 24 * per_hour
    first = FirstStage(*(np.repeat(np.broadcast_to(np.asarray(bids.get(k, 0.0), float), (24,)), per_hour)
                         for k in ("p_da", "r_sr_up", "r_sr_dn", "h_hpa")))
    frame = pd.DataFrame({name: np.repeat(np.broadcast_to(np.asarray(v, float), (24,)), per_hour)
                          for name, v in {"price_sr_up": 0.0, "price_sr_dn": 0.0, **values}.items()},
                         index=pd.RangeIndex(1, nt + 1, name="t"))
    record = evaluate(case, first, Realization(day=case.delivery_date, values=frame), penalties)
    assert record["status"] == "optimal"
    assert record["net_cost_eur"] == pytest.approx(record["market_cost_eur"] + record["penalty_eur"], abs=1e-6)
    return record


def assert_settlement(record, **expected):
    """Every settlement figure [EUR] and slack energy [MWh] named, the others zero."""
    figures = ("market_cost_eur", "penalty_eur", "net_cost_eur", "revenue_dam_eur", "revenue_sr_eur", "cost_hpa_eur",
               "cost_opex_eur", "penalty_deficit_eur", "penalty_surplus_eur", "penalty_reserve_eur",
               "penalty_heat_eur", "deficit_mwh", "surplus_mwh", "reserve_up_short_mwh", "reserve_dn_short_mwh",
               "unserved_heat_mwh")
    for name in figures:
        assert record[name] == pytest.approx(expected.get(name, 0.0), abs=1e-6), name


@pytest.mark.parametrize("dt_h", [1.0, 0.25])
def test_surplus_is_sold_at_the_surplus_price_only_where_it_beats_the_operating_cost(dt_h):
    # Bid 20 MW every hour; the wind farm (O&M 10 EUR/MWh) could give 30. At 50 EUR/MWh
    # (hours 1-12) the 10 MW surplus earns m_sur·λ = 25 > 10 and is produced; at 10 EUR/MWh
    # (hours 13-24) it would earn 5 < 10, so the farm is curtailed to the bid.
    case = tiny_case([wind(om=10)], dt_h=dt_h)
    price = np.where(HOURS <= 12, 50.0, 10.0)
    record = settle(case, {"p_da": 20.0}, {"price_da": price, "W": 30.0})
    revenue = 12 * 50 * 20 + 12 * 10 * 20          # 14,400
    opex = 10 * (12 * 30 + 12 * 20)                 # 6,000
    surplus = -0.5 * 50 * 10 * 12                   # -3,000
    assert_settlement(record, revenue_dam_eur=revenue, cost_opex_eur=opex, market_cost_eur=opex - revenue,
                      penalty_surplus_eur=surplus, penalty_eur=surplus, net_cost_eur=opex - revenue + surplus,
                      surplus_mwh=120.0)


def test_reserve_that_cannot_be_delivered_pays_the_shortfall_price():
    # Bid 20 MW with 5 MW up and 5 MW down bands; the farm can give 22 MW, so up reserve
    # can cover only 2 MW: 3 MW short every hour at m_sr·λup = 2 x 10 = 20 EUR/MW, cheaper
    # than a deficit (m_def·λ − O&M = 90 EUR/MWh). The down band is fully covered.
    case = tiny_case([wind(om=10, share=0.1)], srm=True)
    record = settle(case, {"p_da": 20.0, "r_sr_up": 5.0, "r_sr_dn": 5.0},
                    {"price_da": 50.0, "price_sr_up": 10.0, "price_sr_dn": 4.0, "W": 22.0})
    revenue_dam, revenue_sr, opex = 24 * 50 * 20, 24 * (10 * 5 + 4 * 5), 24 * 10 * 20   # 24,000, 1,680, 4,800
    market = opex - revenue_dam - revenue_sr                                            # -20,880
    shortfall = 24 * 2.0 * 10 * 3                                                       # 1,440
    assert_settlement(record, revenue_dam_eur=revenue_dam, revenue_sr_eur=revenue_sr, cost_opex_eur=opex,
                      market_cost_eur=market, penalty_reserve_eur=shortfall, penalty_eur=shortfall,
                      net_cost_eur=market + shortfall, reserve_up_short_mwh=72.0)


@pytest.mark.parametrize("c_heat, price", [(None, 2 * 80.0), (300.0, 300.0)])
def test_heat_the_hpa_bid_does_not_cover_is_unserved_at_its_price(c_heat, price):
    # 10 MW_th bought every hour at 80 EUR/MWh_th; the demand needs 12 in hours 1-12 (2
    # unserved) and 8 in hours 13-24 (it takes the 10 bought). c_heat defaults to twice
    # the highest tariff.
    case = tiny_case(td_units=[heat(h_max=100)], hpa=True, tariff=80.0)
    need = np.where(HOURS <= 12, 12.0, 8.0)
    record = settle(case, {"h_hpa": 10.0}, {"price_da": 50.0, "H": need}, Penalties(c_heat_eur_per_mwh=c_heat))
    hpa, unserved = 24 * 80 * 10, price * 2 * 12                                         # 19,200
    assert_settlement(record, cost_hpa_eur=hpa, market_cost_eur=hpa, penalty_heat_eur=unserved,
                      penalty_eur=unserved, net_cost_eur=hpa + unserved, unserved_heat_mwh=24.0)


def test_a_shortfall_of_energy_and_reserve_and_heat_adds_up():
    # Hours 1-12: the farm gives 12 MW against a 20 MW bid with a 5 MW up band: 8 MW
    # deficit at m_def·λ = 100 EUR/MWh and the whole 5 MW band short at 2 x 10 (cheaper
    # than a further 5 MW deficit); in hours 13-24 the farm gives exactly the bid and its
    # band (25 MW), so nothing is left over. Heat: 10 MW_th bought, 11 needed.
    case = tiny_case([wind(om=10, share=0.1)], td_units=[heat(h_max=100)], srm=True, hpa=True, tariff=80.0)
    available = np.where(HOURS <= 12, 12.0, 25.0)
    record = settle(case, {"p_da": 20.0, "r_sr_up": 5.0, "h_hpa": 10.0},
                    {"price_da": 50.0, "price_sr_up": 10.0, "W": available, "H": 11.0},
                    Penalties(c_heat_eur_per_mwh=200.0))
    revenue_dam, revenue_sr, hpa = 24 * 50 * 20, 24 * 10 * 5, 24 * 80 * 10
    opex = 10 * (12 * 12 + 12 * 20)
    deficit, shortfall, unserved = 12 * 2.0 * 50 * 8, 12 * 2.0 * 10 * 5, 24 * 200.0 * 1
    market = hpa + opex - revenue_dam - revenue_sr
    assert_settlement(record, revenue_dam_eur=revenue_dam, revenue_sr_eur=revenue_sr, cost_hpa_eur=hpa,
                      cost_opex_eur=opex, market_cost_eur=market, penalty_deficit_eur=deficit,
                      penalty_reserve_eur=shortfall, penalty_heat_eur=unserved,
                      penalty_eur=deficit + shortfall + unserved, net_cost_eur=market + deficit + shortfall + unserved,
                      deficit_mwh=96.0, reserve_up_short_mwh=60.0, unserved_heat_mwh=24.0)


def test_the_stochastic_start_is_a_complete_feasible_point_worth_its_settlements(paper):
    import pyomo.environ as pyo

    from rvpp.settle.recourse import build_recourse_model
    from rvpp.settle.stochastic import recourse_start

    days = [paper.delivery_date - dt.timedelta(days=k) for k in (2, 9)]
    reals = [realization(paper, d) for d in days]
    problems = [realized_problem(paper, r) for r in reals]
    m = build_recourse_model(problems, Penalties())
    flat = np.full(24, 20.0)
    bids = FirstStage(flat, np.zeros(24), np.zeros(24), np.full(24, 30.0))
    start = recourse_start(m, paper, problems, Penalties(), bids)
    free = [v for v in m.component_data_objects(pyo.Var, active=True) if not v.fixed]
    assert all(v in start for v in free), "every free variable has a start value"
    for v in free:
        v.set_value(start[v], skip_validation=True)
    for con in m.component_data_objects(pyo.Constraint, active=True):
        body = pyo.value(con.body)
        assert con.lower is None or body >= pyo.value(con.lower) - 1e-5, con.name
        assert con.upper is None or body <= pyo.value(con.upper) + 1e-5, con.name
    settled = [evaluate(paper, bids, r)["net_cost_eur"] for r in reals]
    assert pyo.value(m.expected_net_cost) == pytest.approx(np.mean(settled), rel=1e-3)


@pytest.mark.slow
def test_the_chain_of_starts_keeps_the_stochastic_optimum(paper):
    """Seven scenarios start from the benchmark over the first two (a chain 2 → 7); the
    optimum matches the same model solved by HiGHS without any start, and the expected
    profit is what its bids earn, settled scenario by scenario."""
    from rvpp.settle.recourse import build_recourse_model
    from rvpp.solving.highs import HighsModel

    exact = rvpp.with_options(paper, rel_gap=1e-6)
    reals = [realization(paper, paper.delivery_date - dt.timedelta(days=k)) for k in (1, 3, 5, 8, 11, 13, 16)]
    chained = solve_stochastic(exact, reals)
    assert chained.status == "optimal" and chained.start_s > 0.0
    plain = HighsModel(build_recourse_model([realized_problem(exact, r) for r in reals], Penalties()))
    outcome = plain.solve(exact.solver)
    assert outcome.status == "optimal"
    assert chained.expected_profit_eur == pytest.approx(-outcome.objective, rel=1e-5)
    settled = [evaluate(exact, chained.bids, r)["net_cost_eur"] for r in reals]
    assert -np.mean(settled) == pytest.approx(chained.expected_profit_eur, rel=1e-5)
