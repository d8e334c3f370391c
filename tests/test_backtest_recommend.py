"""The recommended Γ: chosen on the training days only, reported honestly against the presets."""

from __future__ import annotations

import datetime as dt

import pandas as pd
import pytest

from rvpp import prepare, with_options
from rvpp.backtest import BacktestError, recommendation_from
from rvpp.backtest.figures import cumulative_figure, distribution_figure, robustness_figure
from rvpp.backtest.recommend import verdict_words
from rvpp.outputs.money import IN_KEUR

TRAIN = (dt.date(2025, 3, 1), dt.date(2025, 3, 4))
TEST = (dt.date(2025, 3, 5), dt.date(2025, 3, 6))
DAYS = [dt.date(2025, 3, d).isoformat() for d in range(1, 7)]


def records(costs: dict[tuple[str, str], list[float]]) -> pd.DataFrame:
    """Records whose net cost per day is given (market cost = net, no penalty) per (strategy, gamma)."""
    rows = []
    for (strategy, gamma), values in costs.items():
        for day, net in zip(DAYS, values):
            rows.append({"day": day, "strategy": strategy, "gamma": gamma, "label": strategy, "status": "optimal",
                         "plan_status": "optimal", "market_cost_eur": net - 1.0, "penalty_eur": 1.0,
                         "net_cost_eur": net, "penalty_deficit_eur": 1.0, "penalty_surplus_eur": 0.0,
                         "penalty_reserve_eur": 0.0, "penalty_heat_eur": 0.0, "audit_violations": 0})
    return pd.DataFrame(rows)


BASE = {
    ("deterministic", "preset"): [100, 100, 100, 100, 90, 90],
    ("optimistic", "preset"): [95, 95, 95, 95, 95, 95],
    ("balanced", "preset"): [80, 80, 80, 80, 70, 70],
    ("pessimistic", "preset"): [85, 85, 85, 85, 85, 85],
    ("fraction", "0.25"): [70, 70, 70, 90, 60, 60],     # train mean 75, CVaR 90
    ("fraction", "0.5"): [78, 78, 78, 78, 75, 75],      # train mean 78, CVaR 78
    ("perfect", "preset"): [50, 50, 50, 50, 50, 50],
}


