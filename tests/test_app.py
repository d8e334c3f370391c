"""The dashboard, page by page, driven through Streamlit's AppTest.

Every number the app shows is checked against the library's own result for the same
input (``rvpp.solve`` in this process, while the app solves in its worker processes).
"""

from __future__ import annotations

import base64
import io
import json
import re
import subprocess
import sys
import zipfile
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest
import streamlit as st
from streamlit.testing.v1 import AppTest

import rvpp
from dashboard import solving
from rvpp.outputs.bundle import case_zip_bytes
from rvpp.data.case import STRATEGIES
from rvpp.data.variants import Variant
from rvpp.store import RunLibrary
from tests.factories import click, open_app, shown, shown_table, wait_for

ROOT = Path(__file__).resolve().parent.parent
APP = str(ROOT / "app.py")
TIMEOUT_S = 180  # a generous ceiling for a run that solves (never a performance assertion)
NET = "Net cost [kEUR]"
# Streamlit 1.67's markdown loads its emoji code for any text its frontend reads as an emoji name.
EMOJI_NAME = re.compile(r":(?!material/|streamlit:)[\w+-][\w_+-]*:")
KPI_MONEY = (NET, "DAM revenue [kEUR]", "Reserve revenue [kEUR]", "HPA cost [kEUR]", "Operating cost [kEUR]",
             "Protection [kEUR]")


pytestmark = pytest.mark.usefixtures("run_library")  # every test saves into a store of its own


# ----------------------------------------------------------------------------- helpers


def number(text: str) -> float:
    return float(text.replace("−", "-").replace(",", "").split()[0])


def shown_kpis(at: AppTest) -> dict[str, tuple[str, str]]:
    return {m.label: (m.value, m.proto.help) for m in at.metric}


def expected_kpis(result: rvpp.Result) -> dict[str, float]:
    """The library's numbers [EUR] under the app's card labels."""
    parts = result.parts
    return dict(zip(KPI_MONEY, (-result.objective_eur, parts["revenue_dam_eur"], parts["revenue_sr_eur"],
                                parts["cost_hpa_eur"], parts["cost_opex_eur"], sum(result.protection_eur.values()))))


def assert_kpis_match(at: AppTest, result: rvpp.Result, labels=KPI_MONEY) -> None:
    """Cards show kEUR to one decimal and the exact EUR amount in their help."""
    shown, expected = shown_kpis(at), expected_kpis(result)
    for label in labels:
        value, help_text = shown[label]
        assert number(value) == pytest.approx(expected[label] / 1000, abs=0.051), label
        exact = re.search(r"Exact: (\S+) EUR", help_text).group(1)
        assert number(exact) == pytest.approx(expected[label], abs=0.51), label


def figures(at: AppTest) -> dict[str, dict]:
    """Plotly specs of the page by title."""
    specs = [json.loads(chart.proto.spec) for chart in at.get("plotly_chart")]
    return {spec["layout"]["title"]["text"]: spec for spec in specs}


def trace(spec: dict, name: str) -> dict:
    found = [t for t in spec["data"] if t.get("name") == name]
    assert found, f"no trace {name!r} in {[t.get('name') for t in spec['data']]}"
    return found[0]


def values(data) -> np.ndarray:
    """Trace values as numbers (Plotly may ship arrays as typed base64 buffers)."""
    if isinstance(data, dict) and "bdata" in data:
        return np.frombuffer(base64.b64decode(data["bdata"]), dtype=np.dtype(data["dtype"])).astype(float)
    return np.asarray(data, dtype=float)


def errors(at: AppTest) -> str:
    return "\n".join(e.value for e in at.error)


def case_of(at: AppTest) -> rvpp.Case:
    return at.session_state["case"]


# ----------------------------------------------------------------------------- Home


def test_home_lands_on_the_default_case(paper_case):
    at = open_app()
    assert at.title[0].value.startswith("Robust day-ahead bids")
    assert case_of(at) == paper_case
    (summary,) = [c.value for c in at.caption if c.value.startswith("| Kind | Units | Names | Installed |")]
    rows = [[cell.strip() for cell in line.strip("|").split("|")] for line in summary.splitlines()[2:]]
    assert [int(row[1]) for row in rows] == [2, 3, 1, 3, 2]
    assert rows[2] == ["CSP plants", "1", "CSP1", r"55 MW, TS 1,100 MWh\_th"]  # markdown: the _ shown as typed
    assert {link.proto.page for link in at.get("page_link")} >= {"portfolio", "results", "compare", "learn"}


def test_home_balanced_solve_shows_the_library_numbers(paper_solve):
    at = click(open_app(), "home_solve")
    expected = paper_solve(strategy="balanced")
    assert expected.status == "optimal"
    assert_kpis_match(at, expected, labels=(NET, "DAM revenue [kEUR]", "Reserve revenue [kEUR]",
                                            "Protection [kEUR]"))
    net = [m for m in at.metric if m.label == NET][0]
    assert net.proto.delta == "the plant pays"  # the sign in words: the default day costs money
    timing = [c.value for c in at.caption if c.value.startswith(":material/timer:")]
    assert len(timing) == 1 and "Not solved on this server yet" not in timing[0]  # the solve just measured it
    assert re.search(r"About \d+\.\d s \(the last solve of this case\)", timing[0]), timing
    spec = figures(at)["Day-ahead energy and secondary-reserve bands"]
    np.testing.assert_allclose(values(trace(spec, "DAM energy (+ sell, − buy)")["y"]), expected.market["p_da_mw"])


def test_home_upload_of_a_broken_case_is_explained_and_a_good_one_loads(paper_case):
    at = open_app()
    data = case_zip_bytes(paper_case)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        text = archive.read("paper/case.yaml").decode()
        history = archive.read("paper/history.csv")
    broken = text.replace("e_max_mwh_th: 1100.0", "e_max_mwh_th: 100.0")
    at.file_uploader(key="home_upload").set_value([("case.yaml", broken.encode(), "text/yaml"),
                                                   ("history.csv", history, "text/csv")]).run()
    click(at, "home_load_upload")
    assert "CSP1: TS E min [MWh_th] = 110 must be < TS E max [MWh_th] = 100" in errors(at)
    assert case_of(at) == paper_case
    renamed = text.replace("name: paper", "name: uploaded", 1)
    at.file_uploader(key="home_upload").set_value([("case.yaml", renamed.encode(), "text/yaml"),
                                                   ("history.csv", history, "text/csv")]).run()
    click(at, "home_load_upload")
    assert not errors(at)
    assert case_of(at).name == "uploaded" and case_of(at).replace(name="paper") == paper_case


