"""The studies: shared realizations, consistency of the settlement, Γ law, the reproduce command."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.cli import main
from rvpp.data.history import PRICE_COLUMNS
from rvpp.studies import findings, markets, out_of_sample, sensitivity, stochastic, stress
from rvpp.settle.recourse import FirstStage
from rvpp.solving.outcome import Outcome
from rvpp.studies.evaluation import evaluation_days, sample_days, settlement_warning, summarize, training_days
from rvpp.studies.report import write_all
from rvpp.studies.runner import StudyOutput, plan_table, solve_configs
from rvpp.studies.settings import StudySettings
from rvpp.uncertainty.bands import window_days

from tests.factories import demand, tiny_case, tiny_problem, wind

CASE_DIR = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
SETTINGS = StudySettings(strategies=("deterministic", "pessimistic"), test_days=3, scenario_counts=(1, 2),
                         sp_time_limit_s=120.0, gammas=(0, 4, 12))


@pytest.fixture(scope="module")
def case():
    return rvpp.load_case(CASE_DIR)


@pytest.fixture(scope="module")
def case4(case):
    return out_of_sample.run(case, SETTINGS), stochastic.run(case, SETTINGS)


def _raw_fingerprint(case, day: dt.date) -> str:
    """sha256 of the history's own values of ``day``, written independently of rvpp.settle.recourse."""
    rows = case.history.days(day, 1, case.timezone)
    sources = sorted(list(PRICE_COLUMNS) + case.unit_names())
    digest = hashlib.sha256(",".join(sources).encode())
    digest.update(np.ascontiguousarray(rows[sources].to_numpy(dtype=float)).tobytes())
    return digest.hexdigest()[:16]


def test_every_method_is_settled_on_the_same_realizations(case, case4):
    days = pd.concat([out.tables[name] for out, name in zip(case4, ("out_of_sample_days", "stochastic_days"))])
    assert set(days["method"]) == {"deterministic", "pessimistic", "SP N=1", "SP N=2"}
    expected = {d.isoformat(): _raw_fingerprint(case, d) for d in
                (case.delivery_date + dt.timedelta(days=k) for k in range(SETTINGS.test_days))}
    for method, part in days.groupby("method"):
        assert dict(zip(part["day"], part["fingerprint"])) == expected, method
    assert days["realization_set"].nunique() == 1
    summaries = pd.concat([out.tables[name] for out, name in zip(case4, ("table13_out_of_sample",
                                                                        "table14_stochastic"))])
    assert summaries["realization_set"].nunique() == 1 and (summaries["test_days"] == SETTINGS.test_days).all()


def test_settlements_add_up_and_averages_match_the_days(case4):
    for out, days_name, table_name in zip(case4, ("out_of_sample_days", "stochastic_days"),
                                          ("table13_out_of_sample", "table14_stochastic")):
        days, table = out.tables[days_name], out.tables[table_name].set_index("method")
        assert (days["status"] == "optimal").all()
        np.testing.assert_allclose(days["net_cost_eur"], days["market_cost_eur"] + days["penalty_eur"], rtol=1e-9)
        parts = days[["penalty_deficit_eur", "penalty_surplus_eur", "penalty_reserve_eur", "penalty_heat_eur"]]
        np.testing.assert_allclose(parts.sum(axis=1), days["penalty_eur"], rtol=1e-9, atol=1e-6)
        means = days.groupby("method")[["market_cost_eur", "penalty_eur", "net_cost_eur"]].mean() / 1000
        np.testing.assert_allclose(table.loc[means.index, "avg_net_cost_keur"], means["net_cost_eur"])
        np.testing.assert_allclose(table.loc[means.index, "avg_penalty_keur"], means["penalty_eur"])


