"""Small cases whose optimum is derived by hand (MODEL_SPEC §2-§9)."""

from __future__ import annotations

import numpy as np
import pytest

from rvpp import solve_problem
from rvpp.settle.audit import audit_result

from tests.factories import demand, heat, tiny_case, tiny_problem, wind

NT = 24
HOURS = np.arange(1, NT + 1, dtype=float)


def solved(problem):
    result = solve_problem(problem)
    assert result.status == "optimal", result.message
    assert audit_result(result, bands=problem.bands) == []
    return result


def test_one_wind_farm_one_demand_sells_the_surplus():
    # Wind 30 MW available at O&M 10 EUR/MWh, demand fixed at 10 MW, DAM price 50.
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)])
    result = solved(tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(50, 50, 50)))
    assert result.objective_eur == pytest.approx(NT * (50 * 20 - 10 * 30), rel=1e-9)
    assert np.allclose(result.market["p_da_mw"], 20.0)


def test_wind_is_curtailed_when_the_price_is_below_its_operating_cost():
    price = np.where(HOURS <= 4, 5.0, 50.0)
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)])
    result = solved(tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(price, price, price)))
    expected = 4 * (5 * -10) + 20 * (50 * 20 - 10 * 30)
    assert result.objective_eur == pytest.approx(expected, rel=1e-9)
    wind_output = result.units.query("unit == 'W'")["p_mw"].to_numpy()
    assert np.allclose(wind_output[:4], 0.0) and np.allclose(wind_output[4:], 30.0)


def test_dam_price_protection_is_the_sum_of_the_largest_selling_losses():
    # Downward deviation t EUR/MWh in period t; Γ = 3 -> the adversary hits 24, 23, 22.
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], overrides={"price_da": 3})
    problem = tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(50 - HOURS, 50, 50))
    result = solved(problem)
    assert result.protection_eur["price_da"] == pytest.approx(20 * (24 + 23 + 22), rel=1e-9)
    assert result.objective_eur == pytest.approx(NT * 700 - 20 * 69, rel=1e-9)


def test_dam_price_protection_uses_the_upward_deviation_when_buying():
    # Demand 40 MW > wind 30 MW: the RVPP buys 10 MW; upward deviation 2t, downward t.
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=40, p_max=40)], overrides={"price_da": 2})
    problem = tiny_problem(case, W=(30, 30, 30), D=(40, 40, 40), price_da=(50 - HOURS, 50, 50 + 2 * HOURS))
    result = solved(problem)
    assert result.protection_eur["price_da"] == pytest.approx(10 * (48 + 46), rel=1e-9)
    assert result.objective_eur == pytest.approx(NT * (-500 - 300) - 10 * 94, rel=1e-9)


def test_full_price_budget_curtails_where_the_worst_price_is_below_cost():
    # Γ = NT: every period at its worst price 50 - dev. Selling is worth it only where
    # 50 - dev > 10 (O&M), so the farm is curtailed down to the demand elsewhere.
    dev = np.where(HOURS <= 6, 45.0, 5.0)
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], overrides={"price_da": NT})
    result = solved(tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(50 - dev, 50, 50)))
    per_period = np.where(dev > 40, (50 - dev) * 0 - 10 * 10, (50 - dev) * 20 - 10 * 30)
    assert result.objective_eur == pytest.approx(per_period.sum(), rel=1e-9)
    sold = result.market["p_da_mw"].to_numpy()
    assert np.allclose(sold[:6], 0.0) and np.allclose(sold[6:], 20.0)


def test_availability_budget_removes_the_largest_deviations():
    # Wind hi 30, deviation 0.5·t; Γ = 2 cuts the two largest (periods 24 and 23).
    dev = 0.5 * HOURS
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], overrides={"W": 2})
    result = solved(tiny_problem(case, W=(30 - dev, 30, 30), D=(10, 10, 10), price_da=(50, 50, 50)))
    bound = 30 - np.where(HOURS >= 23, dev, 0.0)
    assert result.objective_eur == pytest.approx(float(np.sum(40 * bound - 500)), rel=1e-9)
    chi = result.units.query("unit == 'W'")["chi"].to_numpy()
    assert list(np.flatnonzero(chi) + 1) == [23, 24]


def test_demand_budget_raises_the_required_consumption():
    dev = np.where(HOURS % 5 == 0, 8.0, 1.0)  # periods 5, 10, 15, 20 deviate most
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=0, p_max=100)], overrides={"D": 3})
    result = solved(tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10 + dev), price_da=(50, 50, 50)))
    chi = result.units.query("unit == 'D'")["chi"].to_numpy()
    assert chi.sum() == 3 and set(np.flatnonzero(chi) + 1) <= {5, 10, 15, 20}
    assert result.objective_eur == pytest.approx(NT * (50 * 20 - 300) - 3 * 50 * 8, rel=1e-9)


