"""The rolling backtest: state continuity, information discipline, reconciliation, exports, command line."""

from __future__ import annotations

import datetime as dt
import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from rvpp import load_case, solve, with_options
from rvpp.backtest import BacktestSettings, BacktestVariant, metrics, run_backtest, variants_of
from rvpp.backtest.engine import DayTask, day_case, plan, run_day
from rvpp.backtest.export import export
from rvpp.backtest.state import initial_state
from rvpp.cli import main
from rvpp.data.history import History
from rvpp.store import BacktestStore
from tests.factories import ROOT, SPAIN

WEEK = (dt.date(2025, 5, 1), dt.date(2025, 5, 7))


@pytest.fixture(scope="module")
def stocked(paper_case):
    """The paper case with a stocked tank (900 MWh_th) and a turbine 3 h into its 6 h minimum up time."""
    csp = paper_case.csp[0].model_dump(mode="python")
    csp["storage"]["e_init_mwh_th"] = 900.0
    csp["power_block"].update(initially_on=True, initial_status_h=3.0)
    return paper_case.replace(csp=[csp])


@pytest.fixture(scope="module")
def week(stocked, tmp_path_factory):
    """A week of the deterministic plan and the perfect-information plan; the tank may run down to 25 %."""
    store = BacktestStore(f"sqlite:///{tmp_path_factory.mktemp('week') / 'store.sqlite3'}")
    settings = BacktestSettings(*WEEK, variants_of(["deterministic"], [], perfect=True), storage_end=0.25)
    ident = run_backtest(stocked, settings, store)
    return store, ident, settings


@pytest.mark.slow
def test_each_day_starts_from_the_state_the_settlement_of_the_day_before_left(week, stocked):
    store, ident, settings = week
    records = store.records(ident)
    for strategy, chain in records.groupby("strategy"):
        chain = chain.sort_values("day").to_dict("records")
        assert [r["day"] for r in chain] == [(WEEK[0] + dt.timedelta(days=k)).isoformat() for k in range(7)]
        assert chain[0]["start_state"] == {"CSP1": {"e_mwh_th": 900.0, "online": True, "status_h": 3.0}}
        for before, after in zip(chain, chain[1:]):
            assert after["start_state"] == before["end_state"], (strategy, after["day"])
            settled = before["settled_csp"]["CSP1"]
            assert before["end_state"]["CSP1"]["e_mwh_th"] == pytest.approx(settled["e_mwh_th"][-1], abs=1e-6)
            # The next day's settled storage moves from there by at most one period's charge or discharge.
            step = after["settled_csp"]["CSP1"]["e_mwh_th"][0] - settled["e_mwh_th"][-1]
            assert -115 / 0.95 - 1e-6 <= step <= 140 * 0.95 + 1e-6
        levels = [r["start_state"]["CSP1"]["e_mwh_th"] for r in chain]
        assert len({round(v, 3) for v in levels}) > 1, "the storage level never changed: nothing carried over"
        # The turbine's settled schedule over the week keeps every minimum down time across midnight.
        schedule = np.concatenate([r["settled_csp"]["CSP1"]["online"] for r in chain])
        starts = np.flatnonzero(np.diff(schedule) == 1) + 1
        stops = np.flatnonzero(np.diff(schedule) == -1) + 1
        for stop in stops:
            later = starts[starts > stop]
            if len(later):
                assert later[0] - stop >= 6, f"{strategy}: off for {later[0] - stop} h only"


# A chain whose state moves at every midnight: a full tank (1,100 MWh_th) that can discharge only
# 20 MW_th, so a day cannot empty it, and heat bought for 10 EUR/MWh_th, so the tank's heat goes to the
# turbine rather than to the thermal demands; the tank may run down to its minimum (storage_end 0).
MOVING = (dt.date(2025, 5, 1), dt.date(2025, 5, 4))
SLOW_DISCHARGE_MW_TH = 20.0


@pytest.fixture(scope="module")
def slow_tank(paper_case):
    csp = paper_case.csp[0].model_dump(mode="python")
    csp["storage"].update(e_init_mwh_th=1100.0, p_dis_max_mw_th=SLOW_DISCHARGE_MW_TH)
    csp["power_block"].update(initially_on=True, initial_status_h=3.0)
    return with_options(paper_case.replace(csp=[csp]), hpa_flat=10.0)