def test_windows_are_disjoint_and_scenarios_come_from_training(case, case4):
    test = evaluation_days(case, 30)
    train = training_days(case)
    first, last = window_days(case.delivery_date, case.uncertainty.window_days)
    assert test[0] == case.delivery_date and not set(test) & set(train)
    assert all(first <= d <= last for d in train) and len(train) == case.uncertainty.window_days
    sp = case4[1].tables["table14_stochastic"]
    assert (sp["status"] == "optimal").all()
    for days in sp["scenario_days"]:
        assert {dt.date.fromisoformat(d) for d in days.split()} <= set(train)
    assert sample_days(train, 5, 7)[:2] == sample_days(train, 2, 7)  # nested samples


def test_clock_change_days_are_left_out_of_the_test_window(case):
    spring = case.replace(delivery_date=dt.date(2025, 3, 28))
    days = evaluation_days(spring, 5)
    assert dt.date(2025, 3, 30) not in days and len(days) == 5


def test_cost_never_falls_as_the_budget_grows(case):
    out = sensitivity.run(case, SETTINGS)
    table = out.tables["sensitivity"]
    assert list(table["gamma"]) == [0, 4, 12] and (table["status"] == "optimal").all()
    assert (table["audit_violations"] == 0).all()
    assert (np.diff(table["cost_keur"]) >= -1e-3).all()


@pytest.mark.slow
def test_reproduce_runs_end_to_end(tmp_path, monkeypatch):
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    monkeypatch.delenv("RVPP_BACKTEST_CASE", raising=False)
    out = tmp_path / "reproduce"
    png = shutil.which("chromium") is not None
    code = main(["study", "reproduce", "--out", str(out), "--scheduler", "serial",
                 "--strategies", "optimistic,pessimistic", "--market-sets", "DAM,DAM+SRM+HPA",
                 "--gammas", "0,6", "--hpa-prices", "60", "--test-days", "2", "--scenarios", "2",
                 "--sp-time-limit", "60", "--backtest-train", "2025-05-02:2025-05-02",
                 "--backtest-test", "2025-05-03:2025-05-03", "--backtest-fractions", "0", "--quiet"]
                + ([] if png else ["--no-png"]))
    assert code == 0
    info = json.loads((out / "run.json").read_text())
    assert set(info["studies"]) == {"case1", "strategies", "sensitivity", "markets", "out_of_sample", "stochastic",
                                    "backtest"}
    backtest = info["backtest"]
    assert backtest["records"] == 2 * 5 and backtest["reconcile_problems"] == 0 and backtest["audit_violations"] == 0
    assert backtest["recommended_fraction"] == 0.0 and backtest["verdict"].startswith("Recommended Γ = 0 ")
    assert (out / "tables" / "backtest_comparison.csv").is_file()
    assert (out / "figures" / "backtest_price_of_robustness.html").is_file()
    assert info["consistency"]["days_with_differing_realizations"] == 0
    assert len(info["consistency"]["realization_sets"]) == 1
    assert info["consistency"]["max_abs_net_minus_cost_plus_penalty_eur"] < 1e-6
    tables = out / "tables"
    for name in ("table10_markets", "table11_without_csp", "table12_hpa_price", "table13_out_of_sample",
                 "table14_stochastic", "flexibility", "sensitivity"):
        assert (tables / f"{name}.csv").is_file() and (tables / f"{name}.md").is_file()
    assert (out / "tables.xlsx").is_file()
    figures = sorted(p.stem for p in (out / "figures").glob("*.html"))
    assert {"case1_trades", "case1_heat", "case1_storage_CSP1", "sensitivity_trades", "out_of_sample_cost"} <= set(figures)
    if png:
        assert (out / "figures" / "sensitivity_trades.png").stat().st_size > 0
    assert list(pd.read_csv(tables / "table10_markets.csv").columns) == ["strategy", "DAM", "DAM+SRM+HPA"]
    # Each verdict of report.md agrees with the tables it quotes.
    verdicts = {f["claim"]: f["holds"] for f in info["findings"]}
    sens = pd.read_csv(tables / "sensitivity.csv")
    assert verdicts["Cost rises with the uncertainty budget Γ"] == bool((np.diff(sens["cost_keur"]) >= -1e-3).all())
    plans = pd.read_csv(tables / "strategies.csv").set_index("strategy")
    assert verdicts["More conservative strategies cost more"] == bool(
        plans.loc["pessimistic", "cost_keur"] >= plans.loc["optimistic", "cost_keur"] - 1e-3)
    oos = pd.read_csv(tables / "table13_out_of_sample.csv").set_index("method")
    sp = pd.read_csv(tables / "table14_stochastic.csv").set_index("method")
    ro_wins = "The best robust strategy has a lower out-of-sample net cost than the stochastic benchmark"
    assert verdicts[ro_wins] == bool(oos["avg_net_cost_keur"].min() < sp.loc["SP N=2", "avg_net_cost_keur"])
    markets = pd.read_csv(tables / "table10_markets.csv").set_index("strategy")
    assert verdicts["DAM+SRM+HPA is the cheapest market set for every strategy"] == bool(
        (markets["DAM+SRM+HPA"] <= markets["DAM"] + 1e-3).all())
    night_market = pd.read_csv(tables / "case1_market.csv")  # hourly periods: MW = MWh per period
    heat, tariff = night_market["h_hpa_mw"], night_market["tariff_hpa"]
    assert verdicts["HPA heat is bought in the night hours of the cheapest tariff"] == bool(
        heat.sum() > 0 and heat[tariff == tariff.min()].sum() >= 0.5 * heat.sum())
    hpa = pd.read_csv(tables / "table12_hpa_price.csv").set_index("strategy")
    cut = (hpa["time-of-use"] - hpa["60"]) / hpa["time-of-use"].abs()
    assert verdicts["A flat HPA tariff of 60 EUR/MWh_th lowers the cost by tens of percent (at least 10%) for "
                    "every strategy"] == bool((cut >= 0.10).all())
    assert "DAM+HPA costs less than DAM alone" not in verdicts  # no DAM+HPA column in this run
    report = (out / "report.md").read_text()
    assert "## Findings of the paper, checked on this run" in report
    assert "## Rolling backtest and the recommended Γ (beyond the paper)" in report
    assert "## Consistency of the backtest settlements" in report
    assert report.count("| yes |") + report.count("| no |") == len(info["findings"])