def test_home_upload_of_a_case_file_without_sections_names_each_missing_section():
    at = open_app()
    at.file_uploader(key="home_upload").set_value([("case.yaml", b"units: 5\n", "text/yaml")]).run()
    click(at, "home_load_upload")
    shown = errors(at)
    assert "Case not loaded" in shown
    assert "units: must be a mapping of unit lists" in shown
    assert "markets: section is required; it needs at least hpa_tariff_eur_per_mwh" in shown


def test_home_loads_a_case_folder_only_when_the_server_allows_it(tmp_path, paper_case, monkeypatch):
    monkeypatch.delenv("RVPP_ALLOW_SERVER_FOLDERS", raising=False)
    at = open_app()
    assert "home_folder" not in [t.key for t in at.text_input]
    monkeypatch.setenv("RVPP_ALLOW_SERVER_FOLDERS", "1")
    at = open_app()
    at.text_input(key="home_folder").input(str(tmp_path / "missing")).run()
    click(at, "home_load_folder")
    assert "no case.yaml found" in errors(at)
    assert case_of(at) == paper_case
    mine = rvpp.with_options(paper_case, strategy="pessimistic")
    rvpp.save_case(mine, tmp_path / "mine")
    at.text_input(key="home_folder").input(str(tmp_path / "mine")).run()
    click(at, "home_load_folder")
    assert not errors(at)
    assert case_of(at) == mine
    click(at, "home_load_shipped")
    assert not errors(at)
    assert case_of(at) == paper_case


# ----------------------------------------------------------------------------- Portfolio


def test_portfolio_renders_tables_and_every_band(paper_case):
    at = open_app("portfolio")
    editors = {e.key for e in at.data_editor}
    assert {f"portfolio_{kind}_0" for kind in ("wind", "pv", "csp", "ed", "td")} <= editors
    titles = figures(at)
    for _, unit in paper_case.units():
        assert any(t.startswith(f"{unit.name} (") for t in titles), unit.name
    assert "Power-block conversion curve" in titles


def test_text_typed_into_a_number_cell_is_quoted_as_typed_never_drawn_as_markdown(paper_case):
    # The refusal quoted the cell's text as markdown: a link typed there became a live link.
    at = open_app("portfolio")
    typed = "[x](https://example.com) **b**"
    at.session_state["portfolio_wind_0"] = {"edited_rows": {1: {"name": "W*F*", "p_max_mw": typed}},
                                            "added_rows": [], "deleted_rows": []}
    at.run()
    said = errors(at)
    quoted = re.search(r'- W\\\*F\\\*: P max \[MW\] "(.*)" is not a number', said)  # the name as typed too
    assert quoted, said
    assert shown(quoted.group(1)) == typed  # unescaped, it is what was typed
    assert not re.search(r"(?<!\\)[\[\]()*]", quoted.group(1)), quoted.group(1)  # every special character escaped
    assert case_of(at) == paper_case


def test_portfolio_edit_changes_the_plan_and_an_invalid_edit_is_refused(paper_case):
    at = open_app("portfolio")
    at.session_state["portfolio_csp_0"] = {"edited_rows": {0: {"storage.e_min_mwh_th": 1200.0}},
                                           "added_rows": [], "deleted_rows": []}
    at.run()
    assert not at.exception
    assert "CSP1: TS E min [MWh_th] = 1200 must be < TS E max [MWh_th] = 1100" in errors(at)
    assert case_of(at) == paper_case
    click(at, "portfolio_csp_discard")
    assert not errors(at) and "portfolio_csp_1" in {e.key for e in at.data_editor}
    at.session_state["portfolio_pv_0"] = {"edited_rows": {0: {"p_max_mw": 20.0}}, "added_rows": [],
                                          "deleted_rows": []}
    at.run()
    assert not errors(at)
    edited = case_of(at)
    assert edited.pv[0].p_max_mw == 20.0 and edited.replace(pv=paper_case.pv) == paper_case
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    expected = rvpp.solve(edited)
    assert expected.status == "optimal"
    assert_kpis_match(at, expected)
    assert number(shown_kpis(at)[NET][0]) != pytest.approx(
        -rvpp.solve(paper_case).objective_eur / 1000, abs=0.05)


def test_portfolio_adds_a_unit_and_switches_the_csp_off(paper_case, paper_solve):
    at = open_app("portfolio")
    at.session_state["portfolio_wind_0"] = {
        "edited_rows": {}, "deleted_rows": [],
        "added_rows": [{"name": "WF3", "p_max_mw": 30.0, "ramp_up_mw_per_min": 15.0, "ramp_dn_mw_per_min": 25.0,
                        "series": "WF2", "scale_with_capacity": True}]}  # the column's default, as the browser sends it
    at.run()
    assert not errors(at)
    assert [u.name for u in case_of(at).wind] == ["WF1", "WF2", "WF3"]
    assert case_of(at).wind[2].column == "WF2"
    at.toggle(key="portfolio_csp_on").set_value(False).run()
    assert at.session_state["csp_on"] is False
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    expected = rvpp.solve(rvpp.with_options(case_of(at), csp=False))
    assert_kpis_match(at, expected)
    assert not any(title.endswith("thermal storage") for title in figures(at))


def accepted(edits: str) -> str:
    """The note under a table whose edit the case took, for ``edits`` as markdown."""
    return f"**Edit accepted**: {edits}. The current case now holds it; solve again on Results to see its plan."


def new_row(at: AppTest, kind: str) -> dict:
    """A new row of the unit table of ``kind`` as the browser sends it: the column defaults, numbers as text."""
    return {column: value if isinstance(value, (str, bool)) else f"{value:g}"
            for column, value in rvpp.service.new_unit_row(case_of(at), kind).items()}


