"""Batteries, hydro and biomass units (MODEL_SPEC §13) on days worked out by hand.

Every expected profit below is derived in the comments from the prices and the unit's
parameters, not from a solve.
"""

import numpy as np
import pytest

from rvpp.settle.audit import audit_result
from rvpp.solving.plan import solve_problem
from tests.factories import tiny_case, tiny_problem

NT = 24
HOURS = np.arange(1, NT + 1)


def battery(name="B", **extra):
    return {"name": name, "e_min_mwh": 0.0, "e_max_mwh": 9.0, "p_ch_max_mw": 10.0, "p_dis_max_mw": 10.0,
            "eta_ch": 0.9, "eta_dis": 0.9, "ramp_mw_per_min": 10.0, **extra}


def dispatchable(name, **extra):
    return {"name": name, "p_max_mw": 30.0, "ramp_mw_per_min": 10.0, **extra}


def solved(case, prices):
    problem = tiny_problem(case, price_da=(prices, prices, prices))
    result = solve_problem(problem)
    assert result.status == "optimal", result.message
    assert audit_result(result, bands=problem.bands) == []
    return result


def test_a_battery_charges_at_the_low_price_and_discharges_at_the_high_one():
    # Hour 1 at 10 EUR/MWh, hour 2 at 100, every other hour 45; wear 50 EUR per MWh discharged.
    # A MWh bought returns 0.9 x 0.9 = 0.81 MWh. 10 -> 100: 81 - 10 - 0.81 x 50 = +30.5 per MWh bought;
    # 10 -> 45: 36.45 - 10 - 40.5 < 0; 45 -> 100: 81 - 45 - 40.5 < 0. So only hour 1 charges: 10 MW
    # stores 9 MWh (= E max, from an empty start on the cyclic day), hour 2 delivers 9 x 0.9 = 8.1 MW.
    # Profit = -10 x 10 + 100 x 8.1 - 50 x 8.1 = 305 EUR.
    prices = np.where(HOURS == 1, 10.0, np.where(HOURS == 2, 100.0, 45.0))
    result = solved(tiny_case(battery_units=[battery(degradation_eur_per_mwh=50.0)]), prices)
    assert result.objective_eur == pytest.approx(305.0, abs=1e-6)
    state = result.dispatch.set_index("t")
    assert state.loc[1, "charge_mw"] == pytest.approx(10.0) and state.loc[1, "energy_mwh"] == pytest.approx(9.0)
    assert state.loc[2, "discharge_mw"] == pytest.approx(8.1) and state.loc[2, "energy_mwh"] == pytest.approx(0.0)
    assert np.allclose(result.market["p_da_mw"].to_numpy()[:2], [-10.0, 8.1])


def test_a_battery_cannot_burn_energy_at_a_negative_price():
    # Price -20 all day, no wear. Energy bought in total C returns 0.81 C (cyclic day), so profit is
    # 20 x (C - 0.81 C) = 3.8 C. Each hour either charges (mode binary) at <= 10 MW, storing <= 9 MWh,
    # or discharges at most what is stored (<= E max = 9 MWh): 0.9 C <= 9 x (discharging hours) and
    # C <= 10 x (charging hours), so C <= 10 x 12 = 120 and profit = 3.8 x 120 = 456 EUR. Charging and
    # discharging at once (no binary) would earn 20 x (10 - 8.1) x 24 = 912.
    result = solved(tiny_case(battery_units=[battery()]), np.full(NT, -20.0))
    assert result.objective_eur == pytest.approx(456.0, abs=1e-6)
    state = result.dispatch
    assert ((state["charge_mw"] < 1e-6) | (state["discharge_mw"] < 1e-6)).all()