@pytest.fixture(scope="module")
def moving(slow_tank, tmp_path_factory):
    store = BacktestStore(f"sqlite:///{tmp_path_factory.mktemp('moving') / 'store.sqlite3'}")
    settings = BacktestSettings(*MOVING, variants_of(["deterministic"], [], perfect=False), storage_end=0.0)
    ident = run_backtest(slow_tank, settings, store)
    chain = store.records(ident).sort_values("day").to_dict("records")
    return chain, settings


def hours_in_status(online: list[int], start: dict) -> float | None:
    """Hours the turbine has been in its last status at the end of a day, counted here from the settled
    schedule: the last run, plus the start state's hours when the turbine never switched."""
    run = 0
    while run < len(online) and online[-1 - run] == online[-1]:
        run += 1
    if run == len(online) and bool(online[-1]) == start["online"]:
        return None if start["status_h"] is None else start["status_h"] + run
    return float(run)


@pytest.mark.slow
def test_the_state_at_every_midnight_moves_and_is_the_next_days_start(moving, slow_tank):
    chain, settings = moving
    assert [r["day"] for r in chain] == [d.isoformat() for d in settings.days]
    midnights = [chain[0]["start_state"]["CSP1"]] + [r["end_state"]["CSP1"] for r in chain]
    assert midnights[0] == {"e_mwh_th": 1100.0, "online": True, "status_h": 3.0}
    # Every midnight differs from the one before in the tank level and the hours in status, and the
    # turbine is found both on and off at midnight: a chain that restarts each day cannot pass.
    for before, after in zip(midnights, midnights[1:]):
        assert abs(after["e_mwh_th"] - before["e_mwh_th"]) > 50.0, (before, after)
        assert after["status_h"] != before["status_h"], (before, after)
    assert {m["online"] for m in midnights} == {True, False}
    for before, after in zip(chain, chain[1:]):
        assert after["start_state"] == before["end_state"], after["day"]
    for record in chain:
        assert record["status"] == "optimal" and record["plan_status"] == "optimal"
        start, end, settled = record["start_state"]["CSP1"], record["end_state"]["CSP1"], record["settled_csp"]["CSP1"]
        # The end state read off the settled schedule by hand.
        assert end["e_mwh_th"] == pytest.approx(settled["e_mwh_th"][-1], abs=1e-6)
        assert end["online"] == bool(settled["online"][-1])
        assert end["status_h"] == hours_in_status(settled["online"], start)
        # The first settled hour moves from the start level by at most one hour's discharge or charge.
        step = settled["e_mwh_th"][0] - start["e_mwh_th"]
        assert -SLOW_DISCHARGE_MW_TH / 0.95 - 1e-6 <= step <= 140 * 0.95 + 1e-6, (record["day"], step)
    # Day 1 by hand: the turbine runs all day (3 h before midnight, so 3 + 24 = 27 h online at its
    # end) and the tank gives its 20 MW_th every hour: 1100 - 24 x 20 / 0.95 = 594.737 MWh_th.
    first = chain[0]
    assert first["settled_csp"]["CSP1"]["online"] == [1] * 24
    assert np.allclose(np.diff([1100.0] + first["settled_csp"]["CSP1"]["e_mwh_th"]), -20.0 / 0.95, atol=1e-6)
    assert first["end_state"]["CSP1"] == pytest.approx({"e_mwh_th": 1100.0 - 24 * 20.0 / 0.95, "online": True,
                                                        "status_h": 27.0})