def test_out_of_sample_command_on_a_second_date(tmp_path):
    code = main(["study", "out-of-sample", "--date", "2025-05-06", "--out", str(tmp_path), "--scheduler", "serial",
                 "--strategies", "deterministic", "--test-days", "2", "--no-png", "--quiet"])
    assert code == 0
    assert json.loads((tmp_path / "run.json").read_text())["delivery_date"] == "2025-05-06"
    days = pd.read_csv(tmp_path / "tables" / "out_of_sample_days.csv")
    assert list(days["day"]) == ["2025-05-06", "2025-05-07"] and (days["status"] == "optimal").all()


def test_bad_study_options_end_with_a_message(tmp_path, capsys):
    assert main(["study", "sensitivity", "--gammas", "0,30", "--out", str(tmp_path), "--quiet",
                 "--scheduler", "serial"]) == 1
    assert "outside 0..24" in capsys.readouterr().err


@pytest.mark.parametrize(("changes", "message"), [
    ({"strategies": ()}, "strategies is empty"),
    ({"strategies": ("cautious",)}, "unknown strategy 'cautious'"),
    ({"gammas": (0, -2)}, "gammas: -2 must be a whole number >= 0"),
    ({"gammas": (1.5,)}, "gammas: 1.5 must be a whole number"),
    ({"market_sets": ("DAM+XYZ",)}, "market_sets: "),
    ({"hpa_flat_prices": (float("nan"),)}, "hpa_flat_prices: nan must be a number in [0, 1e+06]"),
    ({"hpa_flat_prices": (1e308,)}, "hpa_flat_prices: 1e+308 must be a number in [0, 1e+06] [EUR/MWh_th]"),
    ({"hpa_flat_prices": tuple(range(20_000))}, "hpa_flat_prices has 20000 values; a study takes at most 100"),
    ({"gammas": tuple(range(101))}, "gammas has 101 values; a study takes at most 100"),
    ({"test_days": 0}, "test_days=0 must be at least 1"),
    ({"test_days": 10**6}, "test_days=1000000 must be at most 366"),
    ({"scenario_counts": (5, 0)}, "scenario_counts: N=0 must be at least 1"),
    ({"scenario_counts": (5, 10**9)}, "scenario_counts: N=1e+09 must be at most 100"),
    ({"sp_time_limit_s": 0.0}, "sp_time_limit_s=0.0 must be a number > 0"),
    ({"threads": 0}, "threads=0 must be at least 1"),
])
def test_study_settings_name_the_broken_rule(changes, message):
    with pytest.raises(rvpp.RvppError, match="^study settings: ") as err:
        SETTINGS.with_changes(**changes)
    assert message in str(err.value)