def test_a_battery_with_self_discharge_sells_what_would_decay_and_refills_at_the_last_hour():
    # Starts at 9 MWh, must end at >= 9 MWh, loses 10 % per hour, price 10 all day, no wear.
    # A MWh kept from midnight is 0.9^24 = 0.08 MWh at the end (worth 0.08 x 10 / 0.9 = 0.89 EUR of
    # charging saved); sold in hour 1 it is 0.9 (decay) x 0.9 (η_dis) = 0.81 MWh at 10 = 8.1 EUR. So hour 1
    # sells all: e[1] = 0.9 x 9 - p_dis / 0.9 = 0 gives p_dis = 7.29 MW (72.9 EUR); the
    # refill is as late as it can be (a MWh charged earlier decays): hour 24 charges 10 MW, storing 9 MWh
    # (-100 EUR). Profit = 72.9 - 100 = -27.1 EUR.
    result = solved(tiny_case(battery_units=[battery(e_init_mwh=9.0, self_discharge_per_h=0.1)]), np.full(NT, 10.0))
    assert result.objective_eur == pytest.approx(-27.1, abs=1e-6)
    state = result.dispatch.set_index("t")
    assert state.loc[1, "discharge_mw"] == pytest.approx(7.29, abs=1e-6)
    assert state.loc[24, "charge_mw"] == pytest.approx(10.0, abs=1e-6)
    assert state.loc[24, "energy_mwh"] == pytest.approx(9.0, abs=1e-6)


@pytest.mark.parametrize("e_init, e_end_min, profit, end", [
    (9.0, None, 0.0, 9.0),  # no target: ends at its start, and a cycle at one price only loses
    (9.0, 4.5, 202.5, 4.5),  # sells the 4.5 MWh above the target: 4.5 x 0.9 = 4.05 MWh at 50 EUR
    (9.0, 0.0, 405.0, 0.0),  # sells all 9 MWh: 8.1 MWh at 50 EUR
    (2.0, 4.5, 0.0, 2.0),  # started below the target: idles at its start (filling to 4.5 would cost 138.9)
])
def test_a_battery_may_run_down_to_its_end_target_and_no_further(e_init, e_end_min, profit, end):
    # Price 50 all day, no wear, no self-discharge, efficiencies 0.9 each way: charging never pays, so the
    # day sells what lies above min(target, start) and nothing else.
    unit = battery(e_init_mwh=e_init, e_end_min_mwh=e_end_min)
    result = solved(tiny_case(battery_units=[unit]), np.full(NT, 50.0))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)
    state = result.dispatch.set_index("t")
    assert state.loc[NT, "energy_mwh"] == pytest.approx(end, abs=1e-6)
    assert state["charge_mw"].sum() == pytest.approx(0.0, abs=1e-6)
    assert state["discharge_mw"].sum() == pytest.approx(0.9 * (e_init - end), abs=1e-6)


def test_a_hydro_day_at_its_energy_limit_runs_in_the_dearest_hours():
    # 0-30 MW, 5 EUR/MWh, 100 MWh of water. Hours 10-12 at 80 EUR/MWh, the rest at 50: the water
    # goes first to the three dear hours (3 x 30 = 90 MWh), the last 10 MWh to one hour at 50.
    # Profit = 90 x (80 - 5) + 10 x (50 - 5) = 7,200 EUR; the limit binds: 100 MWh produced.
    prices = np.where((HOURS >= 10) & (HOURS <= 12), 80.0, 50.0)
    unit = dispatchable("HY", marginal_cost_eur_per_mwh=5.0, energy_max_mwh=100.0)
    result = solved(tiny_case(hydro_units=[unit]), prices)
    assert result.objective_eur == pytest.approx(7200.0, abs=1e-6)
    output = result.dispatch.set_index("t")["p_mw"]
    assert output.sum() == pytest.approx(100.0) and np.allclose(output.loc[[10, 11, 12]], 30.0)


def test_a_hydro_limit_holds_with_all_up_reserve_called():
    # As above with SRM at 0 EUR/MW: reserve earns nothing but must not break Σ(p + r↑)·dt ≤ Emax.
    prices = np.where((HOURS >= 10) & (HOURS <= 12), 80.0, 50.0)
    unit = dispatchable("HY", marginal_cost_eur_per_mwh=5.0, energy_max_mwh=100.0)
    result = solve_problem(tiny_problem(tiny_case(hydro_units=[unit], srm=True), price_da=(prices, prices, prices),
                                        price_sr_up=(1.0, 1.0, 1.0)))
    assert result.status == "optimal"
    state = result.dispatch
    assert (state["p_mw"] + state["r_up_mw"]).sum() <= 100.0 + 1e-6


def biomass(**extra):
    return dispatchable("BIO", p_min_mw=5.0, p_max_mw=10.0, marginal_cost_eur_per_mwh=30.0, **extra)


