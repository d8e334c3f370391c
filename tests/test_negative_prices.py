"""Zero and negative prices end to end: bands, robust counterpart, settlement, audit (MODEL_SPEC §4, §10).

The imbalance prices are ``π_def = λ + (m_def − 1)·|λ|`` and ``π_sur = λ − (1 − m_sur)·|λ|``;
for λ < 0 they are ``(2 − m_def)·λ`` and ``(2 − m_sur)·λ``, worked out by hand below.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pyomo.environ as pyo
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rvpp
from rvpp.errors import SettlementError
from rvpp.outputs.plots import bands_figure
from rvpp.settle.audit import audit_result
from rvpp.settle.recourse import (FirstStage, Penalties, Realization, build_recourse_model, evaluate, first_stage,
                                  realization, realized_problem)
from rvpp.solving.highs import run_highs
from rvpp.solving.outcome import Outcome
from rvpp.solving.plan import solve_problem
from tests.factories import DAY, PAPER, SPAIN, demand, tiny_case, tiny_problem, wind

NT = 24
OMIE_HOURLY = SPAIN / "omie_spain_prices_2018_2025.csv"
prices = st.floats(-500.0, 3000.0, allow_nan=False)
m_defs = st.floats(1.0, 5.0)
m_surs = st.floats(0.0, 1.0)


# ----------------------------------------------------------------------------- imbalance prices


@settings(max_examples=200, deadline=None)
@given(price=prices, m_def=m_defs, m_sur=m_surs)
def test_short_price_is_never_below_long_price_for_any_sign(price, m_def, m_sur):
    short, long = Penalties(m_def=m_def, m_sur=m_sur).imbalance_prices(np.array([price]))
    assert short[0] >= long[0]
    if price >= 0:
        assert short[0] == pytest.approx(m_def * price) and long[0] == pytest.approx(m_sur * price)
    else:
        assert short[0] == pytest.approx((2.0 - m_def) * price) and long[0] == pytest.approx((2.0 - m_sur) * price)


def short_and_long(price, m_def: float, m_sur: float) -> tuple[np.ndarray, np.ndarray]:
    """MODEL_SPEC §10 written out here: π_def = λ + (m_def − 1)·|λ|, π_sur = λ − (1 − m_sur)·|λ| [EUR/MWh]."""
    lam = np.asarray(price, dtype=float)
    return lam + (m_def - 1.0) * np.abs(lam), lam - (1.0 - m_sur) * np.abs(lam)


@pytest.mark.parametrize("m_def, m_sur, price, short, long", [
    # λ = 60: a deficit is bought back at 60 + 1.5·60 = 150, a surplus sold at 60 − 0.6·60 = 24.
    (2.5, 0.4, 60.0, 150.0, 24.0),
    # λ = −20: a deficit is bought back at −20 + 1.5·20 = 10, a surplus costs −20 − 0.6·20 = −32.
    (2.5, 0.4, -20.0, 10.0, -32.0),
    (2.5, 0.4, -7.5, 3.75, -12.0),
    (2.5, 0.4, 0.0, 0.0, 0.0),
    # m_def = 1, m_sur = 1: both at the DAM price, whatever its sign.
    (1.0, 1.0, -45.0, -45.0, -45.0),
    (1.0, 1.0, 45.0, 45.0, 45.0),
    # m_def = 3, m_sur = 0: a surplus earns nothing above zero and costs 2|λ| below it.
    (3.0, 0.0, 12.0, 36.0, 0.0),
    (3.0, 0.0, -12.0, 12.0, -24.0),
])
def test_imbalance_prices_follow_the_formula_for_either_sign(m_def, m_sur, price, short, long):
    assert short_and_long([price], m_def, m_sur) == (pytest.approx([short]), pytest.approx([long]))
    mine = Penalties(m_def=m_def, m_sur=m_sur).imbalance_prices(np.array([price]))
    assert mine[0].tolist() == pytest.approx([short], abs=1e-12) and mine[1].tolist() == pytest.approx([long],
                                                                                                          abs=1e-12)


def test_imbalance_prices_by_hand_at_zero_and_negative_prices():
    short, long = Penalties(m_def=2.0, m_sur=0.5).imbalance_prices(np.array([-10.0, 0.0, 40.0]))
    # λ = −10: a deficit is bought back at −10 + 10 = 0, a surplus sold at −10 − 5 = −15 (the producer pays).
    assert short.tolist() == [0.0, 0.0, 80.0] and long.tolist() == [-15.0, 0.0, 20.0]


@pytest.mark.parametrize("changes, message", [
    ({"m_sur": 1.2}, "m_sur=1.2 must lie in \\[0, 1\\]"), ({"m_sur": -0.1}, "m_sur=-0.1 must lie in \\[0, 1\\]"),
    ({"m_def": 0.8}, "m_def=0.8 must be >= 1"), ({"m_sr": -1.0}, "m_sr=-1 must be >= 0"),
    ({"m_def": float("nan")}, "m_def=nan must be a finite number"), ({"c_heat_eur_per_mwh": -5.0}, "c_heat"),
])
def test_penalties_refuse_multipliers_that_would_unbound_the_settlement(changes, message):
    with pytest.raises(SettlementError, match=message):
        Penalties(**changes)


def test_real_imbalance_series_replace_the_formula_and_are_refused_where_they_cross():
    penalties = Penalties()
    short, long = penalties.imbalance_prices(np.array([50.0, -5.0]), np.array([70.0, 1.0]), np.array([30.0, -9.0]))
    assert short.tolist() == [70.0, 1.0] and long.tolist() == [30.0, -9.0]
    with pytest.raises(SettlementError, match="imbalance prices at 2025-03-18 01:00: short 1 EUR/MWh is below long 4"):
        penalties.imbalance_prices(np.array([50.0, -5.0]), np.array([70.0, 1.0]), np.array([30.0, 4.0]),
                                   labels=["2025-03-18 00:00", "2025-03-18 01:00"])


# ----------------------------------------------------------------------------- robust counterpart


@pytest.mark.parametrize("gamma, expected", [(0, 24 * 200.0), (6, 24 * 200.0 - 6 * 150.0), (24, 24 * 50.0)])
def test_buying_at_negative_prices_earns_money_and_is_protected_against_the_price_rising(gamma, expected):
    # DAM price band −30 / −20 / −5 EUR/MWh all day: the plan curtails its wind and buys its demand's 10 MW
    # (earning 20 EUR/MWh); the adverse move for a buyer is up by hi − mid = 15 EUR/MWh in Γ periods.
    case = tiny_case([wind("W", om=0.0)], ed_units=[demand("D", p_min=0.0, p_max=10.0)],
                     overrides={"price_da": gamma})
    problem = tiny_problem(case, W=(10.0, 10.0, 10.0), D=(0.0, 0.0, 0.0), price_da=(-30.0, -20.0, -5.0))
    assert (problem.sources["price_da"].deviation == 10.0).all()  # mid − lo ≥ 0 below zero too
    assert (problem.sources["price_da"].deviation_up == 15.0).all()
    result = solve_problem(problem)
    assert result.status == "optimal"
    assert np.allclose(result.market["p_da_mw"], -10.0)
    assert result.objective_eur == pytest.approx(expected, rel=1e-7)
    assert result.protection_eur["price_da"] == pytest.approx(min(gamma, NT) * 150.0, rel=1e-7)
    assert audit_result(result, bands=problem.bands) == []


def test_selling_into_negative_prices_is_avoided_by_curtailing():
    case = tiny_case([wind("W", om=0.0)], overrides={"price_da": 3})
    problem = tiny_problem(case, W=(40.0, 40.0, 40.0), price_da=(np.r_[[-8.0] * 12, [30.0] * 12],
                                                                  np.r_[[-3.0] * 12, [40.0] * 12],
                                                                  np.r_[[0.0] * 12, [45.0] * 12]))
    result = solve_problem(problem)
    assert result.status == "optimal"
    p = result.market["p_da_mw"].to_numpy()
    assert np.allclose(p[:12], 0.0) and np.allclose(p[12:], 40.0)
    # Selling 40 MW at 40 EUR/MWh for 12 h, less the 3 largest losses (10 EUR/MWh × 40 MW).
    assert result.objective_eur == pytest.approx(12 * 40 * 40.0 - 3 * 400.0, rel=1e-7)


# ----------------------------------------------------------------------------- settlement


def _settle(case, bids: FirstStage, real: Realization, penalties: Penalties):
    """Settle with the recourse model and return the outcome and the per-period slacks."""
    problem = realized_problem(case, real)
    m = build_recourse_model([problem], penalties, bids)
    outcome = run_highs(m, case.solver)
    b = m.scenario[0]
    slack = {name: np.array([pyo.value(getattr(b, name)[t]) for t in b.T]) for name in ("s_neg", "s_pos")} \
        if outcome.usable else {}
    return outcome, slack, (float(pyo.value(b.net_cost)) if outcome.usable else None)


def _hand_net_cost(price, available, bid, short, long, om):
    """Cheapest production x ∈ [0, available] per period: cost C·x + π_def·(P − x)⁺ − π_sur·(x − P)⁺
    (convex since π_def ≥ π_sur, so a corner is optimal), plus the DAM revenue −λ·P."""
    total = 0.0
    for lam, a, p, s, lo in zip(price, available, bid, short, long):
        def cost(x):
            return om * x + s * max(0.0, p - x) - lo * max(0.0, x - p)
        total += min(cost(x) for x in (0.0, min(p, a), a)) - lam * p
    return total


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(price=st.lists(st.floats(-200.0, 300.0, allow_nan=False), min_size=NT, max_size=NT),
       available=st.lists(st.floats(0.0, 50.0, allow_nan=False), min_size=NT, max_size=NT),
       bid=st.lists(st.floats(0.0, 50.0, allow_nan=False), min_size=NT, max_size=NT),
       m_def=m_defs, m_sur=m_surs)
def test_settlement_is_bounded_and_exact_for_any_sign_of_the_price(price, available, bid, m_def, m_sur):
    case = tiny_case([wind("W", om=3.0)])
    values = pd.DataFrame({"price_da": price, "price_sr_up": 0.0, "price_sr_dn": 0.0, "W": available},
                          index=pd.RangeIndex(1, NT + 1, name="t"))
    zero = np.zeros(NT)
    bids = FirstStage(np.array(bid), zero, zero, zero)
    penalties = Penalties(m_def=m_def, m_sur=m_sur)
    outcome, slack, net_cost = _settle(case, bids, Realization(DAY, values), penalties)
    assert outcome.status is Outcome.OPTIMAL
    short, long = short_and_long(price, m_def, m_sur)
    assert net_cost == pytest.approx(_hand_net_cost(price, available, bid, short, long, 3.0), rel=1e-6, abs=1e-4)
    strict = short > long + 1e-9
    assert np.all((slack["s_neg"] * slack["s_pos"])[strict] < 1e-6)


def _negative_paper_case(paper_case):
    """The paper case with a midday dip of 90 EUR/MWh: prices below zero from 11:00 to 16:00."""
    frame = paper_case.history.frame
    hour = frame.index.tz_convert(paper_case.timezone).hour
    dip = np.where((hour >= 11) & (hour <= 16), 90.0, 0.0)
    history = paper_case.history.with_columns({"price_da": frame["price_da"].to_numpy() - dip})
    return paper_case.replace(history=history)


def test_a_negative_price_day_solves_settles_bounded_and_passes_the_audit(paper_case):
    case = _negative_paper_case(paper_case)
    result = rvpp.solve(case)
    assert result.status == "optimal"
    assert (result.problem.sources["price_da"].nominal < 0).sum() >= 5
    assert audit_result(result) == []
    real = realization(case, case.delivery_date)
    assert (real.values["price_da"] < 0).sum() == 6
    outcome, slack, net_cost = _settle(case, first_stage(result), real, Penalties())
    assert outcome.status is Outcome.OPTIMAL and np.isfinite(net_cost)
    assert np.all(slack["s_neg"] * slack["s_pos"] < 1e-6)
    record = evaluate(case, first_stage(result), real)
    assert record["net_cost_eur"] == pytest.approx(record["market_cost_eur"] + record["penalty_eur"], rel=1e-9)
    # The price chart keeps the band below zero: no axis starts at 0.
    figure = bands_figure(result.problem, "price_da")
    assert min(min(trace.y) for trace in figure.data) < 0
    assert figure.layout.yaxis.range is None and figure.layout.yaxis.rangemode in (None, "normal")


@pytest.mark.slow
@pytest.mark.skipif(not OMIE_HOURLY.is_file(), reason="real OMIE prices not present")
def test_a_real_negative_price_day_of_2024(tmp_path):
    from rvpp.data.build_case import BuildOptions, build_case

    build_case([OMIE_HOURLY], tmp_path / "april", template=PAPER,
               options=BuildOptions(start="2024-03-01", end="2024-04-30", date="2024-04-14"))
    case = rvpp.load_case(tmp_path / "april")
    real = realization(case, dt.date(2024, 4, 14))
    assert (real.values["price_da"] < 0).sum() == 9 and (real.values["price_da"] <= 0).sum() >= 9
    result = rvpp.solve(case)
    assert result.status == "optimal"
    assert audit_result(result) == []
    outcome, slack, net_cost = _settle(case, first_stage(result), real, Penalties())
    assert outcome.status is Outcome.OPTIMAL and np.isfinite(net_cost)
    assert np.all(slack["s_neg"] * slack["s_pos"] < 1e-6)


def test_a_paper_case_day_settles_to_the_cent_at_the_hand_computed_slacks(paper_case):
    """A fixed bid on the paper case settled against a realization chosen by hand, in four blocks of six hours.

    The realization: wind 30 MW per farm, PV 20 MW per plant (120 MW of renewables at most), no sun for
    the CSP (its tank starts at its minimum, so the CSP stays off), electrical demands 25 / 40 / 25 MW
    (90 MW; the day's minimum energies 600 / 800 / 600 MWh are met at these levels, and they may rise
    to 70 / 80 / 60 MW at no cost), thermal demands 30 MW_th each, bought through the HPA (60 MW_th
    bid). The net injection is then anything between −210 MW (renewables off, demands at their
    maximum) and +30 MW (renewables at full output, demands as realized). With m_def = 2.5, m_sur = 0.4:

    ======  =====  =====  =====  =====  ==============================================================
    hours   λ      π_def  π_sur  bid    cheapest settlement
    ======  =====  =====  =====  =====  ==============================================================
    1-6     60     150    24     50     full output (saves 150 − O&M), injects 30: deficit 20 MW
    7-12    50     125    20     10     full output (20 > O&M 15 and 7.5), injects 30: surplus 20 MW
    13-18   −20    10     −32    −250   renewables off, demands at 210 MW: surplus 40 MW, which costs
    19-24   −10    5      −16    40     a deficit (5) is cheaper than output (O&M ≥ 7.5): renewables
                                        off, demands as realized (−90 MW): deficit 130 MW
    ======  =====  =====  =====  =====  ==============================================================
    """
    hours = np.arange(24)
    block = hours // 6
    price = np.array([60.0, 50.0, -20.0, -10.0])[block]
    bid = np.array([50.0, 10.0, -250.0, 40.0])[block]
    real = pd.DataFrame({"price_da": price, "price_sr_up": 12.0, "price_sr_dn": 7.0,
                         "WF1": 30.0, "WF2": 30.0, "PV1": 20.0, "PV2": 20.0, "PV3": 20.0, "CSP1": 0.0,
                         "ED_industry": 25.0, "ED_service": 40.0, "ED_residential": 25.0,
                         "TD_industry": 30.0, "TD_residential": 30.0}, index=pd.RangeIndex(1, NT + 1, name="t"))
    case = paper_case.replace(solver={"rel_gap": 1e-9, "threads": 1})
    zero = np.zeros(NT)
    bids = FirstStage(bid, zero, zero.copy(), np.full(NT, 60.0))
    record = evaluate(case, bids, Realization(case.delivery_date, real), Penalties(m_def=2.5, m_sur=0.4))
    assert record["status"] == "optimal"

    short, long = short_and_long(price, 2.5, 0.4)
    assert short[[0, 6, 12, 18]].tolist() == [150.0, 125.0, 10.0, 5.0]
    assert long[[0, 6, 12, 18]].tolist() == [24.0, 20.0, -32.0, -16.0]
    deficit = np.array([20.0, 0.0, 0.0, 130.0])[block]  # [MW]
    surplus = np.array([0.0, 20.0, 40.0, 0.0])[block]
    output = np.array([1, 1, 0, 0])[block]  # renewables at full output or off
    opex = output * (2 * 30.0 * 15.0 + 3 * 20.0 * 7.5)  # wind 15, PV 7.5 EUR/MWh
    tariff = np.array([70, 70, 70, 70, 70, 70, 85, 85, 100, 100, 100, 100,
                       100, 100, 95, 95, 95, 95, 120, 120, 120, 120, 90, 90], dtype=float)
    revenue_dam = (price * bid).sum()  # 18,000 + 3,000 + 30,000 − 2,400
    cost_hpa = (tariff * 60.0).sum()
    penalty_deficit = (short * deficit).sum()  # 150·20·6 + 5·130·6
    penalty_surplus = -(long * surplus).sum()  # −20·20·6 + 32·40·6
    assert (revenue_dam, cost_hpa, opex.sum()) == (48_600.0, 133_800.0, 16_200.0)
    assert (penalty_deficit, penalty_surplus) == (21_900.0, 5_280.0)

    cent = 0.005
    assert record["deficit_mwh"] == pytest.approx(deficit.sum(), abs=1e-6)   # 120 + 780
    assert record["surplus_mwh"] == pytest.approx(surplus.sum(), abs=1e-6)   # 120 + 240
    assert record["unserved_heat_mwh"] == pytest.approx(0.0, abs=1e-6)
    assert record["revenue_dam_eur"] == pytest.approx(revenue_dam, abs=cent)
    assert record["cost_hpa_eur"] == pytest.approx(cost_hpa, abs=cent)
    assert record["cost_opex_eur"] == pytest.approx(opex.sum(), abs=cent)
    assert record["penalty_deficit_eur"] == pytest.approx(penalty_deficit, abs=cent)
    assert record["penalty_surplus_eur"] == pytest.approx(penalty_surplus, abs=cent)
    assert record["penalty_eur"] == pytest.approx(penalty_deficit + penalty_surplus, abs=cent)
    assert record["market_cost_eur"] == pytest.approx(-revenue_dam + cost_hpa + opex.sum(), abs=cent)
    assert record["net_cost_eur"] == pytest.approx(-48_600.0 + 133_800.0 + 16_200.0 + 21_900.0 + 5_280.0, abs=cent)
