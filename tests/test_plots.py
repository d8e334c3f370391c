"""Figures carry the plan's own numbers, units on every axis and clock-hour x axes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.outputs import plots
from rvpp.settle.audit import price_exposures
from rvpp.uncertainty.problem import top_gamma_deviation


@pytest.fixture(scope="module")
def case(paper_case):
    return paper_case


@pytest.fixture(scope="module")
def result(paper_solve):
    solved = paper_solve()
    assert solved.status == "optimal"
    return solved


def traces(fig, name):
    found = [t for t in fig.data if t.name == name]
    assert found, f"no trace named {name!r} in {[t.name for t in fig.data]}"
    return found[0]


def assert_readable(fig, labels):
    """Every trace is named and hoverable; axes have units; x shows the delivery day's clock."""
    layout = fig.layout
    assert layout.paper_bgcolor == plots.TRANSPARENT and layout.plot_bgcolor == plots.TRANSPARENT
    for trace in fig.data:
        assert trace.name, "a trace without a legend name"
        assert trace.hovertemplate, f"trace {trace.name!r} has no hover value"
    names = layout.to_plotly_json()
    y_titles = [layout[k].title.text for k in names if k.startswith("yaxis")]
    assert y_titles and all(t and "[" in t for t in y_titles), y_titles
    x_axes = [layout[k] for k in names if k.startswith("xaxis")]
    assert any(ax.title.text == plots.CLOCK_TITLE for ax in x_axes)
    clock = [ax for ax in x_axes if ax.type == "category"]
    assert clock and all(list(ax.categoryarray) == list(labels) for ax in clock)


def test_trades_figure_draws_the_bids(result):
    fig = plots.trades_figure(result)
    market = result.market
    assert_readable(fig, result.problem.labels)
    dam = traces(fig, "DAM energy (+ sell, − buy)")
    np.testing.assert_allclose(dam.y, market["p_da_mw"])
    up, dn = traces(fig, "SR up band"), traces(fig, "SR down band")
    np.testing.assert_allclose(np.asarray(up.base, float), market["p_da_mw"])
    np.testing.assert_allclose(up.y, market["r_sr_up_mw"])
    np.testing.assert_allclose(np.asarray(dn.base, float) + np.asarray(dn.y, float), market["p_da_mw"])
    np.testing.assert_allclose(dn.y, market["r_sr_dn_mw"])
    assert list(dam.x) == result.problem.labels


def test_heat_supply_meets_thermal_demand(result):
    fig = plots.heat_figure(result)
    assert_readable(fig, result.problem.labels)
    supply = sum(np.asarray(t.y, float) for t in fig.data if t.type == "bar")
    demand = np.asarray(traces(fig, "Thermal demand").y, float)
    np.testing.assert_allclose(supply, demand, atol=1e-6)
    np.testing.assert_allclose(traces(fig, "HPA purchase").y, result.market["h_hpa_mw"])


def test_dispatch_balances_with_the_dam_position(result):
    fig = plots.dispatch_figure(result)
    assert_readable(fig, result.problem.labels)
    bars = [t for t in fig.data if t.type == "bar"]
    assert sorted(t.name for t in bars) == sorted(result.units.query("kind != 'td'")["unit"].unique())
    net = sum(np.asarray(t.y, float) for t in bars)
    np.testing.assert_allclose(net, result.market["p_da_mw"], atol=1e-6)
    ed = traces(fig, "ED_service")
    service = result.units.query("unit == 'ED_service'").sort_values("t")["p_mw"]
    np.testing.assert_allclose(ed.y, -service.to_numpy())