def test_a_biomass_unit_may_not_restart_within_its_minimum_down_time():
    # Online at midnight, 5-10 MW at 30 EUR/MWh. Prices: hour 1 at 50, hours 2-3 at 0, hour 4 at 200,
    # then 0. Staying on through hours 2-3 at 5 MW: 10 x 20 - 2 x 5 x 30 + 10 x 170 = 1,600 EUR, then
    # off. Stopping in hour 2 forbids a start before hour 6 (4 h down): only 200 EUR. Without the
    # minimum down time it would stop for hours 2-3 and restart at hour 4: 200 + 1,700 = 1,900 EUR.
    prices = np.select([HOURS == 1, HOURS == 4], [50.0, 200.0], 0.0)
    held = solved(tiny_case(biomass_units=[biomass(initial_online=True, min_down_h=4.0)]), prices)
    assert held.objective_eur == pytest.approx(1600.0, abs=1e-6)
    assert held.dispatch.set_index("t")["online"].loc[[1, 2, 3, 4]].tolist() == [1, 1, 1, 1]
    free = solved(tiny_case(biomass_units=[biomass(initial_online=True)]), prices)
    assert free.objective_eur == pytest.approx(1900.0, abs=1e-6)


def test_a_down_time_begun_before_the_day_carries_over():
    # Offline for 1 h at midnight, 4 h minimum down: hours 1-3 stay off although they pay 200 EUR/MWh;
    # hour 4 (200) runs at 10 MW: 10 x (200 - 30) = 1,700 EUR; then prices 0: off (no minimum up time).
    prices = np.where(HOURS <= 4, 200.0, 0.0)
    unit = biomass(initial_online=False, initial_hours_in_status=1.0, min_down_h=4.0)
    result = solved(tiny_case(biomass_units=[unit]), prices)
    assert result.objective_eur == pytest.approx(1700.0, abs=1e-6)
    assert result.dispatch.set_index("t")["online"].loc[[1, 2, 3, 4, 5]].tolist() == [0, 0, 0, 1, 0]


def test_a_minimum_up_time_keeps_a_started_unit_online_at_a_loss():
    # Hydro 5-30 MW at 5 EUR/MWh, 3 h minimum up time, price 100 in hour 10 and 0 elsewhere. One
    # start: 30 MW in hour 10 earns 30 x 95 = 2,850 EUR, and the two other hours of the minimum run
    # sell 5 MW at 0 for 2 x 5 x 5 = 50 EUR of cost: 2,800 EUR, online exactly 3 hours around hour 10.
    prices = np.where(HOURS == 10, 100.0, 0.0)
    unit = dispatchable("HY", p_min_mw=5.0, marginal_cost_eur_per_mwh=5.0, min_up_h=3.0)
    result = solved(tiny_case(hydro_units=[unit]), prices)
    assert result.objective_eur == pytest.approx(2800.0, abs=1e-6)
    state = result.dispatch.set_index("t")
    assert state["online"].sum() == 3 and state.loc[10, "online"] == 1 and state["startup"].sum() == 1
    assert state.loc[10, "p_mw"] == pytest.approx(30.0)


def test_each_start_is_paid_once_and_whole():
    # Hydro 5-30 MW at 5 EUR/MWh, 100 EUR a start, no minimum times; price 100 in hours 5 and 20, 0
    # elsewhere. Two starts: 2 x (30 x 95 - 100) = 5,500 EUR; staying on from hour 5 to 20 instead
    # costs 14 x 5 x 5 = 350 EUR at price 0 for one start saved (100): 5,250. So two whole starts and
    # two whole stops.
    prices = np.where((HOURS == 5) | (HOURS == 20), 100.0, 0.0)
    unit = dispatchable("HY", p_min_mw=5.0, marginal_cost_eur_per_mwh=5.0, startup_cost_eur=100.0)
    result = solved(tiny_case(hydro_units=[unit]), prices)
    assert result.objective_eur == pytest.approx(5500.0, abs=1e-6)
    state = result.dispatch.set_index("t")
    assert state["online"].tolist() == [1 if t in (5, 20) else 0 for t in HOURS]
    assert state["startup"].tolist() == state["online"].tolist()
    assert state["shutdown"].tolist() == [1 if t in (6, 21) else 0 for t in HOURS]


