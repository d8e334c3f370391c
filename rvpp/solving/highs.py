"""Run HiGHS on a Pyomo model through its matrix and report the outcome as a :class:`SolveOutcome`.

The model is compiled once to a sparse matrix (``compile_model``, by
:func:`rvpp.solving.linear.standard_form`) and handed to highspy directly, which costs a
fraction of Pyomo's own solver interface (measured on the paper case: 0.03 s instead of
0.2 s for a 24-period model, 0.07 s instead of 0.44 s for 96 periods). A :class:`HighsModel`
keeps the compiled matrix and the HiGHS object, so a caller that changes data in the
Pyomo model (mutable parameters, variable bounds) recompiles and re-solves without
rebuilding the model, optionally from a MIP start.

HiGHS's own model status is mapped to :class:`~rvpp.solving.outcome.Outcome`: a plan is
usable only when optimal, or when a limit (or a request) stopped the search with a
feasible incumbent and a finite bound.

A caller may *watch* a MIP search (:data:`~rvpp.solving.outcome.Watch`): it is shown the
search's state (:class:`~rvpp.solving.outcome.Search`) every :data:`WATCH_S` seconds of
HiGHS's clock and may end it, keeping the best plan found so far (``Outcome.STOPPED``).
"""

from __future__ import annotations

import gc
import math
import os
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass

import highspy
import numpy as np
import pyomo.environ as pyo
from pyomo.common.collections import ComponentMap
from pyomo.common.errors import InfeasibleConstraintException
from pyomo.common.gc_manager import PauseGC
from pyomo.core.base.var import VarData
from pyomo.repn.plugins.standard_form import LinearStandardFormCompiler

from .linear import StandardForm, TrivialInfeasibility, Unsupported, standard_form
from .outcome import Outcome, Search, SolveOutcome, Watch, relative_gap

# HiGHS options that are not exposed as settings, chosen by measurement (docs/performance.md).
# The RINS and RENS sub-MIP heuristics spend most of the time on these small, tight models;
# restarting the root after presolving again costs more cut rounds than it saves.
HIGHS_OPTIONS = {"mip_heuristic_run_rins": False, "mip_heuristic_run_rens": False, "mip_allow_restart": False}
# The objective HiGHS receives is scaled by 2^-12 (a power of two, so exactly) and what it reports
# is scaled back. Measured (docs/performance.md): 30- and 15-minute days 13-19 % less solver time;
# hourly days 11-13 % less and their slowest days faster, except days where the solver itself
# places some budgeted deviations (tied deviations at the Γ boundary, or the budget variants
# without the top-Γ fast path), the slowest hourly days, which got slower and keep their path.
# (HiGHS's own option for this, user_objective_scale, reports the dual bound still scaled in 1.15.1.)
OBJECTIVE_SCALE = -12


def objective_scale(dt_h: float, budget_choices: bool = False) -> int:
    """The power of two by which a bidding day's objective is scaled inside HiGHS, for ``dt_h``-hour
    periods; ``budget_choices``: the solver places some budgeted deviations
    (:func:`rvpp.model.robust.budget_choices`)."""
    return OBJECTIVE_SCALE if dt_h < 1.0 or not budget_choices else 0


# HiGHS creates one task scheduler per process at its first run; that first run is
# serialized, later runs in threads of one process go side by side (HiGHS releases the
# interpreter lock while it solves).
_first_run = threading.Lock()
_scheduler_ready = threading.Event()
# Pyomo's compiler sets up shared state at its first use; compiles take turns (they hold
# the interpreter lock anyway).
_compile_lock = threading.Lock()

# HiGHS sizes one thread pool per process at its first run and fails any later run that names
# another size; the size of the first run rvpp makes is kept here (0: sized outside rvpp).
_pool_threads: list[int] = []