def test_the_fraction_with_the_lowest_training_mean_is_recommended_and_judged_on_the_test_days():
    result = recommendation_from(records(BASE), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    assert result.fraction == 0.25
    curve = result.curve.set_index(["fraction", "period"])
    assert curve.loc[(0.0, "train"), "mean_net_cost_eur"] == 100.0  # the fraction 0 is the deterministic plan
    assert curve.loc[(0.25, "train"), "mean_net_cost_eur"] == 75.0
    assert curve.loc[(0.25, "test"), "mean_net_cost_eur"] == 60.0
    assert curve.loc[(0.5, "train"), "mean_penalty_eur"] == 1.0
    comparison = result.comparison.set_index("variant")
    assert comparison.loc["recommended: Γ 0.25 of the day", "test_mean_net_cost_eur"] == 60.0
    assert comparison.loc["balanced", "test_mean_net_cost_eur_minus_recommended"] == 10.0
    assert comparison.loc["perfect information", "test_mean_net_cost_eur"] == 50.0
    assert "no preset does better" in result.verdict and "balanced" in result.verdict
    assert result.variant.fraction == 0.25


def test_the_cvar_criterion_can_choose_another_fraction():
    result = recommendation_from(records(BASE), TRAIN, TEST, [0.0, 0.25, 0.5], "cvar95")
    assert result.fraction == 0.5  # worst training day 78 against 90
    assert "CVaR 95 %" in result.verdict


def test_a_recommendation_that_loses_to_a_preset_on_the_test_days_says_so():
    costs = {**BASE, ("fraction", "0.25"): [70, 70, 70, 90, 75, 75]}  # train 75, test 75 > balanced 70
    result = recommendation_from(records(costs), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    assert result.fraction == 0.25
    assert "LOSES to balanced (70 EUR)" in result.verdict and "did not carry over" in result.verdict


def test_days_of_the_test_period_never_enter_the_choice():
    # Make the 0.5 fraction unbeatable on the test days only: the choice must not move.
    costs = {**BASE, ("fraction", "0.5"): [78, 78, 78, 78, 0, 0]}
    assert recommendation_from(records(costs), TRAIN, TEST, [0.0, 0.25, 0.5], "mean").fraction == 0.25


def test_overlapping_periods_are_refused():
    with pytest.raises(BacktestError, match="--test must start after --train ends"):
        recommendation_from(records(BASE), TRAIN, (dt.date(2025, 3, 4), dt.date(2025, 3, 6)), [0.25], "mean")


def test_the_price_of_robustness_figure_marks_the_recommendation():
    result = recommendation_from(records(BASE), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    figure = robustness_figure(result.curve, result.fraction)
    names = [trace.name for trace in figure.data]
    assert names == ["market cost", "penalty", "net cost", "recommended"]
    assert list(figure.data[3].x) == [0.25] and list(figure.data[3].y) == [75.0]
    assert list(figure.data[2].y) == [100.0, 75.0, 78.0]
    assert figure.layout.yaxis.title.text == "cost [EUR/day]"  # what exports and the command line draw


def test_the_dashboard_draws_the_backtest_figures_in_kEUR():
    costs = {key: [1000.0 * v for v in values] for key, values in BASE.items()}  # 100,000 EUR a day and so on
    result = recommendation_from(records(costs), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    figure = robustness_figure(result.curve, result.fraction, "train", IN_KEUR)
    assert list(figure.data[2].y) == [100.0, 75.0, 78.0] and list(figure.data[3].y) == [75.0]
    assert figure.layout.yaxis.title.text == "cost [kEUR/day]"
    assert all("%{y:,.1f} kEUR/day" in trace.hovertemplate for trace in figure.data)
    deterministic = records(costs).query("strategy == 'deterministic'")
    cumulative = cumulative_figure(deterministic, IN_KEUR)
    assert list(cumulative.data[0].y) == [100.0, 200.0, 300.0, 400.0, 490.0, 580.0]
    assert cumulative.layout.yaxis.title.text == "cumulative net cost [kEUR]"
    boxes = distribution_figure(deterministic, IN_KEUR)
    assert list(boxes.data[0].y) == [100.0, 100.0, 100.0, 100.0, 90.0, 90.0]
    assert boxes.layout.yaxis.title.text == "daily net cost [kEUR/day]"
    assert "%{y:,.1f} kEUR" in boxes.data[0].hovertemplate


def test_the_verdict_is_kept_in_EUR_and_shown_in_kEUR():
    costs = {key: [1000.0 * v for v in values] for key, values in BASE.items()}
    costs[("fraction", "0.25")] = [70_000, 70_000, 70_000, 90_000, 75_000, 75_000]  # loses to balanced, 70,000
    result = recommendation_from(records(costs), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    assert "its mean daily net cost is 75,000 EUR" in result.verdict  # stored with the backtest and exported
    assert "LOSES to balanced (70,000 EUR)" in result.verdict
    shown = verdict_words(result, IN_KEUR)
    assert "its mean daily net cost is 75.0 kEUR" in shown and "LOSES to balanced (70.0 kEUR)" in shown
    assert shown.replace("75.0 kEUR", "75,000 EUR").replace("70.0 kEUR", "70,000 EUR") == result.verdict


def test_the_recommended_fraction_is_usable_in_a_solve(paper_case):
    result = recommendation_from(records(BASE), TRAIN, TEST, [0.0, 0.25, 0.5], "mean")
    case = with_options(paper_case, gamma_fraction=result.fraction)
    assert set(prepare(case).budgets.values()) == {6}


@pytest.mark.slow
def test_the_command_line_recommends_and_exports_the_curve(tmp_path):
    import json
    import os
    import subprocess
    import sys

    from tests.factories import ROOT

    out = tmp_path / "recommend"
    done = subprocess.run([sys.executable, "-m", "rvpp", "backtest", "recommend", "--train", "2025-05-02:2025-05-03",
                           "--test", "2025-05-04:2025-05-04", "--fractions", "0,0.25", "--criterion", "cvar95",
                           "--store", f"sqlite:///{tmp_path / 's.sqlite3'}", "--out", str(out), "--quiet",
                           "--workers", "2"], cwd=ROOT, capture_output=True, text=True, timeout=1200,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stderr
    assert "Recommended Γ = " in done.stdout
    curve = pd.read_csv(out / "curve.csv")
    assert sorted(curve["fraction"].unique()) == [0.0, 0.25] and set(curve["period"]) == {"train", "test"}
    comparison = pd.read_csv(out / "comparison.csv")
    assert list(comparison["variant"])[1:] == ["deterministic", "optimistic", "balanced", "pessimistic",
                                              "perfect information"]
    manifest = json.loads((out / "manifest.json").read_text())
    chosen = manifest["recommendation"]["fraction"]
    train = curve[curve["period"] == "train"].set_index("fraction")["cvar95_net_cost_eur"]
    assert chosen == train.idxmin()
    records = pd.read_csv(out / "records.csv")
    assert len(records) == 3 * 6  # 3 days x (4 presets + the 0.25 fraction + perfect information)
    assert (records["status"] == "optimal").all() and (records["audit_violations"] == 0).all()
    fraction = records[records["strategy"] == "fraction"]
    assert set(fraction[[c for c in records.columns if c.startswith("gamma_")]].stack()) == {6}
