"""The tank at midnight decides which of the paper's heat and up-reserve findings the paper case shows.

data/README.md ("Storage at midnight") argues by hand why the night's heat is bought through the HPA
only where stored heat is scarce, and why scarce heat keeps the turbine, the CSP's only source of
electrical up reserve, off: the same day cannot show both. These tests pin that reading on the paper
case's delivery day with the three tank settings the README compares, from the plan's own columns.
"""

from __future__ import annotations

import numpy as np
import pytest

import rvpp
from tests.factories import with_storage

CHEAPEST_TARIFF = 70.0  # EUR/MWh_th, 00:00-06:00 on the paper case
CARRIED = {"e_init_mwh_th": 975.0, "e_end_min_mwh_th": 110.0, "end_value_eur_per_mwh_th": 66.5}


@pytest.fixture(scope="module")
def paper():
    return rvpp.load_case("data/cases/paper")


def night_heat_and_csp_up(result):
    market = result.market
    heat = market["h_hpa_mw"].to_numpy(float) * result.problem.dt_h
    night = heat[np.isclose(market["tariff_hpa"].to_numpy(float), CHEAPEST_TARIFF)].sum()
    csp = result.csp
    up = float((csp["e_up_mw"] - csp["e_none_mw"]).sum()) * result.problem.dt_h
    return float(heat.sum()), float(night), up


def test_an_empty_tank_buys_the_night_heat_and_backs_no_up_reserve(paper):
    assert paper.csp[0].storage.e_init_mwh_th == 110.0  # the bundled case: the tank starts at its minimum
    result = rvpp.solve(rvpp.with_options(paper, strategy="deterministic"))
    assert result.status == "optimal"
    total, night, up = night_heat_and_csp_up(result)
    assert night > 0.5 * total > 0.0
    assert up == pytest.approx(0.0, abs=1e-6)
    assert not rvpp.solve(rvpp.with_options(paper, strategy="deterministic", markets="DAM")).has_plan


def test_heat_carried_overnight_backs_up_reserve_and_buys_no_night_heat(paper):
    carried = with_storage(paper, **CARRIED)
    result = rvpp.solve(rvpp.with_options(carried, strategy="balanced"))
    assert result.status == "optimal"
    total, night, up = night_heat_and_csp_up(result)
    assert night == pytest.approx(0.0, abs=1e-6)
    assert up > 1.0
    flexibility = result.flexibility
    assert up > 0.5 * flexibility["r_up_mwh"].sum()
    dam = rvpp.solve(rvpp.with_options(carried, strategy="balanced", markets="DAM"))
    with_hpa = rvpp.solve(rvpp.with_options(carried, strategy="balanced", markets="DAM+HPA"))
    assert dam.status == with_hpa.status == "optimal"
    assert with_hpa.cost_keur < dam.cost_keur


def test_scarce_heat_keeps_the_turbine_off_even_with_a_full_margin(paper):
    """A cloudy forecast under the pessimistic budgets: the night's heat is bought and the tank keeps a
    wide margin above its minimum, but the turbine never runs, so the CSP offers no up reserve."""
    carried = with_storage(paper, **{**CARRIED, "e_init_mwh_th": 700.0})
    result = rvpp.solve(rvpp.with_options(carried, strategy="pessimistic", date="2025-05-12"))
    assert result.status == "optimal"
    total, night, up = night_heat_and_csp_up(result)
    assert night > 100.0
    assert result.csp["ts_energy_mwh"].min() > 110.0 + 300.0
    assert up == pytest.approx(0.0, abs=1e-6)
    assert result.csp["online"].sum() == 0