@pytest.mark.slow
def test_the_plan_of_a_day_starts_from_the_settled_end_of_the_day_before(moving, slow_tank):
    chain, settings = moving
    carried = []
    for before, after in zip(chain, chain[1:]):
        case = day_case(slow_tank.replace(solver={"threads": 1}), dt.date.fromisoformat(after["day"]),
                        BacktestVariant("deterministic"), before["end_state"], settings.storage_end,
                        tuple(before["plan_integer_ones"]))
        end = before["end_state"]["CSP1"]
        unit = case.csp[0]
        assert (unit.storage.e_init_mwh_th, unit.power_block.initially_on, unit.power_block.initial_status_h) == (
            end["e_mwh_th"], end["online"], end["status_h"])
        result = solve(case)
        assert result.status == "optimal"
        assert result.objective_eur == pytest.approx(after["plan_objective_eur"], rel=1e-9)
        csp = result.csp.iloc[0]
        first = csp["ts_energy_mwh"] - 0.95 * csp["ts_charge_mw"] + csp["ts_discharge_mw"] / 0.95
        assert first == pytest.approx(end["e_mwh_th"], abs=1e-4)
        if end["status_h"] is not None and end["status_h"] < 6:
            # A minimum up or down time (6 h) begun before midnight is completed first.
            online = result.csp["online"].to_numpy()
            assert (online[: int(6 - end["status_h"])] == int(end["online"])).all(), after["day"]
            carried.append(after["day"])
    # The chain holds such a day: the turbine stopped at 23:00 on 2 May, so 3 May stays off until 05:00.
    assert carried == ["2025-05-03"]


@pytest.mark.slow
def test_each_plan_starts_from_the_plan_of_the_day_before_and_keeps_its_optimum(week, stocked, monkeypatch,
                                                                                  tmp_path):
    store, ident, settings = week
    records = store.records(ident)
    chain = records[records["strategy"] == "deterministic"].sort_values("day").to_dict("records")
    for record in chain:
        assert record["plan_integer_ones"] and all(isinstance(name, str) for name in record["plan_integer_ones"])
        assert record["plan_lp_iterations"] >= 0 and record["plan_nodes"] >= 0
    # The chain hands each day the plan of the day before as its MIP start.
    seen = []
    monkeypatch.setattr("rvpp.backtest.engine.plan", lambda case: seen.append(case.solver.mip_start) or solve(case))
    three_days = BacktestSettings(WEEK[0], WEEK[0] + dt.timedelta(days=2), variants_of(["deterministic"], [], perfect=False),
                                  storage_end=settings.storage_end)
    run_backtest(stocked, three_days, BacktestStore(f"sqlite:///{tmp_path / 'again.sqlite3'}"))
    assert seen[0] == () and seen[1:] == [tuple(r["plan_integer_ones"]) for r in chain[:2]]
    # Without the start, the day's plan is the same optimum within the gap.
    before, after = chain[4], chain[5]
    cold = solve(day_case(stocked.replace(solver={"threads": 1}), dt.date.fromisoformat(after["day"]),
                          BacktestVariant("deterministic"), before["end_state"], settings.storage_end))
    tolerance = 1e-4 * abs(cold.objective_eur) + 0.01
    assert after["plan_objective_eur"] <= cold.bound_eur + 0.01 and cold.objective_eur <= after["plan_bound_eur"] + 0.01
    assert after["plan_objective_eur"] == pytest.approx(cold.objective_eur, abs=tolerance)


@pytest.mark.slow
def test_a_recorded_day_reopens_with_the_plan_it_was_settled_with(week):
    from rvpp.backtest.engine import reopen_plan
    from rvpp.store import RecordKey

    store, ident, settings = week
    assert BacktestSettings.from_stored(store.load(ident)[1]) == settings
    records = store.record_map(ident)
    for key in (RecordKey("2025-05-04", "deterministic", "preset"), RecordKey("2025-05-05", "perfect", "preset")):
        result = reopen_plan(store, ident, key)
        assert result.status == "optimal" and result.objective_eur == records[key]["plan_objective_eur"]
        assert result.market["p_da_mw"].tolist() == records[key]["bids"]["p_da_mw"]


@pytest.mark.slow
def test_every_stored_day_reconciles_and_its_plan_passes_the_audit(week):
    store, ident, _ = week
    records = store.records(ident)
    assert len(records) == 14
    for record in records.to_dict("records"):
        assert record["status"] == "optimal" and record["plan_status"] == "optimal"
        assert abs(record["net_cost_eur"] - record["market_cost_eur"] - record["penalty_eur"]) < 0.01
        parts = sum(record[f"penalty_{p}_eur"] for p in ("deficit", "surplus", "reserve", "heat"))
        assert abs(parts - record["penalty_eur"]) < 0.01
        assert record["audit_violations"] == 0
        assert np.isfinite(record["net_cost_eur"])
    assert metrics.reconcile(records).empty


