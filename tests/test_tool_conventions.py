"""The authors' tool's formulation conventions as case options (docs/gams-tool.md), on days worked
out by hand. Every expected profit is derived in the comments from the prices and the unit's
parameters, not from a solve; each option is off by default (MODEL_SPEC §9).
"""

import numpy as np
import pytest

from rvpp import CaseError
from rvpp.settle.audit import audit_day, audit_result, audit_tables
from rvpp.solving.plan import solve_problem
from tests.factories import tiny_case, tiny_problem

NT = 24
HOURS = np.arange(1, NT + 1)


def demand(**extra):
    return {"name": "D", "p_min_mw": 0.0, "p_max_mw": 50.0, "e_min_mwh": 0.0, "ramp_up_mw_per_min": 10.0,
            "ramp_dn_mw_per_min": 10.0, **extra}


def solved(case, profile, **series):
    problem = tiny_problem(case, D=(profile, profile, profile), **series)
    result = solve_problem(problem)
    assert result.status == "optimal", result.message
    assert audit_result(result, bands=problem.bands) == []
    return result


def consumption(result) -> np.ndarray:
    return result.units.loc[result.units.unit == "D", "p_mw"].to_numpy(float)


@pytest.mark.parametrize(("window", "price", "profit"), [
    # profile 10 MW all day, flex_up 0.2 and flex_dn 0.1: the window is [8, 11] MW.
    # At 50 EUR/MWh the demand buys its least: 10 MW without the window (p >= profile), 8 MW with it:
    # -24 x 10 x 50 = -12,000 and -24 x 8 x 50 = -9,600 EUR.
    (False, 50.0, -12_000.0), (True, 50.0, -9_600.0),
    # At -10 EUR/MWh it is paid to consume: up to p_max 50 MW without the window, 11 MW with it:
    # 24 x 50 x 10 = 12,000 and 24 x 11 x 10 = 2,640 EUR.
    (False, -10.0, 12_000.0), (True, -10.0, 2_640.0),
], ids=["floor at the profile", "floor below the profile", "no ceiling", "ceiling above the profile"])
def test_the_profile_window_lets_consumption_move_around_the_profile(window, price, profit):
    case = tiny_case(ed_units=[demand(flex_up=0.2, flex_dn=0.1, profile_window=window)])
    result = solved(case, 10.0, price_da=(price, price, price))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)


def test_a_ramp_up_between_periods_starts_from_the_initial_consumption():
    # Paid 10 EUR/MWh to consume (price -10), profile 0, p_max 50, p_init 0, ramp up 2 MW/h:
    # p_t <= 2t, so 2 + 4 + ... + 48 = 2 x 300 = 600 MWh: 6,000 EUR (12,000 without the ramp).
    case = tiny_case(ed_units=[demand(p_init_mw=0.0, ramp_up_mw_per_h=2.0)])
    result = solved(case, 0.0, price_da=(-10.0, -10.0, -10.0))
    assert result.objective_eur == pytest.approx(6_000.0, abs=1e-6)
    np.testing.assert_allclose(consumption(result), 2.0 * HOURS, atol=1e-6)


def test_a_ramp_down_makes_the_demand_slow_down_before_the_dear_hours():
    # Paid 10 EUR/MWh in hours 1-12, 100 EUR/MWh to pay in hours 13-24; p_max 50, ramp down 5 MW/h.
    # A MW consumed in hour 13 costs 100 and lets hours 4-12 each consume one MW more (+90): not
    # worth it, so p_13 = 0, p_12 <= 5, p_11 <= 10, ..., p_3 <= 50: hours 1-3 at 50, then 45, 40, ..., 5.
    # Profit = 10 x (3 x 50 + 5 x (9 + 8 + ... + 1)) = 10 x (150 + 225) = 3,750 EUR.
    case = tiny_case(ed_units=[demand(p_init_mw=40.0, ramp_dn_mw_per_h=5.0)])
    prices = np.where(HOURS <= 12, -10.0, 100.0)
    result = solved(case, 0.0, price_da=(prices, prices, prices))
    assert result.objective_eur == pytest.approx(3_750.0, abs=1e-6)
    expected = np.concatenate([[50.0] * 3, 50.0 - 5.0 * np.arange(1, 10), [0.0] * 12])
    np.testing.assert_allclose(consumption(result), expected, atol=1e-6)