def test_study_settings_report_every_broken_rule_at_once():
    with pytest.raises(rvpp.RvppError) as err:
        StudySettings(test_days=0, threads=0)
    assert "test_days=0" in str(err.value) and "threads=0" in str(err.value)


def test_sweep_choices_offer_every_kind_then_every_source(case):
    choices = sensitivity.sweep_choices(case)
    assert choices[:6] == ["wind", "pv", "csp", "ed", "td", "price"]
    assert choices[6:] == case.sources()
    groups = sensitivity.source_groups(case, ("price", "WF1"))
    assert groups == {"price": list(PRICE_COLUMNS), "WF1": ["WF1"]}


def test_stress_screening_matches_the_hand_computed_settlement(case):
    ed = case.ed[2].model_copy(update={"e_min_mwh": 0.0, "flex_up": 0.0, "flex_dn": 0.0})
    small = case.replace(wind=list(case.wind), pv=[], csp=[], ed=[ed], td=[], markets={"srm": False, "hpa": False},
                         budgets={"strategy": "optimistic", "overrides": {}})
    out = stress.run(small, StudySettings(strategies=("optimistic",)))
    table = out.tables["stress"].set_index("pattern")
    assert (table["status"] == "optimal").all()
    assert table.loc[stress.NOMINAL, "deviations"] == 0
    for periods in table.loc[stress.GREEDY, "periods"].split("; "):
        name, ts = periods.split(": ")
        assert len(ts.split(",")) <= 3  # Γ of the optimistic strategy for prices, wind farms and demands
    # Lost wind in one period: first the surplus over p_da goes (m_sur·λ), then a deficit (m_def·λ);
    # the wind farm saves its O&M on every MWh not produced.
    plan = rvpp.solve(small.replace(solver={"threads": 1}))
    problem, market = plan.problem, plan.market.set_index("t")
    src = {n: problem.sources[n] for n in ("WF1", "WF2", ed.name, "price_da")}
    screening = out.tables["stress_screening"]
    rows = screening[screening["source"] == "WF1"]
    assert len(rows) == int((src["WF1"].deviation > 0).sum())
    for row in rows.itertuples():
        i = row.t - 1
        surplus = src["WF1"].nominal[i] + src["WF2"].nominal[i] - src[ed.name].nominal[i] - market.loc[row.t, "p_da_mw"]
        lost, price = src["WF1"].deviation[i], src["price_da"].nominal[i]
        expected = (0.5 * price * min(surplus, lost) + 2.0 * price * max(0.0, lost - surplus)
                    - small.wind[0].om_eur_per_mwh * lost)
        assert row.impact_eur == pytest.approx(expected, rel=1e-6, abs=1e-6)


def _settlement(method, day, status, net, penalty=0.0):
    values = {"market_cost_eur": None if net is None else net - penalty, "penalty_eur": None if net is None else penalty,
              "net_cost_eur": net}
    return {"method": method, "day": day, "status": status, "realization_set": "abc", **values}


