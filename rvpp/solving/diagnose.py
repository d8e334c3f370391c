"""Explain an infeasible day: which balance or requirement cannot be met, where, how much.

The model is rebuilt with non-negative slacks on the constraints a user can act on
(energy and heat balances, daily minimum energies, trading limits), the total slack
[MWh] is minimised, and the constraints that still need slack are reported with the
periods and amounts, plus the remedies that apply.
"""

from __future__ import annotations

import pyomo.environ as pyo

from ..model import build_model
from ..uncertainty.problem import Problem
from .highs import run_highs

REPORT_THRESHOLD = 1e-4  # [MW] or [MWh] of slack worth reporting


def explain_infeasibility(problem: Problem) -> str:
    """A readable account of why ``problem`` has no plan ('' if it has one)."""
    m = build_model(problem)
    case = problem.case
    targets = [(m.electric_balance, "electricity balance"), (m.heat_balance, "heat balance"),
               (m.trade_upper, "DAM selling limit"), (m.trade_lower, "DAM buying limit")]
    targets += [(m.ed[d.name].energy, f'minimum energy of ed "{d.name}"') for d in case.ed]
    targets += [(m.td[k.name].energy, f'minimum heat of td "{k.name}"') for k in case.td]
    rows = [(name, index, row) for constraint, name in targets for index, row in constraint.items()]
    m.slack_plus = pyo.Var(range(len(rows)), domain=pyo.NonNegativeReals)
    m.slack_minus = pyo.Var(range(len(rows)), domain=pyo.NonNegativeReals)
    for i, (_, _, row) in enumerate(rows):  # relax each row in both directions
        row.set_value((row.lower, row.body + m.slack_plus[i] - m.slack_minus[i], row.upper))
    m.profit.deactivate()
    m.shortfall = pyo.Objective(expr=sum(m.slack_plus[i] + m.slack_minus[i] for i in range(len(rows))),
                                sense=pyo.minimize)
    outcome = run_highs(m, case.solver)
    if not outcome.usable:
        return ("no plan exists even with every balance relaxed; check the units' limits "
                "(minimum outputs, storage and power-block bounds)")
    by_name: dict[str, list[tuple[object, float]]] = {}
    for i, (name, index, _) in enumerate(rows):
        amount = (pyo.value(m.slack_plus[i]) or 0.0) + (pyo.value(m.slack_minus[i]) or 0.0)
        if amount > REPORT_THRESHOLD:
            by_name.setdefault(name, []).append((index, amount))
    if not by_name:
        return ""
    parts = []
    for name, rows in by_name.items():
        power, energy = ("MW_th", "MWh_th") if "heat" in name else ("MW", "MWh")
        if rows[0][0] is None:  # a daily minimum: its slack is an energy already
            parts.append(f"{name} short by {rows[0][1]:.1f} {energy}")
            continue
        total = sum(a for _, a in rows) * problem.dt_h
        parts.append(f"{name} short by up to {max(a for _, a in rows):.1f} {power} in {len(rows)} "
                     f"period(s){_where(problem, rows[0][0])} ({total:.1f} {energy} in all)")
    return "; ".join(parts) + ". " + _remedies(problem, by_name)


def _where(problem: Problem, index) -> str:
    t = index[-1] if isinstance(index, tuple) else index
    scenario = f", {index[0]} activation" if isinstance(index, tuple) and index[0] != "none" else ""
    return f", first at {problem.labels[t - 1]}{scenario}"


def _remedies(problem: Problem, by_name: dict) -> str:
    case = problem.case
    hints = []
    if any("heat" in name for name in by_name):
        if not case.markets.hpa:
            hints.append("enable the HPA")
        hints.append("lower the budgets of the solar fields and thermal demands")
    if any(name.startswith(("electricity", "DAM", "minimum energy")) for name in by_name):
        hints.append("lower the budgets of the renewables and electrical demands")
    return "Try to " + " or ".join(dict.fromkeys(hints)) + "." if hints else ""
