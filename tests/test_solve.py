"""The paper case end to end: every plan is optimal, audited and consistent."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rvpp import solve, with_options
from rvpp.data.periods import delivery_periods
from rvpp.settle.audit import audit_result
from rvpp.solving.plan import solve_problem
from rvpp.uncertainty.problem import problem_from_bands

# Γ in hours per strategy (paper Table 7), written here rather than read from rvpp.
TABLE7 = {"deterministic": dict(price=0, wind=0, pv=0, csp=0, ed=0, td=0),
          "optimistic": dict(price=3, wind=3, pv=2, csp=2, ed=3, td=3),
          "balanced": dict(price=6, wind=6, pv=4, csp=4, ed=6, td=6),
          "pessimistic": dict(price=9, wind=9, pv=6, csp=6, ed=9, td=9)}
ROOT = Path(__file__).resolve().parents[1]
STRATEGIES = tuple(TABLE7)


def assert_good(result, periods=24):
    assert result.status == "optimal", result.message
    assert result.mip_gap is not None and result.mip_gap <= result.case.solver.rel_gap + 1e-9
    assert result.problem.nt == periods and len(result.market) == periods
    violations = audit_result(result)
    assert violations == [], "\n".join(map(str, violations[:10]))


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_every_strategy_gives_an_audited_optimal_plan(paper_solve, strategy):
    result = paper_solve(strategy=strategy)
    assert_good(result)
    expected = {name: g for name, g in result.problem.budgets.items()}
    preset = TABLE7[strategy]
    assert expected["price_da"] == preset["price"] and expected["WF1"] == preset["wind"]
    assert expected["PV2"] == preset["pv"] and expected["CSP1"] == preset["csp"]
    assert expected["TD_residential"] == preset["td"]


def test_profit_falls_from_deterministic_to_pessimistic(paper_solve):
    profits = [paper_solve(strategy=s).objective_eur for s in STRATEGIES]
    assert all(a >= b - 1e-4 * abs(a) for a, b in zip(profits, profits[1:])), profits
    assert profits[0] > profits[-1]


def test_raising_one_budget_never_raises_profit(paper_solve):
    base = paper_solve(strategy="balanced")
    for source in ("WF1", "CSP1", "ED_service", "price_sr_up"):
        safer = paper_solve(strategy="balanced", gammas={source: 12})
        assert safer.status == "optimal"
        assert safer.objective_eur <= base.objective_eur + 1e-4 * abs(base.objective_eur), source


@pytest.mark.parametrize("markets", ["DAM", "DAM,HPA", "DAM,SRM", "DAM,SRM,HPA"])
def test_every_market_set_gives_an_audited_plan(cyclic_solve, markets):
    result = cyclic_solve(strategy="deterministic", markets=markets)
    assert_good(result)
    if "SRM" not in markets:
        assert np.allclose(result.market[["r_sr_up_mw", "r_sr_dn_mw"]], 0.0)
    if "HPA" not in markets:
        assert np.allclose(result.market["h_hpa_mw"], 0.0)


def test_more_markets_never_cost_more(cyclic_solve):
    cost = {m: cyclic_solve(strategy="deterministic", markets=m).cost_keur
            for m in ("DAM", "DAM,HPA", "DAM,SRM", "DAM,SRM,HPA")}
    tolerance = 1e-3
    assert cost["DAM,SRM,HPA"] <= min(cost["DAM,HPA"], cost["DAM,SRM"]) + tolerance
    assert max(cost["DAM,HPA"], cost["DAM,SRM"]) <= cost["DAM"] + tolerance


@pytest.mark.parametrize("markets", ["DAM", "DAM,SRM"])
def test_an_empty_tank_without_the_hpa_has_no_plan(paper_solve, markets):
    result = paper_solve(strategy="deterministic", markets=markets)
    assert result.status == "infeasible" and not result.has_plan
    assert result.message.startswith("no feasible plan: heat balance short") and "first at 00:00" in result.message


@pytest.mark.parametrize("markets", ["DAM,HPA", "DAM,SRM,HPA"])
def test_the_hpa_supplies_the_heat_until_the_solar_field_starts(paper_solve, markets):
    result = paper_solve(strategy="deterministic", markets=markets)
    assert_good(result)
    csp, market = result.csp.set_index("t"), result.market.set_index("t")
    td = result.units[result.units["kind"] == "td"].groupby("t")["p_mw"].sum()
    dark = csp.index[: int(np.argmax(csp["p_sf_mw"].to_numpy() > 0))]  # periods before the field's first heat
    assert len(dark) >= 6  # at least the night hours 00:00-06:00
    assert csp.loc[dark.min(), "ts_energy_mwh"] == pytest.approx(result.case.csp[0].storage.e_min_mwh_th)
    assert np.allclose(csp.loc[dark, "heat_to_td_mw"], 0.0, atol=1e-6)
    np.testing.assert_allclose(market.loc[dark, "h_hpa_mw"], td.loc[dark], rtol=1e-9, atol=1e-6)
    assert (td.loc[dark] > 0).all()


def test_the_rvpp_without_csp_is_solved_and_costs_more(paper_solve):
    without = paper_solve(strategy="balanced", csp=False)
    assert_good(without)
    assert without.csp.empty and "csp" not in set(without.units["kind"])
    assert without.cost_keur > paper_solve(strategy="balanced").cost_keur


@pytest.mark.parametrize("day, periods", [("2025-03-30", 23), ("2025-10-26", 25)])
def test_clock_change_days_solve(paper_solve, day, periods):
    result = paper_solve(strategy="balanced", date=day)
    assert_good(result, periods)
    clocks = list(result.market["clock"])
    if periods == 23:
        assert "02:00" not in clocks
    else:
        assert sum(c.startswith("02:00") for c in clocks) == 2


def test_quarter_hour_day_is_at_least_as_good_as_hourly(paper_solve):
    # A March day keeps this quick; make bench times the default day at 15 minutes.
    quarter = paper_solve(strategy="balanced", dt_h=0.25, date="2025-03-18")
    assert_good(quarter, 96)
    assert quarter.problem.budgets["price_da"] == 4 * TABLE7["balanced"]["price"]
    hourly = paper_solve(strategy="balanced", date="2025-03-18")
    # On the hourly bands repeated in each quarter-hour, with budgets scaled by 4, the hourly plan
    # repeated per quarter is feasible at 15 minutes: the finer plan can only be better. (The
    # case's own quarter-hours interpolate the hours, MODEL_SPEC §6, which this law does not cover.)
    stepped = hourly.problem.bands.loc[np.repeat(hourly.problem.bands.index, 4)].reset_index(drop=True)
    stepped.index = pd.RangeIndex(1, 97, name="t")
    case = quarter.case
    steps = solve_problem(problem_from_bands(case, delivery_periods(case.delivery_date, case.timezone, 0.25), stepped))
    assert steps.status == "optimal" and audit_result(steps, bands=stepped) == []
    assert steps.objective_eur >= hourly.objective_eur - 2e-4 * abs(hourly.objective_eur)


def test_power_block_output_follows_the_breakpoint_curve(paper_solve, paper_case):
    result = paper_solve(strategy="deterministic")
    pb = paper_case.csp[0].power_block
    csp = result.csp
    online = csp["online"] == 1
    assert online.any(), "the CSP should run on the default day"
    # The curve as the case gives it: output = input × efficiency at each breakpoint, straight between them.
    inputs = [p for p, _ in pb.breakpoints]
    outputs = [p * eta for p, eta in pb.breakpoints]
    for scenario, shift in (("none", 0), ("up", 1), ("dn", -1)):
        reserve = csp["ts_r_up_mw"] if shift > 0 else csp["ts_r_dn_mw"]
        thermal = csp["p_pb_mw"] + shift * reserve
        expected = np.interp(thermal[online], inputs, outputs)
        assert np.allclose(csp.loc[online, f"e_{scenario}_mw"], expected, atol=1e-5)
    assert (csp.loc[online, "p_pb_mw"] >= pb.p_in_min_mw_th - 1e-6).all()
    assert np.allclose(csp.loc[~online, ["p_pb_mw", "e_none_mw"]], 0.0)


def test_fast_top_gamma_path_equals_the_binary_formulation_on_the_paper_case(paper_case):
    case = with_options(paper_case, strategy="pessimistic", rel_gap=1e-7)
    fast = solve(case)
    exact = solve(with_options(case, budget_encoding="binary"))
    assert fast.status == exact.status == "optimal"
    assert fast.objective_eur == pytest.approx(exact.objective_eur, rel=2e-7)
    assert audit_result(exact) == []
    for name, source in exact.problem.sources.items():
        if source.is_price or source.gamma == 0:
            continue
        table = exact.csp if source.unit_kind == "csp" else exact.units
        rows = table[table["unit"] == name]
        chi = rows["chi"].to_numpy(int)
        dev = source.deviation
        assert chi.sum() == source.gamma
        if 0 < chi.sum() < len(chi):
            assert dev[chi == 1].min() >= dev[chi == 0].max() - 1e-9, name


def test_incremental_and_convex_combination_encodings_agree(paper_case):
    case = with_options(paper_case, strategy="optimistic", rel_gap=1e-7)
    incremental = solve(case)
    convex = solve(with_options(case, pwl_encoding="convex_combination"))
    assert incremental.status == convex.status == "optimal"
    assert incremental.objective_eur == pytest.approx(convex.objective_eur, rel=2e-7)
    assert audit_result(convex) == []


def test_a_conflicting_thread_count_is_reported_not_fatal(monkeypatch):
    solve_module = importlib.import_module("rvpp.solving.highs")

    monkeypatch.setattr(solve_module, "_pool_threads", [1])
    assert solve_module._thread_option(1) == ({}, "")
    assert solve_module._thread_option(0) == ({}, "")
    options, note = solve_module._thread_option(2)
    assert options == {} and "already runs this process with 1 thread" in note
    monkeypatch.setattr(solve_module, "_pool_threads", [])
    assert solve_module._thread_option(3) == ({"threads": 3}, "")


# A fresh process: HiGHS sizes its pool at the process's first run and fails a later run naming
# another size. Half the logical processors is HiGHS's documented default.
THREAD_SEQUENCE = """
import os, sys
import highspy
from rvpp import load_case, solve, with_options
case = load_case(sys.argv[1])
if sys.argv[2] == "outside":  # something else in the process runs HiGHS first, on two threads
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("threads", 2)
    h.addVars(1, [0.0], [1.0])
    h.run()
