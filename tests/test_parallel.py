"""Serial, process-pool and Dask runs of a study give identical numbers (rvpp.solving.parallel, rvpp.solving.batch)."""

from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest

import rvpp
from rvpp.solving.batch import run_many
from rvpp.errors import RvppError
from rvpp.solving.parallel import open_executor
from rvpp.studies import out_of_sample
from rvpp.studies.settings import StudySettings

CASE_DIR = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
SETTINGS = StudySettings(strategies=("optimistic", "pessimistic"), test_days=2)
NUMBERS = ["method", "day", "fingerprint", "status", "market_cost_eur", "penalty_eur", "net_cost_eur",
           "deficit_mwh", "unserved_heat_mwh"]


def _delayed_square(x: int) -> int:
    time.sleep(0.05 * (3 - x))
    return x * x


def _run(scheduler: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    case = rvpp.load_case(CASE_DIR)
    with open_executor(scheduler, workers=2) as executor:
        out = out_of_sample.run(case, SETTINGS, executor)
    return out.tables["table13_out_of_sample"], out.tables["out_of_sample_days"]


@pytest.fixture(scope="module")
def serial():
    return _run("serial")


# A Dask cluster takes half a minute to start: its run is among the slow tests (make test-all).
@pytest.mark.parametrize("scheduler", ["processes", pytest.param("local", marks=pytest.mark.slow)])
def test_parallel_runs_give_the_serial_numbers(serial, scheduler):
    summary, days = _run(scheduler)
    assert (days["status"] == "optimal").all()
    pd.testing.assert_frame_equal(days[NUMBERS], serial[1][NUMBERS])
    numbers = ["method", "plan_cost_keur", "avg_market_cost_keur", "avg_penalty_keur", "avg_net_cost_keur",
               "realization_set"]
    pd.testing.assert_frame_equal(summary[numbers], serial[0][numbers])


def test_run_many_keeps_task_order_and_reports_progress():
    calls = []
    with ThreadPoolExecutor(max_workers=3) as pool:
        results = run_many(_delayed_square, [0, 1, 2], pool, lambda done, total: calls.append((done, total)))
    assert results == [0, 1, 4]
    assert calls == [(0, 3), (1, 3), (2, 3), (3, 3)]
    assert run_many(_delayed_square, [2, 1], None) == [4, 1]


def test_serial_scheduler_has_no_executor_and_workers_are_checked():
    with open_executor("serial") as executor:
        assert executor is None
    with pytest.raises(RvppError, match="workers"):
        with open_executor("processes", workers=-1):
            pass


def _pid_after_a_while(_: int) -> int:
    time.sleep(0.3)
    return os.getpid()


def test_a_local_pool_has_at_most_one_worker_per_core():
    cores = len(os.sched_getaffinity(0))
    with open_executor("processes", workers=10 ** 6) as executor:
        pids = set(executor.map(_pid_after_a_while, range(3 * cores + 2)))
    assert 1 <= len(pids) <= cores


POOL_PARENT = """
import os, sys, time
sys.path.insert(0, sys.argv[1])
from rvpp.solving.parallel import open_executor
if __name__ == "__main__":
    with open_executor("processes", workers=2) as pool:
        for task in [pool.submit(time.sleep, 0.5) for _ in range(2)]:  # two tasks at once start both workers
            task.result()
        print("ready", flush=True)
        time.sleep(600)
"""


def test_pool_workers_end_when_the_process_that_started_them_is_killed(tmp_path):
    """kill -9 of a backtest gives its pool no word: the workers (and the pool's resource tracker)
    notice that their parent is gone and end."""
    import signal
    import subprocess
    import sys

    script = tmp_path / "parent.py"
    script.write_text(POOL_PARENT)
    parent = subprocess.Popen([sys.executable, str(script), str(Path(__file__).resolve().parents[1])],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout.readline().strip() == "ready"
        children = _children(parent.pid)
        assert len(children) >= 2  # two workers, and the resource tracker
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    deadline = time.monotonic() + 60  # a ceiling for the check, not a speed target (workers look every 2 s)
    while any(_running(pid) for pid in children) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [pid for pid in children if _running(pid)], "a pool process outlived its killed parent"


def _stat(pid: int) -> list[str] | None:
    """``/proc/PID/stat`` after the command name: state, parent, ...; ``None`` once gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError):
        return None


def _children(parent: int) -> list[int]:
    pids = [int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()]
    return [pid for pid in pids if (stat := _stat(pid)) and int(stat[1]) == parent]


def _running(pid: int) -> bool:
    """Whether ``pid`` is a live process (a zombie waiting for its reaper counts as ended)."""
    stat = _stat(pid)
    return stat is not None and stat[0] != "Z"
