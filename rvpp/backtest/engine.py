"""The rolling backtest: plan each day from what was known before it, settle it against what happened.

For every variant (a strategy, a Γ fraction or the perfect-information plan) and every
day ``D`` of the period, one pure step (:func:`run_day`):

1. **plan**: the case of day ``D`` starting from the state the settlement of ``D − 1``
   left (storage energy, turbine status and time in it), bands from the history before
   ``D`` (:func:`rvpp.uncertainty.problem.prepare` reads nothing of ``D`` itself), solved by
   :func:`plan`, on hourly days with ``D − 1``'s plan as MIP start (its integer variables
   at one, ``plan_integer_ones`` in the record);
2. **trade** (when intraday sessions are on, :mod:`rvpp.backtest.intraday`): each session in
   turn corrects the position from the forecasts at its gate closure (MODEL_SPEC §14);
3. **settle**: the plan's first-stage bids re-dispatched against ``D``'s own observations
   by the recourse model (:func:`rvpp.settle.recourse.evaluate`), which also reports the
   state at the end of the day;
4. **record**: one plain dict (settlement, plan numbers, bids, audit, start and end
   state), written to the store at once.

Days of one variant form a chain (day ``D + 1`` needs ``D``'s end state); chains run side
by side on the executor, each with at most one day in flight. The keys are computed up
front and a rerun skips the recorded ones, restoring each chain's state from its last
recorded day: resuming is the same code path as starting, and a crash loses at most the
days in flight.
"""

from __future__ import annotations

import datetime as dt
import math
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..data.case import Case
from ..data.history import History
from ..errors import RvppError
from ..settle.audit import audit_result
from ..settle.recourse import FirstStage, Realization, evaluate, first_stage, realization, realized_problem
from ..solving.plan import solve, solve_problem
from ..solving.outcome import Outcome
from ..solving.results import Result
from ..store import BacktestStore, RecordKey
from .intraday import trade_sessions
from .settings import BacktestSettings, BacktestVariant
from .state import State, initial_state, min_up_lifted, with_state

Progress = Callable[[int, int, "float | None"], None]  # (records done, records in all, seconds left)
TRADES = {"sold_mwh": ("p_da_mw", 1), "bought_mwh": ("p_da_mw", -1), "sr_up_mwh": ("r_sr_up_mw", 1),
          "sr_dn_mwh": ("r_sr_dn_mw", 1), "heat_bought_mwh": ("h_hpa_mw", 1)}
BIDS = ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw")
HISTORY_MARGIN_DAYS = 8  # days of history kept before a task's band window (e.g. a price a week before)
# Days of shorter periods are planned cold: at 15 minutes the day before's plan as start shortened 24
# solves in all but made one 4.5 times slower (docs/performance.md), and the tail is what counts there.
STARTED_PERIOD_MIN_H = 1.0


def plan(case: Case, keep_schedule: bool = False) -> Result:
    """The plan of a day: the one place to plug in a faster solve (same case in, same result out);
    ``keep_schedule``: with every unit variable's value, for the intraday sessions after it."""
    return solve(case, keep_schedule=keep_schedule)


def perfect_plan(case: Case, real: Realization) -> Result:
    """The plan made on the realized values of the day: bands of zero width at what happened."""
    return solve_problem(realized_problem(case, real))


TRIP_NOTE = ("planned with the turbine free to stop from the first period: the minimum up time carried from "
             "the day before left no feasible plan (the settlement lets a turbine trip too)")


def day_plan(case: Case, make: Callable[[Case], Result]) -> tuple[Case, Result, bool]:
    """The day's plan by ``make``, and the case it was made for. A day left without a feasible plan by a
    minimum up time carried from the day before (a turbine online at midnight with too little heat
    to run on) is planned again with that time counted as done, as the settlement lets a turbine trip;
    the flag says so (docs/backtest.md)."""
    result = make(case)
    if result.status != Outcome.INFEASIBLE:
        return case, result, False
    lifted = min_up_lifted(case)
    if lifted is case:
        return case, result, False
    again = make(lifted)
    return (lifted, again, True) if again.has_plan else (case, result, False)


@dataclass(frozen=True, eq=False)
class DayTask:
    """One step of a chain, sent to a worker: plain data, nothing Pyomo."""

    case: Case
    day: dt.date
    variant: BacktestVariant
    state: State
    settings: BacktestSettings
    start: tuple[str, ...] = ()  # the day before's plan_integer_ones: the MIP start of this day's plan

    @property
    def key(self) -> RecordKey:
        return RecordKey(self.day.isoformat(), self.variant.strategy, self.variant.gamma)