def test_an_added_or_removed_unit_is_named_without_a_was():
    at = open_app("portfolio")
    at.session_state["portfolio_battery_0"] = {"edited_rows": {}, "added_rows": [new_row(at, "battery")],
                                               "deleted_rows": []}
    at.run()
    assert [s.value for s in at.success] == [accepted("BAT1 added \\(20 MW\\)")]
    key = next(e.key for e in at.data_editor if e.key.startswith("portfolio_battery_"))
    at.session_state[key] = {"edited_rows": {}, "added_rows": [], "deleted_rows": [0]}
    at.run()
    assert [s.value for s in at.success] == [accepted("BAT1 removed")]
    assert [u.name for u in case_of(at).battery] == []


def test_a_new_unit_renamed_is_named_without_a_was():
    # A newcomer types a name into the table's empty row: the row comes in with its default name (BAT1), then
    # takes the typed one; the page said "B1 added (20 MW) (was BAT1 added (20 MW)); BAT1 removed".
    at = open_app("portfolio")
    at.session_state["portfolio_battery_0"] = {"edited_rows": {}, "added_rows": [new_row(at, "battery")],
                                               "deleted_rows": []}
    at.run()
    key = next(e.key for e in at.data_editor if e.key.startswith("portfolio_battery_"))
    at.session_state[key] = {"edited_rows": {0: {"name": "B1"}}, "added_rows": [], "deleted_rows": []}
    at.run()
    assert [s.value for s in at.success] == [accepted("B1 added \\(20 MW\\); BAT1 removed")]
    assert [u.name for u in case_of(at).battery] == ["B1"]


def test_units_added_in_two_tables_both_stay_in_the_case():
    # The browser sends a new row as its column defaults, number cells as text; a new unit's default
    # name then moves on (BAT2), which gave the table a new identity: its added row was dropped on the
    # next run and the unit left the case again.
    at = open_app("portfolio")
    for kind, name, capacity in (("battery", "BAT1", "20 MW"), ("hydro", "HY1", "30 MW")):
        row = new_row(at, kind)
        assert row["name"] == name
        at.session_state[f"portfolio_{kind}_0"] = {"edited_rows": {}, "added_rows": [row], "deleted_rows": []}
        at.run()
        assert not errors(at)
        assert [s.value for s in at.success] == [accepted(f"{name} added \\({capacity}\\)")]
    at.run()
    assert ([u.name for u in case_of(at).battery], [u.name for u in case_of(at).hydro]) == (["BAT1"], ["HY1"])
    assert not at.success
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    assert_kpis_match(at, rvpp.solve(case_of(at)))
    assert "BAT1: state of charge" in figures(at)


def test_a_series_edit_of_the_first_unit_stays_on_the_next_run():
    # A new wind row takes the first farm's series by default: editing that series changed the table's
    # settings, and the edit was dropped on the next run.
    at = open_app("portfolio")
    at.session_state["portfolio_wind_0"] = {"edited_rows": {0: {"series": "WF2"}}, "added_rows": [],
                                            "deleted_rows": []}
    at.run()
    assert [u.column for u in case_of(at).wind] == ["WF2", "WF2"]
    assert [s.value for s in at.success] == [accepted("WF1 History series WF2 \\(was WF1\\)")]
    at.run()
    assert [u.column for u in case_of(at).wind] == ["WF2", "WF2"]
    assert not at.success and not errors(at)


# ----------------------------------------------------------------------------- Markets & tariffs


def test_markets_flat_tariff_preset_and_an_invalid_tariff(paper_case, paper_solve):
    at = open_app("markets")
    titles = figures(at)
    assert {"Day-ahead price: forecast band", "Heat purchase agreement tariff"} <= set(titles)
    click(at, "markets_flat_70")
    assert case_of(at).markets.hpa_tariff_eur_per_mwh == (70.0,) * 24
    np.testing.assert_allclose(values(figures(at)["Heat purchase agreement tariff"]["data"][0]["y"]), 70.0)
    at.session_state["markets_tariff_1"] = {"edited_rows": {3: {"tariff_eur_per_mwh": -5.0}}, "added_rows": [],
                                            "deleted_rows": []}
    at.run()
    assert "HPA tariff at 03:00 [EUR/MWh_th] = −5 must be ≥ 0" in errors(at)
    assert case_of(at).markets.hpa_tariff_eur_per_mwh == (70.0,) * 24
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    assert_kpis_match(at, paper_solve(hpa_flat=70.0))


def test_markets_switches_go_into_the_case():
    at = open_app("markets")
    at.toggle(key="markets_srm").set_value(False).run()
    assert case_of(at).markets.label == "DAM+HPA"
    at.button_group(key="markets_dt").set_value(15).run()
    assert not at.exception and case_of(at).dt_h == 0.25


# ----------------------------------------------------------------------------- Uncertainty


def test_uncertainty_presets_budgets_and_deviating_periods(paper_case, paper_solve):
    at = open_app("uncertainty")
    assert len(figures(at)) == len(paper_case.sources())
    at.button_group(key="uncertainty_strategy").set_value("pessimistic").run()
    assert case_of(at).budgets.strategy == "pessimistic"
    table = at.data_editor(key="uncertainty_budgets_1").value
    wf1 = int(np.flatnonzero(table["source"] == "WF1")[0])
    at.session_state["uncertainty_budgets_1"] = {"edited_rows": {wf1: {"gamma": 30}}, "added_rows": [],
                                                 "deleted_rows": []}
    at.run()
    assert "Γ [hours] of WF1: 30 is outside the allowed range 0 to 24 (the day's 24 hours)" in errors(at)
    assert case_of(at).budgets.overrides == ()
    at.session_state["uncertainty_budgets_1"] = {"edited_rows": {wf1: {"gamma": 2}}, "added_rows": [],
                                                 "deleted_rows": []}
    at.run()
    assert case_of(at).budgets.override_map == {"WF1": 2}
    click(at, "uncertainty_solve")
    expected = rvpp.solve(case_of(at))
    chi = expected.units.query("unit == 'PV1'").sort_values("t")["chi"].to_numpy()
    spec = figures(at)["PV1 (pv): forecast band"]
    marks = trace(spec, f"Deviates (χ = 1) in {int(chi.sum())} periods")
    assert marks["x"] == [label for label, c in zip(expected.problem.labels, chi) if c]
    wf1_spec = figures(at)["WF1 (wind): forecast band"]
    assert trace(wf1_spec, "Deviates (χ = 1) in 2 periods")