def test_the_ramps_between_periods_count_the_bands():
    # Up and down bands sell at 10 EUR/MW (DAM price 0); a windless-reserve 100 MW wind farm makes the
    # VPP's cap 0.3 x (100 - 50) = 15 MW. The demand (0-50 MW, flex 1 each way) was at 50 MW before the
    # day and may fall 4 MW/h: the lowest consumption of a period (its up band called) at most 4 below
    # the highest of the one before (its down band called). Summed over the day from 50:
    # Σ r_up + Σ_{t<24} r_dn <= 24 x 4 - 50 + p_24, and r_dn_24 <= 50 - p_24, so the bands total at most
    # 96 MW·h: 960 EUR (p = 50 and r_up = 4 every hour). Ramps of consumption alone would allow
    # 15 MW of band every hour.
    wind = {"name": "W", "kind": "wind", "p_max_mw": 100.0, "ramp_up_mw_per_min": 0.0, "ramp_dn_mw_per_min": 0.0}
    case = tiny_case(wind_units=[wind], srm=True,
                     ed_units=[demand(flex_up=1.0, flex_dn=1.0, p_init_mw=50.0, ramp_dn_mw_per_h=4.0)])
    result = solved(case, 0.0, W=(100.0, 100.0, 100.0), price_sr_up=(10.0, 10.0, 10.0),
                    price_sr_dn=(10.0, 10.0, 10.0))
    assert result.objective_eur == pytest.approx(960.0, abs=1e-6)


@pytest.mark.parametrize(("net", "profit"), [
    # Wind sells 100 MW at 50 EUR/MWh; the demand (profile 0, flex_up 0.5, e_min 240 MWh) offers the
    # only up band, at 10 EUR/MW. Tool's floor (sum of p >= 240): 10 MW each hour with a band of
    # 0.5 x 10 = 5 MW (one more MW costs 50, earns 5): 50 x (2400 - 240) + 10 x 24 x 5 = 109,200 EUR.
    # Default floor (sum of p - r_up >= 240): each MW of band needs one MW more consumption (50 for 10),
    # so no band: 50 x (2400 - 240) = 108,000 EUR.
    (False, 109_200.0), (True, 108_000.0),
], ids=["tool: up band not netted out", "default: net of up band"])
def test_the_energy_floor_with_or_without_the_up_band(net, profit):
    wind = {"name": "W", "kind": "wind", "p_max_mw": 100.0, "ramp_up_mw_per_min": 0.0, "ramp_dn_mw_per_min": 0.0}
    case = tiny_case(wind_units=[wind], srm=True,
                     ed_units=[demand(e_min_mwh=240.0, flex_up=0.5, flex_dn=0.0, energy_net_of_up_band=net)])
    result = solved(case, 0.0, W=(100.0, 100.0, 100.0), price_da=(50.0, 50.0, 50.0),
                    price_sr_up=(10.0, 10.0, 10.0))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)
    assert consumption(result).sum() == pytest.approx(240.0, abs=1e-6)


def test_the_options_are_off_by_default_and_written_only_when_set():
    (ed,) = tiny_case(ed_units=[demand()]).ed
    assert (ed.profile_window, ed.ramp_up_mw_per_h, ed.ramp_dn_mw_per_h, ed.energy_net_of_up_band) == \
        (False, None, None, True)
    written = tiny_case(ed_units=[demand()]).to_data()["units"]["ed"][0]
    assert not {"profile_window", "ramp_up_mw_per_h", "ramp_dn_mw_per_h", "energy_net_of_up_band"} & set(written)
    written = tiny_case(ed_units=[demand(ramp_up_mw_per_h=3.0, energy_net_of_up_band=False)]).to_data()
    assert {k: written["units"]["ed"][0][k] for k in ("ramp_up_mw_per_h", "energy_net_of_up_band")} == \
        {"ramp_up_mw_per_h": 3.0, "energy_net_of_up_band": False}


