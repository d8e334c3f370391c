"""Studies for the dashboard: run in worker processes with progress, kept by their full input.

A study of :mod:`rvpp.studies` runs as one task in a pool of study processes, never in
the server: Streamlit runs every session in a thread of one process, where a study's
many solves would take turns with the solves of every other session. The study pool is
separate from the plan solvers of :mod:`dashboard.solving`, so a study of minutes never
holds up a plan on another page.

* **Progress.** The study's ``progress(stage, done, total)`` callback puts each report
  on a queue of a multiprocessing manager; the page polls the queue every ``POLL_S`` and
  draws one bar per study.
* **Cancel.** The same callback raises :class:`StudyCancelled` once the study's cancel
  event is set, so a cancelled study stops when the solve under way ends.
* **Kept by the full input.** A study is keyed by its name, the case's content
  (:func:`dashboard.state.case_key`) and the settings. Running and finished studies are
  shared by every session, like a ``st.cache_data`` entry: going back to a page, or
  asking for the same input in another tab, shows the result (or the progress of the
  run under way) without solving again. Each session remembers which keys it asked
  for (``<page>_requested``), so a page shows only what its own tab ran.
* **Waiting never blocks.** A page only polls; leaving it or changing an input ends
  the wait at once, and the study finishes in the background.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import queue
import threading
import time
from collections import OrderedDict
from collections.abc import Sequence
from concurrent.futures import ALL_COMPLETED, CancelledError, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

import pandas as pd
import streamlit as st

from rvpp import Case, RvppError
from rvpp.service import STUDIES, StudyOutput, StudySettings, parse_numbers, table_csv, tables_workbook_bytes

from . import widgets
from .state import case_key

MAX_STUDY_WORKERS = 2  # study processes shared by all sessions, beside the plan solvers
STUDY_WORKERS = max(1, min(MAX_STUDY_WORKERS, os.cpu_count() or 1))
KEPT = 24              # finished studies kept in memory (a few MB at most each)
POLL_S = 0.2           # how often a waiting page refreshes its progress [s]
EXCEL = "application/vnd.openxmlformats-officedocument.spreadsheetml.sheet"


class StudyCancelled(RvppError):
    """The study was cancelled before it ended."""


def run_in_worker(name: str, case: Case, settings: StudySettings, channel, cancel) -> StudyOutput:
    """Worker entry point: run the study ``name``, reporting progress on ``channel``."""

    def progress(stage: str, done: int, total: int) -> None:
        if cancel.is_set():
            raise StudyCancelled(f"{name}: cancelled")
        channel.put((stage, done, total))

    return STUDIES[name](case, settings, None, progress)


def study_key(name: str, case_digest: str, settings: StudySettings) -> str:
    """A digest of everything a study depends on: its name, the case's content
    (``case_digest``, from :func:`dashboard.state.case_key`), the settings."""
    return hashlib.sha256(f"{name}|{case_digest}|{settings!r}".encode()).hexdigest()


@st.cache_resource(show_spinner=False)
def study_pool() -> ProcessPoolExecutor:
    """The shared study processes, spawned by the first study (not at start-up: a first page
    load then shares the two cores only with the plan solvers' imports).

    A spawned process imports the main script as ``__mp_main__``: during a page run that
    is ``app.py``, whose ``__main__`` guard keeps it from drawing anything.
    """
    return ProcessPoolExecutor(max_workers=STUDY_WORKERS, mp_context=multiprocessing.get_context("spawn"))


@st.cache_resource(show_spinner=False)
def _manager():
    """The process that carries progress reports and cancel requests between processes."""
    return multiprocessing.get_context("spawn").Manager()


@dataclass
class Job:
    """One study run: its future in the study pool, its progress and its cancel switch."""

    key: str
    name: str
    future: Future
    channel: object
    cancel: object
    started: float = field(default_factory=time.perf_counter)
    stage: str = ""
    done: int = 0
    total: int = 0
    stages: int = 0
    finished: float | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def poll(self) -> None:
        """Take every progress report that arrived (several pages may poll one job)."""
        with self.lock:
            while True:
                try:
                    stage, done, total = self.channel.get_nowait()
                except (queue.Empty, OSError, EOFError):
                    break
                if stage != self.stage:
                    self.stages += 1
                self.stage, self.done, self.total = stage, done, total
            if self.finished is None and self.future.done():
                self.finished = time.perf_counter()

    def line(self) -> tuple[float, str]:
        """Fraction done and a status line: stage, done of total, elapsed time."""
        elapsed = (self.finished or time.perf_counter()) - self.started
        if not self.stage:
            return 0.0, f"starting (waits for a free study process while other studies run) · {elapsed:.0f} s"
        fraction = self.done / self.total if self.total else 1.0
        return fraction, f"stage {self.stages}: {self.stage}, {self.done} of {self.total} · {elapsed:.0f} s"

    @property
    def usable(self) -> bool:
        """False once cancelled or when its process died: asking again then starts afresh."""
        if self.future.cancelled():
            return False
        if not self.future.done():
            return not self.cancel.is_set()
        return not isinstance(self.future.exception(), (StudyCancelled, BrokenProcessPool))


class Jobs:
    """Running and finished studies of every session, by key; the oldest finished go first."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.items: OrderedDict[str, Job] = OrderedDict()

    def get_or_start(self, key: str, name: str, case: Case, settings: StudySettings) -> Job:
        """The job of ``key`` (see :func:`study_key`) if it is usable, else a new run of it."""
        with self.lock:
            job = self.items.get(key)
            if job is not None and job.usable:
                self.items.move_to_end(key)
                return job
            manager = _manager()
            channel, cancel = manager.Queue(), manager.Event()
            future = study_pool().submit(run_in_worker, name, case, settings, channel, cancel)
            job = self.items[key] = Job(key, name, future, channel, cancel)
            finished = [k for k, j in self.items.items() if j.future.done()]
            for old in finished[:max(0, len(finished) - KEPT)]:
                del self.items[old]
            return job

    def cancel(self, keys: Sequence[str]) -> None:
        """Cancel these studies: a queued one never starts, a running one stops after its solve."""
        with self.lock:
            for key in keys:
                job = self.items.get(key)
                if job is not None and not job.future.done():
                    job.cancel.set()
                    job.future.cancel()


@st.cache_resource(show_spinner=False)
def jobs() -> Jobs:
    return Jobs()


def requested(page: str) -> set[str]:
    return st.session_state.setdefault(f"{page}_requested", set())


def _cancel(page: str, keys: list[str]) -> None:
    jobs().cancel(keys)
    requested(page).difference_update(keys)
    st.session_state[f"{page}_cancelled"] = True


def run(studies: dict[str, str], case: Case, settings: StudySettings, page: str,
        start: bool) -> dict[str, StudyOutput] | None:
    """The outputs of ``studies`` (name → title) for ``case`` and ``settings``, with progress.

    ``start``: the page's run button was pressed. Without it the page shows the
    studies only if this session asked for this very input before (from the store, or
    by waiting for the run under way). Returns ``None`` when there is nothing to show
    yet, or when a study was cancelled or refused (the reason is shown in place).
    """
    digest = case_key(case)
    keyed = {name: study_key(name, digest, settings) for name in studies}
    keys = list(keyed.values())
    asked = requested(page)
    if start:
        asked.update(keys)
        st.session_state.pop(f"{page}_cancelled", None)
    if not all(key in asked for key in keys):
        if st.session_state.pop(f"{page}_cancelled", False):
            st.info("Cancelled. Press **Run** to start again.", icon=":material/cancel:")
        else:
            changed = "The inputs changed since the last run. " if asked else ""
            st.info(f"{changed}Set the inputs and press **Run**.", icon=":material/info:")
        return None
    try:
        running = {name: jobs().get_or_start(key, name, case, settings) for name, key in keyed.items()}
    except (OSError, EOFError, BrokenProcessPool):
        _restart()
        st.error("The study processes stopped unexpectedly; press **Run** again to restart them.",
                 icon=":material/error:")
        return None
    _wait(running, studies, page, keys)
    return _outputs(running, studies, page, keys)


def _wait(running: dict[str, Job], studies: dict[str, str], page: str, keys: list[str]) -> None:
    """Draw a progress bar per study until every one ends; the page can cancel them."""
    for job in running.values():
        job.poll()
    if all(job.future.done() for job in running.values()):
        return
    controls = st.empty()  # cleared once every study ended
    with controls.container():
        st.button("Cancel", key=f"{page}_cancel", icon=":material/stop_circle:", on_click=_cancel,
                  args=(page, keys), help="Stops the studies after the solve under way (for every tab waiting "
                                          "on this input).")
        st.caption("Leaving the page or changing an input only stops waiting: a started study finishes in the "
                   "background and its results are here when you come back. **Cancel** stops it.")
    with st.status(f"Running {len(running)} stud{'y' if len(running) == 1 else 'ies'}…", expanded=True) as status:
        bars = {name: st.progress(0.0, text=f"{studies[name]}: starting") for name in running}
        while True:
            for name, job in running.items():
                job.poll()
                fraction, text = job.line()
                bars[name].progress(min(1.0, fraction), text=f"**{studies[name]}** · {text}")
            if all(job.future.done() for job in running.values()):
                break
            wait([job.future for job in running.values()], timeout=POLL_S, return_when=ALL_COMPLETED)
        elapsed = max((job.finished or time.perf_counter()) - job.started for job in running.values())
        status.update(label=f"Done in {elapsed:.0f} s", state="complete", expanded=False)
    controls.empty()


def _outputs(running: dict[str, Job], studies: dict[str, str], page: str,
             keys: list[str]) -> dict[str, StudyOutput] | None:
    outputs, refused = {}, False
    for name, job in running.items():
        try:
            outputs[name] = job.future.result()
        except (StudyCancelled, CancelledError):
            requested(page).difference_update(keys)
            st.info(f"{studies[name]} was cancelled (in this tab or in another one waiting on the same input). "
                    "Press **Run** to start again.", icon=":material/cancel:")
            return None
        except BrokenProcessPool:
            _restart()
            st.error("The study process stopped unexpectedly (out of memory?); press **Run** again to restart it.",
                     icon=":material/error:")
            return None
        except RvppError as err:
            widgets.refusal(err, f"{studies[name]}: cannot run", note="Change the settings or the case.")
            refused = True
    return None if refused else outputs


def _restart() -> None:
    study_pool.clear()
    _manager.clear()
    with jobs().lock:
        jobs().items.clear()


def numbers(text: str, label: str, whole: bool = False) -> tuple[float, ...] | tuple[int, ...]:
    """``"70, 60, 50"`` → ``(70.0, 60.0, 50.0)`` (whole numbers with ``whole``); a part that
    is not a number is refused with ``label`` and the part."""
    try:
        return parse_numbers(text, whole)
    except ValueError as err:
        raise RvppError(f"{label}: {err}") from None


def listed(values: Sequence[float] | None) -> str:
    """The inverse of :func:`numbers`: ``(70.0, 60.0)`` → ``"70, 60"``."""
    return ", ".join(f"{v:g}" for v in values or ())


def downloads(outputs: Sequence[StudyOutput], stem: str, key: str) -> None:
    """Every table of ``outputs``: all in one Excel workbook, or one as CSV."""
    tables: dict[str, pd.DataFrame] = {name: table for out in outputs for name, table in out.tables.items()}
    first, second, third = st.columns([1, 1, 1], vertical_alignment="bottom")
    first.download_button("All tables (Excel)", lambda: tables_workbook_bytes(tables), file_name=f"{stem}.xlsx",
                          mime=EXCEL, on_click="ignore", key=f"{key}_xlsx", icon=":material/table:",
                          help="One sheet per table, full precision: " + ", ".join(tables))
    chosen = second.selectbox("Table", list(tables), key=f"{key}_csv_table")
    third.download_button("Table (CSV)", table_csv(tables[chosen]), file_name=f"{stem}_{chosen}.csv",
                          mime="text/csv", on_click="ignore", key=f"{key}_csv", icon=":material/download:",
                          help="The chosen table as CSV, full precision" + widgets.CSV_NOTE)
