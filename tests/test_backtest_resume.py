"""A backtest killed with SIGKILL halfway resumes without recomputing a finished day, and ends with
exactly the figures of a run that was never interrupted."""

from __future__ import annotations

import datetime as dt
import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest
import sqlalchemy as sa

from rvpp.backtest import BacktestSettings, metrics, run_backtest, variants_of
from rvpp.store import BacktestStore
from tests.factories import ROOT

FIRST, LAST = dt.date(2025, 5, 2), dt.date(2025, 5, 5)
STRATEGIES = ("deterministic", "balanced")
KILL_AFTER = 3  # records
COSTS = ["market_cost_eur", "penalty_eur", "net_cost_eur", "plan_objective_eur", "end_state"]


def stamps(url: str) -> dict:
    """When each record was written, by key (none yet while the writer is still creating its tables)."""
    engine = sa.create_engine(url)
    if not sa.inspect(engine).has_table("backtest_records"):
        return {}
    with engine.connect() as connection:
        rows = connection.execute(sa.text("SELECT day, strategy, gamma, recorded_at FROM backtest_records"))
        return {tuple(row[:3]): row[3] for row in rows}


def command(url: str, *extra: str) -> list[str]:
    return [sys.executable, "-m", "rvpp", "backtest", "--from", FIRST.isoformat(), "--to", LAST.isoformat(),
            "--strategies", ",".join(STRATEGIES), "--no-perfect", "--store", url, "--quiet", *extra]


@pytest.mark.slow
def test_a_backtest_killed_halfway_resumes_without_recomputing_and_ends_equal(paper_case, tmp_path):
    url = f"sqlite:///{tmp_path / 'killed.sqlite3'}"
    process = subprocess.Popen(command(url, "--scheduler", "serial"), cwd=ROOT, stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline and process.poll() is None:
            if os.path.exists(tmp_path / "killed.sqlite3") and len(stamps(url)) >= KILL_AFTER:
                break
            time.sleep(0.2)
        assert process.poll() is None, process.stderr.read().decode()
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    before = stamps(url)
    assert KILL_AFTER <= len(before) < 8
    [info] = BacktestStore(url).list()
    assert BacktestStore(url).progress(info.id).state == "stopped"

    resumed = subprocess.run(command(url, "--scheduler", "processes", "--workers", "2"), cwd=ROOT,
                             capture_output=True, text=True, timeout=900,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert resumed.returncode == 0, resumed.stderr
    after = stamps(url)
    assert len(after) == 8
    assert {key: after[key] for key in before} == before, "a finished day was computed again"

    clean = BacktestStore(f"sqlite:///{tmp_path / 'clean.sqlite3'}")
    settings = BacktestSettings(FIRST, LAST, variants_of(STRATEGIES, [], perfect=False))
    ident = run_backtest(paper_case, settings, clean)
    assert ident == info.id  # same inputs, same backtest
    killed_records = BacktestStore(url).records(info.id)
    clean_records = clean.records(ident)
    pd.testing.assert_frame_equal(killed_records[["day", "strategy", *COSTS]], clean_records[["day", "strategy", *COSTS]],
                                  check_exact=True)
    figures = [c for c in metrics.aggregates(clean_records).columns if not c.endswith("_s")]
    pd.testing.assert_frame_equal(metrics.aggregates(killed_records)[figures], metrics.aggregates(clean_records)[figures],
                                  check_exact=True)