@pytest.mark.parametrize(("extra", "message"), [
    ({"profile_window": "maybe"}, r'ed "D": profile_window=\'maybe\' must be true or false'),
    ({"energy_net_of_up_band": 3}, r'ed "D": energy_net_of_up_band=3 must be true or false'),
    ({"ramp_up_mw_per_h": -1}, r'ed "D": ramp_up_mw_per_h=-1 must be >= 0'),
    ({"ramp_dn_mw_per_h": True}, r'ed "D": ramp_dn_mw_per_h=True must be a number'),
])
def test_bad_option_values_are_refused_by_name(extra, message):
    with pytest.raises(CaseError, match=message):
        tiny_case(ed_units=[demand(**extra)])


def test_the_audit_finds_a_plan_outside_the_window_or_its_ramps():
    # Profile 10 MW, window [8, 11] MW, ramps 1.5 MW/h from 10 MW before the day, 50 EUR/MWh: the
    # demand buys its least, 8.5 MW in hour 1 (10 - 1.5) and 8 MW after: -50 x (8.5 + 23 x 8) = -9,625 EUR.
    case = tiny_case(ed_units=[demand(flex_up=0.2, flex_dn=0.1, profile_window=True, p_init_mw=10.0,
                                      ramp_up_mw_per_h=1.5, ramp_dn_mw_per_h=1.5)])
    result = solved(case, 10.0, price_da=(50.0, 50.0, 50.0))
    assert result.objective_eur == pytest.approx(-9_625.0, abs=1e-6)
    np.testing.assert_allclose(consumption(result), [8.5] + [8.0] * 23, atol=1e-6)
    day = audit_day(result.case, result.problem.bands)

    def checks(**change):
        units = result.units.copy()
        for column, (t, value) in change.items():
            units.loc[(units.unit == "D") & (units.t == t), column] = value
        return {v.check for v in audit_tables(day, result.market, units, result.csp, result.summary(),
                                              dispatch=result.dispatch) if v.unit == "D"}

    assert checks() == set()
    assert checks(p_mw=(5, 7.9)) == {"ed.window_low"}  # below 0.8 x 10
    assert "ed.window_high" in checks(p_mw=(5, 11.1))  # above 1.1 x 10
    assert checks(p_mw=(5, 9.0)) == set()  # 8 -> 9 -> 8: steps of 1 MW
    # a down band of 0.8 MW (within 0.1 x 10) on 9 MW: the highest consumption 9.8 is 1.8 MW above hour
    # 4's 8 and 1.8 MW above hour 6's lowest (the case has no SRM, so any band is also above its cap 0)
    assert checks(p_mw=(5, 9.0), r_dn_mw=(5, 0.8)) == {"ed.ramp_up", "ed.ramp_dn", "ed.reserve_dn_cap"}
    assert checks(p_mw=(1, 8.0)) == {"ed.ramp_dn"}  # 10 MW before the day to 8: a fall of 2
    # an up band of 2.5 MW: 8 - 2.5 is below the window's 8, above 0.2 x 10, and hour 3's lowest 5.5 is
    # 2.5 below hour 2's 8 and hour 4's 8 is 2.5 above it
    assert checks(r_up_mw=(3, 2.5)) == {"ed.window_low", "ed.flex_up", "ed.ramp_up", "ed.ramp_dn",
                                        "ed.reserve_up_cap"}


# ----------------------------------------------------------------------------- solar thermal plant


def plant(storage=None, power_block=None):
    """A CSP online all day (no minimum times, no start-up heat): power block 10-100 MW_th at 50 %
    (5-50 MW), a cyclic tank of 120 MWh_th with 100 MW_th each way and efficiencies 1, reserve share
    0.5 x 50 = 25 MW."""
    return {"name": "C", "om_eur_per_mwh": 0.0, "heat_efficiency": 1.0, "ramp_mw_per_min": 25, "reserve_share": 0.5,
            "solar_field": {"p_max_mw_th": 100.0},
            "storage": {"e_min_mwh_th": 0.0, "e_max_mwh_th": 120.0, "p_ch_max_mw_th": 100.0,
                        "p_dis_max_mw_th": 100.0, "eta_ch": 1.0, "eta_dis": 1.0, **(storage or {})},
            "power_block": {"p_in_max_mw_th": 100.0, "p_in_min_mw_th": 10.0, "p_el_max_mw": 50.0,
                            "breakpoints": [[0, 0], [10, 0.5], [100, 0.5]], "initially_on": True,
                            **(power_block or {})}}


