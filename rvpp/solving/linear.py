"""A linear Pyomo model as a sparse matrix, faster than Pyomo's general compiler.

:func:`standard_form` gives what Pyomo's ``LinearStandardFormCompiler`` gives with
``mixed_form=True`` (the same columns in the same order, the same rows, coefficients and
right-hand sides), for the expressions rvpp's models are made of: sums, variables times
constants, quotients by constants, negations, named expressions and mutable parameters.
It walks each expression once with a multiplier carried down instead of building a
representation per node, and it reads the two sides of a constraint ``a ≤ b`` without
forming ``a − b`` first. Measured on the paper case: about 40 % less time than Pyomo's
compiler (docs/performance.md). On every kind of model rvpp builds the two give the same
matrix bit for bit (``tests/test_linear.py``), so HiGHS takes the same path. Elsewhere
they can differ in the last bit: where a factor multiplies a sum that repeats a variable
or holds several constants, Pyomo adds inside the sum before it multiplies, this walker
multiplies each part.

Anything else (a product of variables, a function of one, two objectives) raises
:class:`Unsupported`, and the caller compiles with Pyomo instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyomo.environ as pyo
from pyomo.core.base.enums import SortComponents
from pyomo.core.base.expression import NamedExpressionData
from pyomo.core.base.param import ParamData
from pyomo.core.base.var import VarData
from pyomo.core.expr import numeric_expr
from pyomo.core.expr.numvalue import NumericConstant, native_numeric_types, value
from pyomo.core.expr.relational_expr import EqualityExpression, RangedExpression

# Pyomo's default ordering: components and indices in the order they were declared.
ORDERED = SortComponents.ORDERED_INDICES

_VAR, _SUM, _TERM, _PRODUCT, _QUOTIENT, _NEGATION, _NAMED, _CONSTANT = range(8)
_KINDS: dict[type, int] = {}


class Unsupported(Exception):
    """An expression that is not a linear one of the kinds :func:`standard_form` reads."""


class TrivialInfeasibility(Exception):
    """A constraint without variables that no value can satisfy."""


@dataclass(frozen=True, eq=False)
class ColumnMatrix:
    """A sparse matrix stored column by column (compressed sparse columns, as HiGHS takes it): the
    rows of column ``j`` are ``indices[indptr[j]:indptr[j + 1]]``, increasing, with the values
    ``data`` there; no stored zeros.

    NumPy alone: SciPy's sparse matrices would do, but a process that imports SciPy after Pyomo
    has Pyomo import ``scipy.stats`` too (Pyomo's deferred import of SciPy), about a second more
    for every command-line solve (docs/performance.md).
    """

    shape: tuple[int, int]
    indptr: np.ndarray
    indices: np.ndarray
    data: np.ndarray

    @classmethod
    def from_rows(cls, data: list[float], columns: list[int], starts: list[int], n: int) -> ColumnMatrix:
        """The matrix of ``len(starts) − 1`` rows given by their coefficients ``data`` in ``columns``,
        row ``i`` at ``starts[i]:starts[i + 1]`` (zeros dropped), and ``n`` columns."""
        rows = len(starts) - 1
        values = np.asarray(data, dtype=float)
        cols = np.asarray(columns, dtype=np.int64)
        row_of = np.repeat(np.arange(rows, dtype=np.int32), np.diff(np.asarray(starts, dtype=np.int64)))
        kept = values != 0.0
        values, cols, row_of = values[kept], cols[kept], row_of[kept]
        order = np.argsort(cols, kind="stable")  # a stable sort keeps each column's rows increasing
        indptr = np.zeros(n + 1, dtype=np.int32)
        np.cumsum(np.bincount(cols, minlength=n), out=indptr[1:])
        return cls(shape=(rows, n), indptr=indptr, indices=row_of[order], data=values[order])

    def nonzero_columns(self) -> np.ndarray:
        """Whether each column holds a value."""
        return np.diff(self.indptr) > 0

    def columns(self, keep: np.ndarray) -> ColumnMatrix:
        """The columns ``keep`` (increasing positions), in that order."""
        starts, lengths = self.indptr[keep], np.diff(self.indptr)[keep]
        indptr = np.zeros(len(keep) + 1, dtype=np.int32)
        np.cumsum(lengths, out=indptr[1:])
        picked = np.arange(indptr[-1]) + np.repeat(starts - indptr[:-1], lengths)  # each kept column's run
        return ColumnMatrix(shape=(self.shape[0], len(keep)), indptr=indptr, indices=self.indices[picked],
                            data=self.data[picked])

    def times(self, x: np.ndarray) -> np.ndarray:
        """``self · x``, each row's terms added in column order."""
        y = np.zeros(self.shape[0])
        np.add.at(y, self.indices, self.data * np.repeat(x, np.diff(self.indptr)))
        return y


@dataclass(frozen=True, eq=False)
class StandardForm:
    """``rows`` of ``a · x (sense) rhs`` with sense 0 (=), 1 (≤) or −1 (≥); a ranged constraint is two rows.
    ``a`` is a :class:`ColumnMatrix` (or SciPy's, from Pyomo's compiler: the same attributes)."""

    columns: list[VarData]
    a: ColumnMatrix
    rhs: np.ndarray
    sense: np.ndarray
    cost: np.ndarray
    offset: float
    maximize: bool


def _kind(cls: type) -> int:
    if issubclass(cls, VarData):
        kind = _VAR
    elif issubclass(cls, NamedExpressionData):
        kind = _NAMED
    elif (issubclass(cls, (ParamData, NumericConstant, numeric_expr.NPV_Mixin))
          or cls is numeric_expr._MutableNPVSumExpression):
        kind = _CONSTANT
    elif issubclass(cls, numeric_expr.MonomialTermExpression):
        kind = _TERM
    elif issubclass(cls, numeric_expr.SumExpressionBase):
        kind = _SUM
    elif issubclass(cls, numeric_expr.ProductExpression):
        kind = _PRODUCT
    elif issubclass(cls, numeric_expr.DivisionExpression):
        kind = _QUOTIENT
    elif issubclass(cls, numeric_expr.NegationExpression):
        kind = _NEGATION
    else:
        raise Unsupported(f"{cls.__name__} in a linear model")
    _KINDS[cls] = kind
    return kind


def _fixed_value(node) -> float | None:
    """The value of ``node`` if it holds no variable (numbers and parameters), else ``None``."""
    if node.__class__ in native_numeric_types:
        return node
    if not node.is_potentially_variable():
        return value(node)
    return None


class _Columns:
    """Column numbers, given a whole Var component at a time when one of its members is first met
    (as Pyomo's compiler does, so both number the columns alike)."""

    def __init__(self) -> None:
        self.number: dict[int, int] = {}
        self.variables: list[VarData] = []

    def add(self, var: VarData) -> int:
        component = var.parent_component()
        members = component.values(ORDERED) if component.is_indexed() else (component,)
        for member in members:
            self.number[id(member)] = len(self.variables)
            self.variables.append(member)
        return self.number[id(var)]

    def linear(self, expr, minus=None) -> tuple[float, dict[int, float]]:
        """``expr`` (less ``minus``) as a constant and coefficients by column."""
        terms: dict[int, float] = {}
        constant = 0.0
        stack = [(expr, 1.0)] if minus is None else [(minus, -1.0), (expr, 1.0)]
        number = self.number
        while stack:
            node, scale = stack.pop()
            cls = node.__class__
            if cls in native_numeric_types:
                constant += scale * node
                continue
            kind = _KINDS.get(cls)
            if kind is None:
                kind = _kind(cls)
            if kind == _VAR:
                column = number.get(id(node))
                if column is None:
                    if node.fixed:  # a constant until its component is numbered, then a column (as in Pyomo)
                        constant += scale * node.value
                        continue
                    column = self.add(node)
                terms[column] = terms.get(column, 0.0) + scale
            elif kind == _SUM:
                stack.extend((arg, scale) for arg in reversed(node.args))
            elif kind == _TERM:
                coefficient, var = node.args
                if coefficient.__class__ not in native_numeric_types:
                    coefficient = value(coefficient)
                stack.append((var, scale * coefficient))
            elif kind == _NAMED:
                stack.append((node.expr, scale))
            elif kind == _CONSTANT:
                constant += scale * value(node)
            elif kind == _PRODUCT:
                left, right = node.args
                factor = _fixed_value(left)
                if factor is not None:
                    stack.append((right, scale * factor))
                elif (factor := _fixed_value(right)) is not None:
                    stack.append((left, scale * factor))
                else:
                    raise Unsupported("a product of two expressions with variables")
            elif kind == _QUOTIENT:
                numerator, denominator = node.args
                divisor = _fixed_value(denominator)
                if divisor is None:
                    raise Unsupported("a division by a variable")
                stack.append((numerator, scale / divisor))
            else:  # _NEGATION
                stack.append((node.args[0], -scale))
        return constant, terms


def _bounded(con, columns: _Columns) -> tuple:
    """``(lower, constant, terms, upper)`` of a constraint, as Pyomo's ``to_bounded_expression`` splits it."""
    expr = con.expr
    if expr.__class__ is RangedExpression:
        lower, body, upper = expr.args
        constant, terms = columns.linear(body)
    else:
        left, right = expr.args
        equality = expr.__class__ is EqualityExpression
        if right.__class__ in native_numeric_types or not right.is_potentially_variable():
            lower, upper = (right if equality else None), right
            constant, terms = columns.linear(left)
        elif left.__class__ in native_numeric_types or not left.is_potentially_variable():
            lower, upper = left, (left if equality else None)
            constant, terms = columns.linear(right)
        else:
            lower, upper = (0 if equality else None), 0
            constant, terms = columns.linear(left, right)
    if lower is not None and lower.__class__ not in native_numeric_types:
        lower = value(lower)
    if upper is not None and upper.__class__ not in native_numeric_types:
        upper = value(upper)
    return lower, constant, terms, upper


def standard_form(m: pyo.Block) -> StandardForm:
    """The active objective and constraints of ``m`` as a matrix (fixed variables become constants).

    Raises :class:`Unsupported` for anything but one linear objective (or none) and linear
    constraints, and :class:`TrivialInfeasibility` for a constraint without variables that
    cannot hold.
    """
    columns = _Columns()
    objectives = list(m.component_data_objects(pyo.Objective, active=True, sort=ORDERED))
    if len(objectives) > 1:
        raise Unsupported("more than one objective")
    offset, cost_terms = columns.linear(objectives[0].expr) if objectives else (0.0, {})
    indices: list[int] = []
    data: list[float] = []
    starts = [0]
    rhs: list[float] = []
    sense: list[int] = []
    for con in m.component_data_objects(pyo.Constraint, active=True, sort=ORDERED):
        lower, constant, terms, upper = _bounded(con, columns)
        if lower is None and upper is None:
            continue
        terms = {column: coefficient for column, coefficient in terms.items() if coefficient != 0.0}
        if not terms:
            if (lower is None or lower <= constant) and (upper is None or upper >= constant):
                continue
            raise TrivialInfeasibility(f"model contains a trivially infeasible constraint, '{con.name}'")
        if lower == upper:
            rows = ((0, upper),)
        else:
            rows = (((1, upper),) if upper is not None else ()) + (((-1, lower),) if lower is not None else ())
        for row_sense, bound in rows:
            indices.extend(terms)
            data.extend(terms.values())
            starts.append(len(indices))
            rhs.append(bound - constant)
            sense.append(row_sense)
    variables = columns.variables
    n = len(variables)
    a = ColumnMatrix.from_rows(data, indices, starts, n)
    cost = np.zeros(n)
    cost[list(cost_terms)] = list(cost_terms.values())
    used = a.nonzero_columns() | (cost != 0.0)
    constants = np.array(rhs, dtype=float)
    fixed = np.array([v.fixed for v in variables], dtype=bool) & used
    if fixed.any():  # fixed variables met as columns: their terms move to the constants
        at = np.flatnonzero(fixed)
        x = np.array([variables[j].value for j in at], dtype=float)
        moved = 0.0
        for coefficient, value_ in zip(cost[at], x):  # one by one, in column order
            if coefficient != 0.0:
                moved += coefficient * value_
        offset = offset + moved
        constants = constants - a.columns(at).times(x)
        used &= ~fixed
    keep = np.flatnonzero(used)
    if len(keep) < n:
        a, cost = a.columns(keep), cost[keep]
    maximize = bool(objectives) and objectives[0].sense == pyo.maximize
    return StandardForm(columns=[variables[j] for j in keep], a=a, rhs=constants, sense=np.array(sense, dtype=int),
                        cost=cost, offset=float(offset), maximize=maximize)
