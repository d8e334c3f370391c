"""Speed-ups keep the optimum: objectives against those of the formulation before them.

``tests/data/reference_objectives.json`` holds the objective and bound of 64 fixed
cases (13 hourly days and 3 quarter-hour days spread over the year, every strategy),
solved once to a relative gap of 1e-4 with the formulation and solver path before the
speed-ups (``benchmarks/reference_objectives.py``; the commit is recorded in the file).
Both runs stop within the gap of the same optimum, so their incumbents differ by at most
the gap, and each incumbent lies below the other run's bound. Every plan must also pass
the independent audit of MODEL_SPEC's balances and limits. The references were solved
with the cyclic thermal storage the paper case had then, so the cases here keep it. The
quarter-hour references were solved again with that same formulation once hourly data
came to quarter-hours by the mean-keeping interpolation of MODEL_SPEC §6 instead of
repeated hours (``quarter_hour_cases`` in the file): the inputs changed, not the formulation.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest

from rvpp import audit_result, solve, with_options
from tests.factories import cyclic_storage

REFERENCE = json.loads((Path(__file__).parent / "data" / "reference_objectives.json").read_text())
REL_GAP = REFERENCE["rel_gap"]
ABS_TOL = 0.01  # [EUR] round-off on top of the gap


def _cases(dt_h: float) -> list[dict]:
    return [c for c in REFERENCE["cases"] if c["dt_h"] == dt_h]


def _case(paper_case, ref: dict, date: str | None = None):
    return with_options(cyclic_storage(paper_case), date=date or ref["date"], strategy=ref["strategy"], dt_h=ref["dt_h"],
                        rel_gap=REL_GAP)


def _check(paper_case, ref: dict, start: tuple[str, ...] = ()) -> None:
    case = _case(paper_case, ref)
    result = solve(case.replace(solver={"mip_start": start}) if start else case)
    assert result.status == "optimal", result.message
    tol = REL_GAP * abs(ref["objective_eur"]) + ABS_TOL
    assert result.objective_eur == pytest.approx(ref["objective_eur"], abs=tol)
    assert result.objective_eur <= ref["bound_eur"] + ABS_TOL, "better than the old formulation's bound"
    assert result.bound_eur >= ref["objective_eur"] - ABS_TOL, "bound below a plan the old formulation found"
    assert audit_result(result) == []


def test_the_reference_list_has_at_least_fifty_cases_of_both_period_lengths():
    assert len(REFERENCE["cases"]) >= 50
    assert {c["dt_h"] for c in REFERENCE["cases"]} == {1.0, 0.25}
    assert all(c["status"] == "optimal" for c in REFERENCE["cases"])


@pytest.mark.slow
@pytest.mark.parametrize("ref", _cases(1.0), ids=lambda c: f"{c['date']}-{c['strategy']}")
def test_hourly_optimum_is_unchanged(paper_case, ref):
    _check(paper_case, ref)


@pytest.mark.slow
@pytest.mark.parametrize("ref", _cases(0.25), ids=lambda c: f"{c['date']}-{c['strategy']}-15min")
def test_quarter_hour_optimum_is_unchanged(paper_case, ref):
    _check(paper_case, ref)


# Hourly days as a backtest starts them, and one quarter-hour day (backtests plan those cold, but a
# case may carry a start at any period length).
STARTED = [c for c in REFERENCE["cases"] if c["strategy"] in ("deterministic", "optimistic")
           and (c["dt_h"] == 1.0 or (c["strategy"], c["date"]) == ("optimistic", "2025-08-15"))]


@pytest.mark.slow
@pytest.mark.parametrize("ref", STARTED, ids=lambda c: f"{c['date']}-{c['strategy']}-{c['dt_h']:g}h")
def test_a_plan_started_from_the_day_befores_keeps_the_optimum(paper_case, ref):
    """As a backtest plans: HiGHS starts from the day before's plan (its integer variables at one)."""
    before = (dt.date.fromisoformat(ref["date"]) - dt.timedelta(days=1)).isoformat()
    start = solve(_case(paper_case, ref, before)).integer_ones
    assert start, "the day before's plan has no integer variable at one: nothing to start from"
    _check(paper_case, ref, start)