def test_summary_averages_only_optimal_settlements_and_counts_them():
    evaluations = pd.DataFrame([
        _settlement("A", "d1", Outcome.OPTIMAL, 1000.0, 100.0),
        _settlement("A", "d2", Outcome.TIME_LIMIT, 9e6, 9e5),  # usable numbers, but not optimal
        _settlement("A", "d3", Outcome.OPTIMAL, 3000.0, 300.0),
        _settlement("B", "d1", "no_solution", None),  # a plain value, as read back from a CSV
        _settlement("B", "d2", "optimal", 2000.0),
        _settlement("B", "d3", Outcome.ERROR, None),
    ])
    plans = pd.DataFrame({"method": ["A", "B", "C"], "status": [Outcome.OPTIMAL] * 2 + [Outcome.INFEASIBLE]})
    summary = summarize(evaluations, plans).set_index("method")
    assert summary.loc["A", "avg_net_cost_keur"] == pytest.approx(2.0)  # (1000 + 3000) / 2, not / 3
    assert summary.loc["A", "avg_penalty_keur"] == pytest.approx(0.2)
    assert summary.loc["A", "avg_market_cost_keur"] == pytest.approx(1.8)
    assert summary.loc["B", "avg_net_cost_keur"] == pytest.approx(2.0)
    assert list(summary["settlements_optimal"]) == ["2 / 3", "1 / 3", "no plan"]
    assert list(summary["test_days"].iloc[:2]) == [3, 3] and np.isnan(summary.loc["C", "avg_net_cost_keur"])
    warning = settlement_warning(evaluations)
    assert warning.startswith("3 of 6 settlements did not end optimal")
    assert "A: d2 time_limit" in warning and "B: d1 no_solution, d3 error" in warning
    assert settlement_warning(evaluations[evaluations["status"] == "optimal"]) is None


def test_a_failed_settlement_is_left_out_and_named_first_in_the_report(case, monkeypatch, tmp_path):
    from rvpp.studies import evaluation

    settle = evaluation.evaluate
    stopped_day = (case.delivery_date + dt.timedelta(days=1)).isoformat()

    def stopped_on_one_day(*args, **kwargs):
        record = settle(*args, **kwargs)
        if record["day"] == stopped_day:  # as if stopped on its time limit with a poor incumbent
            record.update(status=Outcome.TIME_LIMIT, net_cost_eur=record["net_cost_eur"] + 1e6)
        return record

    monkeypatch.setattr(evaluation, "evaluate", stopped_on_one_day)
    settings = SETTINGS.with_changes(strategies=("deterministic",), png=False)
    out = out_of_sample.run(case, settings)
    days = out.tables["out_of_sample_days"]
    summary = out.tables["table13_out_of_sample"].set_index("method")
    optimal = days[days["day"] != stopped_day]
    assert summary.loc["deterministic", "avg_net_cost_keur"] == pytest.approx(optimal["net_cost_eur"].mean() / 1000)
    assert summary.loc["deterministic", "settlements_optimal"] == "2 / 3"
    write_all([out], tmp_path, case, settings, {"scheduler": "serial"})
    report = (tmp_path / "report.md").read_text()
    section = report.split(f"## {out_of_sample.TITLE}\n\n", 1)[1]
    assert section.splitlines()[0] == (f"**Warning: 1 of 3 settlements did not end optimal and are left out of the "
                                       f"averages (deterministic: {stopped_day} time_limit).**")
    assert "| 2 / 3 |" in section.split("\n## ")[0]


# Γ [periods] per strategy at 1-hour periods (paper Table 7), written here for the check.
TABLE7 = {"deterministic": dict(price=0, wind=0, pv=0, csp=0, ed=0, td=0),
          "optimistic": dict(price=3, wind=3, pv=2, csp=2, ed=3, td=3),
          "balanced": dict(price=6, wind=6, pv=4, csp=4, ed=6, td=6),
          "pessimistic": dict(price=9, wind=9, pv=6, csp=6, ed=9, td=9)}


