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
    assert kpis.loc["deterministic", "Profit [EUR]"] == results["deterministic"].objective_eur
    assert kpis.loc["balanced", "Protection [EUR]"] == pytest.approx(sum(results["balanced"].protection_eur.values()))


def test_kpi_table_prices_safety_against_a_baseline(paper_solve):
    results = {s: paper_solve(strategy=s) for s in ("deterministic", "pessimistic")}
    table = kpi_table(results, baseline="deterministic")
    base = results["deterministic"].cost_keur
    extra = results["pessimistic"].cost_keur - base
    assert table.loc["pessimistic", "Extra cost vs deterministic [kEUR]"] == pytest.approx(extra)
    assert table.loc["pessimistic", "Extra cost vs deterministic [%]"] == pytest.approx(100 * extra / abs(base))
    assert table.loc["deterministic", "Extra cost vs deterministic [kEUR]"] == 0