def test_storage_figure_shows_energy_limits_and_margins(case, result):
    fig = plots.storage_figure(result)
    assert_readable(fig, result.problem.labels)
    rows = result.csp.sort_values("t")
    np.testing.assert_allclose(traces(fig, "Stored energy (end of period)").y, rows["ts_energy_mwh"])
    storage = case.csp[0].storage
    assert set(traces(fig, "Minimum energy").y) == {storage.e_min_mwh_th}
    assert set(traces(fig, "Maximum energy").y) == {storage.e_max_mwh_th}
    np.testing.assert_allclose(traces(fig, "Margin kept for up reserve (σ↑)").y, rows["ts_energy_floor_mwh"])
    np.testing.assert_allclose(traces(fig, "Margin kept for down reserve (σ↓)").y, rows["ts_energy_ceiling_mwh"])
    np.testing.assert_allclose(traces(fig, "Charge").y, rows["ts_charge_mw"])
    np.testing.assert_allclose(traces(fig, "Discharge (negative)").y, -rows["ts_discharge_mw"])


def test_storage_figure_refuses_a_case_without_csp(paper_solve):
    solved = paper_solve(csp=False)
    assert solved.status == "optimal"
    with pytest.raises(ValueError, match="no CSP"):
        plots.storage_figure(solved)


def test_reserve_shares_add_up_to_the_offered_bands(result):
    fig = plots.reserve_share_figure(result)
    assert_readable(fig, result.problem.labels)
    for axis, band in (("y", "r_sr_up_mw"), ("y3", "r_sr_dn_mw")):
        per_kind = [t for t in fig.data if t.type == "bar" and t.yaxis == axis]
        assert {t.name for t in per_kind} == {"Wind", "PV", "CSP", "Electrical demand"}
        np.testing.assert_allclose(sum(np.asarray(t.y, float) for t in per_kind), result.market[band],
                                   atol=1e-6)
    totals = [t for t in fig.data if t.type == "bar" and t.yaxis == "y2"][0]
    expected = result.flexibility.set_index("kind")["r_up_mwh"]
    np.testing.assert_allclose(totals.y, expected.to_numpy())


def test_bands_figure_marks_the_largest_deviations(result):
    problem = result.problem
    chi = plots.deviating_periods(result, "PV1")
    source = problem.sources["PV1"]
    assert chi.sum() == source.gamma
    expected = top_gamma_deviation(source.deviation, source.gamma) > 0
    assert set(np.flatnonzero(chi)) == set(np.flatnonzero(expected))
    fig = plots.bands_figure(problem, "PV1", chi)
    assert_readable(fig, problem.labels)
    lo = np.asarray(traces(fig, "Lower percentile (20th)").y)
    hi = np.asarray(traces(fig, "Upper percentile (80th)").y)
    mid = np.asarray(traces(fig, "Median").y)
    assert (lo <= mid + 1e-9).all() and (mid <= hi + 1e-9).all()
    marks = traces(fig, f"Deviates (χ = 1) in {source.gamma} periods")
    np.testing.assert_allclose(marks.y, lo[chi > 0])
    assert len(fig.layout.shapes) == source.gamma
    rows = result.units.query("unit == 'PV1'").sort_values("t")
    np.testing.assert_allclose(traces(fig, "Bound the plan respects").y, rows["bound_mw"], atol=1e-6)


def test_price_chi_carries_the_protection_the_model_charged(result):
    exposures = price_exposures(result.problem, result.market)
    for name in ("price_da", "price_sr_up", "price_sr_dn"):
        chi = plots.deviating_periods(result, name)
        assert np.count_nonzero(chi) <= result.problem.sources[name].gamma
        charged = float(exposures[name][chi != 0].sum())
        assert charged == pytest.approx(result.protection_eur[name], rel=1e-6, abs=1e-6)


def test_exposure_figure_sums_to_the_protection(result):
    gamma = result.problem.sources["price_da"].gamma
    fig = plots.exposure_figure(result, "price_da", gamma)
    picked = [t for t in fig.data if t.name.startswith("Picked by the adversary")][0]
    assert sum(picked.y) == pytest.approx(result.protection_eur["price_da"] / 1000, rel=1e-6)  # kEUR
    assert f"{result.protection_eur['price_da'] / 1000:,.1f} kEUR" in fig.layout.title.text
    assert fig.layout.yaxis.title.text == "Loss if the price moves adversely [kEUR]"