def test_minimum_energy_shifts_flexible_consumption_to_the_cheapest_periods():
    price = np.where(HOURS <= 3, 20.0, 60.0)
    case = tiny_case(ed_units=[demand(p_min=0, p_max=50, e_min=300)])
    result = solved(tiny_problem(case, D=(5, 5, 5), price_da=(price, price, price)))
    # 24 x 5 = 120 MWh at the floor; the 180 MWh missing go to the 3 cheap hours (60 MW
    # each would exceed p_max 50: 3 x 45 = 135 at 20, the last 45 at 60).
    expected = -(np.sum(price * 5) + 135 * 20 + 45 * 60)
    assert result.objective_eur == pytest.approx(expected, rel=1e-9)


def test_heat_is_bought_from_the_hpa_at_the_tariff():
    tariff = np.where(np.arange(24) < 6, 70.0, 110.0)
    case = tiny_case(td_units=[heat(q_min=0)], hpa=True, tariff=tariff, overrides={"H": 2})
    dev = np.where(HOURS == 12, 9.0, np.where(HOURS == 3, 7.0, 1.0))
    result = solved(tiny_problem(case, H=(20, 20, 20 + dev)))
    need = 20 + np.where(np.isin(HOURS, (3, 12)), dev, 0.0)
    assert result.parts["cost_hpa_eur"] == pytest.approx(float(np.sum(tariff * need)), rel=1e-9)
    assert result.objective_eur == pytest.approx(-float(np.sum(tariff * need)), rel=1e-9)


def test_down_reserve_from_wind_is_free_money_up_reserve_only_when_it_pays():
    # Reserve share 10 % of 50 MW -> bands up to 5 MW. Down reserve costs nothing;
    # up reserve needs curtailment, worth it only if the up price beats the margin 50 - 10.
    def run(up_price):
        case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], srm=True)
        problem = tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(50, 50, 50),
                               price_sr_up=(up_price, up_price, up_price), price_sr_dn=(10, 10, 10))
        return solved(problem)

    cheap = run(20.0)
    assert cheap.objective_eur == pytest.approx(NT * (50 * 20 - 10 * 30 + 10 * 5), rel=1e-9)
    assert np.allclose(cheap.market["r_sr_dn_mw"], 5.0) and np.allclose(cheap.market["r_sr_up_mw"], 0.0)
    dear = run(45.0)
    assert dear.objective_eur == pytest.approx(NT * (50 * 15 - 10 * 25 + 45 * 5 + 10 * 5), rel=1e-9)
    assert np.allclose(dear.market["r_sr_up_mw"], 5.0)


def test_reserve_bands_respect_the_kappa_cap():
    # Two 50 MW farms, demand nameplate 90 MW: κ·(100 − 90) = 3 MW caps the SR bands.
    case = tiny_case([wind("A", om=0), wind("B", om=0)], ed_units=[demand(p_min=10, p_max=90)], srm=True)
    problem = tiny_problem(case, A=(30, 30, 30), B=(30, 30, 30), D=(10, 10, 10), price_da=(50, 50, 50),
                           price_sr_dn=(10, 10, 10))
    result = solved(problem)
    assert np.allclose(result.market["r_sr_dn_mw"], 3.0)


def test_markets_switched_off_fix_their_decisions_to_zero():
    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], td_units=[heat()], srm=False,
                     hpa=True)
    result = solved(tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), H=(5, 5, 5), price_da=(50, 50, 50),
                                 price_sr_dn=(100, 100, 100)))
    assert np.allclose(result.market[["r_sr_up_mw", "r_sr_dn_mw"]], 0.0)
    assert np.allclose(result.units[["r_up_mw", "r_dn_mw"]], 0.0)
    no_hpa = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], td_units=[heat()])
    failed = solve_problem(tiny_problem(no_hpa, W=(30, 30, 30), D=(10, 10, 10), H=(5, 5, 5)))
    assert failed.status == "infeasible"
    assert "no heat source" in failed.message and "H" in failed.message


