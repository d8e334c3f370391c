"""Plans as plain data: the result object and its tidy tables.

Column names of the tables are a public contract (``docs/exports.md``):

* ``market``: one row per period with the bids and the price bands;
* ``units``: one row per unit and period (``kind`` wind|pv|csp|ed|td; td values are
  heat [MW_th]; csp rows carry the electrical output and reserves);
* ``csp``: one row per CSP and period with the thermal side;
* ``dispatch``: one row per battery, hydro or biomass unit and period: a battery's charge,
  discharge and state of charge with its reserve margins, a unit's commitment;
* ``flexibility``: reserve energy per unit kind (MODEL_SPEC §11, paper Table 9).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..data.kinds import FLEX_KINDS
from .outcome import Outcome
from ..uncertainty.problem import Problem

PROTECTION_KEYS = {"price_da": "da", "price_sr_up": "sr_up", "price_sr_dn": "sr_dn"}


@dataclass(frozen=True, eq=False)
class Result:
    """Outcome of one solve: status, timings, objective and its parts, tidy tables."""

    problem: Problem = field(repr=False)
    status: Outcome
    termination: str
    message: str = ""
    objective_eur: float | None = None
    bound_eur: float | None = None
    mip_gap: float | None = None
    build_s: float = 0.0
    solve_s: float = 0.0
    extract_s: float = 0.0
    nodes: int | None = None
    lp_iterations: int | None = None
    # The plan's integer variables at one, by name: the solver settings' ``mip_start`` for the next day.
    integer_ones: tuple[str, ...] = field(default=(), repr=False)
    # Every unit variable's value by name, kept when asked: what an intraday session keeps before its window.
    schedule: dict[str, float] = field(default_factory=dict, repr=False)
    parts: dict[str, float] = field(default_factory=dict)
    protection_eur: dict[str, float] = field(default_factory=dict)
    market: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    units: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    csp: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    dispatch: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    flexibility: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)

    @property
    def has_plan(self) -> bool:
        return self.status.usable and self.objective_eur is not None and not self.market.empty

    @property
    def cost_keur(self) -> float | None:
        """The paper's cost: −profit [kEUR]."""
        return None if self.objective_eur is None else -self.objective_eur / 1000.0

    @property
    def case(self):
        return self.problem.case

    @property
    def day(self) -> dt.date:
        return self.problem.day

    def summary(self) -> dict:
        """The content of ``summary.json``."""
        case = self.problem.case
        summary = {
            "case": case.name,
            "date": self.day.isoformat(),
            "objective_eur": self.objective_eur,
            "cost_keur": self.cost_keur,
            "status": self.status,
            "termination": self.termination,
            "message": self.message,
            "mip_gap": self.mip_gap,
            "objective_bound_eur": self.bound_eur,
            "build_s": round(self.build_s, 4),
            "solve_s": round(self.solve_s, 4),
            "extract_s": round(self.extract_s, 4),
            "strategy": case.budgets.strategy,
            "budget_fraction": case.budgets.fraction,
            "budget_mode": case.budgets.mode,
            "budget_ties": case.budgets.ties,
            "budgets": self.problem.budgets,
            "markets": case.markets.label,
            "csp": [c.name for c in case.csp],
            "dt_h": self.problem.dt_h,
            "periods": self.problem.nt,
            "revenue_dam_eur": self.parts.get("revenue_dam_eur"),
            "revenue_sr_eur": self.parts.get("revenue_sr_eur"),
            "cost_hpa_eur": self.parts.get("cost_hpa_eur"),
            "cost_opex_eur": self.parts.get("cost_opex_eur"),
            "value_heat_kept_eur": self.parts.get("value_heat_kept_eur", 0.0),
            "protection_eur": {PROTECTION_KEYS[k]: v for k, v in self.protection_eur.items()},
            "settings": {
                "markets": case.markets.model_dump(mode="json"),
                "uncertainty": case.uncertainty.model_dump(mode="json"),
                "solver": case.solver.model_dump(mode="json"),
            },
        }
        return summary


def flexibility_table(units: pd.DataFrame, case) -> pd.DataFrame:
    """Reserve energy by unit kind (MODEL_SPEC §11; paper Flexibility1-2, Table 9).

    ``r_up_mwh = Σ r↑·dt``; ``r_up_h`` = ``r_up_mwh`` / installed capacity [h] (the paper's
    Table 9 labels this ratio "%").
    """
    dt_h = case.dt_h
    rows = []
    if units.empty:
        kinds, r_up, r_dn = np.array([], dtype=object), np.zeros(0), np.zeros(0)
    else:
        kinds, r_up, r_dn = (units[c].to_numpy() for c in ("kind", "r_up_mw", "r_dn_mw"))
    for kind in FLEX_KINDS:
        capacity = sum(u.p_max_mw for k, u in case.units() if k == kind)
        if capacity == 0:
            continue
        rows_of_kind = kinds == kind
        up = float(r_up[rows_of_kind].sum() * dt_h)
        dn = float(r_dn[rows_of_kind].sum() * dt_h)
        rows.append({"kind": kind, "r_up_mwh": up, "r_dn_mwh": dn, "capacity_mw": capacity,
                     "r_up_h": up / capacity, "r_dn_h": dn / capacity})
    return pd.DataFrame(rows, columns=["kind", "r_up_mwh", "r_dn_mwh", "capacity_mw", "r_up_h", "r_dn_h"])


@dataclass(frozen=True, eq=False)
class SessionResult:
    """Outcome of one intraday session's solve (MODEL_SPEC §14): status, timings, the trade and
    the position, the objective's parts and the tidy tables of the re-dispatch.

    ``market`` holds, besides the cleared day-ahead bids, ``traded_mw`` (``q_k``, + sell, − buy)
    and ``position_mw`` (``p_da + Σ_{j≤k} q_j``); its ``price_da_*`` columns hold the session's
    intraday price band. ``schedule``: every unit variable's value, which the next session keeps
    before its window.
    """

    problem: Problem = field(repr=False)
    session: str
    gate_closure: str
    first: int
    status: Outcome
    termination: str
    message: str = ""
    objective_eur: float | None = None
    bound_eur: float | None = None
    mip_gap: float | None = None
    build_s: float = 0.0
    solve_s: float = 0.0
    parts: dict[str, float] = field(default_factory=dict)
    market: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    units: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    csp: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    dispatch: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    schedule: dict[str, float] = field(default_factory=dict, repr=False)

    @property
    def has_plan(self) -> bool:
        return self.status.usable and self.objective_eur is not None and not self.market.empty

    @property
    def case(self):
        return self.problem.case

    @property
    def traded_mw(self) -> np.ndarray:
        """The session's trade per period [MW] (zeros without a plan)."""
        return self.market["traded_mw"].to_numpy(float) if self.has_plan else np.zeros(self.problem.nt)
