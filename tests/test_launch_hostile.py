"""Hostile input to a backtest's launch and to the Home page's server folders: labels that look like
options or hold control characters, the same backtest started twice, paths the system refuses.

No backtest process is started here: ``subprocess.Popen`` is replaced by :class:`FakeProcess`,
which records its command line and stays "alive" until the test (or its teardown) ends it.
"""

from __future__ import annotations

import datetime as dt
import os
import subprocess
import threading

import pytest

import rvpp
from dashboard import state
from rvpp.backtest import BacktestSettings, variants_of
from rvpp.backtest import launch
from rvpp.backtest.settings import BacktestError
from rvpp.cli import _parser, main
from rvpp.data.files import excerpt
from rvpp.errors import CasePathError
from rvpp.store import BacktestStore
from tests.factories import click, one_day_backtest_form, open_app
from tests.test_app import case_of, errors

DAY = dt.date(2025, 5, 2)
HOSTILE_LABELS = [("draft\x00", "0000"), ("bt\x1b]0;owned\x07\x1b[2J", "001B"), ("next\x85line", "0085"),
                  ("cost \u202etxt.exe", "202E"), ("\u2066isolated", "2066")]
CEILING_S = 120  # how long a thread may wait for the other one (a ceiling, never a measured time)


@pytest.fixture
def settings():
    return BacktestSettings(DAY, DAY, variants_of(["deterministic"], [], perfect=False))


@pytest.fixture
def store(tmp_path):
    return BacktestStore(f"sqlite:///{tmp_path / 'store.sqlite3'}")


pytestmark = pytest.mark.usefixtures("data_dir")  # every test writes into a data folder of its own


@pytest.fixture
def processes(monkeypatch):
    """The processes the test starts (fakes), in order; each is ended when the test ends."""
    started = []

    class FakeProcess:
        def __init__(self, args, **_options):
            self.args, self.pid, self.returncode = list(args), 4_000_000 + len(started), None
            self.ended = threading.Event()
            started.append(self)

        def poll(self):
            return self.returncode

        def wait(self, timeout=None):  # the launch's reaper thread waits on every process it starts
            self.ended.wait(timeout)
            return self.returncode

    monkeypatch.setattr(subprocess, "Popen", FakeProcess)
    yield started
    for process in started:
        process.returncode = 0
        process.ended.set()


# ----------------------------------------------------------------------------- labels


def test_a_label_starting_with_a_dash_reaches_the_backtest_as_typed(settings, tmp_path):
    args = _parser().parse_args(launch.command_line(settings, tmp_path, label="-draft")[3:])
    assert args.label == "-draft"


@pytest.mark.parametrize(("label", "code"), HOSTILE_LABELS)
def test_a_label_with_control_characters_is_refused_before_anything_is_written(label, code, paper_case, settings,
                                                                               store, processes, data_dir):
    with pytest.raises(BacktestError, match=rf"label .* must not contain .*\(found U\+{code}\)"):
        launch.start(paper_case, settings, store, label=label)
    assert not processes
    assert not data_dir.exists()


@pytest.mark.parametrize(("label", "code"), HOSTILE_LABELS[1:])  # argv itself cannot hold a NUL
def test_the_command_line_refuses_a_label_with_control_characters(label, code, capsys):
    with pytest.raises(SystemExit):
        _parser().parse_args(["backtest", "--from", "2025-05-02", "--to", "2025-05-02", f"--label={label}"])
    assert f"--label: label '{excerpt(label)}' must not contain" in capsys.readouterr().err
    assert _parser().parse_args(["backtest", "--label", "café · 2025"]).label == "café · 2025"


def test_backtest_list_prints_a_stored_label_as_printable_text(paper_case, settings, store, capsys):
    store.open(paper_case, settings.stored(), keys_total=1, label="bt\x1b]0;owned\x07\x1b[2J")  # stored before
    assert main(["backtest", "list", "--store", str(store.engine.url)]) == 0
    out = capsys.readouterr().out
    assert "bt?]0;owned??[2J" in out and "\x1b" not in out and "\x07" not in out


# ----------------------------------------------------------------------------- the same backtest twice