def budgets_named_by(label: str, case) -> dict[str, int]:
    """Γ per source that a row label claims: its strategy's Table 7 budgets, then its Γ edits."""
    strategy, markets, *rest = label.split(" · ")
    kinds = {unit.name: kind for kind, unit in case.units()}
    budgets = {name: TABLE7[strategy]["price"] for name in PRICE_COLUMNS}
    budgets.update({name: TABLE7[strategy][kind] for name, kind in kinds.items()
                    if not (kind == "csp" and "no CSP" in rest)})
    for part in rest:
        if part.startswith("Γ=") and part.endswith(" for every source"):
            budgets = dict.fromkeys(budgets, int(part[2:].split()[0]))
        elif part.startswith("Γ "):
            budgets.update({name: int(g) for name, g in (item.split("=") for item in part[2:].split(", "))})
    return budgets


@pytest.mark.slow
def test_every_study_row_is_labelled_with_the_budgets_it_solved(case):
    # A session's case with edited budgets: the strategy rows must not keep these edits.
    edited = case.replace(budgets={"strategy": "optimistic", "overrides": {"WF1": 12, "price_da": 5}})
    settings = StudySettings(strategies=("balanced",), market_sets=("DAM+SRM+HPA",),
                             market_sets_without_csp=("DAM+HPA",), hpa_flat_prices=(60.0,), gammas=(0, 6),
                             sources=("WF1", "price"))
    configs = markets.configurations(settings) + sensitivity.configurations(edited, settings)
    results = solve_configs(edited, configs, settings)
    rows = plan_table(configs, results)
    assert len(rows) == 8
    for row, result in zip(rows.itertuples(), results):
        assert result.status == "optimal", result.message
        assert budgets_named_by(row.variant, edited) == result.summary()["budgets"], row.variant
    strategy_rows = rows[rows["table"].notna()]
    assert len(strategy_rows) == 4 and not strategy_rows["variant"].str.contains("Γ").any()
    assert (strategy_rows["variant"].str.split(" · ").str[0] == strategy_rows["strategy"]).all()
    assert set(rows["variant"]) >= {"balanced · DAM+SRM+HPA", "balanced · DAM+HPA · no CSP",
                                    "balanced · DAM+SRM+HPA · HPA flat 60 EUR/MWh_th",
                                    "deterministic · DAM+SRM+HPA · Γ WF1=0", "deterministic · DAM+SRM+HPA · Γ WF1=6",
                                    "deterministic · DAM+SRM+HPA · Γ price_da=6, price_sr_dn=6, price_sr_up=6"}


def test_paper_mode_stress_ranks_prices_by_exposure_not_by_deviation():
    # DAM price deviations fall over the day (24 − t EUR/MWh down, 2·(24 − t) up), so
    # ranking by deviation alone would pick the first periods. The plan sells 1 MW in
    # periods 1-12 and 10 MW in 13-20, buys 5 MW in 21-24: the exposures λ_neg·p (selling)
    # and λ_pos·(−p) (buying) are largest in 13, 14, 15 (110, 100, 90 EUR); period 1 loses
    # 23 EUR and the buying periods at most 2·3·5 = 30 EUR.
    # The SR-up price deviates 9 EUR/MW in period 2 and 1 in period 7, where the band is 20 MW.
    t = np.arange(1, 25)
    down = 24.0 - t
    case = tiny_case([wind(om=0)], ed_units=[demand(p_max=100)], srm=True,
                     overrides={"price_da": 3, "price_sr_up": 1, "price_sr_dn": 2, "W": 2})
    wind_dev = np.where(t == 5, 4.0, np.where(t == 9, 3.0, 1.0))
    problem = tiny_problem(case, price_da=(50 - down, 50, 50 + 2 * down),
                           price_sr_up=(np.where(t == 2, 1.0, np.where(t == 7, 9.0, 10.0)), 10, 10),
                           W=(30 - wind_dev, 30, 30), D=(10, 10, 10))
    p_da = np.select([t <= 12, t <= 20], [1.0, 10.0], -5.0)
    r_up = np.where(t == 7, 20.0, 1.0)
    bids = FirstStage(p_da=p_da, r_sr_up=r_up, r_sr_dn=np.zeros(24), h_hpa=np.zeros(24))
    pattern = stress.paper_pattern(problem, bids)
    assert pattern["price_da"] == [13, 14, 15]  # deviations alone would give [1, 2, 3]
    assert pattern["price_sr_up"] == [7]  # 1 x 20 MW beats 9 x 1 MW in period 2
    assert "price_sr_dn" not in pattern  # no down band offered: nothing at stake
    assert pattern["W"] == [5, 9]  # availabilities: the largest deviations [MW]