def one_thread(case: Case) -> Case:
    """``case`` solved by HiGHS on one thread: workers side by side do not oversubscribe the cores, and a
    single-threaded solve is deterministic, so a resumed backtest ends exactly as an uninterrupted one."""
    return case if case.solver.threads == 1 else case.replace(solver={"threads": 1})


def day_history(case: Case, day: dt.date, margin_days: int = HISTORY_MARGIN_DAYS) -> Case:
    """``case`` with only the history a day needs: its band window (plus ``margin_days``) and the day.

    Keeps tasks small when they travel to workers; the plan and settlement are the same
    as on the whole history (a test checks it), since :func:`rvpp.uncertainty.problem.prepare`
    reads the window before the day and the settlement the day itself.
    """
    first = pd.Timestamp(day - dt.timedelta(days=case.uncertainty.window_days + margin_days)).tz_localize(case.timezone)
    last = pd.Timestamp(day + dt.timedelta(days=1)).tz_localize(case.timezone)
    start, end = max(first, case.history.start), min(last, case.history.end)
    frame = case.history.between(start, end)
    return case.replace(history=History(frame, source=case.history.source))


def day_case(base: Case, day: dt.date, variant: BacktestVariant, state: State, storage_end: str | float,
             start: tuple[str, ...] = ()) -> Case:
    """The case a day is planned and settled with: its date, its variant's budgets, its start state and,
    given ``start`` on a day of hourly periods, the day before's plan as MIP start (it shortens the
    solve; any optimum within the gap may come out, so a day is planned again from the same start to
    give the same plan)."""
    case = with_state(variant.case(base, delivery_date=day), state, storage_end)
    return case.replace(solver={"mip_start": start}) if start and case.dt_h >= STARTED_PERIOD_MIN_H else case


def run_day(task: DayTask) -> dict[str, Any]:
    """Plan, settle and audit one day of one variant: the day's record (plain data).

    A day without a usable plan (infeasible, solver failure) bids nothing and is settled
    as such; a day whose case cannot be prepared is recorded as an error. Either way the
    chain goes on: the next day starts from this day's settled state, or from this day's
    start state when there is no settlement.
    """
    started = time.perf_counter(), time.process_time()
    settings = task.settings
    record: dict[str, Any] = {"day": task.day.isoformat(), "strategy": task.variant.strategy,
                              "gamma": task.variant.gamma, "label": task.variant.label,
                              "fraction": task.variant.fraction, "start_state": task.state}
    try:
        case = day_case(task.case, task.day, task.variant, task.state, settings.storage_end, task.start)
        real = realization(case, task.day)
        intraday = settings.trades_intraday(case) and not task.variant.is_perfect
        if task.variant.is_perfect:
            case, result, lifted = day_plan(case, lambda day: perfect_plan(day, real))
        else:
            case, result, lifted = day_plan(case, lambda day: plan(day, keep_schedule=True) if intraday else plan(day))
    except RvppError as exc:
        return _finish({**record, "status": "error", "plan_status": "error", "message": str(exc),
                        "end_state": task.state, "state_source": "start (the day could not be prepared)"}, started)
    record.update(plan_numbers(result))
    if lifted:
        record["message"] = f"{TRIP_NOTE}; {result.message}" if result.message else TRIP_NOTE
    record["plan_integer_ones"] = list(result.integer_ones)
    bids = first_stage(result, settings.fix_commitment) if result.has_plan else no_bids(result.problem.nt)
    record["bids"] = {name: getattr(bids, name.removesuffix("_mw")).tolist() for name in BIDS}
    record.update(trade_numbers(bids, case.dt_h))
    if settings.audit and result.has_plan:
        t0 = time.perf_counter()
        violations = audit_result(result, bands=result.problem.bands if task.variant.is_perfect else None)
        record.update(audit_violations=len(violations), audit_first=str(violations[0]) if violations else "",
                      audit_s=time.perf_counter() - t0)
    if intraday:  # a day without a plan trades no session: it has no schedule to correct
        sessions: list[dict[str, Any]] = []
        if result.has_plan:
            try:
                bids, sessions = trade_sessions(case, result, bids, real, settings.penalties, settings.audit)
            except RvppError as exc:  # the sessions could not be placed on the day: settled on the day-ahead bids
                sessions = [{"status": "error", "message": str(exc)}]
        record["intraday"] = sessions
        record["final_position_mw"] = bids.position.tolist()
    settled = evaluate(case, bids, real, settings.penalties, with_end_state=True)
    record.update({
        "status": str(settled.pop("status")), "realization": settled.pop("fingerprint"),
        "settle_solve_s": settled.pop("solve_s"), "settle_mip_gap": settled.pop("mip_gap"),
    })
    settled.pop("day")
    end = settled.pop("end_state")
    record.update(settled)  # the settlement [EUR], slacks [MWh] and the settled CSP dispatch
    if "intraday" in record:
        record["intraday_revenue_eur"] = record["revenue_intraday_eur"]
    if end is None:
        record.update(end_state=task.state, state_source="start (the settlement has no solution)")
    else:
        record.update(end_state=end, state_source="settlement")
    return _finish(record, started)


