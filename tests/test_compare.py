"""Comparison tables hold each plan's own numbers in the paper's layouts."""

from __future__ import annotations

import numpy as np
import pytest

from rvpp.outputs.compare import MARKET_SETS, cost_table, flexibility_table, kpi_table


def test_cost_table_has_the_layout_of_table_10(paper_solve):
    results = {(s, m): paper_solve(strategy=s, markets=m.replace("+", ","))
               for s in ("deterministic", "balanced") for m in ("DAM+HPA", "DAM+SRM+HPA")}
    table = cost_table(results)
    assert list(table.index) == ["Deterministic", "Balanced"]
    assert list(table.columns) == ["DAM+HPA", "DAM+SRM+HPA"]
    assert set(table.columns) <= set(MARKET_SETS)
    for (strategy, market_set), result in results.items():
        assert result.status == "optimal"
        assert table.loc[strategy.capitalize(), market_set] == pytest.approx(-result.objective_eur / 1000)
    # More markets never cost more: the smaller market set is a restriction of the larger one.
    assert (table["DAM+SRM+HPA"] <= table["DAM+HPA"] + 1e-6).all()


def test_cost_table_puts_a_strategy_other_than_the_presets_after_them(paper_solve):
    results = {("recommended (Γ = 0.25 of the day)", "DAM+SRM+HPA"): paper_solve(gamma_fraction=0.25),
               ("balanced", "DAM+SRM+HPA"): paper_solve(strategy="balanced")}
    table = cost_table(results)
    assert list(table.index) == ["Balanced", "recommended (Γ = 0.25 of the day)"]
    for (strategy, _), result in results.items():
        assert result.status == "optimal"
        row = "Balanced" if strategy == "balanced" else strategy
        assert table.loc[row, "DAM+SRM+HPA"] == pytest.approx(-result.objective_eur / 1000)


def test_flexibility_and_kpi_tables(paper_solve):
    results = {"balanced": paper_solve(), "deterministic": paper_solve(strategy="deterministic")}
    flex = flexibility_table(results)
    assert flex.index.names == ["Strategy", "Unit"]
    balanced = flex.loc["Balanced"]
    assert list(balanced.index) == ["WFs", "PVs", "CSP", "EDs"]
    expected = results["balanced"].flexibility
    np.testing.assert_allclose(balanced["Upward reserve [MWh]"], expected["r_up_mwh"])
    np.testing.assert_allclose(balanced["Downward reserve to capacity [h]"], expected["r_dn_h"])
    kpis = kpi_table(results)
    assert kpis.loc["deterministic", "Net cost [kEUR]"] == pytest.approx(-results["deterministic"].objective_eur / 1000)
    assert kpis.loc["balanced", "Robust protection [kEUR]"] == pytest.approx(
        sum(results["balanced"].protection_eur.values()) / 1000)
    assert "Profit [EUR]" not in kpis and "Cost [kEUR]" not in kpis  # one number for the objective


def test_kpi_table_prices_safety_against_a_baseline(cyclic_solve):
    results = {s: cyclic_solve(strategy=s) for s in ("deterministic", "pessimistic")}
    table = kpi_table(results, baseline="deterministic")
    base = results["deterministic"]
    extra = results["pessimistic"].cost_keur - base.cost_keur
    assert table.loc["pessimistic", "Extra cost vs deterministic [kEUR]"] == pytest.approx(extra)
    assert table.loc["deterministic", "Extra cost vs deterministic [kEUR]"] == 0
    # The deterministic plan's net result is a few kEUR against about 160 kEUR of money flows:
    # under 5 %, so no percentage is shown.
    gross = sum(abs(v) for v in base.parts.values())
    assert abs(base.objective_eur) < 0.05 * gross
    assert "Extra cost vs deterministic [%]" not in table


def test_kpi_table_gives_a_percentage_against_a_large_enough_base(paper_solve):
    results = {s: paper_solve(strategy=s) for s in ("balanced", "pessimistic")}
    base = results["balanced"]
    assert abs(base.objective_eur) >= 0.05 * (sum(abs(v) for v in base.parts.values())
                                              + sum(base.protection_eur.values()))
    table = kpi_table(results, baseline="balanced")
    extra = results["pessimistic"].cost_keur - base.cost_keur
    assert table.loc["pessimistic", "Extra cost vs balanced [%]"] == pytest.approx(
        100 * extra / abs(base.cost_keur))