def test_ramps_limit_a_start_and_the_rise_after_it():
    # 0-30 MW, start-up ramp 10 MW/h, ramp up 10 MW/h, price 50 in hours 1-3 and 0 after, cost 5:
    # from offline the unit reaches 10, 20, 30 MW: profit 45 x (10 + 20 + 30) = 2,700 EUR.
    prices = np.where(HOURS <= 3, 50.0, 0.0)
    unit = dispatchable("HY", marginal_cost_eur_per_mwh=5.0, startup_ramp_mw_per_h=10.0, ramp_up_mw_per_h=10.0,
                        shutdown_ramp_mw_per_h=30.0, ramp_dn_mw_per_h=30.0, p_init_mw=0.0)
    result = solved(tiny_case(hydro_units=[unit]), prices)
    assert result.objective_eur == pytest.approx(2700.0, abs=1e-6)
    assert np.allclose(result.dispatch.set_index("t")["p_mw"].loc[[1, 2, 3]], [10.0, 20.0, 30.0])


def test_a_disabled_unit_stays_in_the_case_and_out_of_the_plan():
    case = tiny_case(battery_units=[battery()], hydro_units=[dispatchable("HY", enabled=False)])
    assert [u.name for _, u in case.all_units()] == ["B", "HY"]
    result = solved(case, np.full(NT, 50.0))
    assert set(result.dispatch["unit"]) == {"B"} and set(result.units["unit"]) == {"B"}


def test_the_installed_reserve_base_counts_supply_alone():
    # Hydro 0-30 MW and a demand of 10-20 MW, κ = 0.3, energy worth 0 and reserve 10 EUR/MW: "net" caps each band
    # at 0.3 x (30 - 20) = 3 MW, "installed" at 0.3 x 30 = 9 MW.
    from tests.factories import demand
    unit = dispatchable("HY", ramp_mw_per_min=10.0, reserve_share=1.0)
    for base, cap in (("net", 3.0), ("installed", 9.0)):
        case = tiny_case(hydro_units=[unit], ed_units=[demand(p_min=10.0, p_max=20.0)], srm=True)
        case = case.replace(markets={"reserve_base": base})
        problem = tiny_problem(case, D=(10.0, 10.0, 10.0), price_da=(0.0, 0.0, 0.0),
                               price_sr_up=(10.0, 10.0, 10.0), price_sr_dn=(10.0, 10.0, 10.0))
        result = solve_problem(problem)
        assert result.status == "optimal"
        assert audit_result(result, bands=problem.bands) == []
        assert np.allclose(result.market["r_sr_up_mw"], cap) and np.allclose(result.market["r_sr_dn_mw"], cap)


def test_the_audit_finds_a_battery_that_breaks_its_energy_balance_or_its_mode():
    prices = np.where(HOURS == 1, 10.0, np.where(HOURS == 2, 100.0, 45.0))
    result = solved(tiny_case(battery_units=[battery(degradation_eur_per_mwh=50.0)]), prices)
    from rvpp.settle.audit import audit_day, audit_tables
    day = audit_day(result.case, result.problem.bands)
    tampered = result.dispatch.copy()
    tampered.loc[tampered["t"] == 2, "energy_mwh"] += 1.0
    checks = {v.check for v in audit_tables(day, result.market, result.units, result.csp, result.summary(),
                                            dispatch=tampered)}
    assert "battery.energy_balance" in checks
    tampered = result.dispatch.copy()
    tampered.loc[tampered["t"] == 1, "discharge_mw"] = 1.0  # discharging while charging
    checks = {v.check for v in audit_tables(day, result.market, result.units, result.csp, result.summary(),
                                            dispatch=tampered)}
    assert "battery.discharge_ceiling" in checks


def test_the_audit_finds_a_battery_that_ends_below_its_end_target():
    # Sold down to its 4.5 MWh target (above); 0.1 MWh less at midnight breaks the end rule
    result = solved(tiny_case(battery_units=[battery(e_init_mwh=9.0, e_end_min_mwh=4.5)]), np.full(NT, 50.0))
    from rvpp.settle.audit import audit_day, audit_tables
    day = audit_day(result.case, result.problem.bands)
    tampered = result.dispatch.copy()
    tampered.loc[tampered["t"] == NT, "energy_mwh"] = 4.4
    checks = {v.check for v in audit_tables(day, result.market, result.units, result.csp, result.summary(),
                                            dispatch=tampered)}
    assert "battery.energy_end" in checks