def reopen_case(store: BacktestStore, ident: str, key: RecordKey) -> Case:
    """The case one recorded day was planned with: its date, its variant's budgets, its recorded
    start state and the day before's plan as MIP start, solved on one thread (``plan`` of it gives
    the recorded plan again)."""
    case, stored = store.load(ident)
    settings = BacktestSettings.from_stored(stored)
    records = store.record_map(ident)
    record = records.get(key)
    if record is None:
        raise RvppError(f"backtest {ident} has no record of {key.day}, {key.strategy}, {key.gamma}")
    variant, day = BacktestVariant(key.strategy, key.gamma), dt.date.fromisoformat(key.day)
    before = records.get(RecordKey((day - dt.timedelta(days=1)).isoformat(), key.strategy, key.gamma)) \
        if day > settings.first_day else None
    return day_case(one_thread(case), day, variant, record["start_state"], settings.storage_end,
                    plan_start(before))


def reopen_plan(store: BacktestStore, ident: str, key: RecordKey) -> Result:
    """The plan of one recorded day, solved again from the day's recorded start state (with every
    table of a :class:`~rvpp.solving.results.Result`, e.g. to show a worst day)."""
    day_of = reopen_case(store, ident, key)
    if key.strategy == BacktestVariant.perfect().strategy:
        real = realization(day_of, dt.date.fromisoformat(key.day))
        return day_plan(day_of, lambda day: perfect_plan(day, real))[1]
    return day_plan(day_of, plan)[1]


def plan_numbers(result: Result) -> dict[str, Any]:
    """How the plan ended and its own numbers (robust objective, budgets, timings)."""
    return {"plan_status": str(result.status), "message": result.message, "periods": result.problem.nt,
            "plan_objective_eur": result.objective_eur, "plan_bound_eur": result.bound_eur,
            "plan_mip_gap": result.mip_gap, "plan_build_s": result.build_s, "plan_solve_s": result.solve_s,
            "plan_nodes": result.nodes, "plan_lp_iterations": result.lp_iterations,
            "plan_protection_eur": sum(result.protection_eur.values()) if result.protection_eur else None,
            "budgets": result.problem.budgets}


def plan_start(record: dict[str, Any] | None) -> tuple[str, ...]:
    """The MIP start a recorded day hands to the next day's plan (none from a day without a plan, or
    from a record written before plans were started from the day before)."""
    return tuple((record or {}).get("plan_integer_ones") or ())


def no_bids(nt: int) -> FirstStage:
    """The bids of a day without a plan: nothing offered, nothing bought."""
    zero = np.zeros(nt)
    return FirstStage(zero, zero.copy(), zero.copy(), zero.copy())


def trade_numbers(bids: FirstStage, dt_h: float) -> dict[str, float]:
    """Energy sold and bought, reserve bands and heat bought over the day [MWh], [MWh_th]."""
    out = {}
    for key, (name, sign) in TRADES.items():
        values = getattr(bids, name.removesuffix("_mw"))
        out[key] = float(np.clip(sign * values, 0.0, None).sum() * dt_h)
    return out


def _finish(record: dict[str, Any], started: tuple[float, float]) -> dict[str, Any]:
    """The record with its wall time and the CPU time of the process that computed it [s]."""
    record["wall_s"] = time.perf_counter() - started[0]
    record["cpu_s"] = time.process_time() - started[1]
    return _plain(record)