def csp(min_up_h=0.0, min_down_h=0.0, startup_duration_h=None):
    """A CSP without storage: 100 MW_th field, power block 10-100 MW_th at 50 % (5-50 MW), start-up
    heat 0.2 x 100 = 20 MW_th, no operating cost."""
    return {"name": "C", "om_eur_per_mwh": 0.0, "heat_efficiency": 1.0, "ramp_mw_per_min": 25, "reserve_share": 0.5,
            "solar_field": {"p_max_mw_th": 100.0},
            "storage": {"e_min_mwh_th": 0.0, "e_max_mwh_th": 1.0, "p_ch_max_mw_th": 0.0, "p_dis_max_mw_th": 0.0,
                        "eta_ch": 1.0, "eta_dis": 1.0},
            "power_block": {"p_in_max_mw_th": 100.0, "p_in_min_mw_th": 10.0, "p_el_max_mw": 50.0,
                            "breakpoints": [[0, 0], [10, 0.5], [100, 0.5]], "min_up_h": min_up_h,
                            "min_down_h": min_down_h, "startup_fraction": 0.2,
                            "startup_duration_h": startup_duration_h}}


@pytest.mark.parametrize("rules, online, profit", [
    # Free turbine: start an hour before each two-hour peak (the start-up heat is cheaper
    # at minimum output, −50 EUR, than in a peak, −1,000 EUR), stop in between (staying on
    # at minimum for 3 h would cost 150 EUR, a restart 50 EUR).
    ({}, [4, 5, 6, 10, 11, 12], 2 * (-50 + 2 * 5000)),
    # Minimum up 4 h, down 3 h: runs 3-6 and 10-13 (each 4 h, 3 h apart) with two hours at
    # minimum per run; running 4-12 through would cost four hours at minimum.
    (dict(min_up_h=4, min_down_h=3), [3, 4, 5, 6, 10, 11, 12, 13], 2 * (-100 + 2 * 5000)),
    # Start-up heat drawn for 2 h: a restart at 10 would draw 20 MW_th in the peak at 11
    # (−1,000 EUR), so the turbine runs 3-12 through, drawing the start-up heat in 3 and 4.
    (dict(min_up_h=4, min_down_h=3, startup_duration_h=2), list(range(3, 13)), -100 - 200 + 4 * 5000),
])
def test_turbine_schedule_follows_minimum_times_and_startup_heat(rules, online, profit):
    # DAM 100 EUR/MWh in hours 5-6 and 11-12, −10 elsewhere; the field gives 100 MW_th all day.
    price = np.where(np.isin(HOURS, (5, 6, 11, 12)), 100.0, -10.0)
    case = tiny_case(csp_units=[csp(**rules)])
    result = solved(tiny_problem(case, C=(100, 100, 100), price_da=(price, price, price)))
    assert result.objective_eur == pytest.approx(profit, rel=1e-9)
    table = result.csp.set_index("t")
    assert list(table.index[table["online"] == 1]) == online
    starts = [t for t in online if t - 1 not in online]
    drawing = {t + k for t in starts for k in range(int(rules.get("startup_duration_h") or 1))}
    heat_drawn = table["p_sf_mw"] - table["p_pb_mw"]
    np.testing.assert_allclose(heat_drawn[sorted(drawing)], 20.0, atol=1e-6)
    np.testing.assert_allclose(heat_drawn.drop(sorted(drawing)), 0.0, atol=1e-6)
    peak = np.isin(table.index, (5, 6, 11, 12))
    expected_output = np.where(np.isin(table.index, online), np.where(peak, 50.0, 5.0), 0.0)
    expected_output[peak & table.index.isin(sorted(drawing))] = 40.0
    np.testing.assert_allclose(table["e_none_mw"], expected_output, atol=1e-6)


def test_impossible_requirements_are_named_before_solving():
    case = tiny_case([wind(om=10, p_min_mw=5)], ed_units=[demand(p_min=0, p_max=100, e_min=3000)],
                     td_units=[heat(h_max=10)], hpa=True)
    result = solve_problem(tiny_problem(case, W=(3, 3, 3), D=(10, 10, 10), H=(12, 12, 12)))
    assert result.status == "infeasible" and result.termination == "not solved"
    assert result.message.split("; ") == [
        'ed "D": e_min_mwh=3000 exceeds p_max_mw x 24 h = 2400 MWh',
        'td "H": required heat 12.00 MW_th at 00:00 exceeds h_max_mw_th=10',
        'wind "W": available power 3.00 MW at 00:00 is below p_min_mw=5',
    ]


def test_solves_from_several_threads_take_turns_and_agree():
    import threading

    case = tiny_case([wind(om=10)], ed_units=[demand(p_min=10, p_max=10)], overrides={"price_da": 3})
    problem = tiny_problem(case, W=(30, 30, 30), D=(10, 10, 10), price_da=(50 - HOURS, 50, 50))
    results = []
    threads = [threading.Thread(target=lambda: results.append(solve_problem(problem)), daemon=True)
               for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=60)
    assert not any(thread.is_alive() for thread in threads), "a threaded solve hung"
    assert [r.status for r in results] == ["optimal"] * 4
    assert {round(r.objective_eur, 6) for r in results} == {NT * 700 - 20 * 69}