TOU_TARIFF = [70.0] * 6 + [85.0] * 2 + [100.0] * 16  # EUR/MWh_th per hour; the night is the cheapest


def case1_output(heat_mw: list[float], dt_h: float = 1.0, hpa: bool = True) -> dict[str, StudyOutput]:
    """A Case 1 output around a stand-in plan: only what the heat finding reads."""
    n = len(heat_mw)
    market = pd.DataFrame({"h_hpa_mw": heat_mw, "tariff_hpa": np.repeat(TOU_TARIFF, round(1 / dt_h))[:n],
                           "clock": [f"{int(k * dt_h):02d}:{int(60 * (k * dt_h % 1)):02d}" for k in range(n)]})
    plan = SimpleNamespace(has_plan=True, market=market, problem=SimpleNamespace(dt_h=dt_h),
                           case=SimpleNamespace(markets=SimpleNamespace(hpa=hpa)))
    out = StudyOutput("case1", "")
    out.facts["result"] = plan
    return {"case1": out}


def markets_output(**facts: pd.DataFrame) -> dict[str, StudyOutput]:
    out = StudyOutput("markets", "")
    out.facts.update(facts)
    return {"markets": out}


def test_night_heat_finding_holds_when_most_heat_is_bought_at_the_cheapest_tariff():
    # 6 h x 30 MW at 70 EUR/MWh_th and 2 h x 20 MW at 85: 180 of 220 MWh_th (82 %) at night.
    found = findings.hpa_heat_bought_at_night(case1_output([30.0] * 6 + [20.0] * 2 + [0.0] * 16))
    assert found.holds
    assert "heat bought 220.0 MWh_th, of which 180.0 MWh_th (82%)" in found.evidence
    assert "in the periods at 70 EUR/MWh_th (00:00-05:00); periods with purchases: 00:00-07:00" in found.evidence


def test_night_heat_finding_fails_for_daytime_or_no_purchases():
    # 10 MW in hours 00-01 (20 MWh_th) against 25 MW in 18-20 (75 MWh_th): 21 % at night.
    daytime = findings.hpa_heat_bought_at_night(case1_output([10.0] * 2 + [0.0] * 16 + [25.0] * 3 + [0.0] * 3))
    assert not daytime.holds and "(21%)" in daytime.evidence
    assert daytime.evidence.endswith("periods with purchases: 00:00-01:00, 18:00-20:00")
    nothing = findings.hpa_heat_bought_at_night(case1_output([0.0] * 24))
    assert not nothing.holds and nothing.evidence.endswith("periods with purchases: none")
    assert findings.hpa_heat_bought_at_night(case1_output([0.0] * 24, hpa=False)) is None


def test_night_heat_finding_counts_energy_of_quarter_hours():
    # 96 quarter hours, the night tariff in the first 24: 6 x 40 MW x 0.25 h = 60 MWh_th in 00:00-01:15,
    # 10 x 8 MW x 0.25 h = 20 MWh_th in 06:30-08:45 (85 and 100 EUR/MWh_th): 75 % at night.
    found = findings.hpa_heat_bought_at_night(case1_output([40.0] * 6 + [0.0] * 20 + [8.0] * 10 + [0.0] * 60,
                                                           dt_h=0.25))
    assert found.holds and "heat bought 80.0 MWh_th, of which 60.0 MWh_th (75%)" in found.evidence
    assert found.evidence.endswith("(00:00-05:45); periods with purchases: 00:00-01:15, 06:30-08:45")


