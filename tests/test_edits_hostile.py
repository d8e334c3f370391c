"""Edits that used to leave the case meaning something the user did not ask for: a new period
length, a refused edit, a renamed unit, crafted table rows, a unit following a price series
and an emptied cell. Library functions first, then the pages through Streamlit's AppTest."""

from __future__ import annotations

import json

import numpy as np
import pytest
from streamlit.testing.v1 import AppTest

import rvpp
from rvpp.data import edits
from rvpp.data.history import PRICE_COLUMNS, History
from rvpp.outputs import workbook
from rvpp.uncertainty.problem import prepare
from tests.factories import open_app


pytestmark = pytest.mark.usefixtures("run_library")  # every test saves into a store of its own


def edit(at: AppTest, key: str, **change) -> AppTest:
    """Send one data-editor edit as the browser does (``edited_rows``, ``added_rows``, ``deleted_rows``)."""
    at.session_state[key] = {"edited_rows": {}, "added_rows": [], "deleted_rows": [], **change}
    at.run()
    assert not at.exception, at.exception
    return at


def editor_key(at: AppTest, prefix: str) -> str:
    return next(e.key for e in at.data_editor if e.key.startswith(prefix))


def errors(at: AppTest) -> str:
    return "\n".join(e.value for e in at.error)


def captions(at: AppTest) -> str:
    return "\n".join(c.value for c in at.caption)


def row_of(at: AppTest, key: str, source: str) -> int:
    table = at.data_editor(key=key).value
    return int(np.flatnonzero(table["source"] == source)[0])


# ----------------------------------------------------------------------------- 1. period length


def test_a_new_period_length_keeps_every_gamma_override_in_hours(paper_case):
    quarter = paper_case.replace(dt_h=0.25, budgets={"overrides": {"WF1": 80, "price_da": 6, "PV1": 5}})
    hourly, notes = edits.with_period_length(quarter, 1.0)
    # 80 quarter-hours are 20 hours; 6 are 1.5 hours, rounded half up to 2; 5 are 1.25 hours, rounded to 1.
    assert hourly.dt_h == 1.0 and hourly.budgets.override_map == {"WF1": 20, "price_da": 2, "PV1": 1}
    assert notes == ["PV1 5 quarter-hours → 1 hour (1.25 h rounded)", "WF1 80 quarter-hours → 20 hours",
                     "price_da 6 quarter-hours → 2 hours (1.5 h rounded)"]
    assert prepare(hourly) is not None  # the day can be prepared: every Γ fits its 24 periods
    back, notes = edits.with_period_length(hourly.replace(budgets={"overrides": {"WF1": 20}}), 0.25)
    assert back.budgets.override_map == {"WF1": 80} and notes == ["WF1 20 hours → 80 quarter-hours"]


def test_a_converted_gamma_is_at_most_the_days_periods_and_nothing_else_changes(paper_case):
    assert edits.convert_overrides({"WF1": 25, "PV1": 3}, 1.0, 0.5, periods=46) == {"WF1": 46, "PV1": 6}
    assert edits.convert_overrides({}, 0.25, 1.0, periods=24) == {}
    same, notes = edits.with_period_length(paper_case, 0.5)
    assert same == paper_case.replace(dt_h=0.5) and notes == []
    with pytest.raises(rvpp.CaseError, match="dt_h=0.3"):
        edits.with_period_length(paper_case, 0.3)


def test_markets_converts_the_overrides_and_says_so(paper_case):
    at = open_app("markets")
    at.button_group(key="markets_dt").set_value(15).run()
    at.switch_page("pages/uncertainty.py").run()
    key = editor_key(at, "uncertainty_budgets_")
    edit(at, key, edited_rows={row_of(at, key, "WF1"): {"gamma": 80}})
    assert at.session_state["case"].budgets.override_map == {"WF1": 80}
    at.switch_page("pages/markets.py").run()
    at.button_group(key="markets_dt").set_value(60).run()
    assert not at.exception and not errors(at)
    case = at.session_state["case"]
    assert case.dt_h == 1.0 and case.budgets.override_map == {"WF1": 20}
    assert "Γ overrides kept their hours: WF1 80 quarter-hours → 20 hours" in captions(at)
    at.switch_page("pages/uncertainty.py").run()
    assert not at.exception and not errors(at)


# ----------------------------------------------------------------------------- 2. refused edit