def test_uncertainty_tie_rule_goes_into_the_case_and_leaves_with_paper_mode():
    at = open_app("uncertainty")
    assert case_of(at).budgets.ties == "choose" and not at.radio(key="uncertainty_ties").disabled
    at.radio(key="uncertainty_ties").set_value("earliest").run()
    assert not at.exception and case_of(at).budgets.ties == "earliest"
    at.radio(key="uncertainty_mode").set_value("planner_chosen").run()
    assert not at.exception and not errors(at)
    assert (case_of(at).budgets.mode, case_of(at).budgets.ties) == ("planner_chosen", "choose")
    assert at.radio(key="uncertainty_ties").disabled


# ----------------------------------------------------------------------------- Results


def test_results_warns_of_tied_deviations_before_the_solve(paper_case):
    tie_day = rvpp.with_options(paper_case, date="2025-04-06", strategy="balanced")
    for case, warned in ((tie_day, True), (rvpp.with_options(tie_day, ties="earliest"), False), (paper_case, False)):
        at = open_app()
        at.session_state["case"] = case
        at.switch_page("pages/results.py").run()
        assert not at.exception and not at.get("plotly_chart")
        said = " ".join(c.value for c in at.caption)
        assert ("This day has deviations tied at the Γ boundary (CSP1: 4 of the 5 periods tied at a deviation of "
                "300 MW_th)" in said) is warned, (case.delivery_date, case.budgets.ties)
        assert "benchmark" not in said and "minute" not in said  # a time shown is measured by this server


def test_a_tie_day_is_not_expected_to_take_a_day_without_ties(paper_case):
    from dashboard.solving import Solver, shape

    tie_day = rvpp.with_options(paper_case, date="2025-04-06", strategy="balanced")
    quiet_day = rvpp.with_options(paper_case, strategy="balanced")
    assert shape(tie_day) != shape(quiet_day)
    assert shape(rvpp.with_options(tie_day, ties="earliest")) == shape(quiet_day)
    solver = Solver(workers=1)
    assert solver.expected_s(tie_day) is None  # nothing measured on this server yet
    solver.shape_seconds[shape(tie_day)] = 7.0
    assert solver.expected_s(tie_day) == (7.0, "the last solve of a case like this one on this server")
    assert solver.expected_s(quiet_day) != (7.0, "the last solve of a case like this one on this server")


def test_results_says_when_the_model_chose_among_tied_deviations(paper_case):
    at = open_app()
    at.session_state["case"] = rvpp.with_options(paper_case, date="2025-04-06", strategy="balanced")
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    assert not at.exception
    said = " ".join(c.value for c in at.caption)
    assert "The model chose which of the tied deviations count" in said
    assert "CSP1: 4 of the 5 periods tied at a deviation of 300 MW_th" in said


def test_results_charts_and_kpis_match_the_library(paper_solve):
    at = open_app("results")
    assert not at.get("plotly_chart")
    click(at, "results_solve")
    expected = paper_solve()
    assert_kpis_match(at, expected)
    specs = figures(at)
    assert set(specs) == {"The day's economics, part by part (balanced)",
                          "Day-ahead energy and secondary-reserve bands", "Heat supply against thermal demand",
                          "Electrical dispatch by unit (consumption negative)", "CSP1: thermal storage",
                          "Reserve by unit kind"}
    waterfall = specs["The day's economics, part by part (balanced)"]["data"][0]
    np.testing.assert_allclose(values(waterfall["y"])[-1], -expected.objective_eur / 1000)
    market = expected.market
    trades = specs["Day-ahead energy and secondary-reserve bands"]
    np.testing.assert_allclose(values(trace(trades, "SR up band")["y"]), market["r_sr_up_mw"])
    heat = specs["Heat supply against thermal demand"]
    np.testing.assert_allclose(values(trace(heat, "HPA purchase")["y"]), market["h_hpa_mw"])
    storage = specs["CSP1: thermal storage"]
    np.testing.assert_allclose(values(trace(storage, "Stored energy (end of period)")["y"]),
                               expected.csp["ts_energy_mwh"])
    assert len(trace(storage, "Charge")["x"]) == expected.problem.nt
    flexibility = at.dataframe[-1].value
    np.testing.assert_allclose(flexibility["r_dn_mwh"], expected.flexibility["r_dn_mwh"])
    assert [b.label for b in at.get("download_button")] == ["Bids as shown (CSV)", "Bids (CSV)", "Full plan (Excel)",
                                                           "Case as edited (zip)", "Case as edited (Excel)"]
    for button in at.get("download_button"):  # a CSV says how it reads in an Excel set to a decimal comma
        assert ("decimal comma" in button.proto.help) == button.label.endswith("(CSV)"), button.label
    texts = [e.value for e in (*at.markdown, *at.caption)]
    assert not [text for text in texts if EMOJI_NAME.search(text)]


def test_the_clock_of_a_solvers_answer_shows_in_markdown_without_an_emoji_name():
    returned = datetime(2026, 11, 26, 10, 15, 22, 123456).timestamp()
    clock = solving.answered(solving.Job("key", None, returned_at=returned))
    assert not EMOJI_NAME.search(clock)
    assert shown(clock) == "10:15:22.123"  # markdown's backslash escapes undone



def test_every_page_loads_the_code_of_a_plans_elements_ahead_once():
    at = open_app()
    scripts = [e.proto.body for e in at.get("html") if "__rvppPreloaded" in e.proto.body]
    assert len(scripts) == 1
    static = Path(st.__file__).parent / "static" / "static" / "js"
    files = json.loads(re.search(r"const files = (\[.*?\]);", scripts[0]).group(1))
    assert sorted(name.split(".")[0] for name in files) == ["DataFrame", "Metric", "PlotlyChart", "TextInput"]
    assert all((static / name).is_file() for name in files)
    assert "window.__rvppPreloaded" in scripts[0]


def test_results_come_back_from_the_cache_without_a_click():
    at = click(open_app("results"), "results_solve")
    at.switch_page("pages/markets.py").run()
    at.switch_page("pages/results.py").run()
    assert len(at.get("plotly_chart")) == 6


# ----------------------------------------------------------------------------- Compare


