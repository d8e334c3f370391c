"""The Backtest page and the recommended Γ on Results and Compare, driven through Streamlit's AppTest.

A small backtest (three days of the paper case: deterministic, Γ 0.25 of the day and the
perfect-information plan) is computed once into a store file; each test works on its own
copy. The page's numbers are checked against sums computed here with plain pandas from the
store's records, never through ``rvpp.backtest.metrics``.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import re
import shutil
import sys
import time

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.backtest import BacktestSettings, variants_of
from rvpp.backtest.engine import run_backtest
from rvpp.backtest.launch import status, stop
from rvpp.store import BacktestStore
from rvpp.studies import STUDIES, StudySettings
from tests.factories import click, one_day_backtest_form, open_app
from tests.test_app import NET, TIMEOUT_S, case_of, figures, number, shown_kpis, trace, values

FIRST, LAST = dt.date(2025, 5, 2), dt.date(2025, 5, 4)
FRACTION = 0.25
RECOMMENDED = f"recommended (Γ = {FRACTION:g} of the day)"
STORE_FILE = "rvpp.sqlite3"


@pytest.fixture(scope="module")
def recorded(paper_case, tmp_path_factory):
    """A data folder holding one finished backtest; returns (folder, backtest id)."""
    folder = tmp_path_factory.mktemp("backtest") / "rvpp-data"
    folder.mkdir()
    store = BacktestStore(f"sqlite:///{folder / STORE_FILE}")
    settings = BacktestSettings(FIRST, LAST, variants_of(["deterministic"], [FRACTION]))
    ident = run_backtest(paper_case, settings, store, label="three May days")
    store.engine.dispose()  # the last connection closes: the WAL is folded into the file
    return folder, ident


pytestmark = pytest.mark.usefixtures("data_dir")  # every test writes into a data folder of its own


@pytest.fixture
def stored(recorded, data_dir):
    """This test's copy of the recorded backtest's store: (store, backtest id)."""
    folder, ident = recorded
    shutil.copytree(folder, data_dir)
    return BacktestStore(f"sqlite:///{data_dir / STORE_FILE}"), ident


def settled_records(store: BacktestStore, ident: str) -> pd.DataFrame:
    records = store.records(ident)
    assert (records["status"] == "optimal").all()
    return records.assign(day=pd.to_datetime(records["day"]).dt.date).sort_values("day")


def test_the_page_without_a_backtest_says_how_to_start_one():
    at = open_app("backtest")
    assert "No backtest in the store yet" in "\n".join(i.value for i in at.info)
    assert not at.get("plotly_chart")
    assert at.date_input(key="backtest_first").value <= at.date_input(key="backtest_last").value


def aggregates_shown(at) -> pd.DataFrame:
    """The per-strategy aggregates as one table: the page draws them in three of a few columns each (after
    the first table, which lists the backtests), one row per strategy in each."""
    parts = [d.value.set_index("label") for d in at.dataframe[1:4]]
    assert all(list(part.index) == list(parts[0].index) for part in parts)
    return pd.concat(parts, axis=1)


@pytest.mark.slow
def test_the_figures_and_tables_are_the_stored_records(stored):
    store, ident = stored
    records = settled_records(store, ident)
    at = open_app("backtest")
    specs = figures(at)
    cumulative = specs["Cumulative net cost of the settled days"]
    boxes = specs["Daily net cost per strategy (box: quartiles and median; points: days)"]
    perfect = records[records["strategy"] == "perfect"].set_index("day")["net_cost_eur"]
    table = aggregates_shown(at)
    for label, part in records.groupby("label"):
        net = part["net_cost_eur"].to_numpy()
        np.testing.assert_allclose(values(trace(cumulative, label)["y"]), np.cumsum(net) / 1000)  # kEUR
        np.testing.assert_allclose(values(trace(boxes, label)["y"]), net / 1000)
        row = table.loc[label]
        assert row["mean_net_cost_keur"] == pytest.approx(net.mean() / 1000)
        assert row["cvar95_net_cost_keur"] == pytest.approx(net.max() / 1000)  # under 20 days: the worst day
        assert row["mean_regret_keur"] == pytest.approx(
            (part.set_index("day")["net_cost_eur"] - perfect).mean() / 1000, abs=1e-9)
    assert at.dataframe[0].value["Days × strategies"].tolist() == ["9 of 9"]


@pytest.mark.slow
def test_the_money_axes_write_kEUR_with_thousands_separators(stored):
    # Plotly's default wrote a cumulative cost as "2M" or "2k", where the tables beside them write the
    # amount with thousands separators.
    at = open_app("backtest")
    specs = figures(at)
    money = ["Cumulative net cost of the settled days",
             "Daily net cost per strategy (box: quartiles and median; points: days)"]
    for title in money:
        axis = specs[title]["layout"]["yaxis"]
        assert (axis.get("exponentformat"), axis.get("separatethousands")) == ("none", True), title


@pytest.mark.slow
def test_opening_a_worst_day_makes_its_plan_the_current_result(stored):
    store, ident = stored
    records = settled_records(store, ident)
    at = open_app("backtest")
    at.selectbox(key="backtest_worst_variant").set_value("Γ 0.25 of the day").run()
    part = records[records["label"] == "Γ 0.25 of the day"]
    worst = part.loc[part["net_cost_eur"].idxmax()]
    assert at.selectbox(key="backtest_worst_day").value == str(worst["day"])
    click(at, "backtest_open_day")
    assert at.title[0].value == "Results"
    case = case_of(at)
    assert case.delivery_date == worst["day"] and case.budgets.fraction == FRACTION
    assert case.csp[0].storage.e_init_mwh_th == worst["start_state"]["CSP1"]["e_mwh_th"]
    net, help_text = shown_kpis(at)[NET]
    assert number(net) == pytest.approx(-worst["plan_objective_eur"] / 1000, abs=0.051)
    assert number(help_text.split("Exact: ")[1]) == pytest.approx(-worst["plan_objective_eur"], abs=0.51)


@pytest.mark.slow
def test_the_price_of_robustness_is_drawn_and_its_recommendation_remembered(stored, monkeypatch):
    store, ident = stored
    records = settled_records(store, ident)
    at = open_app("backtest")
    train = at.date_input(key=f"backtest_train_{ident}").value
    assert tuple(train) == (FIRST, FIRST + dt.timedelta(days=1))  # two thirds of three days
    curve = figures(at)["Price of robustness (train period): mean daily cost against Γ"]
    net = trace(curve, "net cost")
    by_fraction = {0.0: "deterministic", FRACTION: "Γ 0.25 of the day"}
    expected = [records[(records["label"] == by_fraction[f]) & (records["day"] <= train[1])]["net_cost_eur"].mean()
                for f in sorted(by_fraction)]
    np.testing.assert_allclose(values(net["x"]), sorted(by_fraction))
    np.testing.assert_allclose(values(net["y"]), np.asarray(expected) / 1000)  # kEUR/day
    best = sorted(by_fraction)[int(np.argmin(expected))]
    assert values(trace(curve, "recommended")["x"]).tolist() == [best]
    assert "backtest_remember" not in [b.key for b in at.button]  # two training days: too few to remember
    # With the minimum evidence lowered to one day each, a training day on which Γ 0.25 beats the
    # deterministic preset (the only preset of this backtest) offers it to remember.
    evidence = sys.modules["rvpp.backtest.recommend"]  # the module (the package's `recommend` is a function)
    monkeypatch.setattr(evidence, "MIN_TRAIN_DAYS", 1)
    monkeypatch.setattr(evidence, "MIN_TEST_DAYS", 1)
    day = FIRST + dt.timedelta(days=1)
    on_day = records[records["day"] == day].set_index("label")["net_cost_eur"]
    assert on_day["Γ 0.25 of the day"] < on_day["deterministic"]
    at.date_input(key=f"backtest_train_{ident}").set_value((day, day))
    at.date_input(key=f"backtest_test_{ident}").set_value((LAST, LAST)).run()
    assert store.recommendation() is None
    click(at, "backtest_remember")
    remembered = store.recommendation()
    assert remembered.fraction == FRACTION and remembered.backtest_id == ident
    assert (remembered.train, remembered.test) == ((str(day), str(day)), (str(LAST), str(LAST)))


def test_periods_the_recommendation_cannot_use_are_refused_in_the_page_words(stored):
    _store, ident = stored
    at = open_app("backtest")
    at.date_input(key=f"backtest_test_{ident}").set_value((FIRST, LAST)).run()
    message = "\n".join(e.value for e in at.error)
    assert "No recommendation" in message and "**Test days** must start after **Training days** ends" in message


@pytest.mark.slow
def test_the_recommended_strategy_is_offered_only_once_remembered_and_solves_with_its_gamma(stored, paper_case):
    store, ident = stored
    at = open_app("results")
    assert not at.radio and "No recommended Γ yet" in "\n".join(c.value for c in at.caption)
    store.remember_recommendation(ident, FRACTION, "mean", (FIRST, FIRST), (LAST, LAST), "a verdict")
    at.run()
    at.radio(key="results_bid").set_value("recommended").run()
    click(at, "results_solve")
    from dashboard.solving import solver
    solved = [r for r in solver().results.values() if r.case.budgets.fraction == FRACTION
              and r.case.delivery_date == paper_case.delivery_date]
    assert solved and solved[-1].status == "optimal"
    result = solved[-1]
    nt = result.problem.nt
    assert set(result.problem.budgets.values()) == {math.floor(FRACTION * nt + 0.5)}  # 6 of 24 hours
    assert number(shown_kpis(at)[NET][0]) == pytest.approx(-result.objective_eur / 1000, abs=0.051)

    at.switch_page("pages/compare.py").run()
    click(at, "compare_solve")
    cost = at.dataframe[0].value
    assert list(cost.index) == ["Deterministic", "Optimistic", "Balanced", "Pessimistic", RECOMMENDED]
    assert cost.loc[RECOMMENDED, "DAM+SRM+HPA"] == pytest.approx(result.cost_keur)
    assert cost.loc["Balanced", "DAM+SRM+HPA"] == pytest.approx(rvpp.solve(paper_case).cost_keur)


@pytest.mark.slow
def test_a_backtest_started_on_the_page_runs_in_its_own_process(data_dir):
    at = one_day_backtest_form(open_app("backtest"), LAST, "one day")
    click(at, "backtest_start")
    assert not at.error and "Started in the background" in at.info[0].value
    store = BacktestStore(f"sqlite:///{data_dir / STORE_FILE}")
    deadline = time.monotonic() + TIMEOUT_S
    while not (listed := store.list()):
        assert time.monotonic() < deadline, "the backtest's process never opened it in the store"
        time.sleep(0.5)
    assert [(b.label, b.keys_total) for b in listed] == [("one day", 1)]
    ident = listed[0].id
    try:
        while (progress := status(ident, store)) is None or progress.running:
            assert time.monotonic() < deadline, "the backtest did not finish"
            time.sleep(0.5)
        assert progress.state == "finished" and progress.done == progress.total == 1
        assert progress.pid != os.getpid()  # written by another process
        at.run()
        assert at.dataframe[0].value["State"].tolist() == ["finished"]
        assert len(store.records(ident)) == 1
    finally:
        stop(ident, store)


def test_starting_a_backtest_the_store_already_holds_says_so_and_keeps_its_label(stored):
    """The same case, days and strategies give the same backtest: starting it again computes nothing
    and the page says which stored backtest it is, not "Started" under a label that never shows."""
    store, ident = stored
    at = one_day_backtest_form(open_app("backtest"), FIRST, "again")
    at.date_input(key="backtest_last").set_value(LAST)
    at.text_input(key="backtest_fractions").input(f"{FRACTION}")
    at.checkbox(key="backtest_perfect").check()  # as recorded: deterministic, Γ 0.25 and perfect information
    click(at, "backtest_start")
    try:
        assert not at.error, [e.value for e in at.error]
        notice = at.info[0].value
        assert "Started in the background" not in notice, notice
        assert "already holds this backtest" in notice and "“three May days”" in notice, notice
        assert "all 9 days × strategies settled: nothing is computed again" in notice, notice
        assert "It keeps that label." in notice, notice
        assert [(b.id, b.label) for b in store.list()] == [(ident, "three May days")]
    finally:
        deadline = time.monotonic() + TIMEOUT_S
        while (progress := status(ident, store)) is not None and progress.running:
            assert time.monotonic() < deadline, "the backtest's process did not end"
            time.sleep(0.5)


# ----------------------------------------------------------------------------- money in kEUR

KEUR_UNITS = ("[kEUR]", "[kEUR/day]")
MONEY_HEADER = re.compile(r"cost|penalty|regret|CVaR|revenue|protection|profit", re.I)


def money_columns(at) -> dict[str, dict]:
    """Every money column of every table on the page: shown header -> its column settings."""
    found = {}
    for frame in at.dataframe:
        config = json.loads(frame.proto.columns or "{}")
        for column in frame.value.columns:
            settings = config.get(str(column)) or {}
            header = settings.get("label") or str(column)
            if MONEY_HEADER.search(header) and not header.endswith("[%]"):
                found[header] = settings
    return found


def assert_money_in_keur(at, page: str) -> None:
    """Every money header and card of ``page`` in kEUR (per day where a mean), with thousands separators."""
    columns = money_columns(at)
    assert columns, page
    for header, settings in columns.items():
        assert header.endswith(KEUR_UNITS), (page, header)
        assert settings.get("type_config", {}).get("format") == "%,.1f", (page, header)
    for card in at.metric:
        if MONEY_HEADER.search(card.label):
            assert card.label.endswith(KEUR_UNITS), (page, card.label)
    for title, spec in figures(at).items():
        axis = spec["layout"]["yaxis"]
        if "EUR" in axis.get("title", {}).get("text", ""):
            assert axis["title"]["text"].endswith(KEUR_UNITS), (page, title)
            assert axis.get("separatethousands") is True, (page, title)
        for t in spec["data"]:
            hover = t.get("hovertemplate", "")
            if re.search(r"(?<![k/])EUR(?!/MWh)", hover) or "kEUR" in hover:
                assert re.search(r"%\{y:,\.1f\} kEUR", hover), (page, title, hover)


@pytest.mark.slow
def test_backtest_and_out_of_sample_show_every_amount_in_kEUR(stored, paper_case, data_dir):
    # The Backtest page wrote "Mean net cost [EUR/day]" 58,469 where Results writes the same day's net cost
    # as 58.5 kEUR.
    from tests.test_trading_day import store_with, trading_record

    store, ident = stored
    records = settled_records(store, ident)
    at = open_app("backtest")
    assert_money_in_keur(at, "backtest")
    headers = money_columns(at)
    assert {"Mean net cost [kEUR/day]", "Total net cost [kEUR]", "Test: mean net cost [kEUR/day]"} <= set(headers)
    aggregates = aggregates_shown(at)
    deterministic = records[records["label"] == "deterministic"]["net_cost_eur"]
    assert aggregates.loc["deterministic", "total_net_cost_keur"] == pytest.approx(deterministic.sum() / 1000)
    comparison = next(d.value for d in at.dataframe if "test_mean_net_cost_keur" in d.value.columns).set_index("variant")
    on_last = records[(records["day"] == LAST)].set_index("label")["net_cost_eur"]  # the test days: LAST alone
    assert comparison.loc["deterministic", "test_mean_net_cost_keur"] == pytest.approx(on_last["deterministic"] / 1000)
    verdict = "\n".join(m.value for m in [*at.success, *at.warning] if m.value.startswith("Recommended Γ"))
    assert "kEUR" in verdict and not re.search(r"(?<!k)EUR", verdict), verdict
    chosen = "Γ 0.25 of the day" if "recommended: Γ 0.25 of the day" in comparison.index else "deterministic"
    assert f"is {on_last[chosen] / 1000:,.1f} kEUR" in verdict
    worst_days = at.selectbox(key="backtest_worst_day").options
    assert worst_days and all(option.endswith(" kEUR") for option in worst_days), worst_days

    # A backtest traded in intraday sessions draws the trading day's cards and sessions.
    record = trading_record()
    traded = store_with(paper_case, data_dir, [record])
    at.run()
    at.selectbox(key="backtest_chosen").set_value(traded).run()
    assert not at.exception, at.exception
    assert_money_in_keur(at, "backtest, trading day")
    cards = {m.label: m for m in at.metric}
    assert number(cards["Net cost [kEUR]"].value) == pytest.approx(record["net_cost_eur"] / 1000, abs=0.051)
    assert number(cards["Penalty [kEUR]"].value) == pytest.approx(record["penalty_eur"] / 1000, abs=0.051)
    sessions = next(d.value for d in at.dataframe if "Session" in d.value.columns)
    revenue = [s["trading_revenue_eur"] for s in record["intraday"]]
    np.testing.assert_allclose(sessions["Trading cost [kEUR]"], -np.asarray(revenue) / 1000)

    at.switch_page("pages/out_of_sample.py").run()
    at.number_input(key="out_of_sample_test_days").set_value(2)
    at.text_input(key="out_of_sample_scenarios").input("1")
    at.multiselect(key="out_of_sample_strategies").set_value(["deterministic"])
    click(at, "out_of_sample_run")
    assert_money_in_keur(at, "out_of_sample")
    assert {"Avg net cost [kEUR/day]", "Avg penalty [kEUR/day]"} <= set(money_columns(at))
    settings = StudySettings(strategies=("deterministic",), test_days=2, scenario_counts=(1,), sp_time_limit_s=60.0)
    days = STUDIES["out-of-sample"](paper_case, settings).tables["out_of_sample_days"]
    assert (days["status"].astype(str) == "optimal").all()
    table13 = next(d.value for d in at.dataframe if "method" in d.value.columns and "n_scenarios" not in d.value)
    shown = table13.set_index("method").loc["deterministic", "avg_net_cost_keur"]
    assert shown == pytest.approx(days.loc[days["method"] == "deterministic", "net_cost_eur"].mean() / 1000)