def test_the_audit_finds_a_restart_within_the_minimum_down_time():
    prices = np.select([HOURS == 1, HOURS == 4], [50.0, 200.0], 0.0)
    result = solved(tiny_case(biomass_units=[biomass(initial_online=True)]), prices)  # stops and restarts
    held = tiny_case(biomass_units=[biomass(initial_online=True, min_down_h=4.0)])
    from rvpp.settle.audit import audit_day, audit_tables
    checks = {v.check for v in audit_tables(audit_day(held, result.problem.bands), result.market, result.units,
                                            result.csp, dispatch=result.dispatch)}
    assert "dispatchable.min_down" in checks


def test_the_least_run_a_unit_online_before_the_day_is_committed_to_fits_its_water_exactly():
    # Online before the day at 30 MW, 5 MW/h down, a stop only from 10 MW or less, 5 MW minimum: the
    # least it can produce is 25 + 20 + 15 + 10 = 70 MWh before it stops in hour 5. With exactly 70 MWh
    # of water that run is the only plan (the case model refuses 69, tests/test_units13_hostile.py).
    unit = dispatchable("HY", p_min_mw=5.0, initial_online=True, p_init_mw=30.0, ramp_dn_mw_per_h=5.0,
                        shutdown_ramp_mw_per_h=10.0, energy_max_mwh=70.0, marginal_cost_eur_per_mwh=1.0)
    result = solved(tiny_case(hydro_units=[unit]), np.full(NT, 40.0))
    assert result.dispatch["p_mw"].to_numpy() == pytest.approx([25.0, 20.0, 15.0, 10.0] + [0.0] * 20, abs=1e-6)
    assert result.dispatch["online"].tolist() == [1] * 4 + [0] * 20


def test_state_carries_a_battery_energy_and_a_unit_status_to_the_next_day():
    from rvpp.backtest.state import initial_state, with_state
    case = tiny_case(battery_units=[battery(e_init_mwh=3.0)],
                     biomass_units=[biomass(min_up_h=4.0, initial_online=False)])
    assert initial_state(case) == {"B": {"e_mwh": 3.0}, "BIO": {"online": False, "status_h": None, "p_mw": None}}
    nxt = with_state(case, {"B": {"e_mwh": 7.5}, "BIO": {"online": True, "status_h": 2.0, "p_mw": 8.0}})
    assert (nxt.battery[0].e_init_mwh, nxt.battery[0].e_end_min_mwh) == (7.5, None)  # carry: ends at its start
    unit = nxt.biomass[0]
    assert (unit.initial_online, unit.initial_hours_in_status, unit.p_init_mw) == (True, 2.0, 8.0)
    assert unit.initial_periods(1.0) == (2, 0)  # 4 h minimum up, 2 h done: 2 more periods online


def test_the_state_of_charge_chart_draws_the_battery_plan():
    from rvpp.outputs.plots import battery_figure
    prices = np.where(HOURS == 1, 10.0, np.where(HOURS == 2, 100.0, 45.0))
    result = solved(tiny_case(battery_units=[battery(degradation_eur_per_mwh=50.0)]), prices)
    figure = battery_figure(result, "B")
    charge = next(trace for trace in figure.data if trace.name == "State of charge (end of period)")
    assert list(charge.y[:3]) == pytest.approx([9.0, 0.0, 0.0])  # charged in hour 1, emptied in hour 2
    with pytest.raises(ValueError, match="unknown battery 'X'"):
        battery_figure(result, "X")


# ----------------------------------------------------------------------------- settlement


def settled(case, plan, price_da, with_end_state=False):
    """Settle ``plan`` against realized DAM prices ``price_da`` (reserve prices 0)."""
    import pandas as pd

    from rvpp.settle.recourse import Realization, evaluate, first_stage
    values = pd.DataFrame({"price_da": price_da, "price_sr_up": 0.0, "price_sr_dn": 0.0},
                          index=pd.RangeIndex(1, NT + 1, name="t"))
    record = evaluate(case, first_stage(plan), Realization(day=case.delivery_date, values=values),
                      with_end_state=with_end_state)
    assert record["status"] == "optimal"
    return record


