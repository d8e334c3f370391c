"""rvpp's own matrix compiler gives what Pyomo's linear standard-form compiler gives
(rvpp.solving.linear): the same columns in the same order, the same rows and the same
numbers, bit for bit, on every kind of model rvpp builds. The oracle is Pyomo's compiler."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pyomo.environ as pyo
import pytest
import scipy.sparse
from pyomo.common.errors import InfeasibleConstraintException
from pyomo.repn.plugins.standard_form import LinearStandardFormCompiler

from rvpp import prepare, solve, with_options
from rvpp.data.case import SolverSettings
from rvpp.model import build_model
from rvpp.settle.recourse import Penalties, build_recourse_model, first_stage, realization, realized_problem
from rvpp.solving.highs import compile_model, run_highs
from rvpp.solving.linear import TrivialInfeasibility, Unsupported, standard_form
from rvpp.solving.outcome import Outcome
from rvpp.model.robust import set_budgets
from rvpp.solving.sweep import with_budgets
from tests.factories import cyclic_storage


def assert_same_matrix(m: pyo.Block) -> None:
    pyomo = LinearStandardFormCompiler().write(m, mixed_form=True, set_sense=None)
    ours = standard_form(m)
    assert [id(v) for v in ours.columns] == [id(v) for v in pyomo.columns]
    expected = pyomo.A.tocsc()
    assert ours.a.shape == expected.shape
    assert np.array_equal(ours.a.indptr, expected.indptr)
    assert np.array_equal(ours.a.indices, expected.indices)
    assert np.array_equal(ours.a.data, expected.data)
    assert np.array_equal(ours.rhs, np.asarray(pyomo.rhs, dtype=float))
    assert np.array_equal(ours.sense, np.array([op for _, op in pyomo.rows]))
    assert np.array_equal(ours.cost, np.asarray(pyomo.c.toarray()).ravel())
    assert ours.offset == float(pyomo.c_offset[0])
    assert ours.maximize == (pyomo.objectives[0].sense == pyo.maximize)


@pytest.mark.parametrize("dt_h", [1.0, 0.25])
@pytest.mark.parametrize("strategy", ["deterministic", "optimistic", "balanced", "pessimistic"])
def test_plan_models_compile_alike(paper_case, strategy, dt_h):
    case = with_options(paper_case, strategy=strategy, dt_h=dt_h, date="2025-03-15")
    assert_same_matrix(build_model(prepare(case)))


@pytest.mark.parametrize("options", [
    {"markets": "DAM"}, {"markets": "DAM+HPA"}, {"date": "2025-12-15", "pwl_encoding": "convex_combination"},
    {"date": "2025-07-15", "budget_encoding": "binary", "strategy": "pessimistic"},
])
def test_other_market_sets_encodings_and_days_compile_alike(paper_case, options):
    assert_same_matrix(build_model(prepare(with_options(paper_case, **options))))


def test_a_cyclic_storage_day_compiles_alike(paper_case):
    assert_same_matrix(build_model(prepare(cyclic_storage(paper_case))))


def test_new_budgets_in_a_kept_model_compile_alike(paper_case):
    """Mutable budgets changed in place (the Γ sweep) are read at their new values."""
    problem = prepare(with_options(paper_case, strategy="balanced"))
    m = build_model(problem)
    set_budgets(m, with_budgets(problem, with_options(paper_case, strategy="pessimistic")))
    assert_same_matrix(m)


def test_settlement_and_stochastic_models_compile_alike(paper_case):
    case = with_options(paper_case, strategy="balanced", date="2025-01-10")
    real = realization(case, case.delivery_date)
    bids = first_stage(solve(case), False)
    assert_same_matrix(build_recourse_model([realized_problem(case, real)], Penalties(), bids))
    later = with_options(paper_case, date="2025-01-11")
    problems = [realized_problem(case, real), realized_problem(later, realization(later, later.delivery_date))]
    assert_same_matrix(build_recourse_model(problems, Penalties()))


def _small() -> pyo.ConcreteModel:
    m = pyo.ConcreteModel()
    m.T = pyo.RangeSet(3)
    m.x = pyo.Var(m.T, bounds=(0, 10))
    m.y = pyo.Var(domain=pyo.Binary)
    m.z = pyo.Var(m.T)
    m.price = pyo.Param(m.T, initialize={1: 2.0, 2: -1.5, 3: 0.25}, mutable=True)
    m.twice = pyo.Expression(m.T, rule=lambda m, t: 2 * m.x[t] - m.z[t] / 4)
    m.obj = pyo.Objective(expr=sum(m.price[t] * m.x[t] for t in m.T) - 7 * m.y + 3, sense=pyo.maximize)
    m.balance = pyo.Constraint(m.T, rule=lambda m, t: m.twice[t] + 1 == m.z[t] - m.x[1])
    m.cap = pyo.Constraint(expr=sum(m.x[t] for t in m.T) <= 12 * m.y)
    m.band = pyo.Constraint(expr=pyo.inequality(-1, m.x[2] - m.x[3], 4))
    m.scaled = pyo.Constraint(expr=-(m.x[1] + 2) * m.price[2] >= m.price[1])
    m.unused = pyo.Var()
    return m


def test_sums_terms_quotients_negations_ranges_and_parameters_compile_alike():
    m = _small()
    assert_same_matrix(m)
    m.price[2] = 5.0
    assert_same_matrix(m)


def test_a_fixed_variable_becomes_a_constant():
    m = _small()
    m.x[1].fix(4.0)
    assert_same_matrix(m)
    assert all(v is not m.x[1] for v in standard_form(m).columns)


def test_a_product_of_variables_is_left_to_pyomo():
    m = _small()
    m.bilinear = pyo.Constraint(expr=m.x[1] * m.x[2] <= 3)
    with pytest.raises(Unsupported):
        standard_form(m)
    m.bilinear.deactivate()
    m.ratio = pyo.Constraint(expr=m.x[1] / m.z[2] <= 3)
    with pytest.raises(Unsupported, match="division"):
        standard_form(m)


def test_a_model_it_cannot_read_is_compiled_by_pyomo_instead():
    """A fixed variable met first as a factor: Pyomo reads it as the number 2, the walker
    refuses the product, and the model still compiles (through Pyomo)."""
    m = _small()
    m.k = pyo.Var()
    m.k.fix(2.0)
    m.scaled_by_k = pyo.Constraint(expr=m.k * m.x[2] <= 3)
    with pytest.raises(Unsupported):
        standard_form(m)
    compiled = compile_model(m)
    row = compiled.lp.num_row_ - 1
    column = [id(v) for v in compiled.columns].index(id(m.x[2]))
    a = scipy.sparse.csc_array((compiled.lp.a_matrix_.value_, compiled.lp.a_matrix_.index_,
                                compiled.lp.a_matrix_.start_), shape=(compiled.lp.num_row_, compiled.lp.num_col_))
    assert a[row, column] == 2.0 and compiled.lp.row_upper_[row] == 3.0


def test_a_model_pyomo_cannot_read_either_is_refused_by_name():
    """A constraint on a variable squared: Pyomo's compiler refuses it by name either way."""
    m = _small()
    m.square = pyo.Constraint(expr=m.x[1] ** 2 <= 3)
    with pytest.raises(Exception, match="nonlinear"):
        compile_model(m)


