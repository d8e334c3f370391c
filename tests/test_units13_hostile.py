"""Bad batteries, hydro and biomass units are refused by name before any solve (MODEL_SPEC §13)."""

import pytest

from rvpp.data.case import parse_case
from rvpp.errors import CaseError
from tests.factories import tiny_case


def refused(**units) -> list[str]:
    data = tiny_case(battery_units=[{"name": "OK", "e_max_mwh": 10.0, "p_ch_max_mw": 5.0, "p_dis_max_mw": 5.0,
                                     "ramp_mw_per_min": 1.0}]).to_data()
    data["units"].update(units)
    with pytest.raises(CaseError) as info:
        parse_case(data, tiny_case(battery_units=[{"name": "OK", "e_max_mwh": 10.0, "p_ch_max_mw": 5.0,
                                                   "p_dis_max_mw": 5.0, "ramp_mw_per_min": 1.0}]).history)
    return info.value.problems


BAT = {"name": "B1", "e_max_mwh": 40.0, "p_ch_max_mw": 10.0, "p_dis_max_mw": 10.0, "ramp_mw_per_min": 5.0}
HY = {"name": "H1", "p_min_mw": 5.0, "p_max_mw": 30.0, "ramp_mw_per_min": 5.0}


@pytest.mark.parametrize("units, message", [
    ({"battery": [{**BAT, "e_min_mwh": 50.0}]}, 'battery "B1": e_min_mwh=50 must be < e_max_mwh=40'),
    ({"battery": [{**BAT, "e_init_mwh": 45.0}]}, 'battery "B1": e_init_mwh=45 must lie in [e_min_mwh=0, e_max_mwh=40]'),
    ({"battery": [{**BAT, "e_init_mwh": 20.0, "e_end_min_mwh": 45.0}]},
     'battery "B1": e_end_min_mwh=45 must lie in [e_min_mwh=0, e_max_mwh=40]'),
    ({"battery": [{**BAT, "e_min_mwh": 5.0, "e_init_mwh": 20.0, "e_end_min_mwh": 2.0}]},
     'battery "B1": e_end_min_mwh=2 must lie in [e_min_mwh=5, e_max_mwh=40]'),
    ({"battery": [{**BAT, "e_end_min_mwh": 10.0}]},
     'battery "B1": e_end_min_mwh=10 needs e_init_mwh: a cyclic day (no initial energy) has no end target'),
    ({"battery": [{**BAT, "eta_ch": 0.0}]}, 'battery "B1": eta_ch=0 must be > 0'),
    ({"battery": [{**BAT, "eta_dis": 1.2}]}, 'battery "B1": eta_dis=1.2 must be <= 1'),
    ({"battery": [{**BAT, "self_discharge_per_h": 1.0}]}, 'battery "B1": self_discharge_per_h=1 must be < 1'),
    # 0.5 of 20 MWh lost in an hour (10 MW) beside 0.95 x 10 MW charged: the energy must fall below E min
    ({"battery": [{**BAT, "e_min_mwh": 20.0, "self_discharge_per_h": 0.5}]},
     'battery "B1": self_discharge_per_h=0.5 loses 10 MW at e_min_mwh=20, more than charging at full power '
     "restores: eta_ch=0.95 x p_ch_max_mw=10 = 9.5 MW; the energy could not stay at or above its minimum"),
    # 0.25 of 40 MWh (10 MW) against 9.5 MW charged: the day cannot end where it started
    ({"battery": [{**BAT, "e_init_mwh": 40.0, "self_discharge_per_h": 0.25}]},
     'battery "B1": self_discharge_per_h=0.25 loses 10 MW at e_init_mwh=40, more than charging at full power '
     "restores: eta_ch=0.95 x p_ch_max_mw=10 = 9.5 MW; the day could not end at or above its initial energy"),
    # 0.25 of 39 MWh (9.75 MW) against 9.5 MW charged: the day cannot end at its target below its start
    ({"battery": [{**BAT, "e_init_mwh": 40.0, "e_end_min_mwh": 39.0, "self_discharge_per_h": 0.25}]},
     'battery "B1": self_discharge_per_h=0.25 loses 9.75 MW at e_end_min_mwh=39, more than charging at full power '
     "restores: eta_ch=0.95 x p_ch_max_mw=10 = 9.5 MW; the day could not end at or above its end target"),
    ({"hydro": [{**HY, "energy_max_mwh": 10.0, "min_up_h": 4.0}]},
     'hydro "H1": energy_max_mwh=10 is below the 20 MWh of a run at p_min_mw=5 for min_up_h=4: once started, the '
     "unit could not run its minimum up time at its minimum output"),
    ({"hydro": [{**HY, "energy_max_mwh": 4.0}]},
     'hydro "H1": energy_max_mwh=4 is below the 5 MWh of one period (dt_h=1) at p_min_mw=5: the unit could never '
     "run"),
    # online before the day at 30 MW, 5 MW/h down and a stop from 10 MW at most: 25 + 20 + 15 + 10 = 70 MWh
    ({"hydro": [{**HY, "initial_online": True, "p_init_mw": 30.0, "ramp_dn_mw_per_h": 5.0,
                 "shutdown_ramp_mw_per_h": 10.0, "energy_max_mwh": 69.0}]},
     'hydro "H1": energy_max_mwh=69 is below the 70 MWh the day commits the unit to: online before the day '
     "(p_init_mw=30, ramp_dn_mw_per_h=5, shutdown_ramp_mw_per_h=10), it must run 4 h at least before it may stop"),
    # online 1 h of a 6 h minimum up time: 5 more hours at 5 MW = 25 MWh
    ({"biomass": [{**HY, "initial_online": True, "initial_hours_in_status": 1.0, "min_up_h": 6.0,
                   "energy_max_mwh": 31.0, "min_down_h": 0.0}]}, None),
    # a start's period reaches at most 3 MW/h x 1 h = 3 MW, below the 5 MW the unit runs at when online
    ({"hydro": [{**HY, "startup_ramp_mw_per_h": 3.0}]},
     'hydro "H1": startup_ramp_mw_per_h=3 allows at most 3 MW in the period of a start (dt_h=1), below '
     "p_min_mw=5: the unit could never start; give a ramp of at least 5 MW/h"),
    ({"biomass": [{**HY, "shutdown_ramp_mw_per_h": 4.0}]},
     'biomass "H1": shutdown_ramp_mw_per_h=4 allows at most 4 MW in the period before a stop (dt_h=1), below '
     "p_min_mw=5: the unit could never stop; give a ramp of at least 5 MW/h"),
    ({"biomass": [{**HY, "min_up_h": 25.0}]}, 'biomass "H1": min_up_h=25 must be <= 24'),
    ({"biomass": [{**HY, "min_down_h": 30.0}]}, 'biomass "H1": min_down_h=30 must be <= 24'),
    ({"hydro": [{**HY, "min_up_h": 1.5}]}, 'hydro "H1": min_up_h=1.5 must be a multiple of dt_h=1'),
    ({"hydro": [{**HY, "p_init_mw": 3.0}]},
     'hydro "H1": p_init_mw=3 must be 0 for a unit off before the day (initial_online=false)'),
    ({"hydro": [{**HY, "p_min_mw": 40.0}]}, 'hydro "H1": p_min_mw=40 must be <= p_max_mw=30'),
    ({"hydro": [{**HY, "name": "OK"}]}, 'hydro "OK": name is used by more than one unit; names must be unique'),
    ({"biomass": [HY, {**HY, "enabled": False}]},
     'biomass "H1": name is used by more than one unit; names must be unique'),
])
def test_bad_units_are_refused_by_name(units, message):
    if message is None:  # a good unit beside the bad ones: it loads
        base = tiny_case(battery_units=[{**BAT, "name": "OK"}])
        data = base.to_data()
        data["units"].update(units)
        assert [u.name for _, u in parse_case(data, base.history).units()] == ["OK", "H1"]
        return
    problems = refused(**units)
    assert any(p.startswith(message) for p in problems), problems