def default_threads() -> int:
    """The thread count rvpp gives HiGHS when a case leaves ``solver.threads`` at 0: HiGHS's own
    documented default, half the machine's logical processors (at least one)."""
    return max(1, (os.cpu_count() or 1) // 2)


INF = highspy.kHighsInf
_STATUS = highspy.HighsModelStatus
_OUTCOMES = {
    _STATUS.kOptimal: Outcome.OPTIMAL,
    _STATUS.kModelEmpty: Outcome.OPTIMAL,
    _STATUS.kTimeLimit: Outcome.TIME_LIMIT,
    _STATUS.kIterationLimit: Outcome.TIME_LIMIT,
    _STATUS.kSolutionLimit: Outcome.TIME_LIMIT,
    _STATUS.kInterrupt: Outcome.TIME_LIMIT,
    _STATUS.kObjectiveBound: Outcome.TIME_LIMIT,
    _STATUS.kObjectiveTarget: Outcome.TIME_LIMIT,
    _STATUS.kInfeasible: Outcome.INFEASIBLE,
    _STATUS.kUnbounded: Outcome.UNBOUNDED,
    _STATUS.kUnboundedOrInfeasible: Outcome.INFEASIBLE_OR_UNBOUNDED,
}
_FEASIBLE = 2  # HiGHS solution status "feasible"
WATCH_S = 0.25  # how often a watch is shown the search [s of HiGHS's clock]


def _thread_option(requested: int) -> tuple[dict, str]:
    """HiGHS's ``threads`` option for a run that asks for ``requested`` threads (0: the default),
    and a note when the process's pool has another size.

    Only the process's first run names a size (``requested``, or :func:`default_threads`); later
    runs leave the option at 0, which takes the pool as it is, so a case asking for another
    count is solved on the pool and told so instead of failing.
    """
    with _first_run:
        first = not _pool_threads
        if first:
            _pool_threads.append(requested or default_threads())
    return ({"threads": _pool_threads[0]} if first else {}), _ignored(requested)


def _ignored(requested: int) -> str:
    """The note for a run that asked for ``requested`` threads on the process's pool."""
    pool = _pool_threads[0]
    if requested in (0, pool):
        return ""
    held = f"{pool} thread(s)" if pool else "another thread count"
    return f"threads={requested} ignored: HiGHS already runs this process with {held}"


@dataclass(frozen=True, eq=False)
class CompiledModel:
    """A Pyomo model as HiGHS data: the columns (Pyomo variables) and the ``HighsLp``."""

    columns: list[VarData]
    lp: highspy.HighsLp
    integer: np.ndarray

    @property
    def is_mip(self) -> bool:
        return bool(self.integer.any())


def compile_model(m: pyo.Block) -> CompiledModel:
    """The active objective and constraints of ``m`` as a ``HighsLp`` (fixed variables become constants).

    Compiled by :func:`rvpp.solving.linear.standard_form`; a model with an expression it
    does not read goes through Pyomo's own compiler, which gives the same matrix.
    """
    try:
        form = standard_form(m)
    except Unsupported:
        form = _pyomo_standard_form(m)
    columns = form.columns
    n = len(columns)
    a = form.a
    bounds = np.array([v.bounds for v in columns], dtype=float).reshape(n, 2)  # None (no bound) becomes NaN
    lower = np.where(np.isnan(bounds[:, 0]), -INF, bounds[:, 0])
    upper = np.where(np.isnan(bounds[:, 1]), INF, bounds[:, 1])
    integer = np.array([v.is_integer() for v in columns], dtype=bool)
    rhs, sense = form.rhs, form.sense
    row_lower = np.where(sense == 1, -INF, rhs)
    row_upper = np.where(sense == -1, INF, rhs)
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = n, len(rhs)
    lp.col_cost_ = form.cost
    lp.col_lower_, lp.col_upper_ = lower, upper
    lp.row_lower_, lp.row_upper_ = row_lower, row_upper
    lp.offset_ = form.offset
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.num_col_, lp.a_matrix_.num_row_ = n, len(rhs)
    lp.a_matrix_.start_ = a.indptr if n else np.zeros(1, dtype=np.int32)
    lp.a_matrix_.index_, lp.a_matrix_.value_ = (a.indices, a.data) if n else (np.zeros(0), np.zeros(0))
    if integer.any():
        lp.integrality_ = [highspy.HighsVarType.kInteger if i else highspy.HighsVarType.kContinuous
                           for i in integer]
    lp.sense_ = highspy.ObjSense.kMaximize if form.maximize else highspy.ObjSense.kMinimize
    return CompiledModel(columns=list(columns), lp=lp, integer=integer)


def _pyomo_standard_form(m: pyo.Block) -> StandardForm:
    """:func:`standard_form` by Pyomo's linear standard-form compiler (``mixed_form``)."""
    try:
        with _compile_lock:
            info = LinearStandardFormCompiler().write(m, mixed_form=True, set_sense=None)
    except InfeasibleConstraintException as exc:
        raise TrivialInfeasibility(str(exc)) from exc
    n = len(info.columns)
    return StandardForm(columns=list(info.columns), a=info.A.tocsc() if n else info.A,
                        rhs=np.asarray(info.rhs, dtype=float), sense=np.array([op for _, op in info.rows], dtype=int),
                        cost=np.asarray(info.c.toarray()).ravel() if n else np.zeros(0),
                        offset=float(info.c_offset[0]) if len(info.c_offset) else 0.0,
                        maximize=bool(info.objectives) and info.objectives[0].sense == pyo.maximize)


class HighsModel:
    """A Pyomo model held in a HiGHS object for repeated solves.

    :meth:`refresh` recompiles the Pyomo model after its data changed (mutable
    parameters, bounds, fixed values) and passes the new matrix to HiGHS; :meth:`solve`
    runs HiGHS, optionally from a MIP start, and loads a usable incumbent into the Pyomo
    variables. A fresh HiGHS object is used for every solve, so options never leak
    from one solve to the next.
    """

    def __init__(self, m: pyo.Block):
        self.model = m
        self.compiled: CompiledModel | None = None
        self.infeasible_reason = ""
        self.solution: np.ndarray | None = None
        self.refresh()

    def refresh(self) -> None:
        """Recompile the Pyomo model (after its data changed)."""
        try:
            self.compiled, self.infeasible_reason = compile_model(self.model), ""
        except TrivialInfeasibility as exc:
            self.compiled, self.infeasible_reason = None, str(exc)

    def solve(self, settings, *, start: Mapping[VarData, float] | None = None, load: bool = True,
              options: Mapping[str, object] | None = None, scale: int = 0,
              watch: Watch | None = None) -> SolveOutcome:
        """Run HiGHS with ``settings`` (time limit, gap, threads) and extra ``options``.

        ``start`` gives values of some or all variables as a MIP start; HiGHS completes a
        partial start itself and ignores one it cannot complete. HiGHS minimizes the
        objective times ``2**scale``; the objective and bound returned are in the model's units.
        ``watch`` is shown a MIP search as it goes and may end it (:data:`Watch`).
        """
        if self.compiled is None:
            return SolveOutcome.of(Outcome.INFEASIBLE, "trivially infeasible", None, None, 0.0,
                                   self.infeasible_reason)
        threads, note = _thread_option(settings.threads)
        h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        for key, value in {**HIGHS_OPTIONS, **(options or {}), "time_limit": float(settings.time_limit_s),
                           "mip_rel_gap": float(settings.rel_gap), **threads}.items():
            h.setOptionValue(key, value)
        stop = _Stop(watch, scale) if watch is not None and self.compiled.is_mip else None
        try:
            t0 = time.perf_counter()
            h.passModel(self.compiled.lp)
            if scale:
                lp, factor = self.compiled.lp, math.ldexp(1.0, scale)
                h.changeColsCost(lp.num_col_, np.arange(lp.num_col_, dtype=np.int32), np.asarray(lp.col_cost_) * factor)
                h.changeObjectiveOffset(lp.offset_ * factor)
            if start:
                self._set_start(h, start)
            if stop is not None:
                h.cbMipInterrupt.subscribe(stop)
            if _run(h) == highspy.HighsStatus.kError and h.getModelStatus() == _STATUS.kNotset and threads:
                # HiGHS refused the size: something else in this process ran HiGHS first, with another.
                _pool_threads[0] = 0
                h.setOptionValue("threads", 0)
                _run(h)
                note = _ignored(settings.threads)
            seconds = time.perf_counter() - t0
        except Exception as exc:  # the solver library failed; report, do not crash the caller
            return SolveOutcome.of(Outcome.ERROR, type(exc).__name__, None, None, 0.0, f"HiGHS failed: {exc}")
        if stop is not None and stop.error is not None:
            raise stop.error  # the watch's own failure, not the solver's
        outcome = self._outcome(h, seconds, note, scale, stopped=stop is not None and stop.asked)
        self.solution = np.asarray(h.getSolution().col_value, dtype=float) if outcome.usable else None
        if outcome.usable and load:
            self.load()
        return outcome

    def _set_start(self, h: highspy.Highs, start: Mapping[VarData, float]) -> None:
        position = {id(v): j for j, v in enumerate(self.compiled.columns)}
        pairs = [(position[id(v)], float(value)) for v, value in start.items()
                 if id(v) in position and value is not None]
        if not pairs:
            return
        index = np.array([j for j, _ in pairs], dtype=np.int32)
        value = np.array([x for _, x in pairs], dtype=float)
        integer = self.compiled.integer[index]
        value[integer] = np.round(value[integer])
        h.setSolution(len(index), index, value)

    def _outcome(self, h: highspy.Highs, seconds: float, note: str, scale: int, stopped: bool = False) -> SolveOutcome:
        model_status = h.getModelStatus()
        info = h.getInfo()
        status = _OUTCOMES.get(model_status, Outcome.ERROR)
        if stopped and model_status == _STATUS.kInterrupt:
            status = Outcome.STOPPED
        has_point = info.primal_solution_status == _FEASIBLE or model_status == _STATUS.kModelEmpty
        if status is Outcome.OPTIMAL and not has_point:
            status = Outcome.ERROR
        termination = h.modelStatusToString(model_status)
        if status is Outcome.ERROR:
            note = "; ".join(part for part in (f"HiGHS stopped: {termination}", note) if part)
        objective = math.ldexp(info.objective_function_value, -scale) if has_point else None
        if model_status == _STATUS.kModelEmpty:
            objective = self.compiled.lp.offset_
        if self.compiled.is_mip:
            bound = math.ldexp(info.mip_dual_bound, -scale)
        else:
            bound = objective if status is Outcome.OPTIMAL else None
        nodes = int(info.mip_node_count) if self.compiled.is_mip else None
        return SolveOutcome.of(status, termination, objective, bound, seconds, note, nodes,
                               int(info.simplex_iteration_count))

    def values(self, integer_only: bool = False) -> ComponentMap:
        """The last usable solution by Pyomo variable (empty without one); ``integer_only``:
        only the integer variables, the usual MIP start for a neighbouring problem."""
        values = ComponentMap()
        if self.solution is not None:
            for v, x, is_int in zip(self.compiled.columns, self.solution.tolist(), self.compiled.integer.tolist()):
                if is_int or not integer_only:
                    values[v] = x
        return values

    def integer_ones(self) -> tuple[str, ...]:
        """Names of the integer variables at one in the last usable solution (every integer variable
        rvpp builds is binary): the solver settings' ``mip_start`` for a neighbouring day."""
        if self.solution is None:
            return ()
        ones = np.flatnonzero(self.compiled.integer & (self.solution > 0.5))
        return tuple(self.compiled.columns[j].name for j in ones)

    def start_at_ones(self, names: Iterable[str]) -> ComponentMap:
        """A MIP start: the integer variables named in ``names`` at one, every other one at zero; no
        start (an empty map) without names. Names this model does not have are ignored; no name is
        parsed or looked up in the model."""
        wanted = set(names)
        start = ComponentMap()
        if wanted and self.compiled is not None:
            for v, is_int in zip(self.compiled.columns, self.compiled.integer.tolist()):
                if is_int:
                    start[v] = 1.0 if v.name in wanted else 0.0
        return start

    def load(self) -> None:
        """Write the last usable solution into the Pyomo variables."""
        if self.solution is None:
            return
        for v, x in zip(self.compiled.columns, self.solution.tolist()):
            v.set_value(x, skip_validation=True)


class _Stop:
    """HiGHS's MIP interrupt callback for a :data:`Watch`: shows it the search every
    :data:`WATCH_S` and interrupts HiGHS once the watch asked and a plan exists.

    An exception raised in the watch (a ``KeyboardInterrupt`` too) cannot cross HiGHS: it
    ends the search at once and is raised again by :meth:`HighsModel.solve` after it.
    """

    def __init__(self, watch: Watch, scale: int):
        self.watch, self.scale = watch, scale
        self.shown = -math.inf  # HiGHS's clock when the watch was last shown the search
        self.asked = False
        self.error: BaseException | None = None

    def __call__(self, event) -> None:
        try:
            self._show(event)
        except BaseException as exc:  # noqa: BLE001  (raised again once HiGHS has returned)
            self.error = self.error or exc
            event.interrupt()

    def _show(self, event) -> None:
        if self.error is not None:
            event.interrupt()
            return
        data = event.data_out
        has_plan = abs(data.mip_primal_bound) < INF
        if data.running_time - self.shown >= WATCH_S:
            self.shown = data.running_time
            objective = math.ldexp(data.mip_primal_bound, -self.scale) if has_plan else None
            bound = math.ldexp(data.mip_dual_bound, -self.scale) if abs(data.mip_dual_bound) < INF else None
            search = Search(data.running_time, objective, bound, relative_gap(objective, bound),
                            int(data.mip_node_count))
            self.asked |= bool(self.watch(search))
        if self.asked and has_plan:
            event.interrupt()


@contextmanager
def model_lifetime() -> Iterator[None]:
    """Around the life of a Pyomo model: the cyclic collector paused, the youngest generation
    collected after.

    A built model is cyclic garbage once its numbers are read (its rules close over it).
    Collected young, it never reaches the oldest generation, whose full collections scan
    the whole process (60-90 ms with a case's history loaded, about once every four
    hourly solves); and the collector does not run over the model while it is built.
    """
    with PauseGC():
        yield
    if gc.isenabled():
        gc.collect(0)


def _run(h: highspy.Highs) -> highspy.HighsStatus:
    """``h.run()``, the process's first run alone (it creates HiGHS's task scheduler)."""
    if _scheduler_ready.is_set():
        return h.run()
    with _first_run:
        status = h.run()
        _scheduler_ready.set()
        return status


def run_highs(m: pyo.ConcreteModel, settings, *, load: bool = True, start: Mapping[VarData, float] | None = None,
              options: Mapping[str, object] | None = None) -> SolveOutcome:
    """Compile ``m``, run HiGHS once (with extra HiGHS ``options``) and load the incumbent if it is usable.

    Safe to call from several threads, which solve side by side (HiGHS releases the
    interpreter lock while it runs).
    """
    return HighsModel(m).solve(settings, start=start, load=load, options=options)
