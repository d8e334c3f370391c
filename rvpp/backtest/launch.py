"""Run a backtest in a detached process that outlives the page that started it.

:func:`start` saves the case into the data folder, starts ``python -m rvpp backtest``
in a new session (it survives the dashboard's rerun, a closed tab or a server restart)
and returns the backtest's id at once. The process writes its progress into the store
(:meth:`rvpp.store.BacktestStore.set_progress`), so any page can follow it with
:func:`status` and read its records while it runs; :func:`stop` ends it (the days
already settled stay; starting again resumes). A backtest that runs already is not
started twice (:class:`AlreadyRunning`).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

from ..data.case import Case
from ..data.case_yaml import load_case, save_case
from ..data.files import BIDI_CONTROLS, CONTROL_CHARACTERS, excerpt, refused_character
from ..store import BacktestStore
from ..store.backtests import BacktestProgress, backtest_id
from ..store.engine import DEFAULT_DIR, DIR_VARIABLE, URL_VARIABLE
from .settings import CARRY, FRACTION, PERFECT, BacktestError, BacktestSettings

ROOT = Path(__file__).resolve().parents[2]
# What a label may not hold (refused in a case's names and a saved run's label too).
_REFUSED = ((CONTROL_CHARACTERS, "control characters"), (BIDI_CONTROLS, "bidirectional overrides"))

# The processes this server started, by backtest id, until their progress row speaks for them, and
# the lock that makes "is it running? then start it" one step for the server's sessions (a double
# click, two tabs). Two servers (or a server and the command line) on the same store are not covered:
# each sees the other's process only once it wrote its progress row, a second or two after starting.
_STARTED: dict[str, subprocess.Popen] = {}
_STARTING = threading.Lock()


@dataclass(frozen=True)
class Launched:
    """A started backtest: its id in the store, the process and its log file."""

    backtest_id: str
    pid: int
    log: Path


class AlreadyRunning(BacktestError):
    """The backtest runs already (the same case and settings give the same id): a second process
    would settle the same days into the same records."""

    def __init__(self, ident: str, pid: int):
        self.backtest_id, self.pid = ident, pid
        super().__init__(f"backtest {ident} is already running (process {pid}); follow it, or stop it "
                         "before starting it again")


def check_label(label: str) -> str:
    """``label`` if a backtest may be stored under it; :class:`BacktestError` naming the first
    character refused (a control character or a bidirectional override)."""
    if refused := refused_character(label, _REFUSED):
        raise BacktestError(f"label {excerpt(label)!r} must not contain {refused}")
    return label


def command_line(settings: BacktestSettings, case_folder: Path, label: str = "", workers: int | None = None
                 ) -> list[str]:
    """The ``python -m rvpp backtest`` arguments that run ``settings`` (the inverse of the CLI's parsing).

    The store is not among them: the process reads it from ``RVPP_STORE_URL``, so a
    password in the URL never shows in the process list.
    """
    strategies = [v.strategy for v in settings.variants if v.strategy not in (FRACTION, PERFECT)]
    fractions = [v.gamma for v in settings.variants if v.strategy == FRACTION]
    penalties = settings.penalties
    if not strategies and not fractions:
        raise BacktestError("a backtest needs a strategy or a Γ fraction besides the perfect-information plan")
    args = [sys.executable, "-m", "rvpp", "backtest", "--case", str(case_folder),
            "--from", settings.first_day.isoformat(), "--to", settings.last_day.isoformat(), "--m-def", repr(penalties.m_def), "--m-sur", repr(penalties.m_sur),
            "--m-sr", repr(penalties.m_sr), "--storage-end",
            CARRY if settings.storage_end == CARRY else repr(float(settings.storage_end)), "--quiet"]
    if strategies:
        args += ["--strategies", ",".join(strategies)]
    if fractions:
        args += ["--fractions", ",".join(fractions)]
    if penalties.c_heat_eur_per_mwh is not None:
        args += ["--c-heat", repr(penalties.c_heat_eur_per_mwh)]
    if not settings.perfect:
        args.append("--no-perfect")
    if settings.fix_commitment:
        args.append("--fix-commitment")
    if not settings.audit:
        args.append("--no-audit")
    if label:
        args.append(f"--label={label}")  # one argument: a label such as "-draft" is not read as an option
    if workers:
        args += ["--workers", str(workers)]
    return args


def start(case: Case, settings: BacktestSettings, store: BacktestStore | None = None, label: str = "",
          workers: int | None = None) -> Launched:
    """Start the backtest of ``settings`` on ``case`` in a detached process; return at once.

    The case is saved under ``<RVPP_DATA_DIR>/backtests/<id>/case`` and reloaded first, so
    the id is that of the case the process will read (a case edited in memory is saved
    as the CSV files would hold it). Refused with :class:`AlreadyRunning` while a process
    runs that id, and with :class:`BacktestError` for a label :func:`check_label` refuses,
    before anything is written.
    """
    check_label(label)
    store = store or BacktestStore()
    settings.check_case(case)
    backtests = Path(os.environ.get(DIR_VARIABLE, "").strip() or DEFAULT_DIR).resolve() / "backtests"
    backtests.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".case-", dir=backtests))
    try:
        save_case(case, staging)
        ident = backtest_id(load_case(staging), settings.stored())
        with _STARTING:
            if (pid := _running_pid(ident, store)) is not None:
                raise AlreadyRunning(ident, pid)
            folder = backtests / ident
            folder.mkdir(exist_ok=True)
            case_folder = folder / "case"
            if case_folder.exists():  # the same backtest started before: same inputs, keep the first copy
                shutil.rmtree(staging)
            else:
                staging.rename(case_folder)
            log = folder / "backtest.log"
            url = store.engine.url.render_as_string(hide_password=False)
            with open(log, "ab") as output:
                process = subprocess.Popen(command_line(settings, case_folder, label, workers), cwd=ROOT,
                                           stdin=subprocess.DEVNULL, stdout=output, stderr=output,
                                           start_new_session=True,
                                           env={**os.environ, "PYTHONPATH": str(ROOT), URL_VARIABLE: url})
            _STARTED[ident] = process
            # Reaped as soon as it ends, so a finished backtest leaves no zombie behind while the server runs.
            threading.Thread(target=process.wait, name=f"rvpp-backtest-{process.pid}", daemon=True).start()
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return Launched(ident, process.pid, log)


def _running_pid(ident: str, store: BacktestStore) -> int | None:
    """The process running ``ident``: the one its progress row names while that runs (judged alive as
    :meth:`rvpp.store.BacktestStore.progress` does), or one this server started that has not written
    its row yet; ``None`` if none runs."""
    for started, process in list(_STARTED.items()):  # forget the processes that ended (and reap them)
        if process.poll() is not None:
            del _STARTED[started]
    progress = status(ident, store)
    if progress is not None and progress.running:
        return progress.pid
    process = _STARTED.get(ident)
    if process is None or (progress is not None and progress.pid == process.pid):
        return None  # none started here, or it wrote its row, which says it ended
    return process.pid


def status(ident: str, store: BacktestStore | None = None) -> BacktestProgress | None:
    """The progress of backtest ``ident`` (``None`` before its process wrote anything)."""
    return (store or BacktestStore()).progress(ident)


def stop(ident: str, store: BacktestStore | None = None) -> bool:
    """End the process running ``ident`` on this machine (its finished days stay); False if none runs."""
    progress = status(ident, store)
    if progress is None or not progress.running or progress.host != socket.gethostname():
        return False
    try:
        os.killpg(progress.pid, signal.SIGTERM)
    except ProcessLookupError:
        return False
    return True