def test_compare_costs_and_flexibility_match_the_library(paper_case, paper_solve, run_library):
    at = click(open_app("compare"), "compare_solve")
    cost = at.dataframe[0].value
    assert all(Variant(strategy=s, markets="DAM+SRM+HPA").apply(paper_case) == rvpp.with_options(paper_case, strategy=s)
               for s in STRATEGIES)
    expected = {s: paper_solve(strategy=s) for s in STRATEGIES}
    for strategy, result in expected.items():
        assert result.status == "optimal"
        assert cost.loc[strategy.capitalize(), "DAM+SRM+HPA"] == pytest.approx(result.cost_keur)
    spec = figures(at)["Trades of each plan"]
    buys_heat = any(np.abs(r.market["h_hpa_mw"]).max() > 1e-6 for r in expected.values())
    assert buys_heat  # the paper case starts the day with an empty tank and heats the night through the HPA
    assert len([k for k in spec["layout"] if k.startswith("yaxis")]) == 4  # DAM, SR up, SR down, HPA
    assert "no heat bought" not in "\n".join(c.value for c in at.caption)
    for strategy, result in expected.items():
        lines = [t for t in spec["data"] if t["name"] == strategy]
        np.testing.assert_allclose(values(lines[0]["y"]), result.market["p_da_mw"])
    flexibility = at.dataframe[1].value  # after the cost table; the parts are a text table
    assert len(flexibility) == 4 * len(STRATEGIES)
    click(at, "compare_save")
    saved = RunLibrary(run_library).list()
    assert sorted(r.label for r in saved) == sorted(f"{s} · DAM+SRM+HPA" for s in STRATEGIES)
    assert "Trades of each plan" in figures(at)


# ----------------------------------------------------------------------------- Learn


def test_learn_moves_the_adversary_live(paper_solve):
    at = open_app("learn")
    plan = paper_solve()
    # The DAM price's loss per period, worked out here: λ falls by its deviation where the plan sells,
    # rises by its upward deviation where it buys; the adversary takes the 3 largest.
    da, sold = plan.problem.sources["price_da"], plan.market["p_da_mw"].to_numpy(float)
    loss = np.where(sold > 0, da.deviation * sold, -da.deviation_up * sold) * plan.problem.dt_h
    protection = [m for m in at.metric if m.label == "Protection [kEUR]"][0]
    assert number(protection.value) == pytest.approx(plan.protection_eur["price_da"] / 1000, abs=0.051)
    assert number(protection.proto.help.split("Exact: ")[1]) == pytest.approx(plan.protection_eur["price_da"],
                                                                             abs=0.51)
    # The plan's protection for this price and for every price, the total the Protection card on Results shows
    # (it said only "the model charged 3.7 kEUR", beside a card on Results of 4.2).
    this, every = plan.protection_eur["price_da"] / 1000, sum(plan.protection_eur.values()) / 1000
    assert every > this + 0.1  # the reserve prices' protection too
    assert f"charged {this:,.1f} kEUR for it, of {every:,.1f} kEUR for every price (the Protection card on Results)" \
        in "\n".join(c.value for c in at.caption)
    at.slider(key="learn_price_gamma").set_value(3).run()
    protection = [m for m in at.metric if m.label == "Protection [kEUR]"][0]
    assert number(protection.value) == pytest.approx(sum(sorted(np.maximum(loss, 0.0))[-3:]) / 1000, abs=0.051)
    at.slider(key="learn_gamma").set_value(9).run()
    band = next(spec for title, spec in figures(at).items() if title.startswith("WF1 ("))
    assert trace(band, "Deviates (χ = 1) in 9 periods")


@pytest.fixture
def solver_processes(monkeypatch):
    """Every solver process the dashboard starts, as (case, Γ grid or None for one solve)."""
    from dashboard import solving

    started = []
    run = solving.Job._solve

    def counted(job):
        started.append((job.case, job.gammas))
        return run(job)

    monkeypatch.setattr(solving.Job, "_solve", counted)
    return started


def exact_eur(at: AppTest, label: str) -> float:
    """The exact amount in EUR a KPI card gives in its help."""
    help_text = shown_kpis(at)[label][1]
    return number(re.search(r"Exact: (\S+) EUR", help_text).group(1))


def assert_shows_gamma_plan(at: AppTest, paper_case, paper_solve, gamma: int) -> None:
    """The slider's plan is worth what the library's plan of the same Γ for every source is worth,
    within the solver's relative gap (both plans are that close to the same bound)."""
    expected = paper_solve(gammas={source: gamma for source in paper_case.sources()})
    assert expected.status == "optimal"
    tolerance = 1.0 + paper_case.solver.rel_gap * abs(expected.objective_eur)  # + whole euros shown
    assert exact_eur(at, NET) == pytest.approx(-expected.objective_eur, abs=tolerance)
    assert number(shown_kpis(at)[NET][0]) == pytest.approx(-expected.objective_eur / 1000,
                                                           abs=0.051 + tolerance / 1000)
    assert f"Bids at Γ = {gamma}: day-ahead energy and reserve bands" in figures(at)


@pytest.mark.slow
def test_learn_gamma_slider_sweeps_once_then_moves_without_solving(paper_case, paper_solve, solver_processes):
    from dashboard import solving

    solving.solver().sweeps.clear()  # cold, whichever test of this process swept before
    at = open_app("learn")
    assert "learn_sweep_gamma_24" not in [s.key for s in at.select_slider]  # a line says where it will be
    assert "a slider from 0 to 24 appears here" in " ".join(m.value for m in at.markdown)
    assert "25 solves" in at.button(key="learn_sweep").label
    assert [g for _, g in solver_processes if g is not None] == []  # nothing swept before the click
    click(at, "learn_sweep")
    sweeps = [(case, g) for case, g in solver_processes if g is not None]
    assert len(sweeps) == 1 and sweeps[0][1] == tuple(range(25))
    slider = at.select_slider(key="learn_sweep_gamma_24")
    assert not slider.disabled and slider.options == [str(g) for g in range(25)]
    curve = next(spec for title, spec in figures(at).items() if title.startswith("Price of robustness"))
    assert len(values(curve["data"][0]["x"])) == 25
    before = len(solver_processes)
    for gamma in (6, 18, 0):
        at.select_slider(key="learn_sweep_gamma_24").set_value(gamma).run()
        assert not at.exception, at.exception
        assert f"Price of robustness · plan shown: Γ = {gamma}" in figures(at)
        assert_shows_gamma_plan(at, paper_case, paper_solve, gamma)
    assert len(solver_processes) == before  # a warm move solves nothing