@pytest.mark.slow
def test_the_perfect_information_plan_settles_at_its_own_cost_without_penalty(week):
    store, ident, _ = week
    records = store.records(ident)
    perfect = records[records["strategy"] == "perfect"]
    for record in perfect.to_dict("records"):
        assert abs(record["penalty_eur"]) < 1.0
        gap = record["plan_mip_gap"] or 0.0
        assert record["net_cost_eur"] == pytest.approx(-record["plan_objective_eur"],
                                                       abs=1.0 + 2 * gap * abs(record["plan_objective_eur"]))
    table = metrics.aggregates(records).set_index("strategy")
    assert table.loc["perfect", "mean_regret_eur"] == 0.0
    daily = metrics.daily(records)
    mine = daily[daily["strategy"] == "deterministic"].set_index("day")
    theirs = daily[daily["strategy"] == "perfect"].set_index("day")
    assert np.allclose(mine["regret_eur"], mine["net_cost_eur"] - theirs["net_cost_eur"])


def poisoned(case, first_day: dt.date, last_day: dt.date | None = None, value: float = 1e6, columns=None):
    """``case`` whose history ``columns`` (default: all) hold ``value`` in the local days ``first_day..last_day``."""
    frame = case.history.frame
    local = frame.index.tz_convert(case.timezone).date
    rows = (local >= first_day) & ((local <= last_day) if last_day else True)
    frame.loc[rows, list(columns or frame.columns)] = value
    return case.replace(history=History(frame, source="poisoned"))


def test_the_plan_of_a_day_reads_nothing_of_the_day_itself_or_after(paper_case):
    day = dt.date(2025, 5, 20)
    state = initial_state(paper_case)

    def planned(case):
        result = plan(day_case(case.replace(solver={"threads": 1}), day, BacktestVariant("balanced"), state, "carry"))
        assert result.status == "optimal"
        return result

    clean = planned(paper_case)
    future = planned(poisoned(paper_case, day))
    assert future.objective_eur == clean.objective_eur
    for column in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw"):
        assert future.market[column].tolist() == clean.market[column].tolist()
    # The check can fail: a week of poisoned prices just before the day changes the plan.
    past = planned(poisoned(paper_case, day - dt.timedelta(days=7), day - dt.timedelta(days=1), value=500.0,
                            columns=["price_da", "price_sr_up", "price_sr_dn"]))
    assert past.objective_eur != pytest.approx(clean.objective_eur, rel=1e-3)


def test_a_day_without_a_plan_bids_nothing_and_is_still_settled(paper_case, monkeypatch):
    from rvpp.backtest import engine
    from rvpp.solving.outcome import Outcome
    from rvpp.uncertainty.problem import prepare
    from rvpp.solving.results import Result

    def no_plan(case):
        return Result(problem=prepare(case), status=Outcome.INFEASIBLE, termination="test", message="no plan today")

    monkeypatch.setattr(engine, "plan", no_plan)
    settings = BacktestSettings(dt.date(2025, 5, 2), dt.date(2025, 5, 2), variants_of(["balanced"], [], False))
    record = run_day(DayTask(paper_case.replace(solver={"threads": 1}), dt.date(2025, 5, 2), BacktestVariant("balanced"),
                             initial_state(paper_case), settings))
    assert record["plan_status"] == "infeasible" and record["message"] == "no plan today"
    assert record["status"] == "optimal"
    assert record["bids"]["p_da_mw"] == [0.0] * 24 and record["sold_mwh"] == 0.0
    assert abs(record["net_cost_eur"] - record["market_cost_eur"] - record["penalty_eur"]) < 0.01
    assert record["revenue_dam_eur"] == 0.0 and record["state_source"] == "settlement"
    assert "audit_violations" not in record


