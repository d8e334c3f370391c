"""A backtest started for a page runs in its own process, reports its progress through the store,
and can be stopped and started again where it stopped."""

from __future__ import annotations

import datetime as dt

import pytest

from rvpp.backtest import BacktestSettings, variants_of
from rvpp.cli.backtest import settings_from
from rvpp.backtest.launch import command_line, start, status, stop
from rvpp.backtest.settings import parse_day
from rvpp.cli import _parser
from rvpp.settle.recourse import Penalties
from rvpp.store import BacktestStore
from tests.factories import wait_for


@pytest.mark.parametrize("settings", [
    BacktestSettings(dt.date(2025, 5, 2), dt.date(2025, 5, 9), variants_of(["balanced", "pessimistic"], [0.125, 0.5])),
    BacktestSettings(dt.date(2025, 5, 2), dt.date(2025, 5, 2), variants_of([], [0.3], perfect=False),
                     penalties=Penalties(m_def=3.0, m_sur=0.25, m_sr=1.5, c_heat_eur_per_mwh=400.0), storage_end=0.25,
                     fix_commitment=True, audit=False),
])
def test_the_command_line_of_a_launch_runs_exactly_its_settings(settings, tmp_path):
    args = _parser().parse_args(command_line(settings, tmp_path)[3:])
    assert args.store is None  # the store travels in the environment, not on the command line
    strategies = args.strategies if args.strategies is not None else ()
    parsed = settings_from(args, parse_day(args.first, "--from"), parse_day(args.last, "--to"), strategies,
                           args.fractions or ())
    assert parsed.stored() == settings.stored()


@pytest.mark.slow
def test_a_launched_backtest_reports_progress_stops_and_resumes(paper_case, tmp_path, monkeypatch):
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "data"))
    store = BacktestStore(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    settings = BacktestSettings(dt.date(2025, 5, 2), dt.date(2025, 5, 13), variants_of(["deterministic"], [], False))
    launched = start(paper_case, settings, store, label="launched", workers=1)
    assert (tmp_path / "data" / "backtests" / launched.backtest_id / "case" / "case.yaml").is_file()
    running = wait_for(lambda: (p := status(launched.backtest_id, store)) and p.done >= 1 and p)
    assert running.state == "running" and running.total == 12 and running.pid == launched.pid
    assert running.eta_s is not None and running.eta_s > 0
    assert stop(launched.backtest_id, store)
    stopped = wait_for(lambda: (p := status(launched.backtest_id, store)) and p.state != "running" and p, 120)
    assert stopped.state in ("interrupted", "stopped") and stopped.done < 12
    kept = len(store.records(launched.backtest_id))
    assert kept >= 1 and not stop(launched.backtest_id, store)

    again = start(paper_case, settings, store, workers=1)
    assert again.backtest_id == launched.backtest_id
    finished = wait_for(lambda: (p := status(again.backtest_id, store)) and p.state == "finished" and p, 900)
    assert finished.done == finished.total == 12 and finished.eta_s == 0.0
    assert len(store.records(again.backtest_id)) == 12
    assert "Traceback" not in again.log.read_text()
