"""Solve one intraday session: build its model, run HiGHS, read the trade and the re-dispatch.

:func:`solve_session` is a pure function of its :class:`~rvpp.uncertainty.problem.Problem` and
:class:`~rvpp.model.session.Commitments` and returns plain data (a
:class:`~rvpp.solving.results.SessionResult`), as :func:`rvpp.solving.plan.solve_problem` does for
the day-ahead plan.
"""

from __future__ import annotations

import time

from ..data.intraday import SessionTime
from ..model.session import Commitments, build_session_model, schedule_of
from ..uncertainty.problem import Problem, infeasibility_reasons
from .extract import extract_session
from .highs import HighsModel, model_lifetime
from .outcome import Outcome
from .plan import day_scale
from .results import SessionResult

STARTED_PERIOD_MIN_H = 1.0  # [h]: the shortest period whose sessions start from the step before's schedule


def solve_session(problem: Problem, commitments: Commitments, session: SessionTime) -> SessionResult:
    """The robust trade and re-dispatch of ``session`` given what is fixed before it (MODEL_SPEC §14)."""
    started = time.perf_counter()
    head = {"problem": problem, "session": session.name, "gate_closure": session.gate.isoformat(),
            "first": session.first}
    reasons = infeasibility_reasons(problem)
    if reasons:
        return SessionResult(**head, status=Outcome.INFEASIBLE, termination="not solved", message="; ".join(reasons),
                             build_s=time.perf_counter() - started)
    with model_lifetime():
        m = build_session_model(problem, commitments)
        build_s = time.perf_counter() - started
        highs = HighsModel(m)
        # The step before's integer schedule as MIP start on hourly days: where the forecasts moved
        # little it is still feasible, and HiGHS completes it or drops it otherwise. Shorter periods
        # start cold, as the backtest's day-ahead plans do (docs/performance.md).
        started_days = problem.dt_h >= STARTED_PERIOD_MIN_H
        ones = (name for name, value in commitments.schedule.items() if value > 0.5 and started_days)
        outcome = highs.solve(problem.case.solver, start=highs.start_at_ones(ones), scale=day_scale(problem, m))
        tables, schedule = ({}, {})
        if outcome.usable:
            tables, schedule = extract_session(m, problem), schedule_of(m, problem)
        del m
    return SessionResult(**head, status=outcome.status, termination=outcome.termination,
                         message=outcome.message if outcome.usable else (outcome.message or "no feasible trade"),
                         objective_eur=outcome.objective, bound_eur=outcome.bound, mip_gap=outcome.gap,
                         build_s=build_s, solve_s=outcome.seconds, schedule=schedule, **tables)