def test_a_refused_case_writes_nothing(tmp_path):
    from rvpp.data.case_yaml import load_case
    import yaml
    case = tiny_case(battery_units=[BAT])
    data = case.to_data()
    data["units"]["battery"][0]["e_min_mwh"] = 99.0
    (tmp_path / "case.yaml").write_text(yaml.safe_dump({**data, "history": "history.csv"}))
    case.history.frame.reset_index(names="timestamp").to_csv(tmp_path / "history.csv", index=False)
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(CaseError, match="e_min_mwh=99 must be < e_max_mwh=40"):
        load_case(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_the_fuzz_base_with_the_new_units_loads(paper_case):
    # the unmutated base of the fuzzed case model must itself be valid, or every mutation is refused
    from tests.test_fuzz_case import RAW_NEW_UNITS
    case = parse_case(RAW_NEW_UNITS, paper_case.history)
    assert [u.name for _, u in case.units()][-2:] == ["BAT1", "HY1"]  # BIO1 is disabled
    assert [u.name for _, u in case.all_units()][-3:] == ["BAT1", "HY1", "BIO1"]


@pytest.mark.parametrize("units, shown", [
    ({"hydro": [{**HY, "energy_max_mwh": 10.0, "min_up_h": 4.0}]},
     "H1: Energy max [MWh] = 10 is below the 20 MWh of a run at P min [MW] = 5 for Min up [h] = 4: once started, "
     "the unit could not run its minimum up time at its minimum output"),
    ({"hydro": [{**HY, "energy_max_mwh": 4.0}]},
     "H1: Energy max [MWh] = 4 is below the 5 MWh of one period (Market time unit [h] = 1) at P min [MW] = 5: "
     "the unit could never run"),
    ({"hydro": [{**HY, "p_init_mw": 3.0}]},
     "H1: P start [MW] = 3 must be 0 for a unit off before the day (On at midnight = false): an offline unit "
     "produces nothing"),
    ({"battery": [{**BAT, "e_init_mwh": 20.0, "e_end_min_mwh": 45.0}]},
     "B1: E end min [MWh] = 45 must lie in [E min [MWh] = 0, E max [MWh] = 40]"),
    ({"battery": [{**BAT, "e_min_mwh": 20.0, "self_discharge_per_h": 0.5}]},
     "B1: Self-discharge [1/h] = 0.5 loses 10 MW at E min [MWh] = 20, more than charging at full power restores: "
     "η charge [-] = 0.95 x Charge max [MW] = 10 = 9.5 MW; the energy could not stay at or above its minimum"),
])
def test_the_forms_show_the_refusals_in_their_column_names(units, shown):
    # the Portfolio page shows these messages: every field in the table's words, no case.yaml name left
    from rvpp.data.edits import plain_message
    texts = [plain_message(p) for p in refused(**units)]
    assert shown in texts, texts


def test_a_battery_at_the_balance_of_self_discharge_and_charging_loads():
    # 0.5 of 19 MWh lost in an hour is 9.5 MW, what 0.95 x 10 MW of charging restores: the day can hold
    # 19 MWh, and a level a ten-millionth of a MWh above it (a settled day's end) is still taken
    base = tiny_case(battery_units=[{**BAT, "e_min_mwh": 19.0, "self_discharge_per_h": 0.5}])
    assert [b.e_min_mwh for b in base.battery] == [19.0]
    carried = tiny_case(battery_units=[{**BAT, "e_init_mwh": 19.0 + 1e-7, "self_discharge_per_h": 0.5}])
    assert [b.e_init_mwh for b in carried.battery] == [19.0 + 1e-7]
    with pytest.raises(CaseError, match="loses 9.50001 MW at e_init_mwh=19, more than"):
        tiny_case(battery_units=[{**BAT, "e_init_mwh": 19.00002, "self_discharge_per_h": 0.5}])


def test_a_battery_that_cannot_hold_its_start_loads_with_an_end_target_it_can_hold():
    # 0.25 of 40 MWh (10 MW) outruns 9.5 MW of charging (refused above without a target); 0.25 of a
    # 20 MWh target is 5 MW, which charging restores: the day may run down to 20 MWh and hold there
    unit = tiny_case(battery_units=[{**BAT, "e_init_mwh": 40.0, "e_end_min_mwh": 20.0,
                                     "self_discharge_per_h": 0.25}]).battery[0]
    assert (unit.e_init_mwh, unit.e_end_min_mwh, unit.end_floor_mwh) == (40.0, 20.0, 20.0)


def test_a_start_up_ramp_that_fits_an_hour_but_not_15_minutes_is_refused_at_15_minutes():
    # 8 MW/h reaches 8 MW in an hour (above P min 5 MW: the unit may start) but 8 x 0.25 = 2 MW in a
    # 15-minute period: at 15 minutes the unit could never start, nor stop from P min
    unit = {**HY, "startup_ramp_mw_per_h": 8.0, "shutdown_ramp_mw_per_h": 8.0}
    hourly = tiny_case(hydro_units=[unit])
    assert [u.name for _, u in hourly.units()] == ["H1"]
    data = hourly.to_data()
    data["dt_h"] = 0.25
    with pytest.raises(CaseError) as info:
        parse_case(data, hourly.history)
    assert info.value.problems == [
        'hydro "H1": startup_ramp_mw_per_h=8 allows at most 2 MW in the period of a start (dt_h=0.25), below '
        "p_min_mw=5: the unit could never start; give a ramp of at least 20 MW/h",
        'hydro "H1": shutdown_ramp_mw_per_h=8 allows at most 2 MW in the period before a stop (dt_h=0.25), below '
        "p_min_mw=5: the unit could never stop; give a ramp of at least 20 MW/h"]


def test_a_case_whose_every_unit_is_switched_off_is_refused():
    # a battery and a hydro unit, both enabled: false: the plan would have no unit and profit 0
    base = tiny_case(battery_units=[{**BAT, "enabled": False}, {**BAT, "name": "B2"}])
    data = base.to_data()
    data["units"]["battery"][1]["enabled"] = False
    data["units"]["hydro"] = [{**HY, "enabled": False}]
    with pytest.raises(CaseError) as info:
        parse_case(data, base.history)
    assert info.value.problems == ['units: every unit is switched off (enabled: false: "B1", "B2", "H1"); the plan '
                                   "would hold no unit and trade nothing; switch one on"]
    data["units"]["hydro"][0]["enabled"] = True
    assert [u.name for _, u in parse_case(data, base.history).units()] == ["H1"]


def test_a_unit_switched_off_for_a_dry_day_loads_and_its_twin_switched_on_is_refused():
    # docs/case-format.md: "to keep it off, set enabled: false"; a day with an empty reservoir has no water at all
    dry = {**HY, "energy_max_mwh": 0.0, "min_up_h": 4.0, "initial_online": True, "p_init_mw": 30.0,
           "ramp_dn_mw_per_h": 5.0, "shutdown_ramp_mw_per_h": 10.0}
    base = tiny_case(battery_units=[{**BAT, "name": "OK"}])
    data = base.to_data()
    data["units"]["hydro"] = [{**dry, "enabled": False}]
    case = parse_case(data, base.history)
    assert [(u.name, u.enabled, u.energy_max_mwh) for u in case.hydro] == [("H1", False, 0.0)]
    assert [u.name for _, u in case.units()] == ["OK"]  # left out of the plan
    problems = refused(hydro=[dry])
    assert any(p.startswith('hydro "H1": energy_max_mwh=0 is below the 20 MWh of a run at p_min_mw=5 for '
                            "min_up_h=4") for p in problems), problems
    problems = refused(hydro=[{**dry, "min_up_h": 0.0}])
    assert any(p.startswith('hydro "H1": energy_max_mwh=0 is below the 5 MWh of one period') for p in problems), problems
