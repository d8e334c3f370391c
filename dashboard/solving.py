"""Solves for the dashboard: one solver process per solve, kept by their full input, cancellable.

A solve is a pure function of its frozen :class:`~rvpp.data.case.Case`, so its result is
kept by the case's content (:func:`dashboard.state.case_key`) in a server-wide table
shared by every session: going back to a page is instant and any changed input is a new
key. Saved runs reopened from the library go into the same table, so they show without
a solve.

Each solve runs in a **process of its own**, forked from a fork server that imported
Pyomo and HiGHS once (``multiprocessing``'s ``forkserver`` start method with a preload),
so starting one takes milliseconds. Two reasons for processes:

* two solves in threads of one process are not safe (the solver interface redirects the
  process's output streams), and Streamlit runs every session in a thread of one
  process;
* a process can be stopped: **Cancel** kills the solve's process at once, wherever HiGHS
  is, and frees the core immediately.

A single solve also reports the solver's search (the best plan so far and its gap, every
quarter second) and can be **stopped early**: the page sets the job's event, the solver
process's watch (:data:`rvpp.solving.outcome.Watch`) sees it and HiGHS ends with the best
plan found so far (status ``stopped``). That plan is kept like any other until Solve is
pressed again, which searches on to the optimum; its time is not taken as the case's
expected time.

A **sweep** solves one case for a grid of budgets Γ (the same Γ for every source) in one
solver process with :func:`rvpp.solving.sweep.sweep_gamma`, which builds the day's
model once and re-solves it in place for each Γ. It is kept like a solve, by the case's
content and the grid, in a table of its own: once it is warm, a page picks the plan of
any Γ of the grid without solving (:func:`swept`).

At most :data:`WORKERS` solves run at once (the others wait for a free slot, shown on
the page). A page waiting for its solve only polls (every :data:`POLL_S`) and draws
the elapsed time, the solver's stage and an estimate from the last solve of the same
case, or of a case of the same shape; leaving the page or changing an input only stops
waiting, and the solve finishes and is kept for when the page is shown again.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import threading
import time
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime

import streamlit as st

import rvpp
from rvpp import Case, CaseError, Problem, Result, RvppError
from rvpp.service import Outcome, tied_budgets

from . import widgets, worker
from .state import REQUESTED, case_key

MAX_WORKERS = 2        # solves at once; more would compete for a small server's cores
WORKERS = max(1, min(MAX_WORKERS, os.cpu_count() or 1))
KEPT = 64              # solved cases kept in memory (about 1.3 MB each)
KEPT_SWEEPS = 4        # sweeps kept in memory (25 plans, about 30 MB, on the default day)
POLL_S = 0.1           # how often a waiting page refreshes its progress [s]
JOIN_S = 5.0           # how long to wait for a finished solver process to exit [s]
PRELOAD = ["dashboard.preload"]  # what every solver process starts with
CONTEXT = multiprocessing.get_context("forkserver")
CANCELLED = "solve_cancelled"  # session key: the last solve of this session was cancelled


class SolveCancelled(rvpp.RvppError):
    """The solve was cancelled before it ended."""


@dataclass(eq=False)
class Job:
    """One solve (or, with ``gammas``, one sweep) in its own process: its stage, its outcome
    and its cancel switch."""

    key: str
    case: Case
    gammas: tuple[int, ...] | None = None
    started: float = field(default_factory=time.perf_counter)
    began: float | None = None  # when it had a solver slot: a solve's time counts from here
    stage: str = "waiting for a free solver"
    done_points: tuple[int, int] | None = None  # a sweep's plans solved so far, of how many
    finished: float | None = None
    returned_at: float | None = None  # wall-clock time (epoch) the answer came back from the solver
    result: Result | list[Result] | None = None
    problems: list[str] | None = None
    cancelled: bool = False
    search: object | None = None  # the solver's last report on its search (rvpp.Search)
    stop: object = field(default_factory=CONTEXT.Event)  # set: end the search at its best plan
    process: multiprocessing.process.BaseProcess | None = None
    done: threading.Event = field(default_factory=threading.Event)

    @property
    def elapsed_s(self) -> float:
        """How long the page has waited for it, its time waiting for a free solver included."""
        return (self.finished or time.perf_counter()) - self.started

    @property
    def solve_s(self) -> float:
        """How long it took once it had a solver: the time an estimate of the same work may promise
        (a solve that waited for another's slot would otherwise count that wait as its own)."""
        return (self.finished or time.perf_counter()) - (self.began or self.started)

    def run(self, solver: "Solver") -> None:
        """In a thread of the server: wait for a slot, solve in a new process, keep the outcome.

        The outcome is handed over before the solver process has exited: the page draws the plan
        while the process ends (5-15 ms), and the slot is freed once it has.
        """
        with solver.slots:
            self.began = time.perf_counter()
            if not self.cancelled:
                self._solve()
            solver.finish(self)
            if self.process is not None:
                self.process.join(JOIN_S)

    def _solve(self) -> None:
        receive, send = CONTEXT.Pipe(duplex=False)
        target, args = ((worker.solve_into, (send, self.case, self.stop)) if self.gammas is None
                        else (worker.sweep_into, (send, self.case, list(self.gammas))))
        self.process = CONTEXT.Process(target=target, args=args, daemon=True, name="rvpp-solve")
        self.stage = "starting the solver"
        self.process.start()
        send.close()
        try:
            while True:
                kind, payload = receive.recv()
                if kind == "stage":
                    self.stage = payload
                    continue
                if kind == "search":
                    self.search = payload
                    self.stage = searching(payload, self.stop.is_set())
                    continue
                if kind == "progress":
                    self.done_points = payload
                    self.stage = f"{payload[0]} of {payload[1]} plans solved"
                    continue
                self.returned_at = time.time()
                if kind == "result":
                    self.result = payload
                else:
                    self.problems = payload if kind == "refused" else [f"the solver failed: {payload}"]
                break
        except EOFError:  # the process ended without an answer: killed by Cancel, or out of memory
            self.process.join(JOIN_S)  # gone before the job says it is done
            if not self.cancelled:
                self.problems = ["the solver process stopped unexpectedly (out of memory?); solve again"]
        finally:
            receive.close()


class Solver:
    """The server's solves: running jobs, kept results and measured times."""

    def __init__(self, workers: int):
        self.slots = threading.BoundedSemaphore(workers)
        self.lock = threading.Lock()
        self.jobs: dict[str, Job] = {}
        self.results: OrderedDict[str, Result] = OrderedDict()
        self.sweeps: OrderedDict[str, list[Result]] = OrderedDict()
        self.seconds: dict[str, float] = {}        # case key -> wall time of its last solve [s]
        self.shape_seconds: dict[tuple, float] = {}  # case shape -> wall time of its last solve [s]
        self.last_solve: tuple[float, int] | None = None  # the last single solve without ties: [s], periods

    def result(self, key: str) -> Result | None:
        with self.lock:
            if key in self.results:
                self.results.move_to_end(key)
            return self.results.get(key)

    def remember(self, result: Result) -> None:
        """Keep a result (e.g. of a reopened saved run) as if it had been solved here."""
        with self.lock:
            self._keep(case_key(result.case), result)

    def sweep(self, key: str) -> list[Result] | None:
        """The plans of a finished sweep (:func:`sweep_key`), or ``None``."""
        with self.lock:
            if key in self.sweeps:
                self.sweeps.move_to_end(key)
            return self.sweeps.get(key)

    def start(self, case: Case, gammas: Sequence[int] | None = None) -> Job:
        """The job solving ``case`` (or sweeping it over ``gammas``): the one under way, or a new one."""
        grid = None if gammas is None else tuple(int(g) for g in gammas)
        key = case_key(case) if grid is None else sweep_key(case, grid)
        with self.lock:
            job = self.jobs.get(key)
            if job is not None and not job.cancelled:
                return job
            job = self.jobs[key] = Job(key, case, grid)
        threading.Thread(target=job.run, args=(self,), name="rvpp-solve", daemon=True).start()
        return job

    def cancel(self, keys: Sequence[str]) -> None:
        """Stop the solves of ``keys``: a waiting one never starts, a running one is killed."""
        for job in self._jobs(keys):
            job.cancelled = True
            if job.process is not None and job.process.is_alive():
                job.process.kill()

    def running(self, key: str) -> bool:
        """Whether a solve of ``key`` is waiting or under way."""
        with self.lock:
            job = self.jobs.get(key)
            return job is not None and not job.cancelled

    def stop(self, keys: Sequence[str]) -> None:
        """End the searches of the single solves ``keys`` at their best plan (at once if they have
        one, else at their first)."""
        for job in self._jobs(keys):
            job.stop.set()

    def _jobs(self, keys: Sequence[str]) -> list[Job]:
        """The jobs of ``keys`` waiting or under way."""
        with self.lock:
            return [self.jobs[k] for k in keys if k in self.jobs]

    def finish(self, job: Job) -> None:
        job.finished = time.perf_counter()
        with self.lock:
            if self.jobs.get(job.key) is job:
                del self.jobs[job.key]
            if job.result is not None:
                if job.gammas is None:
                    self._keep(job.key, job.result)
                else:
                    self.sweeps[job.key] = job.result
                    while len(self.sweeps) > KEPT_SWEEPS:
                        self.sweeps.popitem(last=False)
                if not stopped(job.result):  # a search cut short says nothing of the case's time
                    self.seconds[job.key] = job.solve_s
                    prepared = (job.result if job.gammas is None else job.result[0]).problem
                    self.shape_seconds[shape(job.case, job.gammas, prepared)] = job.solve_s
                    if job.gammas is None and not tied_budgets(prepared):
                        self.last_solve = (job.solve_s, periods_of(job.case))
        job.done.set()

    def expected_s(self, case: Case, gammas: Sequence[int] | None = None) -> tuple[float, str] | None:
        """How long a solve of ``case`` (or its sweep over ``gammas``) should take and where
        that number comes from: always a time measured by this server, never a recorded one.

        The last solve (sweep) of the same case, else of a case of the same shape, else an
        extrapolation: the last solve measured here, scaled by the number of periods (and, for a
        sweep, times its number of Γ: each re-solve of a sweep is at most as long as a solve, so
        this errs on the long side). ``None`` before this server has solved anything, and for a
        day with ties without a measured solve of its shape (such days are several times slower).
        """
        work = "solve" if gammas is None else "sweep"
        key = case_key(case) if gammas is None else sweep_key(case, gammas)
        if key in self.seconds:
            return self.seconds[key], f"the last {work} of this case"
        like = shape(case, gammas)
        if like in self.shape_seconds:
            return self.shape_seconds[like], f"the last {work} of a case like this one on this server"
        if like[-1] or self.last_solve is None:
            return None
        last_s, last_periods = self.last_solve
        periods = periods_of(case)
        estimate = last_s * periods / last_periods * (1 if gammas is None else len(gammas))
        plans = "" if gammas is None else f"{len(gammas)} plans × "
        scale = "" if periods == last_periods else f" of {last_periods} periods, scaled to {periods}"
        return estimate, f"{plans}the last solve on this server{scale}"

    def _keep(self, key: str, result: Result) -> None:
        self.results[key] = result
        self.results.move_to_end(key)
        while len(self.results) > KEPT:
            self.results.popitem(last=False)


def stopped(result: Result | list[Result]) -> bool:
    """Whether ``result`` is a plan whose search was stopped early on request."""
    return isinstance(result, Result) and result.status is Outcome.STOPPED


def searching(search, stopping: bool) -> str:
    """The stage line of a solve whose solver reports its search (``rvpp.Search``)."""
    if search.objective is None:
        return "stopping at the first plan found" if stopping else "searching for a first plan"
    within = f"within {search.gap:.2%} of the optimum" if search.gap is not None else "no bound yet"
    return f"{'stopping: ' if stopping else ''}best plan so far {within} ({search.nodes:,} nodes)"


# Where a day's tied deviations are named, before and after its solve.
EARLIEST_HINT = ("On the Uncertainty page, *The earliest of them deviate* fixes them instead: faster, and a more "
                 "cautious plan.")


def shape(case: Case, gammas: Sequence[int] | None = None, problem: Problem | None = None) -> tuple:
    """What a solve's time depends on most: periods, strategy, budget mode, units, markets
    (and a sweep's number of Γ), and whether the solver must choose among tied deviations
    (:func:`tied`, read from ``problem`` when the case is already prepared; for a sweep, at
    how many of its Γ, :func:`tied_gammas`), which makes a day several times slower."""
    if gammas is None:
        ties = bool(tied_budgets(problem)) if problem is not None else bool(tied(case))
        return (*_case_shape(case), ties)
    return (*_case_shape(case), len(gammas), len(tied_gammas(case, gammas, problem)))


def _case_shape(case: Case) -> tuple:
    """Periods, strategy, budget mode, units and markets of ``case``."""
    return (case.dt_h, case.budgets.strategy, case.budgets.mode, len(case.unit_names()), case.markets.label)


def tied(case: Case) -> list[str]:
    """The deviations tied at the Γ boundary that a solve of ``case`` leaves to the solver
    (:func:`rvpp.uncertainty.problem.tied_budgets`) on the day :func:`prepare_cached` keeps, empty
    when the case cannot be prepared (its solve says why)."""
    try:
        return tied_budgets(prepare_cached(case))
    except RvppError:
        return []


def tied_gammas(case: Case, gammas: Sequence[int], problem: Problem | None = None) -> dict[int, list[str]]:
    """``{Γ: tied deviations}`` for the Γ of a sweep of ``case`` (one Γ for every source) at
    which the solver must choose among tied deviations (:func:`tied`); read from ``problem``
    (the case prepared, at any Γ) when given."""
    if problem is None:
        try:
            problem = prepare_cached(case)
        except RvppError:
            return {}
    return {g: ties for g in gammas if (ties := tied_budgets(problem, g))}


def sweep_key(case: Case, gammas: Sequence[int]) -> str:
    """A digest of a sweep's input: the case's content and the grid of Γ."""
    return hashlib.sha256(f"{case_key(case)}|sweep|{','.join(map(str, gammas))}".encode()).hexdigest()


def sweep_grid(nt: int, dt_h: float) -> list[int]:
    """The Γ a sweep solves for a day of ``nt`` periods of ``dt_h`` hours: every whole hour of
    periods from 0 to ``nt`` (25 plans on a day of 24 hours at any period length), always
    ending at ``nt``.

    A Γ between whole hours splits an hour's periods, which carry the same hourly forecast
    on most days, so every source's deviations would tie at the Γ boundary and the solver
    would have to choose among them (docs/performance.md, the tie days)."""
    step = max(1, round(1.0 / dt_h))
    return sorted({*range(0, nt + 1, step), nt})


def periods_of(case: Case) -> int:
    """The number of periods of ``case``'s delivery day (a whole day of its period length)."""
    return round(24 / case.dt_h)


@st.cache_resource(show_spinner=False)
def solver() -> Solver:
    """The server's solver; its fork server starts with :func:`start_fork_server`, or with the
    first solve if no run has got that far."""
    CONTEXT.set_forkserver_preload(PRELOAD)
    return Solver(WORKERS)


@st.cache_resource(show_spinner=False)
def start_fork_server() -> threading.Thread:
    """Start the fork server in the background, once per server process. ``app.py`` calls it
    once the page has been sent: its imports take about 3 s of processor time, which on a
    two-core server competed with the first session's script and browser for its first page."""
    solver()  # the preload is set before the fork server starts
    thread = threading.Thread(target=_start_fork_server, name="rvpp-fork-server", daemon=True)
    thread.start()
    return thread


def _start_fork_server() -> None:
    from multiprocessing import forkserver

    forkserver.ensure_running()


def solve(case: Case, label: str, again: bool = False, stoppable: bool = False) -> Result | None:
    """The plan of ``case``, solving it if needed while the page shows progress and Cancel
    (and, with ``stoppable``, **Stop early**: the page then shows the plan's status).

    ``again``: the user pressed the page's Solve button, so a kept plan whose search was
    stopped early is searched again. Returns ``None`` when the case cannot be solved at all
    (the reason is shown in place) or when the solve was cancelled.
    """
    results = solve_all([case], label, again, stoppable)
    return results[0] if results else None


def solve_all(cases: Sequence[Case], label: str, again: bool = False, stoppable: bool = False) -> list[Result] | None:
    """The plans of several cases, solved side by side, with one progress bar and Cancel
    (``again``, ``stoppable``: as for :func:`solve`).

    Each case is kept on its own, so a plan solved here is instant on another page and
    the other way round. Returns ``None`` (with the reason shown) when a case cannot be
    solved at all or the solves were cancelled.
    """
    server = solver()
    found = {case_key(c): server.result(case_key(c)) for c in cases}
    # A plan stopped early is searched again when asked, and not shown while that search runs.
    found = {key: None if result is not None and stopped(result) and (again or server.running(key)) else result
             for key, result in found.items()}
    jobs = [server.start(c) for c in cases if found[case_key(c)] is None]
    if jobs:
        _wait(jobs, label, len(cases), stoppable)
        for job in jobs:
            if _without_result(job, label, again="the solve button"):
                return None
            found[job.key] = job.result
        if len(cases) == 1:
            result = jobs[0].result
            # An expander, not st.status: st.status sleeps 50 ms on creation, before the plan is drawn.
            icon = ":material/check:" if result.has_plan else ":material/error:"
            with st.expander(f"{label}: {result.status} in {jobs[0].elapsed_s:.1f} s", icon=icon):
                st.caption(f"The solver's answer came back at {answered(jobs[0])} (server clock); what follows "
                           "is drawing.")
                if result.has_plan and (ties := tied_budgets(result.problem)):
                    st.caption("The model chose which of the tied deviations count (the exact rule, which makes "
                               f"such days slower to solve): {'; '.join(ties)}. {EARLIEST_HINT}")
    return [found[case_key(c)] for c in cases]


def swept(case: Case, gammas: Sequence[int]) -> list[Result] | None:
    """The plans of ``case`` for each Γ of ``gammas`` if this server has swept them, else ``None``
    (never solves)."""
    return solver().sweep(sweep_key(case, gammas))


def sweep(case: Case, gammas: Sequence[int], label: str) -> list[Result] | None:
    """The plans of ``case`` for each Γ of ``gammas`` (the same Γ for every source), sweeping
    them in one solver process if needed while the page shows progress and Cancel.

    Returns ``None`` (with the reason shown) when the case cannot be swept or the sweep
    was cancelled.
    """
    found = swept(case, gammas)
    if found is not None:
        return found
    job = solver().start(case, gammas)
    _wait([job], label, 1)
    return None if _without_result(job, label, again="the button") else job.result


def _without_result(job: Job, label: str, again: str) -> bool:
    """Whether ``job`` ended without a result; if so, say why in place (cancelled: press
    ``again`` to start again; refused: the reasons)."""
    if job.cancelled:
        st.info(f"{label}: cancelled after {job.elapsed_s:.1f} s. Press {again} to start again.",
                icon=":material/cancel:")
        return True
    if job.problems:
        widgets.problems(job.problems, "Cannot solve", note="Fix the case on the other pages and solve again.")
        return True
    return False


def answered(job: Job) -> str:
    """When the solver's answer reached the server, to the millisecond, as markdown that shows
    ``HH:MM:SS.mmm``. The colons are escaped: to Streamlit's markdown "10:15:22" holds an emoji
    name (":15:"), and its emoji code (about 270 kB) would then be loaded while the plan is drawn."""
    return f"{datetime.fromtimestamp(job.returned_at):%H:%M:%S.%f}"[:-3].replace(":", "\\:")


def _wait(jobs: list[Job], label: str, total: int, stoppable: bool = False) -> None:
    """Poll the jobs, drawing elapsed time, stage and an estimate, with a Cancel button (and, for
    ``stoppable`` single solves, Stop early)."""
    slot = st.empty()
    keys = [job.key for job in jobs]
    stoppable = stoppable and all(job.gammas is None for job in jobs)
    with slot.container():
        columns = st.columns([4, 1.5, 1.1] if stoppable else [6, 1], vertical_alignment="bottom")
        bar = columns[0].progress(0.0, text=f"{label}…")
        if stoppable:
            columns[1].button("Stop early", key=f"stop_{keys[0][:16]}", icon=":material/done_all:",
                              on_click=_stop, args=(keys,),
                              help="Ends the search with the best plan found so far, which may not be optimal: "
                                   "its gap to the optimum is shown with it. Solve again to search to the end.")
        columns[-1].button("Cancel", key=f"cancel_{keys[0][:16]}", icon=":material/stop_circle:",
                           on_click=_cancel, args=(keys,),
                           help="Stops the solve at once, without a plan (for every tab waiting on the same input).")
    expected = solver().expected_s(jobs[0].case, jobs[0].gammas) if len(jobs) == 1 else None
    while True:
        running = [job for job in jobs if not job.done.is_set()]
        elapsed = max(job.elapsed_s for job in jobs)
        done = total - len(running)
        points = jobs[0].done_points if len(jobs) == 1 else None
        if points and points[0]:  # a sweep under way: its share of plans solved, the rest extrapolated
            fraction = points[0] / points[1]
            left = elapsed * (points[1] - points[0]) / points[0]
            hint = f" · about {left:.0f} s left" if running and left >= 1 else ""
        elif expected:
            fraction = min(0.95, elapsed / max(expected[0], 1e-3))
            hint = f" · about {expected[0]:.0f} s expected ({expected[1]})" if expected[0] >= 1 else ""
        else:
            fraction = done / total if total > 1 else elapsed / (elapsed + 5.0)
            hint = ""
        stage = running[0].stage if len(jobs) == 1 and running else f"{done} of {total} solved"
        bar.progress(fraction if running else 1.0, text=f"{label}… {elapsed:.1f} s · {stage}{hint}")
        if not running:
            break
        running[0].done.wait(POLL_S)
    slot.empty()


def _stop(keys: list[str]) -> None:
    solver().stop(keys)


def _cancel(keys: list[str]) -> None:
    solver().cancel(keys)
    st.session_state[REQUESTED].difference_update(keys)
    st.session_state[CANCELLED] = True


def cancelled() -> bool:
    """Whether this session's last solve was cancelled (asked once: the answer is then forgotten)."""
    return bool(st.session_state.pop(CANCELLED, False))


@st.cache_data(max_entries=KEPT, show_spinner=False, hash_funcs={Case: case_key})
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