def test_quarter_hours_keep_hourly_ticks(case):
    problem = rvpp.prepare(rvpp.with_options(case, dt_h=0.25))
    fig = plots.bands_figure(problem, "price_da")
    axis = fig.layout.xaxis
    assert len(axis.categoryarray) == 96
    hourly = [label for label in problem.labels if label.endswith(":00")]
    assert list(axis.tickvals) == hourly
    assert list(plots.thin_clock_ticks(fig, 3).layout.xaxis.tickvals) == hourly[::3]


def test_compare_overlays_every_plan_and_leaves_out_idle_trades(paper_solve, cyclic_solve):
    plans = {"balanced": cyclic_solve(strategy="balanced"), "deterministic": cyclic_solve(strategy="deterministic")}
    # With a cyclic storage day neither plan buys heat: the HPA panel would be a flat line.
    assert not any(r.market["h_hpa_mw"].any() for r in plans.values())
    assert plots.idle_trades(plans) == ["h_hpa_mw"]
    fig = plots.compare_trades_figure(plans)
    for label, plan in plans.items():
        lines = [t for t in fig.data if t.name == label]
        assert len(lines) == 3
        np.testing.assert_allclose(lines[0].y, plan.market["p_da_mw"])
        np.testing.assert_allclose(lines[2].y, plan.market["r_sr_dn_mw"])
    styles = {t.name: (t.line.dash, t.marker.symbol) for t in fig.data}
    assert styles["balanced"] != styles["deterministic"]  # told apart without colour
    buying = paper_solve(csp=False)  # without the CSP, the HPA serves all heat
    assert buying.market["h_hpa_mw"].sum() > 0
    fig = plots.compare_trades_figure({"no CSP": buying, **plans})
    heat = [t for t in fig.data if t.name == "no CSP"][3]
    np.testing.assert_allclose(heat.y, buying.market["h_hpa_mw"])


def test_robustness_and_curve_figures_have_units(case):
    points = pd.DataFrame({"gamma": [0, 6], "cost_keur": [100.0, 120.0], "protection_keur": [0.0, 5.0]})
    fig = plots.robustness_figure(points)
    assert "[periods]" in fig.layout.xaxis.title.text and "[kEUR]" in fig.layout.yaxis.title.text
    pb = case.csp[0].power_block
    curve = plots.curve_figure(pb.breakpoints, pb.p_el_max_mw)
    np.testing.assert_allclose(curve.data[0].y, [p * eta for p, eta in pb.breakpoints])


def test_figures_refuse_results_without_a_plan(paper_solve):
    infeasible = paper_solve(csp=False, markets="DAM,SRM")
    assert infeasible.status == "infeasible"
    with pytest.raises(ValueError, match="no plan"):
        plots.trades_figure(infeasible)


@pytest.mark.parametrize("rows, cols, options", [
    (1, 1, dict(shared_yaxes=True, horizontal_spacing=0.03)),
    (1, 4, dict(shared_yaxes=True, horizontal_spacing=0.03, subplot_titles=["a", "bb", "c", "d"])),
    (2, 1, dict(shared_xaxes=True, row_heights=[0.68, 0.32], vertical_spacing=0.05)),
    (2, 2, dict(column_widths=[0.78, 0.22], shared_xaxes="columns", horizontal_spacing=0.09, vertical_spacing=0.08)),
    (4, 1, dict(shared_xaxes=True, vertical_spacing=0.06)),
    (3, 3, dict(row_heights=[3, 1, 2], horizontal_spacing=0.1, vertical_spacing=0.07, shared_xaxes=True,
                shared_yaxes=True, subplot_titles=["a", "", "c", "d", "e", "f", "g", "h", "i"])),
])
def test_subplot_grids_are_laid_out_as_make_subplots_lays_them_out(rows, cols, options):
    from plotly.subplots import make_subplots

    expected = make_subplots(rows=rows, cols=cols, **options).layout.to_plotly_json()
    expected.pop("template", None)
    assert plots.subplots_layout(rows, cols, **options) == expected