def test_a_refused_edit_leaves_the_scale_tick_boxes_as_they_were():
    at = open_app("portfolio")
    edit(at, "portfolio_wind_0", edited_rows={0: {"scale_with_capacity": False, "p_max_mw": 0.0}})
    assert "WF1: P max [MW] = 0 must be > 0" in errors(at)
    at.button(key="portfolio_wind_discard").click().run()
    assert "WF1" not in at.session_state["portfolio_fixed_scale"]
    key = editor_key(at, "portfolio_wind_")
    assert list(at.data_editor(key=key).value["scale_with_capacity"]) == [True, True]
    edit(at, key, edited_rows={0: {"p_max_mw": 80.0}})
    wf1 = at.session_state["case"].wind[0]
    assert wf1.p_max_mw == 80.0 and wf1.series_scale == pytest.approx(1.6)


# ----------------------------------------------------------------------------- 3. rename


def forecast_case(case):
    """``case`` with a day-ahead forecast column for WF1 and WF1 on forecast bands."""
    frame = case.history.frame
    frame["WF1_fc"] = frame["WF1"]
    wind = [case.wind[0].model_copy(update={"forecast_series": "WF1_fc"}), *case.wind[1:]]
    return case.replace(history=History(frame, source=case.history.source), wind=wind,
                        uncertainty={"bands": {"WF1": "forecast"}}, budgets={"overrides": {"WF1": 20, "PV1": 3}})


def test_a_renamed_unit_keeps_its_gamma_override_and_band_method(paper_case):
    case = forecast_case(paper_case)
    table = workbook.unit_table(case, "wind")
    table.loc[0, "name"] = "WF9"
    renamed = workbook.with_unit_table(case, "wind", table)
    assert [u.name for u in renamed.wind] == ["WF9", "WF2"] and renamed.wind[0].column == "WF1"
    assert renamed.budgets.override_map == {"WF9": 20, "PV1": 3}
    assert dict(renamed.uncertainty.bands) == {"WF9": "forecast"}
    # Removing the unit drops both, as it always dropped the override.
    removed = workbook.with_unit_table(case, "wind", table.iloc[1:])
    assert [u.name for u in removed.wind] == ["WF2"]
    assert removed.budgets.override_map == {"PV1": 3} and dict(removed.uncertainty.bands) == {}


def test_a_rename_next_to_a_removed_row_is_matched_by_row_not_by_position(paper_case):
    case = paper_case.replace(budgets={"overrides": {"PV1": 4, "PV3": 7}})
    table = workbook.unit_table(case, "pv").drop(index=0)  # PV1 deleted; PV2 and PV3 keep their rows
    table.loc[2, "name"] = "PV9"
    edited = workbook.with_unit_table(case, "pv", table)
    assert [u.name for u in edited.pv] == ["PV2", "PV9"] and edited.budgets.override_map == {"PV9": 7}


def test_portfolio_rename_carries_the_gamma_override():
    at = open_app("uncertainty")
    key = editor_key(at, "uncertainty_budgets_")
    edit(at, key, edited_rows={row_of(at, key, "WF1"): {"gamma": 20}})
    at.switch_page("pages/portfolio.py").run()
    edit(at, "portfolio_wind_0", edited_rows={0: {"name": "WF9"}})
    case = at.session_state["case"]
    assert [u.name for u in case.wind] == ["WF9", "WF2"] and case.budgets.override_map == {"WF9": 20}


# ----------------------------------------------------------------------------- 4. crafted budget rows


@pytest.mark.parametrize("row, message", [
    ({"source": "ZZ", "gamma": 3}, "Budgets Γ: 'ZZ' is not a source of this case"),
    ({"gamma": 3}, "Budgets Γ: a row without a source"),
    ({"source": "WF1", "gamma": 3}, "Budgets Γ: WF1 has more than one row"),
])
def test_uncertainty_refuses_budget_rows_the_table_does_not_have(paper_case, row, message):
    at = open_app("uncertainty")
    edit(at, editor_key(at, "uncertainty_budgets_"), added_rows=[row])
    assert message in errors(at)
    assert at.session_state["case"] == paper_case


# ----------------------------------------------------------------------------- 5. history series


def test_a_unit_cannot_choose_a_price_column_as_its_series():
    at = open_app("portfolio")
    for kind, series in (("wind", "series"), ("csp", "solar_field.series")):
        columns = json.loads(at.data_editor(key=f"portfolio_{kind}_0").proto.columns)
        for field in (series, "forecast_series" if kind == "wind" else "solar_field.forecast_series"):
            options = columns[field]["type_config"]["options"]
            assert "WF1" in options and not set(PRICE_COLUMNS) & set(options), field