def fake_records() -> pd.DataFrame:
    """Two variants over three days of two months, with numbers chosen by hand."""
    rows = []
    costs = {"balanced": [(100.0, 20.0), (50.0, 0.0), (10.0, 40.0)], "perfect": [(90.0, 0.0), (40.0, 0.0), (30.0, 0.0)]}
    for strategy, days in costs.items():
        for day, (market, penalty) in zip(("2025-01-31", "2025-02-01", "2025-02-02"), days):
            rows.append({"day": day, "strategy": strategy, "gamma": "preset", "label": strategy, "status": "optimal",
                         "plan_status": "optimal", "market_cost_eur": market, "penalty_eur": penalty,
                         "net_cost_eur": market + penalty, "penalty_deficit_eur": penalty,
                         "penalty_surplus_eur": 0.0, "penalty_reserve_eur": 0.0, "penalty_heat_eur": 0.0,
                         "audit_violations": 0, "plan_solve_s": 1.0, "wall_s": 2.0})
    return pd.DataFrame(rows)


def test_aggregates_match_hand_computed_figures():
    table = metrics.aggregates(fake_records()).set_index("strategy")
    balanced = table.loc["balanced"]
    # Net costs 120, 50, 50: mean 73.33, median 50, CVaR 95 % = the worst day (120).
    assert balanced["mean_net_cost_eur"] == pytest.approx(220 / 3)
    assert balanced["median_net_cost_eur"] == 50.0 and balanced["cvar95_net_cost_eur"] == 120.0
    assert balanced["penalty_share"] == pytest.approx(60 / 220)
    assert balanced["total_penalty_deficit_eur"] == 60.0
    # Regret against the perfect plan: 120 − 90, 50 − 40, 50 − 30.
    assert balanced["mean_regret_eur"] == pytest.approx(20.0) and balanced["total_regret_eur"] == 60.0
    months = metrics.monthly(fake_records()).set_index(["strategy", "month"])
    assert months.loc[("balanced", "2025-01"), "net_cost_eur"] == 120.0
    assert months.loc[("balanced", "2025-02"), "net_cost_eur"] == 100.0
    assert months.loc[("balanced", "2025-02"), "days"] == 2
    worst = metrics.worst_days(fake_records(), "balanced", "preset", n=1)
    assert worst["day"].tolist() == [dt.date(2025, 1, 31)]


def test_reconcile_names_a_day_that_does_not_add_up():
    records = fake_records()
    records.loc[1, "net_cost_eur"] += 5.0
    records.loc[2, "audit_violations"] = 3
    records.loc[3, "status"] = "unbounded"
    problems = metrics.reconcile(records)
    assert set(zip(problems["day"].astype(str), problems["check"])) == {
        ("2025-02-01", "net = market cost + penalty"), ("2025-02-02", "plan audit"), ("2025-01-31", "settled")}


@pytest.mark.parametrize("n, worst", [(20, [20]), (21, [21, 20]), (365, list(range(365, 346, -1))), (1, [1])])
def test_cvar_95_is_the_mean_of_the_worst_five_percent_of_days(n, worst):
    values = np.random.default_rng(n).permutation(np.arange(1, n + 1, dtype=float))
    assert metrics.cvar(values) == pytest.approx(sum(worst) / len(worst))


@pytest.mark.slow
def test_an_export_holds_the_records_and_reproduces_the_inputs(week, tmp_path):
    store, ident, settings = week
    target = tmp_path / "export"
    export(store, ident, target)
    (target / "records.csv").write_text("an earlier export's table")  # an earlier export is replaced as a whole
    export(store, ident, target)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "a staging folder was left behind"
    records = pd.read_csv(target / "records.csv")
    assert len(records) == 14 and {"net_cost_eur", "gamma_price_da", "start_CSP1_e_mwh_th"} <= set(records.columns)
    assert len(pd.read_parquet(target / "records.parquet")) == 14
    assert len(pd.read_csv(target / "bids.csv")) == 14 * 24
    assert len(pd.read_csv(target / "dispatch.csv")) == 14 * 24
    manifest = json.loads((target / "manifest.json").read_text())
    assert manifest["backtest_id"] == ident and manifest["settings"] == settings.stored()
    case = load_case(target / "case")
    assert case.history.fingerprint == manifest["history_fingerprint"] == store.load(ident)[0].history.fingerprint
    stored = store.records(ident).sort_values(["day", "strategy"]).reset_index(drop=True)
    assert np.allclose(records.sort_values(["day", "strategy"])["net_cost_eur"], stored["net_cost_eur"], atol=1e-6)