def solved_plant(case, field, **series):
    problem = tiny_problem(case, C=(field, field, field), **series)
    result = solve_problem(problem)
    assert result.status == "optimal", result.message
    assert audit_result(result, bands=problem.bands) == []
    return result


@pytest.mark.parametrize(("capped", "profit"), [
    # Curve (0, 0), (10, 5), (100, 60): 60 MW at the full input of 100 MW_th, above p_el_max 50.
    # At 100 EUR/MWh, with 100 MW_th from the field all day: capped, 50 MW: 24 x 50 x 100 = 120,000;
    # uncapped (the tool's), 60 MW: 24 x 60 x 100 = 144,000 EUR. A windless 20 MW wind farm lifts the
    # VPP's trading limit (its installed generation) from 50 to 70 MW.
    (True, 120_000.0), (False, 144_000.0),
], ids=["capped at p_el_max", "the curve's own top"])
def test_the_power_block_output_capped_or_not(capped, profit):
    unit = plant(power_block={"breakpoints": [[0, 0], [10, 0.5], [100, 0.6]], "output_capped": capped})
    wind = {"name": "W", "kind": "wind", "p_max_mw": 20.0, "ramp_up_mw_per_min": 0.0, "ramp_dn_mw_per_min": 0.0}
    result = solved_plant(tiny_case(wind_units=[wind], csp_units=[unit]), 100.0, W=(0.0, 0.0, 0.0),
                          price_da=(100.0, 100.0, 100.0))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)
    np.testing.assert_allclose(result.csp["e_none_mw"], 50.0 if capped else 60.0, atol=1e-6)


@pytest.mark.parametrize(("factor", "share_max", "profit"), [
    # The field gives 10 MW_th, the power block's minimum (5 MW, at DAM price 0); the up band comes from
    # the tank's discharge side and sells at 10 EUR/MW, 0.5 MW per MW_th (the curve's slope). The tank
    # holds nothing back in the hour (its bands may reach 100 MW_th, the plant's share 25 MW = 50 MW_th,
    # the VPP's 0.3 x 50 = 15 MW = 30 MW_th, so 24 x 30 = 720 MW_th·h in a day) but in the day:
    # Σ r_ts_up ≤ k·σ·ΔE with the level e ≥ σ·ΔE, e ≤ 120 = ΔE, so σ ≤ 1 and σ ≤ share_max.
    # k 1, σ ≤ 1 (default): 120 MW_th·h, 10 x 0.5 x 120 = 600 EUR; k 2, σ ≤ 1: 240, 1,200 EUR;
    # k 2, σ ≤ 0.5 (the tool's): 120, 600 EUR; k 1, σ ≤ 0.5: 60, 300 EUR.
    (1.0, 1.0, 600.0), (2.0, 1.0, 1_200.0), (2.0, 0.5, 600.0), (1.0, 0.5, 300.0),
])
def test_the_tanks_reserve_energy_factor_and_share_limit(factor, share_max, profit):
    unit = plant(storage={"reserve_energy_factor": factor, "reserve_share_max": share_max})
    result = solved_plant(tiny_case(csp_units=[unit], srm=True), 10.0, price_sr_up=(10.0, 10.0, 10.0))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)
    assert result.csp["ts_r_up_mw"].sum() == pytest.approx(profit / 5.0, abs=1e-6)


