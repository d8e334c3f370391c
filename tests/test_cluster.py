"""A backtest on a Dask cluster whose scheduler and worker are processes of their own, started
from outside the checkout without PYTHONPATH (as on another machine), so that the worker imports
rvpp from the install (`make install`); its records equal the local process pool's to the cent."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.factories import ROOT

FIRST, LAST = "2025-05-02", "2025-05-03"
STRATEGIES = "deterministic,balanced"
MONEY = ("market_cost_eur", "penalty_eur", "net_cost_eur")
START_S = 120  # for the scheduler to write its address and the worker to join it
RUN_S = 600


def outside_env() -> dict[str, str]:
    """This environment without PYTHONPATH and without a store of the user's."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "RVPP_STORE_URL", "RVPP_DATA_DIR")}


@pytest.fixture(scope="module")
def outside(tmp_path_factory) -> Path:
    """A folder outside the checkout, where rvpp can only come from the install; the test is skipped
    when this Python's install does not hold this checkout's rvpp."""
    folder = tmp_path_factory.mktemp("outside")
    found = subprocess.run([sys.executable, "-c", "import rvpp; print(rvpp.__file__)"], cwd=folder,
                           env=outside_env(), capture_output=True, text=True, timeout=60)
    if found.returncode != 0:
        pytest.skip(f"rvpp is not installed in {sys.prefix} (make install installs it)")
    if Path(found.stdout.strip()).resolve().parent.parent != ROOT.resolve():
        pytest.skip(f"the rvpp installed in {sys.prefix} is another checkout's ({found.stdout.strip()})")
    return folder


def start(args: list[str], cwd: Path, log: Path) -> subprocess.Popen:
    with open(log, "wb") as out:
        return subprocess.Popen([sys.executable, "-m", *args], cwd=cwd, env=outside_env(), stdout=out,
                                stderr=subprocess.STDOUT, start_new_session=True)


def stop(process: subprocess.Popen) -> None:
    """End a started process and whatever it started (a worker's nanny starts the worker)."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait(timeout=30)


def wait_for(what: str, ready, processes: list[subprocess.Popen], logs: list[Path]) -> None:
    deadline = time.monotonic() + START_S
    while not ready():
        ended = [p for p in processes if p.poll() is not None]
        if ended or time.monotonic() > deadline:
            text = "\n".join(f"--- {log.name}\n{log.read_text(errors='replace')[-3000:]}" for log in logs)
            pytest.fail(f"{what} did not come up ({'a process ended' if ended else 'timed out'}):\n{text}")
        time.sleep(0.2)


def backtest(cwd: Path, store: Path, *scheduler: str) -> None:
    """The short backtest through the installed `rvpp` command."""
    command = [str(Path(sys.executable).parent / "rvpp"), "backtest", "--from", FIRST, "--to", LAST,
               "--strategies", STRATEGIES, "--no-perfect", "--quiet", "--store", f"sqlite:///{store}", *scheduler]
    done = subprocess.run(command, cwd=cwd, env=outside_env(), capture_output=True, text=True, timeout=RUN_S)
    assert done.returncode == 0, done.stderr


def cents(store: Path) -> dict[tuple[str, str, str], tuple]:
    """Status and money of every stored record, in cents, read from the database itself."""
    with sqlite3.connect(store) as connection:
        rows = connection.execute("SELECT day, strategy, gamma, status, record FROM backtest_records").fetchall()
    return {(day, strategy, gamma): (status, *(round(json.loads(record)[k] * 100) for k in MONEY))
            for day, strategy, gamma, status, record in rows}


@pytest.mark.slow
def test_a_backtest_on_a_separate_scheduler_and_worker_equals_the_local_pool(outside):
    address_file = outside / "scheduler.json"
    logs = [outside / "scheduler.log", outside / "worker.log"]
    processes: list[subprocess.Popen] = []
    try:
        processes.append(start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                                "--no-dashboard", "--scheduler-file", str(address_file)], outside, logs[0]))
        wait_for("the scheduler", address_file.exists, processes, logs)
        processes.append(start(["distributed.cli.dask_worker", "--scheduler-file", str(address_file),
                                "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                                "--local-directory", str(outside / "worker")], outside, logs[1]))
        wait_for("the worker", lambda: "Registered to" in logs[1].read_text(errors="replace"), processes, logs)
        address = json.loads(address_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")

        backtest(outside, outside / "cluster.sqlite3", "--scheduler", address)
    finally:
        for process in reversed(processes):
            stop(process)
    backtest(outside, outside / "pool.sqlite3", "--scheduler", "processes", "--workers", "1")

    on_cluster, on_pool = cents(outside / "cluster.sqlite3"), cents(outside / "pool.sqlite3")
    assert sorted(on_cluster) == [(day, strategy, "preset") for day in (FIRST, LAST)
                                  for strategy in sorted(STRATEGIES.split(","))]
    assert {status for status, *_ in on_cluster.values()} == {"optimal"}
    assert on_cluster == on_pool
    assert "ModuleNotFoundError" not in logs[1].read_text(errors="replace")