def test_the_settlement_records_every_periods_battery_and_unit_dispatch_and_the_export_writes_it():
    # The battery day of the first test: hour 1 at 10 EUR/MWh charges 10 MW to E max = 9 MWh, hour 2 at
    # 100 delivers 9 x 0.9 = 8.1 MW, every other hour (45) idles. The biomass unit (5-10 MW at 30 EUR/MWh,
    # no start cost) is off in hour 1 (10 < 30) and runs 10 MW from hour 2 on (100 and 45 > 30). Settled
    # at the same prices, the dispatch is the plan's, and a backtest export writes it row by row.
    import pandas as pd

    from rvpp.backtest.export import dispatch_table
    from rvpp.settle.recourse import Realization, evaluate, first_stage
    prices = np.where(HOURS == 1, 10.0, np.where(HOURS == 2, 100.0, 45.0))
    case = tiny_case(battery_units=[battery(degradation_eur_per_mwh=50.0)], biomass_units=[biomass()])
    plan = solved(case, prices)
    values = pd.DataFrame({"price_da": prices, "price_sr_up": 0.0, "price_sr_dn": 0.0},
                          index=pd.RangeIndex(1, NT + 1, name="t"))
    record = evaluate(case, first_stage(plan), Realization(day=case.delivery_date, values=values),
                      with_end_state=True)
    assert record["status"] == "optimal"
    bat, bio = record["settled_units"]["B"], record["settled_units"]["BIO"]
    assert (bat["kind"], bio["kind"]) == ("battery", "biomass")
    charge, discharge, energy = (np.array(bat[key]) for key in ("charge_mw", "discharge_mw", "e_mwh"))
    assert charge == pytest.approx([10.0] + [0.0] * 23, abs=1e-6)
    assert discharge == pytest.approx([0.0, 8.1] + [0.0] * 22, abs=1e-6)
    assert energy == pytest.approx([9.0] + [0.0] * 23, abs=1e-6)
    # each period's energy follows from the one before it (a cyclic day: period 1 from period 24)
    assert energy == pytest.approx(np.roll(energy, 1) + 0.9 * charge - discharge / 0.9, abs=1e-6)
    assert record["end_state"]["B"]["e_mwh"] == pytest.approx(energy[-1], abs=1e-9)
    assert bio["online"] == [0] + [1] * 23
    assert bio["p_mw"] == pytest.approx([0.0] + [10.0] * 23, abs=1e-6)
    unsettled = {"day": "2025-05-06", "strategy": "balanced", "gamma": "preset", "settled_csp": None}
    table = dispatch_table(pd.DataFrame([{"day": "2025-05-05", "strategy": "balanced", "gamma": "preset",
                                          "settled_csp": {}, "settled_units": record["settled_units"]},
                                         unsettled]))
    assert list(table.columns) == ["day", "strategy", "gamma", "unit", "t", "online", "e_mwh_th", "kind", "p_mw",
                                   "charge_mw", "discharge_mw", "e_mwh"]
    rows = table.set_index(["unit", "t"])
    assert len(table) == 2 * NT and set(table["day"]) == {"2025-05-05"}
    assert rows.loc["B", "kind"].eq("battery").all() and rows.loc["BIO", "kind"].eq("biomass").all()
    assert rows.loc["B", "e_mwh"].to_numpy() == pytest.approx(energy)
    assert rows.loc["B", "charge_mw"].to_numpy() == pytest.approx(charge)
    assert rows.loc["BIO", "online"].tolist() == [0] + [1] * 23
    assert rows.loc["BIO", "p_mw"].to_numpy() == pytest.approx([0.0] + [10.0] * 23, abs=1e-6)
    assert rows.loc["B", "online"].isna().all() and rows.loc["BIO", "e_mwh"].isna().all()