@pytest.mark.parametrize(("band_max", "profit"), [
    # As above with a tank of 2,400 MWh_th and κ = 1 (VPP cap 50 MW): the plant's share, 25 MW = 50 MW_th
    # an hour, binds: 24 x 50 = 1,200 MW_th·h, 10 x 0.5 x 1,200 = 6,000 EUR. With each tank band at most
    # 20 MW_th (the tool's per-band limit): 24 x 20 = 480, 2,400 EUR.
    (None, 6_000.0), (20.0, 2_400.0),
], ids=["no band limit", "20 MW_th a band"])
def test_the_tanks_per_band_limit(band_max, profit):
    unit = plant(storage={"e_max_mwh_th": 2400.0, "reserve_band_max_mw_th": band_max})
    result = solved_plant(tiny_case(csp_units=[unit], srm=True, kappa=1.0), 10.0, price_sr_up=(10.0, 10.0, 10.0))
    assert result.objective_eur == pytest.approx(profit, abs=1e-6)


def test_the_audit_finds_a_tank_band_or_share_beyond_the_tools_limits():
    unit = plant(storage={"reserve_band_max_mw_th": 20.0, "reserve_energy_factor": 2.0, "reserve_share_max": 0.5})
    result = solved_plant(tiny_case(csp_units=[unit], srm=True), 10.0, price_sr_up=(10.0, 10.0, 10.0))
    day = audit_day(result.case, result.problem.bands)

    def checks(column, t, value):
        csp = result.csp.copy()
        if t is None:
            csp[column] = value
        else:
            csp.loc[csp.t == t, column] = value
        return {v.check for v in audit_tables(day, result.market, result.units, csp, result.summary(),
                                              dispatch=result.dispatch)}

    assert "csp.ts_band_max" in checks("ts_r_ch_dn_mw", 3, 20.5)
    assert "csp.sigma_range" in checks("sigma_up", None, 0.6)
    assert "csp.ts_band_max" not in checks("ts_r_ch_dn_mw", 3, 19.5)


@pytest.mark.parametrize(("part", "extra", "message"), [
    ("storage", {"reserve_band_max_mw_th": -1}, r'csp "C": storage.reserve_band_max_mw_th=-1 must be >= 0'),
    ("storage", {"reserve_energy_factor": 0}, r'csp "C": storage.reserve_energy_factor=0 must be > 0'),
    ("storage", {"reserve_share_max": 1.5}, r'csp "C": storage.reserve_share_max=1.5 must be <= 1'),
    ("power_block", {"output_capped": "no way"}, r'csp "C": power_block.output_capped=\'no way\' must be true or false'),
])
def test_bad_plant_option_values_are_refused_by_name(part, extra, message):
    with pytest.raises(CaseError, match=message):
        tiny_case(csp_units=[plant(**{part: extra})])


def test_the_plant_options_are_written_only_when_set():
    written = tiny_case(csp_units=[plant()]).to_data()["units"]["csp"][0]
    assert not {"reserve_band_max_mw_th", "reserve_energy_factor", "reserve_share_max"} & set(written["storage"])
    assert "output_capped" not in written["power_block"]
    written = tiny_case(csp_units=[plant(storage={"reserve_share_max": 0.5}),
                                   ]).to_data()["units"]["csp"][0]
    assert written["storage"]["reserve_share_max"] == 0.5


def test_the_options_survive_the_unit_tables_and_the_case_workbook():
    from rvpp.outputs.workbook import case_workbook_bytes, read_case_workbook, unit_table, with_unit_table

    set_ = tiny_case(ed_units=[demand(profile_window=True, p_init_mw=5.0, ramp_up_mw_per_h=3.0,
                                      energy_net_of_up_band=False)],
                     csp_units=[plant(storage={"reserve_band_max_mw_th": 30.0, "reserve_energy_factor": 2.0,
                                               "reserve_share_max": 0.5},
                                      power_block={"output_capped": False})])
    plain = tiny_case(ed_units=[demand()], csp_units=[plant()])
    for case in (set_, plain):
        for kind in ("ed", "csp"):
            assert with_unit_table(case, kind, unit_table(case, kind)).to_data() == case.to_data()
        assert read_case_workbook(case_workbook_bytes(case)).to_data() == case.to_data()
    row = unit_table(plain, "ed").iloc[0]  # a cell shows the default where the case leaves an option out
    assert (row["profile_window"], row["energy_net_of_up_band"]) == (False, True)
    assert unit_table(set_, "csp").iloc[0]["storage.reserve_share_max"] == 0.5
