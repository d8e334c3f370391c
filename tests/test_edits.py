"""Edits in the user's words: labels of saved runs, bands that follow capacity, plain messages."""

from __future__ import annotations

import numpy as np
import pytest

import rvpp
from rvpp.data.edits import describe_edits, follow_capacity, label, plain_message


def with_unit(case, kind, index, **changes):
    units = list(getattr(case, kind))
    units[index] = units[index].model_copy(update=changes)
    return case.replace(**{kind: units})


def test_an_unedited_case_has_nothing_to_say(paper_case):
    assert describe_edits(paper_case, paper_case) == []
    assert describe_edits(paper_case, rvpp.with_options(paper_case, strategy="pessimistic", markets="DAM")) == []


def test_capacity_edits_read_as_the_user_typed_them(paper_case):
    edited = follow_capacity(paper_case, with_unit(paper_case, "wind", 0, p_max_mw=80.0))
    assert describe_edits(paper_case, edited) == ["WF1 80 MW"]  # the followed series scale is not repeated
    heat = with_unit(paper_case, "td", 1, h_max_mw_th=90.0)
    assert describe_edits(paper_case, heat) == [f"{paper_case.td[1].name} 90 MW_th"]


def test_settings_budgets_and_unit_lists_are_described(paper_case):
    edited = with_unit(paper_case, "pv", 0, om_eur_per_mwh=20.0).replace(
        dt_h=0.25, markets={"kappa": 0.2, "hpa_tariff_eur_per_mwh": [60.0] * 24},
        budgets={"overrides": {"WF2": 3}, "mode": "planner_chosen"}, pv=[])
    assert describe_edits(paper_case, edited) == [
        "15-min periods", "HPA flat 60", "κ 0.2", "planner-chosen Γ", "Γ WF2 3", "PV1 removed", "PV2 removed",
        "PV3 removed"]
    one = with_unit(paper_case, "pv", 0, om_eur_per_mwh=20.0)
    assert describe_edits(paper_case, one) == ["PV1 O&M 20 EUR/MWh"]
    tou = list(paper_case.markets.hpa_tariff_eur_per_mwh)
    tou[3] += 1.0
    assert describe_edits(paper_case, paper_case.replace(markets={"hpa_tariff_eur_per_mwh": tou})) == [
        "HPA tariff edited"]


def test_an_added_unit_is_named_with_its_capacity(paper_case):
    third = paper_case.wind[1].model_copy(update={"name": "WF3", "p_max_mw": 30.0, "series": "WF2"})
    edited = paper_case.replace(wind=[*paper_case.wind, third])
    assert describe_edits(paper_case, edited) == ["WF3 added (30 MW)"]


def test_a_capacity_change_scales_the_forecast_band(paper_case):
    scaled = follow_capacity(paper_case, with_unit(paper_case, "wind", 0, p_max_mw=80.0))
    assert scaled.wind[0].series_scale == pytest.approx(1.6)  # 80 MW / 50 MW
    assert scaled.wind[1] == paper_case.wind[1]
    before = rvpp.prepare(paper_case).sources["WF1"]
    after = rvpp.prepare(scaled).sources["WF1"]
    # The band is the history's percentiles times 1.6 (clipped to 50 MW before, to 80 MW now).
    history = rvpp.prepare(with_unit(paper_case, "wind", 0, p_max_mw=1e6)).sources["WF1"]
    np.testing.assert_allclose(after.nominal, np.clip(history.nominal * 1.6, 0, 80.0), rtol=1e-9)
    assert after.nominal.max() > before.nominal.max()


def test_a_unit_kept_fixed_or_with_its_scale_edited_is_not_rescaled(paper_case):
    bigger = with_unit(paper_case, "wind", 0, p_max_mw=80.0)
    assert follow_capacity(paper_case, bigger, fixed={"WF1"}).wind[0].series_scale == 1.0
    own = with_unit(paper_case, "wind", 0, p_max_mw=80.0, series_scale=1.2)
    assert follow_capacity(paper_case, own).wind[0].series_scale == 1.2
    csp = paper_case.csp[0]
    field = csp.solar_field.model_copy(update={"p_max_mw_th": 450.0})
    larger = paper_case.replace(csp=[csp.model_copy(update={"solar_field": field})])
    assert follow_capacity(paper_case, larger).csp[0].solar_field.series_scale == pytest.approx(1.5)


@pytest.mark.parametrize("message, plain", [
    ('csp "CSP1": storage.e_min_mwh_th=1200 must be < storage.e_max_mwh_th=1100',
     "CSP1: TS E min [MWh_th] = 1200 must be < TS E max [MWh_th] = 1100"),
    ("markets: hpa_tariff_eur_per_mwh hour 03:00 = -5 must be >= 0", "HPA tariff at 03:00 [EUR/MWh_th] = −5 must be ≥ 0"),
    ("markets: kappa=2 must be <= 1", "κ: reserve band cap [-] = 2 must be ≤ 1"),
    ('wind "WF1": p_max_mw=-5 must be > 0', "WF1: P max [MW] = −5 must be > 0"),
    ("the history does not cover 2025-05-05", "the history does not cover 2025-05-05"),
])
def test_messages_name_fields_as_the_forms_show_them(message, plain):
    assert plain_message(message) == plain


def test_labels_carry_their_units():
    assert label("p_max_mw") == "P max [MW]"
    assert label("storage.e_max_mwh_th") == "TS E max [MWh_th]"
    assert label("markets.kappa") == "κ: reserve band cap [-]"
    assert label("unknown_field") == "unknown_field"


def test_a_run_label_names_strategy_markets_and_edits(paper_case):
    from rvpp.data.edits import run_label

    edited = follow_capacity(paper_case, with_unit(paper_case, "wind", 0, p_max_mw=80.0))
    assert run_label(paper_case, edited) == "balanced · DAM+SRM+HPA · WF1 80 MW"
    pessimistic = rvpp.with_options(edited, strategy="pessimistic", markets="DAM,SRM")
    assert run_label(paper_case, pessimistic, csp=False) == "pessimistic · DAM+SRM · WF1 80 MW · no CSP"
    many = paper_case.replace(markets={"kappa": 0.2}, budgets={"overrides": {"WF1": 1, "WF2": 2, "PV1": 3}})
    short = run_label(paper_case, many, limit=55)
    assert short == "balanced · DAM+SRM+HPA · κ 0.2 · … and 3 more edits" and len(short) <= 55


def test_study_settings_are_named_as_the_study_pages_show_them():
    assert plain_message("study settings: hpa_flat_prices: -5.0 must be a number in [0, 1e+06] [EUR/MWh_th]") == \
        "study settings: Flat HPA tariffs [EUR/MWh_th]: −5.0 must be a number in [0, 1e+06] [EUR/MWh_th]"
    assert plain_message("study settings: test_days=0 must be at least 1; scenario_counts: N=0 must be at least 1") \
        == "study settings: Test days = 0 must be at least 1; Scenario counts N: N = 0 must be at least 1"