@pytest.mark.slow
def test_compare_names_the_plans_not_proven_optimal_until_solved_again(paper_case):
    from dashboard import solving
    from dashboard.state import case_key

    at = click(open_app("compare"), "compare_solve")
    assert not [w for w in at.warning if "Not proven optimal" in w.value]
    balanced = rvpp.with_options(paper_case, strategy="balanced")
    early = rvpp.solve(balanced, watch=lambda search: True)  # stopped at HiGHS's first plan
    assert early.status == "stopped"
    solving.solver().remember(early)
    at.run()
    warned = [w.value for w in at.warning if "Not proven optimal" in w.value]
    assert len(warned) == 1 and warned[0].endswith(
        f"\n\n- balanced / DAM+SRM+HPA: stopped early, as asked, within {early.mip_gap:.2%} of the optimum"), warned
    click(at, "compare_solve")  # searches on
    assert not [w for w in at.warning if "Not proven optimal" in w.value]
    assert solving.solver().result(case_key(balanced)).status == "optimal"


@pytest.mark.slow
def test_compare_gamma_slider_reuses_the_sweep_in_a_new_session(paper_case, paper_solve, solver_processes):
    at = open_app("compare")
    if "compare_sweep_gamma_24" not in [s.key for s in at.select_slider]:  # not swept yet
        click(at, "compare_sweep")
    swept = len(solver_processes)
    assert swept <= 1
    other = open_app("compare")  # another tab: the server's sweep shows without a click
    slider = other.select_slider(key="compare_sweep_gamma_24")
    assert not slider.disabled and slider.value == 12
    assert_shows_gamma_plan(other, paper_case, paper_solve, 12)
    other.select_slider(key="compare_sweep_gamma_24").set_value(3).run()
    assert_shows_gamma_plan(other, paper_case, paper_solve, 3)
    assert "The day's economics at Γ = 3" in figures(other)
    assert len(solver_processes) == swept


# ----------------------------------------------------------------------------- sessions


def test_two_sessions_keep_their_own_case():
    first, second = open_app("uncertainty"), open_app("uncertainty")
    first.button_group(key="uncertainty_strategy").set_value("optimistic").run()
    second.run()
    assert case_of(first).budgets.strategy == "optimistic"
    assert case_of(second).budgets.strategy == "balanced"


# ----------------------------------------------------------------------------- saved runs


def edit_capacity(at: AppTest, row: int, p_max_mw: float, follow: bool = True) -> AppTest:
    """Type a wind farm's capacity into the Portfolio table (and the scale tick box)."""
    key = next(e.key for e in at.data_editor if e.key.startswith("portfolio_wind_"))
    edit = {"p_max_mw": p_max_mw} | ({} if follow else {"scale_with_capacity": False})
    at.session_state[key] = {"edited_rows": {row: edit}, "added_rows": [], "deleted_rows": []}
    at.run()
    assert not at.exception, at.exception
    return at


def test_a_capacity_edit_scales_the_band_and_moves_the_plans_bound(paper_case, paper_solve):
    at = edit_capacity(open_app("portfolio"), 0, 80.0)
    wf1 = case_of(at).wind[0]
    assert wf1.p_max_mw == 80.0 and wf1.series_scale == pytest.approx(80.0 / 50.0)
    # The table is drawn again from the case: it shows the scale that followed the capacity.
    table = next(e for e in at.data_editor if e.key.startswith("portfolio_wind_")).value
    assert table.loc[0, "series_scale"] == "1.6"  # number cells are text cells, as typed
    # (AppTest runs a switched-to page without app.py, so the sidebar is checked in tests/test_browser.py.)
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    before = paper_solve().units.query("unit == 'WF1'")["bound_mw"].to_numpy()
    after = rvpp.solve(case_of(at)).units.query("unit == 'WF1'")["bound_mw"].to_numpy()
    # The band is the history's WF1 profile times the series scale, and scaling every deviation by 1.6
    # keeps the same periods the largest: the bound is 1.6 times the unedited plan's, below 80 MW.
    np.testing.assert_allclose(after, 1.6 * before, rtol=1e-9, atol=1e-6)
    assert after.max() <= 80.0 + 1e-9
    assert_kpis_match(at, rvpp.solve(case_of(at)))
    band = figures(at)["Day-ahead energy and secondary-reserve bands"]
    assert values(trace(band, "DAM energy (+ sell, − buy)")["y"]).sum() > paper_solve().market["p_da_mw"].sum()


def test_an_unticked_unit_keeps_its_band_when_its_capacity_changes(paper_case):
    at = edit_capacity(open_app("portfolio"), 1, 80.0, follow=False)
    assert case_of(at).wind[1].p_max_mw == 80.0 and case_of(at).wind[1].series_scale == 1.0
    assert "WF2" in at.session_state["portfolio_fixed_scale"]


def test_saved_runs_keep_distinct_labels_and_reopen_without_a_solve(run_library, paper_solve):
    at = click(open_app("results"), "results_solve")
    assert at.text_input(key="results_run_label").value == "balanced · DAM+SRM+HPA"
    click(at, "results_save")
    click(at, "results_save")  # the same label again: the library numbers it
    at.switch_page("pages/portfolio.py").run()
    edit_capacity(at, 0, 80.0)
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    assert at.text_input(key="results_run_label").value == "balanced · DAM+SRM+HPA · WF1 80 MW"
    click(at, "results_save")
    library = RunLibrary(run_library)
    runs = library.list()
    assert [r.label for r in runs] == ["balanced · DAM+SRM+HPA · WF1 80 MW", "balanced · DAM+SRM+HPA (2)",
                                       "balanced · DAM+SRM+HPA"]
    edited = library.load(runs[0].id)
    assert edited.case.wind[0].p_max_mw == 80.0 and edited.settings["csp"] is True
    assert edited.result.objective_eur == pytest.approx(rvpp.solve(edited.case).objective_eur, abs=1.0)

    # A link opens the run in a new session: its case, its plan, no solve.
    fresh = AppTest.from_file(APP, default_timeout=TIMEOUT_S)
    fresh.query_params["run"] = runs[0].id
    fresh.run()
    assert not fresh.exception, fresh.exception
    assert case_of(fresh).wind[0].p_max_mw == 80.0
    assert number(shown_kpis(fresh)[NET][0]) == pytest.approx(
        -edited.result.objective_eur / 1000, abs=0.051)
    assert "WF1 80 MW" in "\n".join(m.value for m in fresh.sidebar.markdown)