def test_an_export_that_fails_leaves_the_previous_one_untouched(week, tmp_path, monkeypatch):
    from rvpp.backtest import export as module

    store, ident, _ = week
    target = tmp_path / "export"
    export(store, ident, target)
    before = {p.name: p.read_bytes() for p in target.iterdir() if p.is_file()}

    def broken(*_args, **_kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(module, "save_case", broken)
    with pytest.raises(OSError, match="disk full"):
        export(store, ident, target)
    assert {p.name: p.read_bytes() for p in target.iterdir() if p.is_file()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["export"]


def recorded_at(url: str) -> dict:
    """When each record was written, read straight from the store's table."""
    import sqlalchemy as sa

    with sa.create_engine(url).connect() as connection:
        rows = connection.execute(sa.text("SELECT day, strategy, gamma, recorded_at FROM backtest_records"))
        return {tuple(row[:3]): row[3] for row in rows}


def cli(*args, store=None):
    command = [sys.executable, "-m", "rvpp", "backtest", *args]
    if store:
        command += ["--store", store]
    return subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=300)


@pytest.mark.parametrize("args, message", [
    (["--from", "2024-12-05", "--to", "2024-12-06"], "--from 2024-12-05: the first day needs the 30 days of history"),
    (["--from", "2025-12-30", "--to", "2026-01-02"], "--to 2026-01-02: the day is settled against its own"),
    (["--to", "2025-05-02"], "backtest needs --from D1 and --to D2"),
    (["--from", "2025-05-02", "--to", "2025-05-01"], "--to 2025-05-01 is before --from 2025-05-02"),
    (["--from", "2025-5-2x", "--to", "2025-05-03"], "--from '2025-5-2x' is not a date such as 2025-03-18"),
    (["--from", "2025-05-02", "--to", "2025-05-03", "--fractions", "6"], "--fractions/--gammas: '6' is not allowed; give a number in [0, 1] [fraction of the day]"),
    (["--from", "2025-05-02", "--to", "2025-05-03", "--strategies", "bold"], "unknown strategy 'bold'"),
    (["--from", "2025-05-02", "--to", "2025-05-03", "--storage-end", "full"], "--storage-end: 'full' is not a number; give a number in [0, 1]"),
])
def test_the_command_line_refuses_bad_options_by_name(args, message, tmp_path, capsys):
    """In this process (the program's own exit status is checked by test_cli); an exception other
    than the named refusal would fail the test here instead of printing a traceback."""
    code = main(["backtest", *args, "--store", f"sqlite:///{tmp_path / 's.sqlite3'}"])
    error = capsys.readouterr().err
    assert code == 1, error
    assert message in error


def test_recommend_refuses_a_test_period_that_overlaps_the_training(tmp_path):
    done = cli("recommend", "--train", "2025-03-01:2025-03-31", "--test", "2025-03-31:2025-04-30",
               store=f"sqlite:///{tmp_path / 's.sqlite3'}")
    assert done.returncode == 1
    assert "--test must start after --train ends (2025-03-31)" in done.stderr


@pytest.mark.slow
def test_the_command_line_runs_resumes_and_exports(tmp_path):
    store = f"sqlite:///{tmp_path / 's.sqlite3'}"
    args = ["--from", "2025-05-02", "--to", "2025-05-03", "--strategies", "deterministic", "--no-perfect",
            "--scheduler", "serial", "--quiet"]
    first = cli(*args, "--out", str(tmp_path / "out"), store=store)
    assert first.returncode == 0, first.stderr
    assert len(pd.read_csv(tmp_path / "out" / "records.csv")) == 2
    stamps = recorded_at(store)
    again = cli(*args[:-1], store=store)  # everything recorded: nothing to compute
    assert again.returncode == 0 and "2 records" in again.stderr
    assert recorded_at(store) == stamps
    [info] = BacktestStore(store).list()
    assert (info.keys_done, info.keys_total) == (2, 2)
    assert BacktestStore(store).progress(info.id).state == "finished"
    listing = cli("list", store=store)
    assert info.id in listing.stdout and "finished" in listing.stdout


def spain_folder():
    folder = SPAIN
    return folder if (folder / "omie_spain_prices_2018_2025.csv").is_file() else None


@pytest.mark.slow
@pytest.mark.skipif(spain_folder() is None, reason="the real Spanish data (shared/data/spain, or RVPP_SPAIN_DATA) "
                                                   "is not on this machine")
def test_a_day_with_negative_prices_plans_and_settles(paper_case):
    # OMIE's 2024 day-ahead prices moved 52 weeks later (weekdays and clock changes line up) into the
    # paper case's history: 2024-04-21 had 8 hours below zero and becomes 2025-04-20.
    omie = pd.read_csv(spain_folder() / "omie_spain_prices_2018_2025.csv")
    prices = pd.Series(omie["price_es_eur_mwh"].to_numpy(),
                       index=pd.to_datetime(omie["time_utc"], utc=True) + pd.Timedelta(days=364))
    frame = paper_case.history.frame
    window = (frame.index >= pd.Timestamp("2025-03-01", tz="UTC")) & (frame.index < pd.Timestamp("2025-05-01",
                                                                                                   tz="UTC"))
    frame.loc[window, "price_da"] = prices.reindex(frame.index[window]).to_numpy()
    case = paper_case.replace(history=History(frame, source="paper history with OMIE 2024 prices"))
    day = dt.date(2025, 4, 20)
    settings = BacktestSettings(day, day, variants_of(["balanced"], [], perfect=True))
    for variant in settings.variants:
        record = run_day(DayTask(case.replace(solver={"threads": 1}), day, variant, initial_state(case), settings))
        realized = case.history.days(day, 1, case.timezone)["price_da"]
        assert (realized < 0).sum() == 8
        assert record["plan_status"] == "optimal", record["message"]
        assert record["status"] == "optimal", f"{variant.label}: settlement {record['status']}"
        assert abs(record["net_cost_eur"] - record["market_cost_eur"] - record["penalty_eur"]) < 0.01
        assert record["audit_violations"] == 0


@pytest.mark.slow
def test_a_dask_cluster_computes_the_same_records_as_the_calling_process(paper_case, tmp_path):
    from rvpp.solving.parallel import open_executor

    settings = BacktestSettings(dt.date(2025, 5, 2), dt.date(2025, 5, 3), variants_of(["optimistic"], [], False))
    serial = BacktestStore(f"sqlite:///{tmp_path / 'serial.sqlite3'}")
    dask = BacktestStore(f"sqlite:///{tmp_path / 'dask.sqlite3'}")
    ident = run_backtest(paper_case, settings, serial)
    with open_executor("local", 1) as executor:
        assert run_backtest(paper_case, settings, dask, executor) == ident
    columns = ["day", "net_cost_eur", "market_cost_eur", "plan_objective_eur", "end_state", "bids"]
    pd.testing.assert_frame_equal(serial.records(ident)[columns], dask.records(ident)[columns], check_exact=True)


@pytest.mark.slow
def test_a_task_carries_only_the_history_its_day_needs_and_computes_the_same_record(paper_case):
    from rvpp.backtest.engine import day_history

    day = dt.date(2025, 3, 31)  # the window holds the change to summer time
    small = day_history(paper_case, day)
    assert len(small.history.frame) == 24 * (30 + 8 + 1) - 1
    assert small.history.local_days(paper_case.timezone)[-1] == day
    settings = BacktestSettings(day, day, variants_of(["balanced"], [], perfect=True))
    timings = {"wall_s", "cpu_s", "plan_build_s", "plan_solve_s", "settle_solve_s", "audit_s"}
    for variant in settings.variants:
        full, sliced = (run_day(DayTask(case.replace(solver={"threads": 1}), day, variant, initial_state(case),
                                        settings)) for case in (paper_case, small))
        assert {k: v for k, v in full.items() if k not in timings} == {k: v for k, v in sliced.items()
                                                                       if k not in timings}


def test_only_days_of_hourly_periods_start_from_the_plan_of_the_day_before(paper_case):
    day, start = dt.date(2025, 5, 5), ("csp[CSP1].online[12]",)
    variant, state = BacktestVariant("balanced"), initial_state(paper_case)
    hourly = day_case(paper_case, day, variant, state, "carry", start)
    quarter = day_case(paper_case.replace(dt_h=0.25), day, variant, state, "carry", start)
    assert hourly.solver.mip_start == start and quarter.solver.mip_start == ()
    assert day_case(paper_case, day, variant, state, "carry").solver.mip_start == ()


def test_a_battery_and_a_hydro_unit_carry_their_settled_state_across_every_midnight(paper_case, tmp_path):
    # Three days of the paper case with a battery and a hydro plant, checked from the exported files
    # alone: each day's first period continues the day before's last one, by the battery's own energy
    # balance (efficiencies, self-discharge) and the hydro plant's ramp limit.
    keep, eta_ch, eta_dis, ramp_up, ramp_dn = 1 - 0.002, 0.93, 0.92, 12.0, 15.0
    case = paper_case.replace(
        battery=[{"name": "BAT", "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 20.0, "p_dis_max_mw": 20.0,
                  "eta_ch": eta_ch, "eta_dis": eta_dis, "self_discharge_per_h": 0.002, "e_init_mwh": 12.0,
                  "ramp_mw_per_min": 4.0}],
        hydro=[{"name": "HY", "kind": "hydro", "p_min_mw": 6.0, "p_max_mw": 30.0, "marginal_cost_eur_per_mwh": 8.0,
                "ramp_up_mw_per_h": ramp_up, "ramp_dn_mw_per_h": ramp_dn, "min_up_h": 3.0, "min_down_h": 2.0,
                "initial_online": True, "initial_hours_in_status": 1.0, "p_init_mw": 8.0, "energy_max_mwh": 220.0,
                "ramp_mw_per_min": 1.0}])
    store = BacktestStore(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    days = (dt.date(2025, 5, 1), dt.date(2025, 5, 3))
    ident = run_backtest(case, BacktestSettings(*days, variants_of(["deterministic"], [], perfect=False)), store)
    export(store, ident, tmp_path / "export")
    records = pd.read_csv(tmp_path / "export" / "records.csv").sort_values("day")
    dispatch = pd.read_csv(tmp_path / "export" / "dispatch.csv")
    assert (records["status"] == "optimal").all()
    battery = dispatch[dispatch["unit"] == "BAT"].sort_values(["day", "t"])
    hydro = dispatch[dispatch["unit"] == "HY"].sort_values(["day", "t"])
    assert len(battery) == len(hydro) == 3 * 24 and set(battery["kind"]) == {"battery"}
    energy = np.concatenate([[12.0], battery["e_mwh"].to_numpy()])
    moved = eta_ch * battery["charge_mw"].to_numpy() - battery["discharge_mw"].to_numpy() / eta_dis
    assert np.allclose(energy[1:], keep * energy[:-1] + moved, atol=1e-5)  # 71 steps, two of them midnights
    assert (battery["e_mwh"] >= 12.0 - 1e-5).groupby(battery["day"]).last().all()  # each day ends at its start
    ends = battery.groupby("day")["e_mwh"].last().to_numpy()
    assert np.allclose(records["start_BAT_e_mwh"].to_numpy()[1:], ends[:-1], atol=1e-6)
    output = np.concatenate([[8.0], hydro["p_mw"].to_numpy()])
    online = np.concatenate([[1], hydro["online"].to_numpy()])
    steps = np.diff(output)
    # a running unit moves at most its ramp; a start or a stop is bounded by Pmax (no start-up ramp set)
    running = (online[1:] == 1) & (online[:-1] == 1)
    assert (steps[running] <= ramp_up + 1e-6).all() and (-steps[running] <= ramp_dn + 1e-6).all()
    assert np.allclose(records["start_HY_p_mw"].to_numpy()[1:], hydro.groupby("day")["p_mw"].last().to_numpy()[:-1])