for threads in map(int, sys.argv[3:]):
    result = solve(with_options(case, threads=threads))
    print(result.status, result.objective_eur, "|", result.message)
"""


@pytest.mark.parametrize("first, counts", [("rvpp", (0, 2, 1)), ("outside", (1, 0))])
def test_any_thread_count_after_any_first_run_solves(first, counts):
    command = [sys.executable, "-c", THREAD_SEQUENCE, str(ROOT / "data" / "cases" / "paper"), first, *map(str, counts)]
    run = subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = [line.split("|", 1) for line in run.stdout.strip().splitlines()]
    assert len(lines) == len(counts)
    assert {line[0].split()[0] for line in lines} == {"optimal"}, run.stdout
    objectives = [float(line[0].split()[1]) for line in lines]
    assert max(objectives) - min(objectives) <= 1e-4 * abs(objectives[0]), objectives
    if first == "rvpp":
        pool = max(1, (os.cpu_count() or 1) // 2)
        for count, (_, message) in zip(counts, lines):
            expected = "" if count in (0, pool) else f"threads={count} ignored: HiGHS already runs this process with {pool} thread(s)"
            assert message.strip() == expected, (count, message)
    else:
        assert "threads=1 ignored: HiGHS already runs this process with another thread count" in lines[0][1]
        assert lines[1][1].strip() == ""


def test_an_infeasible_day_is_explained(paper_solve):
    # On a cloudy March day, pessimistic budgets without the HPA leave the thermal
    # demands short of heat.
    result = paper_solve(strategy="pessimistic", markets="DAM,SRM", date="2025-03-18")
    assert result.status == "infeasible" and not result.has_plan
    assert result.message.startswith("no feasible plan: heat balance short by up to")
    assert "enable the HPA" in result.message


def test_startup_heat_lasts_one_period_unless_a_duration_is_given(paper_case):
    # The schedule a start-up draws is checked on a hand-built case in test_model.py.
    pb = paper_case.csp[0].power_block
    assert pb.startup_duration_h is None
    assert pb.startup_periods(1.0) == 1 and pb.startup_periods(0.25) == 1
    spread = pb.model_copy(update={"startup_duration_h": 1.0})
    assert spread.startup_periods(0.25) == 4 and spread.startup_periods(1.0) == 1


def test_a_plan_started_from_its_own_optimum_finds_it_with_fewer_lp_iterations(paper_case):
    """The solver settings' ``mip_start`` reaches HiGHS: started from the integer variables of its
    own optimum, one thread (a reproducible path), the same day takes fewer LP iterations."""
    case = with_options(paper_case, date="2025-05-05", strategy="optimistic", threads=1)
    cold = solve(case)
    assert cold.status == "optimal" and any(".online[" in name for name in cold.integer_ones)
    started = solve(case.replace(solver={"mip_start": cold.integer_ones}))
    assert started.status == "optimal"
    assert started.objective_eur == pytest.approx(cold.objective_eur, abs=1e-4 * abs(cold.objective_eur))
    assert started.lp_iterations < cold.lp_iterations
    assert set(started.integer_ones) == set(cold.integer_ones)