def _plain(value: Any) -> Any:
    """JSON-safe data: numpy numbers as Python numbers, NaN and infinities as ``None``."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    return value


# ----------------------------------------------------------------------------- the loop


def backtest_keys(settings: BacktestSettings) -> list[RecordKey]:
    """Every record the backtest will hold, day by day."""
    return [RecordKey(day.isoformat(), v.strategy, v.gamma) for day in settings.days for v in settings.variants]


@dataclass
class _Chain:
    """The days of one variant, where it stands and the state it hands on."""

    variant: BacktestVariant
    position: int
    state: State
    start: tuple[str, ...] = ()


def run_backtest(case: Case, settings: BacktestSettings, store: BacktestStore | None = None,
                 executor: Executor | None = None, progress: Progress | None = None, label: str = "",
                 on_record: Callable[[RecordKey, dict], None] | None = None) -> str:
    """Run (or resume) the backtest of ``settings`` on ``case``; return its id in ``store``.

    Every record is written to ``store`` as it finishes. ``executor``: ``None`` runs every
    day in this process; a process pool or a Dask executor runs the chains side by side.
    ``progress(done, total, eta_s)`` is called once before the first day and after each.
    """
    settings.check_case(case)
    store = store or BacktestStore()
    base = one_thread(case)
    keys = backtest_keys(settings)
    ident = store.open(case, settings.stored(), keys_total=len(keys), label=label)
    recorded = store.record_map(ident)
    days = settings.days
    chains = [_Chain(variant, 0, initial_state(base)) for variant in settings.variants]
    clock = _Clock(len(keys), len(recorded))
    report = progress or (lambda _done, _total, _eta: None)
    store.set_progress(ident, "running", clock.done, clock.total, None, "", started_at=_now())

    sliced: dict[dt.date, Case] = {}

    def task_case(day: dt.date) -> Case:
        """The case of a task, with the history of its day only (shared by the chains, kept while in use)."""
        if day not in sliced:
            for old in [d for d in sliced if d < day - dt.timedelta(days=1)]:
                del sliced[old]
            sliced[day] = day_history(base, day)
        return sliced[day]

    def advance(chain: _Chain) -> DayTask | None:
        """Skip the recorded days (taking their end state); the next day to compute, if any."""
        while chain.position < len(days):
            day = days[chain.position]
            key = RecordKey(day.isoformat(), chain.variant.strategy, chain.variant.gamma)
            if key not in recorded:
                return DayTask(task_case(day), day, chain.variant, chain.state, settings, chain.start)
            chain.state, chain.start = recorded[key]["end_state"], plan_start(recorded[key])
            chain.position += 1
        return None

    pool = executor or _InlineExecutor()
    running: dict[Future, tuple[_Chain, DayTask]] = {}

    def submit(chain: _Chain) -> None:
        task = advance(chain)
        if task is not None:
            running[pool.submit(run_day, task)] = (chain, task)

    report(clock.done, clock.total, None)
    try:
        for chain in chains:
            submit(chain)
        while running:
            finished, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for future in finished:
                chain, task = running.pop(future)
                record = future.result()
                store.record(ident, task.key, record)
                recorded[task.key] = record
                if on_record is not None:
                    on_record(task.key, record)
                clock.tick()
                store.set_progress(ident, "running", clock.done, clock.total, clock.eta_s)
                report(clock.done, clock.total, clock.eta_s)
                chain.state, chain.start = record["end_state"], plan_start(record)
                chain.position += 1
                submit(chain)
    except BaseException as exc:
        for future in running:
            future.cancel()
        state = "interrupted" if isinstance(exc, (KeyboardInterrupt, SystemExit)) else "failed"
        store.set_progress(ident, state, clock.done, clock.total, None, _describe(exc))
        raise
    store.set_progress(ident, "finished", clock.done, clock.total, 0.0, "")
    return ident


def _describe(exc: BaseException) -> str:
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted; run the same backtest again to resume"
    if isinstance(exc, SystemExit):
        return "stopped; run the same backtest again to resume"
    return f"{type(exc).__name__}: {exc}"


def _now() -> str:
    return dt.datetime.now(dt.timezone.utc).isoformat(timespec="microseconds")


class _Clock:
    """Records done and the time left, from this run's pace (earlier runs' records count as done)."""

    def __init__(self, total: int, done: int):
        self.total, self.done, self.computed = total, done, 0
        self.started = time.perf_counter()

    def tick(self) -> None:
        self.done += 1
        self.computed += 1

    @property
    def eta_s(self) -> float | None:
        if not self.computed:
            return None
        return (time.perf_counter() - self.started) / self.computed * (self.total - self.done)


class _InlineExecutor(Executor):
    """Runs each task when submitted, in this process (the serial case of the same loop)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as exc:  # handed to the loop, which re-raises it through future.result()
            future.set_exception(exc)
        return future
