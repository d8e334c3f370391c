"""The dashboard as a newcomer meets it, through Streamlit's AppTest: the bids on screen, one
money convention on every page, edits confirmed, estimates measured here, recommendations
with their evidence, a refused upload named in file order.

Expected numbers come from ``rvpp.solve`` of the same case in this process (or the store's
records), converted here by hand: a cost is minus the objective.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import rvpp
from rvpp.backtest import BacktestSettings, variants_of
from rvpp.backtest.engine import run_backtest
from rvpp.store import BacktestStore, RunLibrary
from tests.factories import APP, click, one_day_backtest_form, open_app, shown_table, wait_for
from tests.test_app import NET, TIMEOUT_S, case_of, edit_capacity, errors, figures, number, shown_kpis

pytestmark = pytest.mark.usefixtures("run_library")  # every test writes into a data folder of its own

MONEY_WORDS = re.compile(r"cost|revenue|protection|penalty|regret|price|tariff|result|profit|EUR", re.I)
STORE_FILE = "rvpp.sqlite3"


def headers(at) -> list[str]:
    """Every column header of every table drawn, as the page shows it (the label its column
    settings give, else the column's name; a table's index names too)."""
    found = []
    for frame in at.dataframe:
        value = frame.value
        config = json.loads(frame.proto.columns or "{}")
        shown = {name: settings.get("label") for name, settings in config.items() if settings.get("label")}
        found += [shown.get(str(c), str(c)) for c in value.columns] + [str(n) for n in value.index.names if n]
    for table in at.table:  # text tables: their headers as shown, without the markdown escapes
        found += [str(c) for c in shown_table(table).columns]
    return found


def money_labels(at) -> list[str]:
    return [label for label in [m.label for m in at.metric] + headers(at) if MONEY_WORDS.search(label)]


# ----------------------------------------------------------------------------- bids


@pytest.mark.parametrize("page, button", [(None, "home_solve"), ("results", "results_solve")])
def test_home_and_results_show_the_bids_as_a_table(page, button, paper_solve):
    at = click(open_app(page), button)
    expected = paper_solve().market
    table = next(f.value for f in at.dataframe if "DAM [MW]" in f.value.columns)
    assert list(table.columns) == ["Period", "DAM [MW]", "Up [MW]", "Down [MW]", "HPA [MW_th]", "DAM [EUR/MWh]",
                                   "Up [EUR/MW]", "Down [EUR/MW]", "HPA [EUR/MWh_th]"]
    assert list(table["Period"]) == [f"{hour:02d}:00" for hour in range(24)]
    np.testing.assert_allclose(table["DAM [MW]"], expected["p_da_mw"])
    np.testing.assert_allclose(table["Down [MW]"], expected["r_sr_dn_mw"])
    np.testing.assert_allclose(table["HPA [MW_th]"], expected["h_hpa_mw"])
    np.testing.assert_allclose(table["DAM [EUR/MWh]"], expected["price_da_mid"])
    downloads = [d for d in at.get("download_button") if d.proto.label == "Bids as shown (CSV)"]
    assert len(downloads) == 1


# ----------------------------------------------------------------------------- one money convention


def test_every_page_speaks_of_money_one_way(paper_solve):
    """Cards and table headers on every page: a net is a net cost (never a net result or profit),
    every money label names its unit, and the net cost card is minus the objective."""
    expected = paper_solve()
    at = click(open_app(), "home_solve")
    seen = {"Home": money_labels(at)}
    net = shown_kpis(at)[NET]
    assert number(net[0]) == pytest.approx(-expected.objective_eur / 1000, abs=0.051) and number(net[0]) > 0
    for page, button in (("results", "results_solve"), ("compare", "compare_solve"), ("portfolio", None),
                         ("markets", None), ("uncertainty", None), ("runs", None), ("sensitivity", None),
                         ("market_sets", None), ("out_of_sample", None), ("backtest", None), ("learn", None)):
        at.switch_page(f"pages/{page}.py").run()
        assert not at.exception, (page, at.exception)
        if button:
            click(at, button)
        if page == "results":
            click(at, "results_save")
        if page == "learn":
            click(at, "learn_modes")
        seen[page] = money_labels(at)
    at.switch_page("pages/runs.py").run()
    seen["runs"] = money_labels(at)
    for page, labels in seen.items():
        for label in labels:
            assert not re.search(r"net result|profit", label, re.I), (page, label)
            if not re.search(r"price|tariff", label, re.I) or "[" in label:
                assert re.search(r"\[(k?EUR(/day)?|EUR/[\w ]+|%)\]", label), (page, label)
    assert "Net cost [kEUR]" in seen["runs"] and "Net cost [kEUR]" in seen["compare"]
    assert "Net cost, planner-chosen [kEUR]" in seen["learn"]


def test_the_compare_cost_table_is_the_net_cost(paper_solve):
    at = click(open_app("compare"), "compare_solve")
    cost = at.dataframe[0].value
    assert cost.loc["Balanced", "DAM+SRM+HPA"] == pytest.approx(-paper_solve().objective_eur / 1000)
    kpis = shown_table(at.table[0])
    extra = kpis["Extra cost vs deterministic [kEUR]"]
    assert extra["deterministic"] == 0 and (extra.drop("deterministic") > 0).all()  # safer costs more


def test_the_reserve_chart_says_when_a_plan_offers_no_up_reserve(paper_solve):
    assert not paper_solve().market["r_sr_up_mw"].any()  # the default day offers none
    at = click(open_app("results"), "results_solve")
    layout = figures(at)["Reserve by unit kind"]["layout"]
    # Both up panels say so: the day's total beside the periods was an empty frame from 0 to 1.
    said = {(a["xref"], a["yref"]): a["text"] for a in layout.get("annotations", [])}
    assert said == {("x domain", "y domain"): "No up reserve in this plan", ("x2 domain", "y2 domain"): "0 MWh"}
    assert list(layout["yaxis"]["range"]) == list(layout["yaxis2"]["range"]) == [0, 1]


def test_an_amount_that_rounds_to_zero_shows_no_minus(paper_case, paper_solve):
    # Compare's Γ slider at 12 showed "DAM revenue [kEUR] −0.0" for a plan that sells almost nothing (it
    # buys 23 EUR): a minus that reads as a loss the cards cannot show.
    from dashboard.widgets import kpis

    result = paper_solve(gammas={source: 12 for source in paper_case.sources()})
    assert -50 < result.parts["revenue_dam_eur"] < 0  # this plan's DAM revenue rounds to 0.0 kEUR from below
    value, help_text = kpis(result)["DAM revenue [kEUR]"]
    assert value == "0.0"
    assert f"Exact: {-round(-result.parts['revenue_dam_eur'])} EUR".replace("-", "−") in help_text


# ----------------------------------------------------------------------------- Learn


def test_learn_reaches_every_source_and_states_the_variants_difference_in_kEUR(paper_case):
    at = open_app("learn")
    assert not at.get("button_group")  # no pill rows to clip
    sources = at.selectbox(key="learn_source")
    wanted = [u.name for _, u in paper_case.units()]
    assert set(sources.options) <= set(wanted) and "CSP1" in sources.options and "PV3" in sources.options
    assert len(at.selectbox(key="learn_price").options) == 3
    click(at, "learn_modes")
    cards = {m.label: m for m in at.metric}
    paper, chosen = cards["Net cost, paper mode [kEUR]"], cards["Net cost, planner-chosen [kEUR]"]
    difference = number(chosen.value) - number(paper.value)
    assert chosen.proto.delta.endswith("kEUR vs paper mode")
    assert number(chosen.proto.delta) == pytest.approx(difference, abs=0.11)
    from streamlit.proto.Metric_pb2 import Metric

    assert chosen.proto.color == Metric.MetricColor.GRAY  # neutral: a lower cost here is less protection


# ----------------------------------------------------------------------------- edits


def test_an_accepted_edit_is_confirmed_and_results_says_what_changed(paper_case, paper_solve):
    at = click(open_app("results"), "results_solve")
    assert not [i for i in at.info if "What changed" in i.value]  # nothing changed yet
    at.switch_page("pages/portfolio.py").run()
    at.session_state["portfolio_pv_0"] = {"edited_rows": {0: {"p_max_mw": 20.0}}, "added_rows": [],
                                          "deleted_rows": []}
    at.run()
    assert not errors(at)
    said = "\n".join(s.value for s in at.success)
    assert "Edit accepted" in said and "PV1 20 MW \\(was 50 MW\\)" in said
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    before = -paper_solve().objective_eur / 1000
    after = -rvpp.solve(case_of(at)).objective_eur / 1000
    changed = next(i.value for i in at.info if "What changed" in i.value)
    assert f"net cost {before:,.1f} → {after:,.1f} kEUR" in changed
    assert "PV1 20 MW \\(was 50 MW\\)" in changed


def test_what_changed_writes_a_fall_in_cost_with_a_true_minus(paper_solve):
    # The cards write −13.4; the line saying what changed wrote "-13.4 kEUR" with a hyphen.
    at = click(open_app("results"), "results_solve")
    at.switch_page("pages/portfolio.py").run()
    edit_capacity(at, 0, 80.0)  # more wind: the plant pays less
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    before = -paper_solve().objective_eur / 1000
    after = -rvpp.solve(case_of(at)).objective_eur / 1000
    assert after < before - 1
    changed = next(i.value for i in at.info if "What changed" in i.value)
    fall = f"{before - after:,.1f}"
    assert f"net cost {before:,.1f} → {after:,.1f} kEUR (−{fall} kEUR)" in changed
    assert not re.search(r"-\d", changed), changed


def test_a_solve_without_a_plan_says_why_in_words_and_names_the_time_limit(paper_case):
    # Results said "No plan: no_solution. time limit reached before any feasible plan was found": the solver's
    # status code, and no word of which limit or where it is set.
    at = open_app("results")
    at.session_state["case"] = rvpp.with_options(paper_case, dt_h=0.25, strategy="pessimistic").replace(
        solver={"time_limit_s": 0.001})
    said = click(at.run(), "results_solve").error[0].value
    assert "no_solution" not in said and "the limit is 0.001 s per solve" in said, said
    assert "solver.time_limit_s" in said
    at.session_state["case"] = paper_case.replace(markets={"hpa": False})
    said = click(at.run(), "results_solve").error[0].value
    assert said.startswith("**No plan.** No feasible plan: heat balance short"), said
    assert "infeasible." not in said


# ----------------------------------------------------------------------------- estimates


def test_estimates_are_measured_on_this_server_never_read_from_a_file(paper_case):
    from dashboard.solving import Solver

    solver = Solver(workers=1)
    assert solver.expected_s(paper_case) is None and solver.expected_s(paper_case, range(25)) is None
    solver.last_solve = (2.0, 24)  # a solve of 2 s on a day of 24 hourly periods
    quarter = rvpp.with_options(paper_case, dt_h=0.25, strategy="pessimistic")
    assert solver.expected_s(quarter) == (8.0, "the last solve on this server of 24 periods, scaled to 96")
    assert solver.expected_s(paper_case, list(range(25))) == (50.0, "25 plans × the last solve on this server")
    at = open_app()
    said = " ".join(c.value for c in at.caption) + " ".join(m.value for m in at.markdown)
    assert "benchmarks" not in said and ".json" not in said


def test_a_solve_that_waited_for_a_free_solver_does_not_count_the_wait_as_its_time(paper_case):
    # Compare's four plans share two solvers: the last one's time counted its wait for a slot, and the
    # sweep button then promised "about 222 s" for a sweep that took 32 s.
    from dashboard.solving import Solver

    solver = Solver(workers=1)
    solver.slots.acquire()  # another solve holds the only slot
    job = solver.start(paper_case)
    time.sleep(3.0)
    freed = time.perf_counter()
    solver.slots.release()
    assert job.done.wait(TIMEOUT_S) and job.result.status == "optimal"
    own = job.finished - freed  # the most it can have taken once it had the slot
    assert job.elapsed_s > own + 2.9  # the page did wait that long
    assert solver.seconds[job.key] <= own and solver.last_solve[0] <= own
    assert solver.expected_s(paper_case)[0] <= own


def test_study_pages_give_no_time_this_server_has_not_measured(monkeypatch, paper_case):
    # Backtest said "about a second" per day and strategy, Out-of-sample "about two minutes", whatever this
    # machine measured.
    from dashboard import solving

    solver = solving.Solver(workers=1)
    monkeypatch.setattr(solving, "solver", lambda: solver)
    for page in ("backtest", "out_of_sample"):
        said = " ".join(c.value for c in open_app(page).caption)
        assert not re.search(r"\bminutes?\b|\bhour\b|a second", said), (page, said)
    solver.last_solve = (2.0, 24)  # a solve of 2 s on a day of 24 hourly periods, measured here
    said = " ".join(c.value for c in open_app("backtest").caption)
    assert "two solves of about 2.0 s each (the last solve on this server)" in said


# ----------------------------------------------------------------------------- upload order


def test_an_upload_is_refused_for_its_first_problem_in_file_order():
    at = open_app()
    at.file_uploader(key="home_upload").set_value([("case.yaml", b"units: 5\n", "text/yaml")]).run()
    click(at, "home_load_upload")
    problems = [line for line in errors(at).splitlines() if line.startswith("- ")]
    assert problems[0].startswith("- units"), problems
    assert any("history" in p for p in problems[1:])


def test_an_upload_with_a_bad_history_cell_is_refused_for_the_case_files_problems_first(paper_case):
    # A non-numeric cell of the history was the only problem named: κ = 1.5 and a P max of "fifty" above it
    # in case.yaml showed only once the history was mended and the files uploaded again.
    folder = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
    settings = (folder / "case.yaml").read_text()
    assert settings.count("kappa: 0.3") == 1 and "{name: WF2, p_max_mw: 50," in settings
    settings = settings.replace("kappa: 0.3", "kappa: 1.5").replace("{name: WF2, p_max_mw: 50,", "{name: WF2, p_max_mw: fifty,")
    lines = (folder / "history.csv").read_text().splitlines()
    header, row = lines[0].split(","), lines[5].split(",")
    row[header.index("price_sr_up")] = "abc"
    history = "\n".join([*lines[:5], ",".join(row), *lines[6:]]) + "\n"
    at = open_app()
    at.file_uploader(key="home_upload").set_value([("case.yaml", settings.encode(), "text/yaml"),
                                                   ("history.csv", history.encode(), "text/csv")]).run()
    click(at, "home_load_upload")
    problems = [line for line in errors(at).splitlines() if line.startswith("- ")]
    assert len(problems) == 3, problems
    assert problems[0].startswith("- κ") and "1.5" in problems[0], problems
    assert "P max" in problems[1] and "fifty" in problems[1], problems
    assert problems[2].startswith('- history.csv: column "price_sr_up" has a non-numeric value \'abc\''), problems
    assert case_of(at).markets.kappa == paper_case.markets.kappa  # the current case is unchanged


# ----------------------------------------------------------------------------- a restart


def warnings_of(at) -> str:
    return "\n".join(w.value for w in at.warning)


def test_a_tab_whose_case_the_server_lost_says_so():
    # A tab edits its case (its address then says it holds a case of its own, own_case=1; tests/test_browser.py
    # restarts a server under such a tab); the tab's new session showed the shipped case as if nothing happened.
    assert not open_app().warning  # a new tab without a case of its own: nothing to say
    from streamlit.testing.v1 import AppTest

    restarted = AppTest.from_file(APP, default_timeout=TIMEOUT_S)
    restarted.query_params["own_case"] = "1"  # the tab's address, its session gone
    restarted.run()
    assert not restarted.exception, restarted.exception
    assert case_of(restarted).dt_h == 1.0 and case_of(restarted).name == "paper"
    assert "This tab's case (loaded, opened or edited here) is gone" in warnings_of(restarted)
    assert "own_case" not in restarted.query_params  # the shipped case is not the tab's own


# ----------------------------------------------------------------------------- wording


def test_saved_runs_says_how_many_to_tick_in_words(paper_solve):
    library = RunLibrary(f"sqlite:///{Path(os.environ['RVPP_DATA_DIR']) / STORE_FILE}")
    library.save("one", paper_solve().case, paper_solve(), settings={"csp": True})
    at = open_app("runs")
    said = " ".join(c.value for c in at.caption)
    assert "tick two, three or 4 to compare" in said and "two to 4" not in said


def test_uncertainty_says_where_prices_and_units_deviate_without_contradicting_itself():
    # It said prices deviate "where the plan loses most", then "Neither searches the hours that hurt the profit most".
    said = " ".join(c.value for c in open_app("uncertainty").caption)
    assert "Neither searches" not in said
    assert ("Prices deviate in the periods where that costs the plan's trades most (found exactly); units deviate "
            "in their periods of largest deviation in MW (paper mode), which need not be the periods that cost the "
            "plan most.") in said


# ----------------------------------------------------------------------------- recommendations


FIRST, LAST = dt.date(2025, 5, 2), dt.date(2025, 5, 4)


@pytest.fixture(scope="module")
def three_days(paper_case, tmp_path_factory):
    """A data folder holding a finished three-day backtest of the deterministic plan and Γ 0.25."""
    folder = tmp_path_factory.mktemp("newcomer") / "rvpp-data"
    folder.mkdir()
    store = BacktestStore(f"sqlite:///{folder / STORE_FILE}")
    ident = run_backtest(paper_case, BacktestSettings(FIRST, LAST, variants_of(["deterministic"], [0.25])), store,
                         label="three May days")
    records = store.records(ident)
    store.engine.dispose()
    return folder, ident, records


def copy_store(three_days, data_dir: Path) -> str:
    folder, ident, _ = three_days
    shutil.copytree(folder, data_dir, dirs_exist_ok=True)
    return ident


@pytest.mark.slow
def test_a_recommendation_from_three_days_warns_and_offers_nothing_to_remember(three_days, data_dir):
    copy_store(three_days, data_dir)
    at = open_app("backtest")
    warned = "\n".join(w.value for w in at.warning)
    assert "Small sample" in warned
    assert "2 settled training days, fewer than the 14" in warned and "1 settled test day, fewer than the 7" in warned
    assert "backtest_remember" not in [b.key for b in at.button]


@pytest.mark.slow
def test_remember_is_not_offered_when_the_recommendation_does_not_beat_the_presets_on_training(three_days, data_dir,
                                                                                        monkeypatch):
    copy_store(three_days, data_dir)
    _, _, records = three_days
    evidence = sys.modules["rvpp.backtest.recommend"]  # the module (the package's `recommend` is a function)
    monkeypatch.setattr(evidence, "MIN_TRAIN_DAYS", 1)
    monkeypatch.setattr(evidence, "MIN_TEST_DAYS", 1)
    at = open_app("backtest")
    assert not [w for w in at.warning if "Small sample" in w.value]
    # By hand: mean daily net cost on the two training days of Γ 0.25 against the deterministic preset.
    train = records[records["day"].astype(str) <= str(FIRST + dt.timedelta(days=1))]
    mean = train.groupby("label")["net_cost_eur"].mean()
    assert mean["deterministic"] <= mean["Γ 0.25 of the day"]  # the recommendation is Γ = 0, the preset itself
    assert "backtest_remember" not in [b.key for b in at.button]
    assert any("does not beat every preset" in i.value for i in at.info)


# ----------------------------------------------------------------------------- a backtest's process


@pytest.mark.slow
def test_a_finished_backtest_leaves_no_zombie_process(data_dir):
    at = one_day_backtest_form(open_app("backtest"), LAST, "one day")
    click(at, "backtest_start")
    pid = int(re.search(r"process (\d+)", at.info[0].value).group(1))
    store = BacktestStore(f"sqlite:///{data_dir / STORE_FILE}")
    wait_for(lambda: store.list() and store.progress(store.list()[0].id) is not None
             and not store.progress(store.list()[0].id).running, TIMEOUT_S)
    # Reaped once it ended: gone from the process table, not left as a zombie until the server exits.
    wait_for(lambda: not Path(f"/proc/{pid}").exists(), TIMEOUT_S, every_s=0.2)
    time.sleep(0.1)
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)
