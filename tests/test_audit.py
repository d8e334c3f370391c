"""The audit catches broken plans: each family of rules, broken on purpose."""

from __future__ import annotations

import copy
import datetime as dt

import numpy as np
import pandas as pd
import pytest

from rvpp.settle.audit import audit_day, audit_tables, curve_output_mw


@pytest.fixture(scope="module")
def plan(paper_solve):
    result = paper_solve(strategy="deterministic")
    assert result.status == "optimal"
    assert result.csp["online"].sum() >= 6, "the mutations below need the turbine running"
    return result


def broken(plan, table, row_filter, column, delta, summary_change=None):
    tables = {name: getattr(plan, name).copy() for name in ("market", "units", "csp")}
    frame = tables[table]
    rows = frame.index[row_filter(frame)]
    frame.loc[rows, column] = frame.loc[rows, column] + delta
    summary = copy.deepcopy(plan.summary())
    if summary_change:
        summary_change(summary)
    return {v.check for v in audit_tables(audit_day(plan.case), tables["market"], tables["units"], tables["csp"],
                                          summary)}


def test_a_good_plan_passes(plan):
    assert audit_tables(audit_day(plan.case), plan.market, plan.units, plan.csp, plan.summary()) == []


def test_electric_balance_is_checked_in_every_scenario(plan):
    checks = broken(plan, "market", lambda f: f["t"] == 5, "p_da_mw", 0.5)
    assert {"electric_balance[none]", "electric_balance[up]", "electric_balance[dn]"} <= checks


def test_reserve_delivery_is_checked_in_its_scenario(plan):
    checks = broken(plan, "market", lambda f: f["t"] == 12, "r_sr_up_mw", 0.5)
    assert "electric_balance[up]" in checks and "electric_balance[none]" not in checks


def test_heat_balance(plan):
    assert "heat_balance" in broken(plan, "market", lambda f: f["t"] == 3, "h_hpa_mw", 1.0)


def test_storage_recursion(plan):
    assert "csp.ts_energy_balance" in broken(plan, "csp", lambda f: f["t"] == 8, "ts_energy_mwh", 2.0)


def test_power_block_curve(plan):
    online = plan.csp["online"] == 1
    t = int(plan.csp.loc[online, "t"].iloc[0])
    checks = broken(plan, "csp", lambda f: f["t"] == t, "e_up_mw", 0.3)
    assert "csp.pb_curve[up]" in checks


def test_minimum_up_time(plan):
    online = plan.csp.index[plan.csp["online"] == 1]
    middle = int(plan.csp.loc[online[len(online) // 2], "t"])
    checks = broken(plan, "csp", lambda f: f["t"] == middle, "online", -1)
    assert "csp.commitment_transition" in checks or "csp.min_up" in checks


def test_availability_bound(plan):
    checks = broken(plan, "units", lambda f: (f["unit"] == "PV1") & (f["t"] == 13), "p_mw", 80.0)
    assert "ndres.available" in checks


def test_budget_placement(plan):
    checks = broken(plan, "units", lambda f: (f["unit"] == "WF2") & (f["t"] == 4), "chi", 1)
    assert {"budget.count", "budget.bound"} <= checks


def test_price_protection_and_objective(plan):
    def inflate(summary):
        summary["protection_eur"]["sr_dn"] += 10.0
    checks = broken(plan, "market", lambda f: f["t"] < 0, "p_da_mw", 0.0, inflate)
    assert checks == {"objective.protection_sr_dn"}

    def shift(summary):
        summary["objective_eur"] += 5.0
    assert broken(plan, "market", lambda f: f["t"] < 0, "p_da_mw", 0.0, shift) == {"objective.total"}


def test_the_audit_derives_the_bands_itself(plan):
    # The market table's price bands are checked against the audit's own §6 arithmetic.
    assert "market.price_da_mid" in broken(plan, "market", lambda f: f["t"] == 9, "price_da_mid", 1.0)
    assert "budget.nominal" in broken(plan, "units", lambda f: (f["unit"] == "WF1") & (f["t"] == 2),
                                      "nominal_mw", 0.5)
    # Median at 12:00 local of the 30 days before the delivery day, computed here with pandas.
    case = plan.case
    local = case.history.frame.tz_convert(case.timezone)
    first = pd.Timestamp(case.delivery_date - dt.timedelta(days=30)).tz_localize(case.timezone)
    window = local[(local.index >= first) & (local.index < pd.Timestamp(case.delivery_date).tz_localize(case.timezone))]
    noon = window[window.index.hour == 12]
    assert len(noon) == 30
    day = audit_day(case)
    assert day.sources["price_da"].nominal[12] == pytest.approx(noon["price_da"].median(), rel=1e-12)
    assert day.sources["price_sr_up"].nominal[12] == pytest.approx(noon["price_sr_up"].quantile(0.8), rel=1e-12)
    assert day.sources["WF1"].gamma == 0 and day.sources["price_da"].gamma == 0  # deterministic


def test_a_stated_budget_other_than_the_cases_is_caught(plan):
    def claim(summary):
        summary["budgets"]["PV2"] = 3

    assert broken(plan, "market", lambda f: f["t"] < 0, "p_da_mw", 0.0, claim) == {"budget.gamma"}


def test_the_audit_evaluates_the_power_block_curve_itself(paper_case):
    pb = paper_case.csp[0].power_block
    # Breakpoints 19 -> 0.27, 40 -> 0.34, 70 -> 0.38, 140 -> 0.395 (MW_th -> efficiency).
    expected = [19 * 0.27, 40 * 0.34, 40 * 0.34 + (55 - 40) / 30 * (70 * 0.38 - 40 * 0.34), 140 * 0.395]
    np.testing.assert_allclose(curve_output_mw(pb, np.array([19.0, 40.0, 55.0, 140.0])), expected, rtol=1e-12)