def test_a_constraint_without_variables_that_cannot_hold_is_named():
    m = _small()
    m.w = pyo.Var()
    m.w.fix(2.0)
    m.impossible = pyo.Constraint(expr=m.w >= 5)
    with pytest.raises(InfeasibleConstraintException, match="'impossible'"):
        LinearStandardFormCompiler().write(m, mixed_form=True, set_sense=None)
    with pytest.raises(TrivialInfeasibility, match="'impossible'"):
        standard_form(m)
    outcome = run_highs(m, SolverSettings(rel_gap=0.0, time_limit_s=30))
    assert outcome.status is Outcome.INFEASIBLE and "'impossible'" in outcome.message


def test_a_fixed_variable_of_a_numbered_component_leaves_an_empty_row():
    """As in Pyomo: ``x[1] ≥ 5`` with ``x[1]`` fixed at 2 is a row without coefficients, bounds
    that cannot hold, and HiGHS finds the model infeasible."""
    m = _small()
    m.x[1].fix(2.0)
    m.impossible = pyo.Constraint(expr=m.x[1] >= 5)
    assert_same_matrix(m)
    assert run_highs(m, SolverSettings(rel_gap=0.0, time_limit_s=30)).status is Outcome.INFEASIBLE


def test_an_hourly_solve_imports_no_scipy():
    """The matrix is built with NumPy alone: an hourly solve in a fresh process never imports SciPy,
    which would make Pyomo import ``scipy.stats`` as well (seconds of a command-line solve)."""
    code = "\n".join([
        "import sys", "import rvpp",
        "result = rvpp.solve(rvpp.load_case('data/cases/paper'))",
        "print(result.status, sorted(m for m in ('scipy', 'scipy.sparse', 'scipy.stats') if m in sys.modules))"])
    done = subprocess.run([sys.executable, "-c", code], cwd=Path(__file__).resolve().parent.parent,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "optimal []"
