"""Solves for the dashboard: cached by their full input, run in worker processes.

A solve is a pure function of its frozen :class:`~rvpp.data.case.Case`, so results are cached
with ``st.cache_data`` keyed by the case's content (:func:`dashboard.state.case_key`):
going back to a page is instant and any changed input is a new key.

Solves run in a small pool of worker processes shared by every session. Two solves in
threads of one process are not safe (the solver interface redirects the process's
output streams), and a process keeps the server responsive: a session waiting for its
solve only polls, so other sessions never freeze, and pressing Stop (or changing an
input) ends the wait at once while the worker finishes and caches the result.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

import streamlit as st
from streamlit.runtime.scriptrunner import add_script_run_ctx, get_script_run_ctx

import rvpp
from rvpp import Case, CaseError, ModelError, Problem, Result, RvppError

from . import widgets
from .state import case_key

MAX_WORKERS = 2        # solver processes shared by all sessions; more would compete for a small server's cores
WORKERS = max(1, min(MAX_WORKERS, os.cpu_count() or 1))
CACHE_ENTRIES = 64     # solved cases kept in memory (about 1.3 MB each)
POLL_S = 0.1           # how often a waiting page refreshes its progress [s]


@st.cache_resource(show_spinner=False)
def worker_pool() -> ProcessPoolExecutor:
    """The shared solver processes, started once and warmed up (imports done)."""
    pool = ProcessPoolExecutor(max_workers=WORKERS, mp_context=multiprocessing.get_context("spawn"))
    for _ in range(WORKERS):
        pool.submit(_import_solver)
    return pool


def _import_solver() -> None:
    """Runs in a worker: import Pyomo and the model once (returns nothing to send back)."""
    importlib.import_module("rvpp.solving.plan")


@st.cache_data(max_entries=CACHE_ENTRIES, show_spinner=False, hash_funcs={Case: case_key})
def solve_cached(case: Case) -> Result:
    """``rvpp.solve(case)`` in a worker process, cached by the case's content."""
    try:
        return worker_pool().submit(rvpp.solve, case).result()
    except BrokenProcessPool:
        worker_pool.clear()
        raise ModelError("the solver process stopped unexpectedly (out of memory?); solve again to restart it") \
            from None


def solve(case: Case, label: str) -> Result | None:
    """Solve ``case`` showing a status line with the elapsed time.

    Returns the result, or ``None`` when the case cannot be solved at all (e.g. its
    history does not cover the delivery date); the reason is shown in place.
    """
    started = time.perf_counter()
    with st.status(f"{label}…", expanded=False) as status:
        future = _in_background(solve_cached, case)
        while not future.done():
            status.update(label=f"{label}… {time.perf_counter() - started:.1f} s")
            wait([future], timeout=POLL_S)
        try:
            result = future.result()
        except RvppError as err:
            status.update(label=f"{label}: the case cannot be solved", state="error")
            widgets.refusal(err, "Cannot solve", note="Fix the case on the other pages and solve again.")
            return None
        state = "complete" if result.has_plan else "error"
        status.update(label=f"{label}: {result.status} in {time.perf_counter() - started:.1f} s", state=state)
    return result


def solve_all(cases: Sequence[Case], label: str) -> list[Result]:
    """Solve several cases side by side in the worker processes, with a progress bar.

    Each case is cached on its own, so a plan solved here is instant on the Results
    page and the other way round. Raises :class:`~rvpp.errors.RvppError` if a case
    cannot be solved at all.
    """
    started = time.perf_counter()
    bar = st.progress(0.0, text=f"{label}: 0 of {len(cases)} solved")
    futures = [_in_background(solve_cached, case) for case in cases]
    pending = set(futures)
    while pending:
        _, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
        done = len(cases) - len(pending)
        bar.progress(done / len(cases), text=f"{label}: {done} of {len(cases)} solved, "
                                             f"{time.perf_counter() - started:.1f} s")
    bar.empty()
    return [f.result() for f in futures]


def _in_background(fn: Callable, *args) -> Future:
    """Run ``fn(*args)`` in a thread of this session, so the page can keep drawing progress."""
    future: Future = Future()

    def run() -> None:
        if future.set_running_or_notify_cancel():
            try:
                future.set_result(fn(*args))
            except BaseException as exc:  # handed to the page, which shows it
                future.set_exception(exc)

    thread = threading.Thread(target=run, name="rvpp-solve", daemon=True)
    add_script_run_ctx(thread, get_script_run_ctx())
    thread.start()
    return future


@st.cache_data(max_entries=CACHE_ENTRIES, show_spinner=False, hash_funcs={Case: case_key})
def prepare_cached(case: Case) -> Problem:
    """``rvpp.prepare(case)``: the delivery day's periods, forecast bands and budgets."""
    return rvpp.prepare(case)


def prepare(case: Case) -> Problem | None:
    """The prepared day, or ``None`` with the reason shown when the case cannot be prepared."""
    try:
        return prepare_cached(case)
    except CaseError as err:
        widgets.problems(err.problems, "The delivery day cannot be prepared",
                         note="Change the date, the history window or the budgets.")
        return None
