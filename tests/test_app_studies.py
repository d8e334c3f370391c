"""The study pages of the dashboard, driven through Streamlit's AppTest.

Each page runs its study in the dashboard's study processes; the numbers it shows are
checked against the same study run directly in this process, on a reduced setting.
"""

from __future__ import annotations

import json
import time

import numpy as np
import pandas as pd
import pytest
from streamlit.testing.v1 import AppTest

from rvpp.studies import STUDIES, StudySettings
from tests.test_app import TIMEOUT_S, click, errors, figures, open_app, values


def infos(at: AppTest) -> str:
    return "\n".join(i.value for i in at.info)


def numeric(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.select_dtypes("number").drop(columns=[c for c in frame if c.endswith("_s")], errors="ignore")


# ----------------------------------------------------------------------------- Sensitivity


@pytest.mark.slow
def test_sensitivity_page_matches_the_study_and_comes_back_without_a_click(paper_case, paper_solve):
    at = open_app("sensitivity")
    assert "press **Run**" in infos(at)
    assert not at.get("plotly_chart")

    at.text_input(key="sensitivity_gammas").input("0, 12, 24")
    click(at, "sensitivity_run")
    shown = at.dataframe[0].value
    expected = STUDIES["sensitivity"](paper_case, StudySettings(gammas=(0, 12, 24))).tables["sensitivity"]
    assert list(shown["gamma"]) == [0, 12, 24]
    assert list(shown["status"]) == ["optimal"] * 3
    pd.testing.assert_frame_equal(numeric(shown), numeric(expected), rtol=1e-6, atol=1e-6)
    # Γ = 0 everywhere is the deterministic plan, solved here on its own.
    assert shown["cost_keur"].iloc[0] == pytest.approx(-paper_solve(strategy="deterministic").objective_eur / 1000,
                                                       rel=1e-6)
    assert shown["cost_keur"].is_monotonic_increasing
    assert shown["audit_violations"].eq(0).all()
    # Money in kEUR with thousands separators; the profit (minus the cost) is not repeated in EUR.
    config = json.loads(at.dataframe[0].proto.columns)
    assert config["cost_keur"]["label"] == "Cost [kEUR]" and config["cost_keur"]["type_config"]["format"] == "%,.1f"
    assert config["profit_eur"] == {"hidden": True}

    spec = figures(at)["Sensitivity to the uncertainty budget: cost and traded energy"]
    cost = next(t for t in spec["data"] if t["name"].startswith("Cost"))
    np.testing.assert_allclose(values(cost["y"]), shown["cost_keur"], rtol=1e-9)
    assert spec["layout"]["xaxis"]["title"]["text"] == "Uncertainty budget Γ [periods]"
    assert "Reserve by unit kind against Γ (sources: all)" in figures(at)

    at.switch_page("pages/home.py").run()
    at.switch_page("pages/sensitivity.py").run()
    assert not at.exception, at.exception
    assert list(at.dataframe[0].value["cost_keur"]) == list(shown["cost_keur"])

    # A new grid is a new study (inputs of a form count once Run is pressed); the old one is kept.
    at.text_input(key="sensitivity_gammas").input("0, 24")
    click(at, "sensitivity_run")
    assert list(at.dataframe[0].value["gamma"]) == [0, 24]
    assert at.dataframe[0].value["cost_keur"].iloc[1] == pytest.approx(shown["cost_keur"].iloc[2], rel=1e-9)


def test_sensitivity_page_refuses_bad_settings_and_keeps_working():
    """Settings are checked before anything is solved; a refusal names the rule."""
    at = open_app("sensitivity")
    at.text_input(key="sensitivity_gammas").input("0, 99")
    click(at, "sensitivity_run")
    assert "Γ grid: 99 is outside 0..24" in errors(at)
    at.text_input(key="sensitivity_gammas").input("0, six")
    click(at, "sensitivity_run")
    assert "'six' is not a whole number" in errors(at)
    at.text_input(key="sensitivity_gammas").input("0, 6")
    at.radio(key="sensitivity_mode").set_value("Chosen sources one at a time")
    click(at, "sensitivity_run")
    assert "choose at least one source or kind" in errors(at)
    assert not at.exception


@pytest.mark.slow
def test_sensitivity_page_sweeps_one_source_at_a_time(paper_case):
    at = open_app("sensitivity")
    at.text_input(key="sensitivity_gammas").input("0, 8")
    at.radio(key="sensitivity_mode").set_value("Chosen sources one at a time")
    at.multiselect(key="sensitivity_sources").set_value(["price", "wind"])
    click(at, "sensitivity_run")
    shown = at.dataframe[0].value
    expected = STUDIES["sensitivity"](paper_case, StudySettings(gammas=(0, 8), sources=("price", "wind")))
    expected = expected.tables["sensitivity"]
    assert list(shown["sources"]) == ["price", "price", "wind", "wind"]
    pd.testing.assert_frame_equal(numeric(shown), numeric(expected), rtol=1e-6, atol=1e-6)
    # Γ = 0 is the same deterministic plan whichever source is swept.
    assert shown["cost_keur"].iloc[0] == pytest.approx(shown["cost_keur"].iloc[2], rel=1e-9)


# ----------------------------------------------------------------------------- Market sets


@pytest.mark.slow
def test_market_sets_page_matches_the_study(paper_case, paper_solve):
    at = open_app("market_sets")
    at.multiselect(key="market_sets_strategies").set_value(["deterministic", "pessimistic"])
    at.multiselect(key="market_sets_sets").set_value(["DAM", "DAM+SRM+HPA"])
    at.multiselect(key="market_sets_without_csp").set_value(["DAM+SRM+HPA"])
    at.text_input(key="market_sets_prices").input("50")
    click(at, "market_sets_run")

    settings = StudySettings(strategies=("deterministic", "pessimistic"), market_sets=("DAM", "DAM+SRM+HPA"),
                             market_sets_without_csp=("DAM+SRM+HPA",), hpa_flat_prices=(50.0,))
    expected = STUDIES["markets"](paper_case, settings).tables
    # The cost tables are shown as text ("1,234.5", "−3.2", "n/a" without a plan): read back as numbers here.
    shown = [d.value for d in at.dataframe[:3]]
    assert shown[0].loc["deterministic", "DAM"] == "n/a"  # no plan without the HPA (the grid drew "None")
    markets, without_csp, hpa = (frame.map(lambda text: float("nan") if text == "n/a" else
                                           float(text.replace(",", "").replace("−", "-"))) for frame in shown)
    shown_to = 0.05 + 1e-9  # shown to one decimal
    np.testing.assert_allclose(markets.to_numpy(float), expected["table10_markets"].to_numpy(float), atol=shown_to)
    np.testing.assert_allclose(without_csp.to_numpy(float), expected["table11_without_csp"].to_numpy(float),
                               atol=shown_to)
    np.testing.assert_allclose(hpa.to_numpy(float), expected["table12_hpa_price"].to_numpy(float), atol=shown_to)
    assert list(markets.columns) == ["DAM", "DAM+SRM+HPA"]
    assert list(hpa.columns) == ["time-of-use", "50"]
    # The full market set with the time-of-use tariff is the case's own pessimistic plan.
    assert markets.loc["pessimistic", "DAM+SRM+HPA"] == pytest.approx(
        -paper_solve(strategy="pessimistic").objective_eur / 1000, abs=shown_to)
    assert hpa["time-of-use"].tolist() == pytest.approx(markets["DAM+SRM+HPA"].tolist(), rel=1e-9)
    assert {"Cost by market set", "Cost without the CSP"} <= set(figures(at))
    plans = next(d for d in at.dataframe if "profit_eur" in d.value.columns)
    config = json.loads(plans.proto.columns)
    assert config["cost_keur"]["type_config"]["format"] == "%,.1f" and config["profit_eur"] == {"hidden": True}


def test_market_sets_page_refuses_a_negative_tariff_and_an_empty_strategy_list():
    at = open_app("market_sets")
    at.text_input(key="market_sets_prices").input("70, -5")
    click(at, "market_sets_run")
    assert "Flat HPA tariffs [EUR/MWh_th]: −5.0 must be a number in [0, 1e+06] [EUR/MWh_th]" in errors(at)
    at.text_input(key="market_sets_prices").input("70")
    at.multiselect(key="market_sets_strategies").set_value([])
    click(at, "market_sets_run")
    assert "Strategies is empty" in errors(at)
    assert not at.exception


# ----------------------------------------------------------------------------- Out-of-sample


@pytest.mark.slow
def test_out_of_sample_page_matches_the_studies_on_the_same_days(paper_case):
    at = open_app("out_of_sample")
    at.number_input(key="out_of_sample_test_days").set_value(2)
    at.text_input(key="out_of_sample_scenarios").input("1, 2")
    at.multiselect(key="out_of_sample_strategies").set_value(["deterministic", "balanced"])
    click(at, "out_of_sample_run")

    settings = StudySettings(strategies=("deterministic", "balanced"), test_days=2, scenario_counts=(1, 2),
                             sp_time_limit_s=60.0)
    robust = STUDIES["out-of-sample"](paper_case, settings).tables["table13_out_of_sample"]
    stochastic = STUDIES["stochastic"](paper_case, settings).tables["table14_stochastic"]
    used, table13, table14 = (d.value for d in at.dataframe[:3])
    assert list(used["methods"]) == [4, 4]  # two strategies and two stochastic programs on each day
    assert "settled on the same 2 days" in "\n".join(s.value for s in at.success)
    assert set(table13["realization_set"]) == set(table14["realization_set"]) == set(robust["realization_set"])
    for shown, expected in ((table13, robust), (table14, stochastic)):
        for column in ("avg_market_cost_keur", "avg_penalty_keur", "avg_net_cost_keur"):
            np.testing.assert_allclose(shown[column], expected[column], rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(shown["avg_net_cost_keur"],
                                   shown["avg_market_cost_keur"] + shown["avg_penalty_keur"], rtol=1e-9)
    assert list(table13["method"]) == ["deterministic", "balanced"]
    assert list(table14["n_scenarios"]) == [1, 2]
    assert {"Out-of-sample: average cost per test day", "Net cost on each test day",
            "Solve time of the first-stage plan", "Penalty per test day by cause"} <= set(figures(at))
    # The causes add up to each method's average penalty (Table 13), on linear axes.
    causes = figures(at)["Penalty per test day by cause"]
    assert [t["name"] for t in causes["data"]] == ["Energy short of the DAM bid", "Energy beyond the DAM bid",
                                                   "Reserve not delivered", "Heat not served"]
    total = sum(values(t["y"]) for t in causes["data"])
    np.testing.assert_allclose(total[:2], table13["avg_penalty_keur"], rtol=1e-6, atol=1e-9)
    assert figures(at)["Solve time of the first-stage plan"]["layout"]["yaxis"].get("type") != "log"
    method = next(m.value for m in at.markdown if m.value.startswith("**How it works.**"))
    assert all(word in method for word in ("m_def", "m_sur", "m_sr", "same days for every method"))


def test_out_of_sample_page_refuses_empty_scenario_counts():
    at = open_app("out_of_sample")
    at.text_input(key="out_of_sample_scenarios").input(" ")
    click(at, "out_of_sample_run")
    assert "give at least one" in errors(at)
    at.text_input(key="out_of_sample_scenarios").input("0")
    click(at, "out_of_sample_run")
    assert "Scenario counts N: N = 0 must be at least 1" in errors(at)
    assert not at.exception


# ----------------------------------------------------------------------------- the study processes


def test_a_cancelled_study_stops_after_its_solve_and_is_started_afresh(paper_case):
    """Cancel reaches the study process through its progress callback; the next ask runs it anew."""
    from dashboard import studies
    from dashboard.state import case_key

    settings = StudySettings(gammas=tuple(range(25)))
    key = studies.study_key("sensitivity", case_key(paper_case), settings)
    job = studies.jobs().get_or_start(key, "sensitivity", paper_case, settings)
    deadline = time.monotonic() + TIMEOUT_S
    while job.done < 1 and time.monotonic() < deadline:  # one plan solved: the study is under way
        time.sleep(0.1)
        job.poll()
    assert job.total == 25 and job.done >= 1
    studies.jobs().cancel([job.key])
    with pytest.raises(studies.StudyCancelled):
        job.future.result(timeout=TIMEOUT_S)
    job.poll()
    assert job.done < job.total
    assert not job.usable
    again = studies.jobs().get_or_start(key, "sensitivity", paper_case, settings)
    assert again is not job and not again.cancel.is_set()
    studies.jobs().cancel([again.key])