TABLE12 = pd.DataFrame({"time-of-use": [20.0, 50.0], "70": [19.0, 49.0], "60": [16.0, 48.0], "50": [12.0, 44.0]},
                       index=pd.Index(["deterministic", "balanced"], name="strategy"))


def test_flat_tariff_finding_needs_tens_of_percent_for_every_strategy():
    # 50 EUR/MWh_th: deterministic (20 - 12) / 20 = 40 %, balanced (50 - 44) / 50 = 12 %.
    found = findings.flat_hpa_tariff_cuts_cost(markets_output(hpa_price=TABLE12))
    assert found.holds and found.claim.startswith("A flat HPA tariff of 50 EUR/MWh_th")
    assert "deterministic: 70 5.0%, 60 20.0%, 50 40.0%; balanced: 70 2.0%, 60 4.0%, 50 12.0%" in found.evidence
    # Balanced at 50 EUR/MWh_th only 8 % cheaper: (50 - 46) / 50.
    weaker = findings.flat_hpa_tariff_cuts_cost(markets_output(hpa_price=TABLE12.assign(**{"50": [12.0, 46.0]})))
    assert not weaker.holds and "50 8.0%" in weaker.evidence
    # A strategy without a time-of-use plan cannot show the effect.
    missing = findings.flat_hpa_tariff_cuts_cost(markets_output(
        hpa_price=TABLE12.assign(**{"time-of-use": [20.0, np.nan]})))
    assert not missing.holds and "balanced: 70 n/a" in missing.evidence
    assert findings.flat_hpa_tariff_cuts_cost(markets_output(hpa_price=TABLE12[["time-of-use"]])) is None
    # 1 EUR dearer at 70 EUR/MWh_th on 20 kEUR (within the solver's gap) reads as 0.0 %, not -0.0 %.
    tie = findings.flat_hpa_tariff_cuts_cost(markets_output(hpa_price=TABLE12.assign(**{"70": [20.001, 49.0]})))
    assert "deterministic: 70 0.0%, 60 20.0%" in tie.evidence


TABLE10 = pd.DataFrame({"DAM": [10.0, 40.0], "DAM+HPA": [9.8, 40.0], "DAM+SRM": [8.0, 39.0],
                        "DAM+SRM+HPA": [7.9, 39.0]}, index=pd.Index(["deterministic", "pessimistic"], name="strategy"))


def test_hpa_finding_compares_dam_with_and_without_the_hpa():
    # Deterministic 0.2 kEUR (2.0 %) cheaper with the HPA, pessimistic equal (the paper's Table 10 pattern).
    found = findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10))
    assert found.holds
    assert found.evidence.endswith("deterministic 0.200 kEUR (2.00%), pessimistic 0.000 kEUR (0.00%)")
    equal = findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10.assign(**{"DAM+HPA": [10.0, 40.0]})))
    assert not equal.holds
    # 5 EUR on 10 kEUR (0.05 %) is within the solver's gap: a tie, not a saving.
    noise = findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10.assign(**{"DAM+HPA": [9.995, 40.0]})))
    assert not noise.holds and "deterministic 0.005 kEUR (0.05%)" in noise.evidence
    dearer = findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10.assign(**{"DAM+HPA": [9.8, 40.5]})))
    assert not dearer.holds and "pessimistic -0.500 kEUR (-1.25%)" in dearer.evidence
    # Without a DAM-only plan the comparison the paper makes is not possible.
    no_dam = findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10.assign(DAM=[np.nan, 40.0])))
    assert not no_dam.holds and "deterministic n/a (no DAM plan)" in no_dam.evidence
    assert findings.hpa_lowers_dam_cost(markets_output(markets=TABLE10.drop(columns="DAM+HPA"))) is None
