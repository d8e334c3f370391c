"""One way to derive a variant of a case, and the label of what a run solved.

A :class:`Variant` names what a run changes in a case: the strategy preset, the Γ
edits, the market set, the period length, the CSPs kept and a flat HPA tariff. The
command line (``solve``), the dashboard's pages and every study derive their runs with
:meth:`Variant.apply`, and a table row is labelled with :func:`describe` of the case it
solved, so the label always names the budgets actually in force, e.g.
``balanced · DAM+SRM+HPA · Γ WF1=12``.

A strategy given by the variant is the strategy *as published* (paper Table 7): the
case's own Γ edits are set aside and only the variant's ``gammas`` apply on top of the
preset. Without a strategy, the case keeps its strategy and Γ edits and the variant's
``gammas`` are added to them.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import CaseError, require
from .case import MARKET_NAMES, BudgetEncoding, BudgetMode, Case, PwlEncoding, Strategy, Ties
from .edits import convert_overrides
from .files import excerpt
from .periods import ALLOWED_DT_H, delivery_periods

SEPARATOR = " · "


@dataclass(frozen=True)
class Variant:
    """What a run changes in a case; ``None`` (or ``csp=True``) keeps the case's own setting.

    ``strategy``: a preset of paper Table 7 (the case's Γ edits are then dropped);
    ``gamma_fraction``: Γ of every source as a fraction of the day, ``⌊f·NT + ½⌋`` periods,
    in place of any preset (the case's Γ edits are dropped too);
    ``gammas``: Γ per source [periods], as ``{name: Γ}`` or sorted pairs;
    ``markets``: a market set such as ``"DAM+SRM"`` or ``"DAM,SRM"``; ``dt_h``: period
    length [h]; ``csp``: ``False`` removes every CSP (and its Γ edit); ``hpa_flat``: one
    HPA tariff for every hour [EUR/MWh_th].
    """

    strategy: Strategy | None = None
    gamma_fraction: float | None = None
    gammas: tuple[tuple[str, int], ...] = ()
    markets: str | None = None
    dt_h: float | None = None
    csp: bool = True
    hpa_flat: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.gammas, Mapping):
            object.__setattr__(self, "gammas", tuple(sorted(self.gammas.items())))

    def changes(self, case: Case) -> dict[str, Any]:
        """The :meth:`Case.replace` changes that make this variant of ``case``."""
        changes: dict[str, Any] = {}
        own = case.budgets.override_map  # the case's own Γ edits, in periods of its period length
        if self.dt_h is not None:
            changes["dt_h"] = self.dt_h
            if own and self.dt_h in ALLOWED_DT_H and self.dt_h != case.dt_h:  # they keep their hours
                periods = len(delivery_periods(case.delivery_date, case.timezone, self.dt_h))
                own = convert_overrides(own, case.dt_h, self.dt_h, periods)
        budgets: dict[str, Any] = {}
        if self.gamma_fraction is not None:
            budgets = {"fraction": self.gamma_fraction, "overrides": dict(self.gammas)}
        elif self.strategy is not None:
            budgets = {"strategy": self.strategy, "fraction": None, "overrides": dict(self.gammas)}
        elif self.gammas or own != case.budgets.override_map:
            budgets = {"overrides": {**own, **dict(self.gammas)}}
        markets: dict[str, Any] = parse_markets(self.markets) if self.markets is not None else {}
        if self.hpa_flat is not None:
            markets["hpa_tariff_eur_per_mwh"] = [self.hpa_flat] * 24
        if markets:
            changes["markets"] = markets
        if not self.csp and case.csp:
            changes["csp"] = []
            dropped = {c.name for c in case.csp}
            overrides = budgets.get("overrides", own)
            budgets["overrides"] = {k: v for k, v in overrides.items() if k not in dropped}
        if budgets:
            changes["budgets"] = budgets
        return changes

    def apply(self, case: Case, **more: Any) -> Case:
        """This variant of ``case``; ``more`` are further :meth:`Case.replace` changes made in
        the same step (e.g. ``solver={"threads": 1}``)."""
        changes = {**self.changes(case), **more}
        return case.replace(**changes) if changes else case

    def label(self, case: Case) -> str:
        """The label of this variant of ``case`` (see :func:`describe`)."""
        return describe(self.apply(case))


def describe(case: Case) -> str:
    """What a case solves, in one line: strategy, markets, then what differs from a plain run.

    ``balanced · DAM+SRM+HPA`` (``Γ 0.25 of the day · DAM+SRM+HPA`` for a Γ fraction); Γ edits
    follow as ``Γ WF1=12, price_da=3`` (or ``Γ=6 for every source`` when one value covers every
    source); then ``no CSP``, ``HPA flat 60
    EUR/MWh_th``, ``15-min periods`` and ``planner-chosen hours`` where they apply.
    """
    parts = [case.budgets.label, case.markets.label]
    overrides = case.budgets.override_map
    if overrides:
        values = set(overrides.values())
        if len(values) == 1 and set(overrides) == set(case.sources()) and len(overrides) > 1:
            parts.append(f"Γ={values.pop()} for every source")
        else:
            parts.append("Γ " + ", ".join(f"{name}={gamma}" for name, gamma in overrides.items()))
    if not case.csp:
        parts.append("no CSP")
    tariff = set(case.markets.hpa_tariff_eur_per_mwh)
    if case.markets.hpa and len(tariff) == 1:
        parts.append(f"HPA flat {tariff.pop():g} EUR/MWh_th")
    if case.dt_h != 1.0:
        parts.append(f"{case.dt_h * 60:g}-min periods")
    if case.budgets.mode != "paper":
        parts.append("planner-chosen hours")
    if case.budgets.ties == "earliest":
        parts.append("earliest tied periods")
    return SEPARATOR.join(parts)


def parse_markets(text: str) -> dict[str, bool]:
    """``"DAM,SRM"`` -> ``{"srm": True, "hpa": False}``; the DAM is always required."""
    if not isinstance(text, str):
        raise CaseError(f"markets={excerpt(text)!r} must be text such as DAM,SRM,HPA")
    names = [part.strip().upper() for part in text.replace("+", ",").split(",") if part.strip()]
    if not names:
        raise CaseError(f"markets={excerpt(text)!r} names no market; give a comma-separated subset of "
                        f"{','.join(MARKET_NAMES)}, e.g. DAM,SRM")
    unknown = [n for n in names if n not in MARKET_NAMES]
    if unknown:
        raise CaseError(f"markets: unknown market {excerpt(unknown[0])!r}; choose from {', '.join(MARKET_NAMES)}")
    if "DAM" not in names:
        raise CaseError(f"markets={excerpt(text)!r} must include DAM (the day-ahead market is always on)")
    return {"srm": "SRM" in names, "hpa": "HPA" in names}


def with_options(
    case: Case,
    *,
    date: dt.date | str | None = None,
    strategy: Strategy | None = None,
    gamma_fraction: float | None = None,
    gammas: Mapping[str, int] | None = None,
    markets: str | None = None,
    csp: bool = True,
    hpa_flat: float | None = None,
    dt_h: float | None = None,
    budget_mode: BudgetMode | None = None,
    ties: Ties | None = None,
    time_limit_s: float | None = None,
    rel_gap: float | None = None,
    threads: int | None = None,
    budget_encoding: BudgetEncoding | None = None,
    pwl_encoding: PwlEncoding | None = None,
) -> Case:
    """A copy of ``case`` with run options applied (what the command line offers).

    Strategy, Γ fraction, Γ edits, markets, CSPs, HPA tariff and period length make a
    :class:`~rvpp.data.variants.Variant` (a strategy sets the case's own Γ edits aside);
    the date, budget mode and solver settings are changed in the same step.
    """
    require(case, Case, "rvpp.with_options: case", "from rvpp.load_case")
    require(csp, bool, "rvpp.with_options: csp", "True keeps the CSPs, False removes them")
    require(gammas if gammas is not None else {}, Mapping, "rvpp.with_options: gammas", "{source: Γ}")
    variant = Variant(strategy=strategy, gamma_fraction=gamma_fraction, gammas=dict(gammas or {}), markets=markets,
                      dt_h=dt_h, csp=csp, hpa_flat=hpa_flat)
    changes: dict[str, Any] = variant.changes(case)
    if date is not None:
        changes["delivery_date"] = date
    if budget_mode is not None:
        changes["budgets"] = {**changes.get("budgets", {}), "mode": budget_mode}
    if ties is not None:
        changes["budgets"] = {**changes.get("budgets", {}), "ties": ties}
    solver = {k: v for k, v in {"time_limit_s": time_limit_s, "rel_gap": rel_gap, "threads": threads,
                                "budget_encoding": budget_encoding, "pwl_encoding": pwl_encoding}.items()
              if v is not None}
    if solver:
        changes["solver"] = solver
    return case.replace(**changes) if changes else case