def test_the_saved_runs_page_renames_deletes_and_compares(run_library, paper_solve):
    library = RunLibrary(run_library)
    pessimistic, balanced = paper_solve(strategy="pessimistic"), paper_solve()
    first = library.save("pessimistic · DAM+SRM+HPA", pessimistic.case, pessimistic, settings={"csp": True})
    second = library.save("balanced · DAM+SRM+HPA", balanced.case, balanced, settings={"csp": True})
    at = open_app("runs")
    table = at.dataframe[0].value
    assert list(table["label"]) == [second.label, first.label]
    assert list(table["link"]) == [f"/?run={second.id}", f"/?run={first.id}"]
    np.testing.assert_allclose(table["net_cost_keur"], [-balanced.objective_eur / 1000,
                                                        -pessimistic.objective_eur / 1000])
    with pytest.raises(Exception):
        library.rename(first.id, second.label)  # the page relies on the library refusing a taken label

    at.switch_page("pages/compare.py").run()
    at.button_group(key="compare_mode").set_value("Saved runs").run()
    at.multiselect(key="compare_runs").set_value([first.id, second.id]).run()
    assert not at.exception, at.exception
    kpis = shown_table(at.table[0])
    assert list(kpis.index) == [first.label, second.label]
    # Read forwards: the extra cost of the safer (pessimistic) run over the least safe (balanced) one,
    # positive when it costs more.
    extra = kpis.loc[first.label, f"Extra cost vs {second.label} [kEUR]"]
    assert extra == pytest.approx((balanced.objective_eur - pessimistic.objective_eur) / 1000)
    assert extra > 0 and kpis.loc[second.label, f"Extra cost vs {second.label} [kEUR]"] == 0
    economics = figures(at)["The day's economics, part by part"]
    assert [values(t["y"])[-1] for t in economics["data"]] == pytest.approx(
        [-pessimistic.objective_eur / 1000, -balanced.objective_eur / 1000])
    library.delete(first.id)
    assert [r.label for r in RunLibrary(run_library).list()] == [second.label]


def _cancel_stops_at_once(solver, job) -> None:
    """Cancel ``job`` and check that its process was killed: it ends without a result (a solve
    left to run would have brought one)."""
    solver.cancel([job.key])
    assert job.done.wait(TIMEOUT_S)
    assert job.cancelled and job.result is None and not job.process.is_alive()


def test_a_cancelled_solve_stops_its_process_at_once(paper_case):
    from dashboard.solving import Solver

    solver = Solver(workers=1)
    slow = rvpp.with_options(paper_case, dt_h=0.25, strategy="pessimistic")
    job = solver.start(slow)
    wait_for(lambda: job.stage == "solving with HiGHS", TIMEOUT_S, every_s=0.05)
    assert job.process.is_alive()
    _cancel_stops_at_once(solver, job)
    assert solver.result(job.key) is None
    quick = solver.start(paper_case)  # the solver keeps working after a cancel
    assert quick.done.wait(TIMEOUT_S) and quick.result.status == "optimal"
    assert solver.expected_s(paper_case)[1] == "the last solve of this case"


def test_a_solve_stopped_early_keeps_its_best_plan_and_its_time_says_nothing(paper_case):
    """6 April, 15 minutes, balanced: HiGHS has plans within a second and the optimum after 15-30 s."""
    from dashboard.solving import Solver, stopped

    solver = Solver(workers=1)
    slow = rvpp.with_options(paper_case, date="2025-04-06", strategy="balanced", dt_h=0.25)
    job = solver.start(slow)
    wait_for(lambda: job.search is not None and job.search.objective is not None, TIMEOUT_S, every_s=0.05)
    assert re.fullmatch(r"best plan so far within \d+\.\d\d% of the optimum \([\d,]+ nodes\)", job.stage), job.stage
    solver.stop([job.key])
    assert job.done.wait(TIMEOUT_S) and not job.cancelled
    kept = solver.result(job.key)
    assert kept is job.result and stopped(kept) and kept.has_plan
    assert kept.mip_gap > slow.solver.rel_gap and kept.objective_eur < kept.bound_eur
    assert job.key not in solver.seconds and solver.expected_s(slow) is None  # no time from a search cut short


def fresh_process_output(code: str, timeout_s: int) -> list[str]:
    """The lines ``code`` prints when run by a fresh Python process in the project's folder,
    checked to have ended without an error."""
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=timeout_s)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout.strip().splitlines()


def test_the_head_start_reads_the_shipped_case_for_the_first_session():
    """``python -m dashboard``'s head start (``dashboard.serve``) leaves the shipped case in the cache
    the sessions share: the first session after a server start reads no case file of its own."""
    code = "\n".join([
        "import rvpp", "from dashboard import serve, state",
        "serve._warm()",
        "read = []", "real = rvpp.load_case",
        "rvpp.load_case = lambda folder: read.append(folder) or real(folder)",
        "case = state._load(str(state.DEFAULT_CASE))",
        "print(len(read), case.name)"])
    assert fresh_process_output(code, timeout_s=300)[-1] == "0 paper"


@pytest.mark.slow
def test_the_server_process_never_imports_the_solver_stack():
    """A solve's reports (stages, the search) and its result reach the server as plain data: the server
    process, where every session runs, stays without Pyomo and HiGHS (1-2 s to import, and memory)."""
    code = "\n".join([
        "import sys", "import rvpp", "from dashboard.solving import Solver",
        "job = Solver(workers=1).start(rvpp.load_case('data/cases/paper'))",
        "assert job.done.wait(300), 'no answer'",
        "assert job.search is not None and job.result.status == 'optimal', (job.search, job.problems)",
        "print(sorted(m for m in ('pyomo', 'highspy') if m in sys.modules))"])
    assert fresh_process_output(code, timeout_s=600) == ["[]"]