# ----------------------------------------------------------------------------- 6. emptied cells


def test_an_empty_cell_is_named_as_its_column():
    assert edits.table_message('wind "WF1": p_max_mw is required') == "WF1: P max [MW] is empty; enter a number"
    assert edits.table_message('csp "CSP1": power_block.p_el_max_mw is required') == \
        "CSP1: Turbine max [MW] is empty; enter a number"
    assert edits.table_message("units.wind item 2: name is required") == \
        "wind farm in row 2: Name is empty; enter a name"
    assert edits.table_message('wind "WF1": p_max_mw=0 must be > 0') == "WF1: P max [MW] = 0 must be > 0"
    # A case file keeps its own words: the field as written in case.yaml.
    assert edits.plain_message('wind "WF1": p_max_mw is required') == "WF1: p_max_mw is required"


@pytest.mark.parametrize("change, message", [
    ({"p_max_mw": None}, "WF1: P max [MW] is empty; enter a number"),
    # Number cells are text cells in the browser, so letters reach the server and are named as typed.
    ({"p_max_mw": "eighty"}, 'WF1: P max [MW] "eighty" is not a number'),
    ({"p_max_mw": "1,5"}, 'WF1: P max [MW] "1,5" is not a number (write decimals with a point: 1.5)'),
    ({"p_max_mw": "nan"}, 'WF1: P max [MW] "nan" is not a number'),
    ({"name": None}, "wind farm in row 1: Name is empty; enter a name"),
])
def test_portfolio_names_an_emptied_cell_by_its_column(paper_case, change, message):
    at = edit(open_app("portfolio"), "portfolio_wind_0", edited_rows={0: change})
    assert message in errors(at)
    assert "is required" not in errors(at)
    assert at.session_state["case"] == paper_case


def test_one_edit_with_letters_and_a_bad_number_names_both(paper_case):
    """Every problem of an edit at once: letters in one cell do not hide a rule another cell breaks."""
    at = edit(open_app("portfolio"), "portfolio_wind_0", edited_rows={0: {"p_max_mw": "abc"}, 1: {"p_max_mw": "-5"}})
    shown = errors(at)
    assert 'WF1: P max [MW] "abc" is not a number' in shown
    assert "WF2: P max [MW] = −5 must be > 0" in shown  # a true minus, as every message writes it
    assert shown.index('"abc" is not a number') < shown.index("WF2: P max")  # the typed cells first
    assert at.session_state["case"] == paper_case


def test_letters_in_a_budget_or_tariff_cell_are_named_and_the_case_is_kept(paper_case):
    at = open_app("uncertainty")
    key = editor_key(at, "uncertainty_budgets_")
    edit(at, key, edited_rows={row_of(at, key, "WF1"): {"gamma": "abc"}})
    assert 'WF1: Γ [hours] "abc" is not a number' in errors(at)
    assert at.session_state["case"] == paper_case
    at.switch_page("pages/markets.py").run()
    edit(at, editor_key(at, "markets_tariff_"), edited_rows={3: {"tariff_eur_per_mwh": "cheap"}})
    assert '03:00–04:00: Tariff [EUR/MWh_th] "cheap" is not a number' in errors(at)
    assert at.session_state["case"] == paper_case
    edit(at, editor_key(at, "markets_tariff_"), edited_rows={3: {"tariff_eur_per_mwh": " 42.5 "}})
    assert not errors(at)
    assert at.session_state["case"].markets.hpa_tariff_eur_per_mwh[3] == 42.5


def test_a_run_at_another_period_length_keeps_the_cases_own_overrides_in_hours(paper_case):
    """``with_options(dt_h=...)`` (the command line's --dt): the case's WF1 Γ of 20 hours is 80
    quarter-hours, and back; Γ given with the run are already in the new periods."""
    case = paper_case.replace(budgets={"overrides": {"WF1": 20}})
    quarter = rvpp.with_options(case, dt_h=0.25)
    assert quarter.budgets.override_map == {"WF1": 80}
    assert rvpp.with_options(quarter, dt_h=1.0).budgets.override_map == {"WF1": 20}
    assert rvpp.with_options(quarter, dt_h=1.0, gammas={"PV1": 3}).budgets.override_map == {"WF1": 20, "PV1": 3}
    assert rvpp.with_options(case, dt_h=0.25, csp=False).budgets.override_map == {"WF1": 80}
    assert rvpp.with_options(case, dt_h=0.25, strategy="balanced").budgets.override_map == {}
    assert prepare(quarter).budgets["WF1"] == 80
