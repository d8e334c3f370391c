"""Intraday sessions (MODEL_SPEC §14): the settings, what a session knows at gate closure, its
trade and re-dispatch, the audit and the settlement against the final position.

The hand-worked day: one 50 MW wind farm, a flat DAM price of 50 EUR/MWh, no reserve, no heat.
The day-ahead forecast is 40 MW; the IDA2 forecast 20 MW; the wind then blows 18 MW. Every
figure below is computed by hand in the test.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.backtest.engine import DayTask, run_backtest, run_day
from rvpp.backtest.settings import BacktestSettings, variants_of
from rvpp.backtest.state import initial_state
from rvpp.data.history import History
from rvpp.data.intraday import session_times
from rvpp.data.periods import delivery_periods
from rvpp.errors import CaseError
from rvpp.model.session import Commitments
from rvpp.settle.audit import audit_session
from rvpp.settle.recourse import first_stage, realization
from rvpp.solving.intraday import solve_session
from rvpp.solving.plan import solve
from rvpp.store import BacktestStore
from rvpp.uncertainty.intraday import lead_factor, realized_price, session_problem
from rvpp.uncertainty.problem import prepare

from tests.factories import DAY, PAPER, tiny_case, wind

PRICE, OM, M_DEF = 50.0, 10.0, 2.0  # [EUR/MWh], [EUR/MWh], [-] (the default deficit multiplier)
DA_FC, IDA2_FC, ACTUAL, IDA2_PRICE = 40.0, 20.0, 18.0, 55.0  # [MW], [MW], [MW], [EUR/MWh]
CENT = 0.01


def _history(dt_days: int = 2, **on_day) -> History:
    """D-1 and D hourly: wind 40 MW and its forecast 40 MW on D-1 (so the climatology band of D is
    40 MW wide of nothing), the realized values of D given by ``on_day``."""
    first = pd.Timestamp(DAY - dt.timedelta(days=1), tz="Europe/Madrid")
    stamps = pd.date_range(first.tz_convert("UTC"), periods=24 * dt_days, freq="1h")
    on_d = np.arange(len(stamps)) >= 24
    columns = {"price_da": PRICE, "price_sr_up": 0.0, "price_sr_dn": 0.0, "W": DA_FC, "wind_fc": DA_FC}
    data = {name: np.where(on_d, on_day.get(name, value), value) for name, value in columns.items()}
    for name, value in on_day.items():
        if name not in data:
            data[name] = np.full(len(stamps), value)
    return History(pd.DataFrame({"timestamp": stamps, **data}))


def _hand_case(dt_h: float = 1.0, sessions=None, **on_day):
    case = tiny_case(wind_units=[wind("W", p_max=50.0, om=OM)], dt_h=dt_h)
    intraday = {"enabled": True, "sessions": sessions or [
        {"name": "IDA2", "gate_closure": "22:00", "gate_day": -1, "window_from": "00:00"}]}
    return case.replace(uncertainty={"window_days": 1}, intraday=intraday,
                        wind=[wind("W", p_max=50.0, om=OM, forecast_series="wind_fc")],
                        history=_history(**{"W": ACTUAL, "wind_fc_ida2": IDA2_FC, "price_ida2": IDA2_PRICE, **on_day}))


def _run(case, intraday: bool = True) -> dict:
    settings = BacktestSettings(DAY, DAY, variants_of(["deterministic"], perfect=False), intraday=intraday)
    return run_day(DayTask(case, DAY, settings.variants[0], initial_state(case), settings))


# ----------------------------------------------------------------------------- the hand-worked day


@pytest.mark.parametrize("dt_h", [1.0, 0.25])
def test_a_wind_forecast_20_mw_lower_at_ida2_is_bought_back_and_settled_as_computed_by_hand(dt_h):
    case = _hand_case(dt_h)
    record = _run(case)
    nt = int(round(24 / dt_h))
    assert record["plan_status"] == "optimal" and record["status"] == "optimal"
    # Day-ahead: 40 MW available at 50 EUR/MWh > O&M 10: sell 40 MW every period.
    assert record["bids"]["p_da_mw"] == pytest.approx([DA_FC] * nt, abs=1e-6)
    [ida2] = record["intraday"]
    assert ida2["session"] == "IDA2" and ida2["status"] == "optimal" and ida2["window_first_period"] == 0
    assert ida2["gate_closure"] == "2025-03-17T22:00:00+01:00"
    # IDA2: only 20 MW can be delivered, so 20 MW is bought back in every period ...
    assert ida2["traded_mw"] == pytest.approx([IDA2_FC - DA_FC] * nt, abs=1e-6)
    assert ida2["position_mw"] == pytest.approx([IDA2_FC] * nt, abs=1e-6)
    assert ida2["forecast_change_mw"]["W"] == pytest.approx([-20.0] * nt, abs=1e-9)
    # ... at the real IDA2 price of 55 EUR/MWh: 55 × (−20 MW) × 24 h = −26,400 EUR.
    assert ida2["price_eur_per_mwh"] == pytest.approx([IDA2_PRICE] * nt)
    assert ida2["trading_revenue_eur"] == pytest.approx(-26_400.0, abs=CENT)
    # Expected imbalance by the IDA2 forecast: |20 − 40| × 24 h = 480 MWh before, 0 after.
    assert ida2["expected_imbalance_before_mwh"] == pytest.approx(480.0, abs=1e-6)
    assert ida2["expected_imbalance_after_mwh"] == pytest.approx(0.0, abs=1e-6)
    assert ida2["origin"] == {"W": "real", "price": "real"}
    assert ida2["audit_violations"] == 0
    assert record["final_position_mw"] == pytest.approx([IDA2_FC] * nt, abs=1e-6)
    # Settlement: the wind blows 18 MW against a 20 MW position: 2 MW × 24 h = 48 MWh short at
    # π_def = 2 × 50 = 100 EUR/MWh: 4,800 EUR. Market: −(48,000 DAM − 26,400 intraday) + O&M
    # 18 × 10 × 24 = 4,320: −17,280 EUR. Net −12,480 EUR.
    assert record["deficit_mwh"] == pytest.approx(48.0, abs=1e-6)
    assert record["penalty_eur"] == pytest.approx(4_800.0, abs=CENT)
    assert record["revenue_dam_eur"] == pytest.approx(48_000.0, abs=CENT)
    assert record["intraday_revenue_eur"] == pytest.approx(-26_400.0, abs=CENT)
    assert record["cost_opex_eur"] == pytest.approx(4_320.0, abs=CENT)
    assert record["market_cost_eur"] == pytest.approx(-17_280.0, abs=CENT)
    assert record["net_cost_eur"] == pytest.approx(-12_480.0, abs=CENT)
    assert round(record["net_cost_eur"], 2) == round(record["market_cost_eur"] + record["penalty_eur"], 2)


def test_without_intraday_the_same_day_pays_the_whole_shortfall_as_imbalance():
    record = _run(_hand_case().replace(intraday={"enabled": False}), intraday=False)
    assert "intraday" not in record and record["revenue_intraday_eur"] == 0.0
    # 22 MW × 24 h = 528 MWh short at 100 EUR/MWh = 52,800 EUR; market −48,000 + 4,320.
    assert record["deficit_mwh"] == pytest.approx(528.0, abs=1e-6)
    assert record["penalty_eur"] == pytest.approx(52_800.0, abs=CENT)
    assert record["net_cost_eur"] == pytest.approx(-48_000.0 + 4_320.0 + 52_800.0, abs=CENT)


def test_a_forecast_that_rises_is_sold_only_where_the_price_pays_the_o_and_m():
    case = _hand_case(**{"wind_fc_ida2": 45.0, "W": 45.0})
    record = _run(case)
    [ida2] = record["intraday"]
    # 5 MW more than the day-ahead 40 MW, sold at the day-ahead price 50 > O&M 10.
    assert ida2["traded_mw"] == pytest.approx([5.0] * 24, abs=1e-6)
    assert ida2["trading_revenue_eur"] == pytest.approx(IDA2_PRICE * 5.0 * 24, abs=CENT)
    assert ida2["expected_imbalance_before_mwh"] == pytest.approx(0.0, abs=1e-6)
    assert record["penalty_eur"] == pytest.approx(0.0, abs=CENT)


# ----------------------------------------------------------------------------- sessions on the day


def test_the_iberian_preset_at_15_minutes_places_ida3_at_noon_and_the_gates_in_local_time():
    case = _hand_case(0.25).replace(intraday={"enabled": True, "sessions": []})
    periods = delivery_periods(DAY, case.timezone, 0.25)
    times = session_times(case.intraday, DAY, periods, case.timezone, 0.25)
    assert [(s.name, s.first, s.gate.strftime("%d %H:%M")) for s in times] == [
        ("IDA1", 0, "17 15:00"), ("IDA2", 0, "17 22:00"), ("IDA3", 48, "18 10:00")]


def test_the_tool_preset_has_seven_sessions_with_their_windows():
    case = _hand_case().replace(intraday={"enabled": True, "sessions": [], "preset": "tool_seven"})
    periods = delivery_periods(DAY, case.timezone, 1.0)
    times = session_times(case.intraday, DAY, periods, case.timezone, 1.0)
    assert [(s.name, s.first) for s in times] == [("IDM1", 0), ("IDM2", 0), ("IDM3", 4), ("IDM4", 7), ("IDM5", 12),
                                                  ("IDM6", 16), ("IDM7", 20)]


def test_a_window_not_on_a_period_boundary_is_refused_by_name():
    case = _hand_case(0.25, sessions=[{"name": "X1", "gate_closure": "10:00", "gate_day": 0, "window_from": "12:10"}])
    periods = delivery_periods(DAY, case.timezone, 0.25)
    with pytest.raises(CaseError, match="X1: window_from=12:10 is not the start of a 15-minute period"):
        session_times(case.intraday, DAY, periods, case.timezone, 0.25)


@pytest.mark.parametrize("intraday, words", [
    ({"sessions": [{"name": "A", "gate_closure": "13:00", "gate_day": 0, "window_from": "12:00"}]},
     "session A: the gate closes at 13:00 on D, after its window starts at 12:00"),
    ({"sessions": [{"name": "A", "gate_closure": "22:00", "gate_day": -1, "window_from": "24:00"}]},
     "window_from=24:00 lies outside the delivery day"),
    ({"sessions": [{"name": "A", "gate_closure": "22:00", "gate_day": -1, "window_from": "25:30"}]},
     "'25:30' is not a clock time"),
    ({"sessions": [{"name": "A", "gate_closure": "22:00", "gate_day": -2}]}, "gate_day"),
    ({"sessions": [{"name": "A", "gate_closure": "22:00", "gate_day": -1},
                   {"name": "B", "gate_closure": "15:00", "gate_day": -1}]},
     "sessions out of time order: B closes at 15:00 on D-1, not after A at 22:00 on D-1"),
    ({"sessions": [{"name": "A", "gate_closure": "11:00", "gate_day": -1}]}, "not after the day-ahead gate"),
    ({"lead_time_exponent": -0.5}, "lead_time_exponent=-0.5 must be >= 0"),
    ({"lead_time_exponent": float("nan")}, "lead_time_exponent=nan must be a finite number"),
    ({"price_spread_eur_per_mwh": float("inf")}, "price_spread_eur_per_mwh=inf must be a finite number"),
    ({"price_spread_eur_per_mwh": -1}, "price_spread_eur_per_mwh=-1 must be >= 0"),
    ({"gamma_shrink": 1.5}, "gamma_shrink=1.5 must be <= 1"),
])
def test_bad_intraday_settings_are_refused_by_name_before_any_solve(intraday, words):
    case = tiny_case(wind_units=[wind("W")])
    with pytest.raises(CaseError) as refused:
        case.replace(intraday=intraday)
    assert words in str(refused.value) and str(refused.value).startswith("intraday")


def test_the_intraday_section_is_written_only_when_set_and_read_back(tmp_path):
    plain = tiny_case(wind_units=[wind("W")])
    assert "intraday" not in plain.to_data()
    case = _hand_case()
    rvpp.save_case(case, tmp_path / "c")
    again = rvpp.load_case(tmp_path / "c")
    assert again.intraday == case.intraday and again.intraday.resolved[0].name == "IDA2"


# ----------------------------------------------------------------------------- what a session knows


def test_the_case_says_which_session_prices_and_forecasts_are_real_and_which_modelled():
    case = _hand_case(sessions=[{"name": "IDA2", "gate_closure": "22:00", "gate_day": -1},
                                {"name": "IDA3", "gate_closure": "10:00", "gate_day": 0, "window_from": "12:00"}])
    said = ("Intraday sessions IDA2, IDA3: prices real for IDA2, modelled (the day-ahead price and a seeded "
            "spread); forecasts real in wind_fc_ida2, otherwise modelled (the day-ahead error shrunk with the "
            "lead time).")
    assert case.intraday_summary() == said
    assert case.provenance_summary() == said  # a case without history provenance still says it
    bundled = rvpp.load_case(PAPER).replace(intraday={"enabled": True})
    assert bundled.intraday_summary() == ("Intraday sessions IDA1, IDA2, IDA3: prices modelled (the day-ahead "
                                          "price and a seeded spread); forecasts modelled (the day-ahead error "
                                          "shrunk with the lead time).")
    assert rvpp.load_case(PAPER).provenance_summary() is None  # sessions off: nothing to say


def test_lead_time_factor_is_the_square_root_of_the_lead_time_ratio():
    periods = delivery_periods(DAY, "Europe/Madrid", 1.0)
    gate = pd.Timestamp("2025-03-17 22:00", tz="Europe/Madrid")
    reference = pd.Timestamp("2025-03-17 12:00", tz="Europe/Madrid")
    factor = lead_factor(periods, gate, reference, 0.5)
    # 00:00 of D: 2 h after IDA2's gate, 12 h after the day-ahead gate; 23:00: 25 h and 35 h.
    assert factor[0] == pytest.approx(math.sqrt(2 / 12))
    assert factor[23] == pytest.approx(math.sqrt(25 / 35))
    assert lead_factor(periods, gate, reference, 0.0) == pytest.approx(np.ones(24))


def test_a_modelled_forecast_shrinks_the_day_ahead_band_towards_what_happened():
    # No per-session column: the band of D-1 is 30..50 MW (two days of 30 and 50), the actual 18 MW.
    first = pd.Timestamp(DAY - dt.timedelta(days=2), tz="Europe/Madrid")
    stamps = pd.date_range(first.tz_convert("UTC"), periods=72, freq="1h")
    wind_mw = np.repeat([30.0, 50.0, ACTUAL], 24)
    history = History(pd.DataFrame({"timestamp": stamps, "price_da": PRICE, "price_sr_up": 0.0, "price_sr_dn": 0.0,
                                    "W": wind_mw, "wind_fc": wind_mw, "price_ida2": IDA2_PRICE}))
    case = _hand_case()
    case = case.replace(history=history, uncertainty={"window_days": 2})
    day_ahead = prepare(case)
    lo, hi = (day_ahead.bands[("W", s)].to_numpy() for s in ("lo", "hi"))
    assert lo[0] == pytest.approx(30 + 0.2 * 20) and hi[0] == pytest.approx(30 + 0.8 * 20)  # percentiles of 30, 50
    actual = pd.DataFrame({"W": np.full(24, ACTUAL), "price_da": np.full(24, PRICE)}, index=pd.RangeIndex(1, 25))
    [session] = session_times(case.intraday, DAY, day_ahead.periods, case.timezone, 1.0)
    problem, origin = session_problem(case, day_ahead, day_ahead, session, actual)
    s0, s23 = math.sqrt(2 / 12), math.sqrt(25 / 35)
    assert origin["W"] == "modelled"
    for t, s in ((0, s0), (23, s23)):
        assert problem.bands[("W", "lo")].iloc[t] == pytest.approx(ACTUAL + s * (lo[t] - ACTUAL))
        assert problem.bands[("W", "hi")].iloc[t] == pytest.approx(ACTUAL + s * (hi[t] - ACTUAL))
    # The session's price band: λ_da ± σ·z(q_hi) with σ = 5 EUR/MWh and z(0.8) = 0.841621...
    assert problem.bands[("price_da", "hi")].iloc[5] == pytest.approx(PRICE + 5.0 * 0.8416212335729143)


def test_a_modelled_intraday_price_is_seeded_and_centred_on_the_day_ahead_price():
    case = _hand_case()
    case = case.replace(history=History(case.history.frame.drop(columns=["price_ida2"])))
    periods = delivery_periods(DAY, case.timezone, 1.0)
    [session] = session_times(case.intraday, DAY, periods, case.timezone, 1.0)
    first, origin = realized_price(case, session, periods, np.full(24, PRICE))
    again, _ = realized_price(case, session, periods, np.full(24, PRICE))
    other, _ = realized_price(case.replace(intraday={"price_seed": 7}), session, periods, np.full(24, PRICE))
    assert origin == "modelled"
    assert np.array_equal(first, again) and not np.allclose(first, other)
    assert abs(first.mean() - PRICE) < 5.0 and first.std() > 0.5


# ----------------------------------------------------------------------------- the bundled case


@pytest.mark.slow
def test_every_session_of_the_paper_day_keeps_its_commitments_and_net_is_market_plus_penalty():
    case = rvpp.with_options(rvpp.load_case(PAPER), threads=1)
    settings = BacktestSettings(case.delivery_date, case.delivery_date, variants_of(["balanced"], perfect=False),
                                intraday=True)
    record = run_day(DayTask(case, case.delivery_date, settings.variants[0], initial_state(case), settings))
    assert record["plan_status"] == "optimal" and record["status"] == "optimal"
    sessions = record["intraday"]
    assert [s["session"] for s in sessions] == ["IDA1", "IDA2", "IDA3"]
    p_da = np.array(record["bids"]["p_da_mw"])
    position = p_da.copy()
    cash = 0.0
    for s in sessions:
        assert s["status"] == "optimal", s["message"]
        assert s["audit_violations"] == 0, s["audit_first"]
        q = np.array(s["traded_mw"])
        assert np.all(q[:s["window_first_period"]] == 0.0)
        position = position + q
        assert np.allclose(s["position_mw"], position, atol=1e-9)
        revenue = float(np.dot(s["price_eur_per_mwh"], q) * case.dt_h)
        assert s["trading_revenue_eur"] == pytest.approx(revenue, abs=CENT)
        cash += revenue
        assert s["expected_imbalance_after_mwh"] <= s["expected_imbalance_before_mwh"] + 1e-6
    assert sessions[2]["window_first_period"] == 12
    assert np.allclose(record["final_position_mw"], position, atol=1e-9)
    assert record["intraday_revenue_eur"] == pytest.approx(cash, abs=CENT)
    market = (-(record["revenue_dam_eur"] + record["revenue_sr_eur"] + record["intraday_revenue_eur"])
              + record["cost_hpa_eur"] + record["cost_opex_eur"])
    assert record["market_cost_eur"] == pytest.approx(market, abs=CENT)
    assert abs(record["net_cost_eur"] - record["market_cost_eur"] - record["penalty_eur"]) < CENT / 2


# ----------------------------------------------------------------------------- a window from noon, and the audit


IDA3_ONLY = [{"name": "IDA3", "gate_closure": "10:00", "gate_day": 0, "window_from": "12:00"}]


def test_a_session_from_noon_trades_only_its_window_and_the_morning_stays_as_planned():
    case = _hand_case(sessions=IDA3_ONLY, **{"wind_fc_ida3": IDA2_FC, "price_ida3": IDA2_PRICE})
    record = _run(case)
    [ida3] = record["intraday"]
    assert ida3["status"] == "optimal" and ida3["window_first_period"] == 12 and ida3["audit_violations"] == 0
    assert ida3["traded_mw"] == pytest.approx([0.0] * 12 + [-20.0] * 12, abs=1e-6)
    assert ida3["forecast_change_mw"]["W"] == pytest.approx([0.0] * 12 + [-20.0] * 12, abs=1e-9)
    # Morning: 40 MW sold, 18 MW blown: 22 MW × 12 h short; afternoon: 2 MW × 12 h; at 100 EUR/MWh.
    assert record["deficit_mwh"] == pytest.approx(22 * 12 + 2 * 12, abs=1e-6)
    assert record["penalty_eur"] == pytest.approx(100.0 * (22 * 12 + 2 * 12), abs=CENT)
    assert record["intraday_revenue_eur"] == pytest.approx(-20.0 * 12 * IDA2_PRICE, abs=CENT)


def _session_and_commitments(case):
    plan = solve(case, keep_schedule=True)
    bids = first_stage(plan)
    [session] = session_times(case.intraday, DAY, plan.problem.periods, case.timezone, case.dt_h)
    problem, _ = session_problem(case, plan.problem, plan.problem, session, realization(case, DAY).values)
    commitments = Commitments(bids.p_da, bids.r_sr_up, bids.r_sr_dn, bids.h_hpa, np.zeros(24), session.first,
                              plan.schedule)
    return plan, solve_session(problem, commitments, session), commitments


def test_the_session_audit_finds_a_changed_bid_a_trade_before_the_window_and_a_moved_morning():
    case = _hand_case(sessions=IDA3_ONLY, **{"wind_fc_ida3": IDA2_FC, "price_ida3": IDA2_PRICE})
    plan, result, commitments = _session_and_commitments(case)
    assert result.status == "optimal"
    assert audit_session(result, commitments, plan.units) == []
    market = result.market.copy()
    market.loc[3, "p_da_mw"] += 1.0
    checks = {v.check for v in audit_session(replace(result, market=market), commitments, plan.units)}
    assert "session.fixed_p_da" in checks
    market = result.market.copy()
    market.loc[5, ["traded_mw", "position_mw"]] += 1.0
    checks = {v.check for v in audit_session(replace(result, market=market), commitments, plan.units)}
    assert "session.no_trade_before_window" in checks and "electric_balance[none]" in checks
    units = result.units.copy()
    units.loc[(units["unit"] == "W") & (units["t"] == 2), "p_mw"] -= 3.0
    checks = {v.check for v in audit_session(replace(result, units=units), commitments, plan.units)}
    assert "session.kept_p_mw" in checks
    traded = result.market.copy()
    traded.loc[15, ["traded_mw", "position_mw"]] -= 1.0
    checks = {v.check for v in audit_session(replace(result, market=traded), commitments, plan.units)}
    assert "session.revenue" in checks and "electric_balance[none]" in checks


def test_an_interrupted_intraday_backtest_resumes_to_the_records_of_an_uninterrupted_one(tmp_path):
    case = _hand_case().replace(history=_history(3, W=ACTUAL, wind_fc_ida2=IDA2_FC, price_ida2=IDA2_PRICE))
    settings = BacktestSettings(DAY, DAY + dt.timedelta(days=1), variants_of(["deterministic"], perfect=False),
                                intraday=True)
    store = BacktestStore(f"sqlite:///{tmp_path / 'resumed.sqlite3'}")

    def stop(_key, _record):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_backtest(case, settings, store, on_record=stop)
    ident = run_backtest(case, settings, store)
    whole = BacktestStore(f"sqlite:///{tmp_path / 'whole.sqlite3'}")
    resumed, straight = store.records(ident), whole.records(run_backtest(case, settings, whole))
    assert len(resumed) == len(straight) == 2
    # D: the day-ahead band is D-1's 40 MW, IDA2 says 20: buy 20 MW × 24 h at 55 EUR/MWh. D+1: the band
    # is D's 18 MW, IDA2 says 20: sell 2 MW × 24 h at 55 EUR/MWh.
    for (_, a), (_, b), cash in zip(resumed.iterrows(), straight.iterrows(), (-26_400.0, 2_640.0)):
        assert a["net_cost_eur"] == pytest.approx(b["net_cost_eur"], abs=CENT)
        assert a["intraday"][0]["traded_mw"] == pytest.approx(b["intraday"][0]["traded_mw"], abs=1e-9)
        assert a["intraday_revenue_eur"] == pytest.approx(cash, abs=CENT)
