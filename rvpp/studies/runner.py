"""The shared runner: a study is a list of configurations solved by one function.

A :class:`Config` names its labels (e.g. ``strategy``, ``markets``) and the
:class:`~rvpp.data.variants.Variant` that makes its case. :func:`solve_configs` solves
them through :func:`rvpp.solving.batch.solve_many` (serially or on any executor), solves
identical cases once, and :func:`plan_row` turns every plan into one flat record whose
``variant`` column describes the case it solved (:func:`~rvpp.data.variants.describe`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from ..settle.audit import audit_result
from ..solving.batch import solve_many
from ..data.case import Case
from ..data.variants import Variant, describe
from ..data.kinds import FLEX_KINDS
from ..solving.results import Result
from .settings import StudySettings

Progress = Callable[[str, int, int], None]  # (stage, done, total)


def no_progress(_stage: str, _done: int, _total: int) -> None:
    """Default progress callback: report nothing."""


def stage(progress: Progress | None, name: str) -> Callable[[int, int], None]:
    """A ``(done, total)`` callback that reports under the stage ``name``."""
    report = progress or no_progress
    return lambda done, total: report(name, done, total)


@dataclass(frozen=True)
class Config:
    """One solve of a study: labels for the tables and the variant that makes its case."""

    labels: tuple[tuple[str, Any], ...]
    variant: Variant = Variant()

    @classmethod
    def of(cls, labels: dict[str, Any], **variant: Any) -> "Config":
        """``Config.of({"strategy": "balanced"}, strategy="balanced", markets="DAM+SRM")``."""
        return cls(tuple(labels.items()), Variant(**variant))

    def case(self, base: Case, settings: StudySettings) -> Case:
        return self.variant.apply(base, solver={"threads": settings.threads})


@dataclass
class StudyOutput:
    """What a study hands back: tables, figures, facts for the report, notes.

    ``warnings`` say what makes the study's numbers less than complete (e.g. settlements
    that did not end optimal); they open the study's section of ``report.md``.
    """

    name: str
    title: str
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    figures: dict[str, Any] = field(default_factory=dict)
    facts: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0


def solve_configs(base: Case, configs: Sequence[Config], settings: StudySettings,
                  executor: Executor | None = None, progress: Progress | None = None,
                  stage_name: str = "solves") -> list[Result]:
    """The plan of every configuration, in order; identical cases are solved once."""
    cases = [config.case(base, settings) for config in configs]
    unique = list(dict.fromkeys(cases))
    results = dict(zip(unique, solve_many(unique, executor, stage(progress, stage_name))))
    return [results[case] for case in cases]


def plan_row(config: Config, result: Result) -> dict[str, Any]:
    """One flat record of a plan: labels, the variant solved, status, cost, trades and
    reserves by unit kind.

    ``variant`` describes the case the plan was solved for (strategy, markets and any Γ
    edit, e.g. ``balanced · DAM+SRM+HPA · Γ WF1=12``). Energies are ``Σt x·dt`` [MWh] / [MWh_th]; ``audit_violations`` counts the rules of
    MODEL_SPEC the plan breaks (:func:`rvpp.settle.audit.audit_result`; 0 expected).
    """
    row: dict[str, Any] = dict(config.labels)
    row.update({"variant": describe(result.case), "status": result.status, "cost_keur": result.cost_keur, "profit_eur": result.objective_eur,
                "mip_gap": result.mip_gap, "solve_s": result.solve_s})
    if not result.has_plan:
        return row
    dt_h = result.problem.dt_h
    market = result.market
    row.update({
        "sold_mwh": float(market["p_da_mw"].clip(lower=0).sum() * dt_h),
        "bought_mwh": float(-market["p_da_mw"].clip(upper=0).sum() * dt_h),
        "net_traded_mwh": float(market["p_da_mw"].sum() * dt_h),
        "heat_bought_mwh": float(market["h_hpa_mw"].sum() * dt_h),
        "sr_up_mwh": float(market["r_sr_up_mw"].sum() * dt_h),
        "sr_dn_mwh": float(market["r_sr_dn_mw"].sum() * dt_h),
    })
    flexibility = result.flexibility.set_index("kind")
    for kind in FLEX_KINDS:
        present = kind in flexibility.index
        row[f"{kind}_up_mwh"] = float(flexibility.loc[kind, "r_up_mwh"]) if present else 0.0
        row[f"{kind}_dn_mwh"] = float(flexibility.loc[kind, "r_dn_mwh"]) if present else 0.0
    row["audit_violations"] = len(audit_result(result))
    return row


def plan_table(configs: Sequence[Config], results: Sequence[Result]) -> pd.DataFrame:
    return pd.DataFrame([plan_row(c, r) for c, r in zip(configs, results)])