def test_the_settlement_holds_a_batterys_end_target_and_hands_its_energy_to_the_next_day():
    # The plan of the end-target day above (9 MWh start, 4.5 MWh target, price 50) sells 4.05 MWh; settled
    # at the same prices it does the same, ends at 4.5 MWh (held at 9 MWh it would have to miss its
    # bids) and hands 4.5 MWh to the next day
    case = tiny_case(battery_units=[battery(e_init_mwh=9.0, e_end_min_mwh=4.5)])
    prices = np.full(NT, 50.0)
    record = settled(case, solved(case, prices), prices, with_end_state=True)
    energy = np.array(record["settled_units"]["B"]["e_mwh"])
    assert energy[-1] == pytest.approx(4.5, abs=1e-6)
    assert sum(record["settled_units"]["B"]["discharge_mw"]) == pytest.approx(4.05, abs=1e-6)
    assert record["end_state"]["B"]["e_mwh"] == pytest.approx(4.5, abs=1e-6)


def test_the_settlement_keeps_a_unit_online_where_the_plan_committed_it():
    # Biomass 5-10 MW at 30 EUR/MWh, price 50 all day: the plan runs 10 MW every hour and sells it.
    # Realized, hour 12 pays 0, where a deficit costs π_def = 0 + (2 - 1) x 0 = 0. The unit stays
    # committed, so it delivers at least 5 MW (5 x 30 = 150 EUR) and is 5 MW short, at no penalty.
    # Revenue 23 x 50 x 10 = 11,500; opex 23 x 10 x 30 + 150 = 7,050; net cost -4,450 EUR.
    # Re-committed (stopped in hour 12) it would settle at 6,900 - 11,500 = -4,600 EUR.
    case = tiny_case(biomass_units=[biomass()])
    plan = solved(case, np.full(NT, 50.0))
    assert plan.dispatch["online"].tolist() == [1] * NT
    record = settled(case, plan, np.where(HOURS == 12, 0.0, 50.0))
    assert record["revenue_dam_eur"] == pytest.approx(11500.0, abs=1e-6)
    assert record["cost_opex_eur"] == pytest.approx(7050.0, abs=1e-6)
    assert record["deficit_mwh"] == pytest.approx(5.0, abs=1e-6)
    assert record["penalty_eur"] == pytest.approx(0.0, abs=1e-6)
    assert record["net_cost_eur"] == pytest.approx(-4450.0, abs=1e-6)


def test_the_settlement_keeps_a_unit_offline_where_the_plan_left_it_off():
    # Hydro 5-30 MW at 5 EUR/MWh; planned at 50 EUR/MWh in hours 1-12 (30 MW each) and 0 after (off:
    # 5 MW would lose 25 EUR an hour). Realized, hour 18 pays 100: a start would sell 30 MW of surplus
    # at π_sur = 100 - 0.5 x 100 = 50 for a gain of 30 x (50 - 5) = 1,350 EUR, but the plan has the unit
    # off there. Net cost = 12 x 30 x 5 - 12 x 50 x 30 = 1,800 - 18,000 = -16,200 EUR (-17,550 if restarted).
    case = tiny_case(hydro_units=[dispatchable("HY", p_min_mw=5.0, marginal_cost_eur_per_mwh=5.0)])
    plan = solved(case, np.where(HOURS <= 12, 50.0, 0.0))
    assert plan.dispatch["online"].tolist() == [1] * 12 + [0] * 12
    record = settled(case, plan, np.where(HOURS == 18, 100.0, np.where(HOURS <= 12, 50.0, 0.0)))
    assert record["surplus_mwh"] == pytest.approx(0.0, abs=1e-6)
    assert record["cost_opex_eur"] == pytest.approx(1800.0, abs=1e-6)
    assert record["net_cost_eur"] == pytest.approx(-16200.0, abs=1e-6)


def test_a_commitment_for_a_unit_the_case_lacks_is_refused():
    from rvpp.errors import SettlementError
    from rvpp.settle.recourse import FirstStage, Realization, evaluate, nominal_realization
    case = tiny_case(biomass_units=[biomass()])
    plan = solved(case, np.full(NT, 50.0))
    zero = np.zeros(NT)
    real = nominal_realization(plan.problem)
    for committed, words in (({"HY": np.ones(NT)}, "not a hydro or biomass unit"),
                             ({"BIO": np.full(NT, 0.5)}, "0 or 1"), ({"BIO": np.ones(3)}, "0 or 1")):
        with pytest.raises(SettlementError, match=words):
            evaluate(case, FirstStage(zero, zero, zero, zero, committed=committed),
                     Realization(day=real.day, values=real.values))