def test_results_shows_a_plan_stopped_early_until_solve_searches_on(paper_case, paper_solve):
    from dashboard import solving
    from dashboard.state import REQUESTED, case_key

    case = rvpp.with_options(paper_case, strategy="balanced")
    early = rvpp.solve(case, watch=lambda search: True)  # stopped at HiGHS's first plan
    assert early.status == "stopped" and early.mip_gap > case.solver.rel_gap
    at = open_app()
    at.session_state["case"] = case
    solving.solver().remember(early)
    at.session_state[REQUESTED] = {case_key(case)}  # asked for before: the page shows what is kept
    at.switch_page("pages/results.py").run()
    assert not at.exception, at.exception
    warned = [w.value for w in at.warning]
    assert any(w.startswith("Stopped early, as asked") and f"within {early.mip_gap:.2%} of the optimum" in w
               for w in warned), warned
    assert at.get("plotly_chart")  # the plan is drawn
    click(at, "results_solve")  # searches on
    assert [s.value for s in at.success][0].startswith("Optimal plan")
    solved = solving.solver().result(case_key(case))
    assert solved.status == "optimal"
    expected = paper_solve(strategy="balanced")
    assert solved.objective_eur == pytest.approx(expected.objective_eur,
                                                 abs=case.solver.rel_gap * abs(expected.objective_eur))


def test_the_sweep_grid_takes_every_whole_hour_of_periods():
    from dashboard.solving import sweep_grid

    assert sweep_grid(24, 1.0) == list(range(25))
    assert sweep_grid(23, 1.0) == list(range(24))  # the spring change of clocks
    assert sweep_grid(48, 0.5) == [0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30, 32, 34, 36, 38,
                                   40, 42, 44, 46, 48]
    assert sweep_grid(96, 0.25) == [4 * hours for hours in range(25)]
    assert sweep_grid(100, 0.25) == [4 * hours for hours in range(26)]  # the autumn change


def test_a_sweep_names_its_gammas_with_tied_deviations(paper_case):
    from dashboard.solving import Solver, shape, sweep_grid, tied_gammas

    # Half-hour periods interpolate the hourly forecast (MODEL_SPEC §6) instead of repeating it,
    # so no Γ splits a pair of equal half-hours on the bundled day (with repeated hours every odd
    # Γ from 1 to 47 did).
    half_hours = rvpp.with_options(paper_case, dt_h=0.5)
    assert tied_gammas(half_hours, range(49)) == {}
    # 6 April: the field of CSP1 deviates by its 300 MW_th in five hours, so Γ = 1 to 4 tie there.
    tie_day = rvpp.with_options(paper_case, date="2025-04-06")
    tied = tied_gammas(tie_day, range(25))
    assert sorted(tied) == [1, 2, 3, 4]
    assert tied[4] == ["CSP1: 4 of the 5 periods tied at a deviation of 300 MW_th"]
    assert tied_gammas(rvpp.with_options(tie_day, ties="earliest"), range(25)) == {}
    solver = Solver(workers=1)
    grid = list(range(25))
    assert solver.expected_s(tie_day, grid) is None  # nothing measured on this server yet
    solver.shape_seconds[shape(tie_day, grid)] = 40.0
    assert solver.expected_s(tie_day, grid) == (40.0, "the last sweep of a case like this one on this server")
    assert solver.expected_s(paper_case, grid) != (40.0, "the last sweep of a case like this one on this server")


def test_learn_names_the_tied_gammas_before_a_sweep(paper_case):
    from dashboard import solving

    solving.solver().sweeps.clear()  # cold, whichever test of this process swept before
    tie_day = rvpp.with_options(paper_case, date="2025-04-06")
    for case, warned in ((tie_day, True), (rvpp.with_options(tie_day, ties="earliest"), False), (paper_case, False)):
        at = open_app()
        at.session_state["case"] = case
        at.switch_page("pages/learn.py").run()
        assert not at.exception and "learn_sweep_gamma_24" not in [s.key for s in at.select_slider]
        said = " ".join(c.value for c in at.caption)
        assert ("At Γ = 1, 2, 3, 4 this day has deviations tied at the Γ boundary (CSP1)" in said) is warned, \
            case.budgets.ties


@pytest.mark.slow
def test_a_sweep_counts_its_plans_and_a_cancelled_one_stops_at_once(paper_case, paper_solve):
    from dashboard.solving import Solver, sweep_key

    solver = Solver(workers=1)
    slow = rvpp.with_options(paper_case, dt_h=0.25)
    grid = list(range(0, 97, 2))
    job = solver.start(slow, grid)
    wait_for(lambda: job.done_points and job.done_points[0] >= 1, TIMEOUT_S, every_s=0.05)
    assert job.done_points[1] == len(grid) and job.process.is_alive()
    _cancel_stops_at_once(solver, job)
    assert solver.sweep(job.key) is None
    quick = solver.start(paper_case, [0, 12, 24])
    assert quick.done.wait(TIMEOUT_S) and quick.done_points == (3, 3)
    points = solver.sweep(sweep_key(paper_case, [0, 12, 24]))
    for gamma, point in zip((0, 12, 24), points):
        expected = paper_solve(gammas={source: gamma for source in paper_case.sources()})
        assert dict(point.case.budgets.overrides) == {source: gamma for source in paper_case.sources()}
        assert point.objective_eur == pytest.approx(expected.objective_eur,
                                                    abs=1.0 + paper_case.solver.rel_gap * abs(expected.objective_eur))
    assert solver.expected_s(paper_case, [0, 12, 24])[1] == "the last sweep of this case"


def test_the_first_page_loads_neither_the_store_nor_the_workbook_nor_the_solver():
    """Home's first run in a fresh process imports no SQLAlchemy (run store), openpyxl (workbooks),
    SciPy's interpolation, Pyomo or HiGHS: each is loaded by the page that uses it, so a fresh
    server draws its first chart without paying for them (SQLAlchemy alone took 0.6 s)."""
    code = "\n".join([
        "import sys", "from streamlit.testing.v1 import AppTest",
        "at = AppTest.from_file('app.py', default_timeout=120).run()",
        "assert not at.exception, [e.value for e in at.exception]",
        "assert any('What should I bid tomorrow' in m.value for m in at.header), 'no Home'",
        "print(sorted(m for m in ('sqlalchemy', 'openpyxl', 'scipy.interpolate', 'pyomo', 'highspy') if m in sys.modules))",
        "from dashboard.serve import FIRST_PAGE",
        "print(sorted(m for m in FIRST_PAGE if m not in sys.modules))"])
    loaded_too_early, not_needed = fresh_process_output(code, timeout_s=300)[-2:]
    assert loaded_too_early == "[]"
    assert not_needed == "[]"  # `python -m dashboard` loads ahead only what the first page imports