def test_a_backtest_is_not_started_again_while_its_process_runs(paper_case, settings, store, processes, data_dir):
    first = launch.start(paper_case, settings, store, label="-draft")
    assert "--label=-draft" in processes[0].args
    with pytest.raises(BacktestError, match="already running") as refused:
        launch.start(paper_case, settings, store, label="-draft")
    assert (refused.value.backtest_id, refused.value.pid) == (first.backtest_id, first.pid)
    assert len(processes) == 1 and [p.name for p in (data_dir / "backtests").iterdir()] == [first.backtest_id]
    processes[0].returncode = 1  # it ended before writing any progress
    again = launch.start(paper_case, settings, store)
    assert again.backtest_id == first.backtest_id and len(processes) == 2


def test_a_backtest_whose_progress_row_says_running_is_not_started_again(paper_case, settings, store, processes):
    ident = launch.start(paper_case, settings, store).backtest_id
    processes[0].returncode = 0
    assert store.open(paper_case, settings.stored(), keys_total=1) == ident  # as its process would
    store.set_progress(ident, "running", 0, 1)  # this test's process: alive, on this machine
    with pytest.raises(BacktestError, match="already running") as refused:
        launch.start(paper_case, settings, store)
    assert refused.value.pid == os.getpid() and len(processes) == 1
    store.set_progress(ident, "finished", 1, 1)
    assert launch.start(paper_case, settings, store).backtest_id == ident and len(processes) == 2


def test_two_starts_at_once_start_one_process(paper_case, settings, store, processes, monkeypatch):
    """A double click: the second start waits for the first to have started its process, then sees it."""
    second_waits = threading.Event()

    class WatchedLock:
        """The launch's lock, telling when a second start waits on it."""

        def __init__(self):
            self.lock = threading.Lock()

        def __enter__(self):
            if self.lock.locked():
                second_waits.set()
            self.lock.acquire()

        def __exit__(self, *_exc):
            self.lock.release()

    fake = subprocess.Popen

    def slow_popen(args, **options):  # the first process starts only once the second start waits
        assert second_waits.wait(CEILING_S), "the second start never waited for the first"
        return fake(args, **options)

    monkeypatch.setattr(launch, "_STARTING", WatchedLock())
    monkeypatch.setattr(subprocess, "Popen", slow_popen)
    outcomes = []

    def start():
        try:
            outcomes.append(launch.start(paper_case, settings, store))
        except BacktestError as err:
            outcomes.append(err)

    threads = [threading.Thread(target=start) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(CEILING_S)
    assert len(processes) == 1
    started, refused = sorted(outcomes, key=lambda o: isinstance(o, BacktestError))
    assert isinstance(started, launch.Launched) and refused.backtest_id == started.backtest_id


def test_the_page_refuses_a_hostile_label_and_a_second_start(processes, data_dir):
    at = one_day_backtest_form(open_app("backtest"), DAY, "bt\x1b[2J")
    click(at, "backtest_start")
    assert "must not contain control characters (found U+001B)" in errors(at)
    assert not processes and not (data_dir / "backtests").exists()
    at.text_input(key="backtest_label").input("-draft")
    click(at, "backtest_start")
    assert not errors(at) and "Started in the background" in at.info[0].value
    click(at, "backtest_start")
    assert not errors(at) and "already running" in at.info[0].value
    assert len(processes) == 1 and "--label=-draft" in processes[0].args


# ----------------------------------------------------------------------------- server folders


@pytest.mark.parametrize("typed", ["mine\x00/case", "x" * 5000])
def test_a_folder_path_the_system_refuses_is_refused_in_the_users_words(typed, monkeypatch):
    monkeypatch.setenv(state.SERVER_FOLDERS, "1")
    with pytest.raises(CasePathError, match="case folder") as refused:
        state.load_folder(typed)
    assert f"'{excerpt(typed)}'" in str(refused.value)


def test_a_case_folder_holding_a_dangling_link_loads(paper_case, tmp_path, monkeypatch):
    """An editor's lock file (Emacs' ``.#case.yaml``) is a link to nowhere beside the case's files."""
    rvpp.save_case(paper_case, tmp_path / "mine")
    (tmp_path / "mine" / ".#case.yaml").symlink_to(tmp_path / "nowhere")
    monkeypatch.setenv(state.SERVER_FOLDERS, "1")
    at = open_app()
    at.text_input(key="home_folder").input(str(tmp_path / "mine")).run()
    click(at, "home_load_folder")
    assert not errors(at) and case_of(at) == paper_case
