"""One delivery day made concrete: periods, forecast bands, uncertain sources, budgets.

:func:`prepare` turns a :class:`~rvpp.data.case.Case` into a :class:`Problem`, the only
input of the model builder. The conventions of MODEL_SPEC §6 live here:

=====================  ==================  ==========================================
series                 nominal             adverse deviation
=====================  ==================  ==========================================
DAM price              median              down ``mid - lo`` (selling), up ``hi - mid``
SR up / down price     upper percentile    ``hi - lo`` (downwards)
ND-RES, SF available   upper percentile    ``hi - lo`` (downwards)
ED, TD consumption     lower percentile    ``hi - lo`` (upwards)
=====================  ==================  ==========================================

Availabilities are clipped to ``[0, nameplate]``; budgets of the strategy presets
(paper Table 7) count hours and are scaled by ``1/dt`` to count periods.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import pandas as pd

from ..data.case import STRATEGY_BUDGETS_H, Case
from ..data.kinds import KINDS, Role, UnitKind, power_unit
from ..errors import CaseError
from ..data.history import PRICE_COLUMNS
from ..data.periods import delivery_periods, period_labels
from .forecast import band_specs, case_bands

MARGIN = 1e-6  # [MW], [MWh]: a limit counts as broken before solving only beyond the solver's tolerance


class SourceKind(StrEnum):
    """What an uncertain series is: a price, or a unit's production (bad direction: down) or
    consumption (bad direction: up), as its kind's :class:`~rvpp.data.kinds.Role` says."""

    PRICE_DA = "price_da"
    PRICE_SR = "price_sr"
    PRODUCTION = Role.PRODUCTION.value
    CONSUMPTION = Role.CONSUMPTION.value


@dataclass(frozen=True, eq=False)
class Source:
    """An uncertain series with its budget.

    ``deviation`` is the adverse deviation per period (for the DAM price, the downward one
    ``mid - lo``); ``deviation_up`` is the DAM price's upward deviation ``hi - mid``.
    """

    name: str
    kind: SourceKind
    unit_kind: UnitKind | None
    nominal: np.ndarray
    deviation: np.ndarray
    gamma: int
    deviation_up: np.ndarray | None = None

    @property
    def is_price(self) -> bool:
        return self.unit_kind is None


@dataclass(frozen=True, eq=False)
class Problem:
    """Everything the model needs for one delivery day."""

    case: Case
    day: dt.date
    periods: pd.DatetimeIndex
    bands: pd.DataFrame
    sources: dict[str, Source]
    tariff_hpa: np.ndarray
    labels: list[str] = field(default_factory=list)

    @property
    def nt(self) -> int:
        return len(self.periods)

    @property
    def dt_h(self) -> float:
        return self.case.dt_h

    @property
    def budgets(self) -> dict[str, int]:
        return {name: src.gamma for name, src in self.sources.items()}

    def periods_for_hours(self, hours: float) -> int:
        """A duration [h] as a whole number of periods."""
        return int(round(hours / self.dt_h))


def strategy_budgets(case: Case, nt: int) -> dict[str, int]:
    """Γ [periods] per source: strategy preset scaled to the period length (or the fraction
    ``⌊f·NT + ½⌋`` of the day when ``budgets.fraction`` is set), then overrides."""
    if case.budgets.fraction is not None:
        gamma = fraction_budget(case.budgets.fraction, nt)
        budgets = {name: gamma for name in case.sources()}
    else:
        preset = STRATEGY_BUDGETS_H[case.budgets.strategy]
        per_hour = int(round(1.0 / case.dt_h))
        budgets = {name: preset["price"] * per_hour for name in PRICE_COLUMNS}
        for kind, unit in case.uncertain_units():
            budgets[unit.name] = preset[KINDS[kind].budget] * per_hour
        budgets = {name: min(g, nt) for name, g in budgets.items()}
    for name, gamma in case.budgets.overrides:
        if gamma > nt:
            raise CaseError(f"budgets.overrides: Γ for {name!r}={gamma} exceeds the {nt} periods of "
                            f"{case.delivery_date} at dt_h={case.dt_h:g}")
        budgets[name] = gamma
    return budgets


def fraction_budget(fraction: float, nt: int) -> int:
    """Γ [periods] of a fraction of a day of ``nt`` periods, rounded half up: ``⌊f·NT + ½⌋``."""
    return min(nt, int(math.floor(fraction * nt + 0.5)))


def source_columns(case: Case) -> dict[str, tuple[str, float]]:
    """History column and scale of every uncertain source."""
    return {name: (spec.column, spec.scale) for name, spec in band_specs(case).items()}


def prepare(case: Case) -> Problem:
    """Resolve the delivery day of ``case`` into a :class:`Problem` (bands by each source's
    method: climatology or forecast, MODEL_SPEC §6)."""
    periods = delivery_periods(case.delivery_date, case.timezone, case.dt_h)
    return problem_from_bands(case, periods, case_bands(case, periods))


def problem_from_bands(case: Case, periods: pd.DatetimeIndex, bands: pd.DataFrame) -> Problem:
    """A :class:`Problem` from given bands ``(source, lo|mid|hi)`` per period."""
    budgets = strategy_budgets(case, len(periods))
    sources: dict[str, Source] = {}
    values = bands.to_numpy(float, copy=True)
    position = {key: j for j, key in enumerate(bands.columns)}
    lo, mid, hi = ({name: values[:, position[(name, stat)]] for name in bands.columns.levels[0]}
                   for stat in ("lo", "mid", "hi"))
    sources["price_da"] = Source("price_da", SourceKind.PRICE_DA, None, mid["price_da"],
                                 mid["price_da"] - lo["price_da"], budgets["price_da"],
                                 deviation_up=hi["price_da"] - mid["price_da"])
    for name in ("price_sr_up", "price_sr_dn"):
        sources[name] = Source(name, SourceKind.PRICE_SR, None, hi[name], hi[name] - lo[name], budgets[name])
    for kind, unit in case.uncertain_units():
        n = unit.name
        role = KINDS[kind].role
        if role is Role.PRODUCTION:
            cap = unit.series_capacity
            top, bottom = np.clip(hi[n], 0.0, cap), np.clip(lo[n], 0.0, cap)
            sources[n] = Source(n, SourceKind.PRODUCTION, kind, top, top - bottom, budgets[n])
        elif role is Role.CONSUMPTION:
            sources[n] = Source(n, SourceKind.CONSUMPTION, kind, lo[n], hi[n] - lo[n], budgets[n])
    tariff = np.array([case.markets.hpa_tariff_eur_per_mwh[h] for h in periods.hour], dtype=float)
    return Problem(case=case, day=case.delivery_date, periods=periods, bands=bands,
                   sources=sources, tariff_hpa=tariff, labels=period_labels(periods))


def top_gamma_deviation(deviation: np.ndarray, gamma: int) -> np.ndarray:
    """Paper-mode deviation: ``dev`` in the Γ largest-deviation periods, 0 elsewhere.

    Ties are broken towards earlier periods. When tied values straddle the Γ boundary
    the model may deviate in any of the tied periods (:func:`budget_split`); this
    single pattern is for display.
    """
    y = np.zeros_like(deviation, dtype=float)
    if gamma > 0:
        order = np.argsort(-deviation, kind="stable")[:gamma]
        y[order] = deviation[order]
    return y


def budget_split(deviation: np.ndarray, gamma: int, ties: str = "choose") -> tuple[np.ndarray, np.ndarray, int]:
    """Where paper mode may put Γ deviations (MODEL_SPEC §5): ``(sure, tied, count)``.

    ``sure`` marks the periods that deviate under every tie-break (deviation above the
    Γ-th largest); ``count`` more deviate among the periods marked ``tied`` (deviation
    equal to the Γ-th largest), and the model may choose which. Nothing is tied when
    that deviation is 0 (a zero deviation changes no bound). Under ``ties="earliest"``
    (``budgets.ties``) the earliest ``count`` tied periods are sure and nothing is left
    to choose.
    """
    sure, tied, count = _split(np.asarray(deviation, dtype=float), gamma)
    if ties == "earliest" and count:
        sure = sure.copy()
        sure[np.flatnonzero(tied)[:count]] = True
        return sure, np.zeros_like(tied), 0
    return sure, tied, count


def tied_budgets(problem: Problem, gamma: int | None = None) -> list[str]:
    """The sources whose Γ the model places among tied deviations, one phrase each, e.g.
    ``CSP1: 4 of the 5 periods tied at a deviation of 300 MW_th`` (empty when the data decide
    every period: no such tie, another budget variant, or ``budgets.ties: earliest``);
    with ``gamma``, for that Γ given to every source instead of each source's own.

    These are the days the solver has to search (docs/performance.md, the tie days)."""
    budgets = problem.case.budgets
    if budgets.mode != "paper" or budgets.ties != "choose":
        return []
    phrases = []
    for name, source in problem.sources.items():
        if source.is_price:
            continue
        _, tied, count = budget_split(source.deviation, int(source.gamma if gamma is None else gamma))
        if count and int(tied.sum()) > count:
            phrases.append(f"{name}: {count} of the {int(tied.sum())} periods tied at a deviation of "
                           f"{float(source.deviation[tied][0]):g} {power_unit(source.unit_kind)}")
    return phrases


def _split(dev: np.ndarray, gamma: int) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`budget_split` with the tied periods left to the model."""
    nothing = np.zeros(len(dev), dtype=bool)
    if gamma <= 0:
        return nothing, nothing, 0
    if gamma >= len(dev):
        return dev > 0.0, nothing, 0
    threshold = np.sort(dev)[::-1][gamma - 1]
    sure = dev > threshold
    if threshold <= 0.0:
        return sure, nothing, 0
    return sure, dev == threshold, gamma - int(sure.sum())


def infeasibility_reasons(problem: Problem) -> list[str]:
    """Causes of infeasibility that can be named before solving (empty if none found).

    Only what no plan can meet is refused: where Γ splits tied deviations, a bound is
    refused only if every choice of the tied periods breaks it.
    """
    case, hours = problem.case, problem.nt * problem.dt_h
    labels = problem.labels
    reasons = []
    needs_heat = [td.name for td in case.td
                  if td.q_min_mwh_th > 0 or td.h_min_mw_th > 0 or problem.sources[td.name].nominal.max() > MARGIN]
    if needs_heat and not case.csp and not case.markets.hpa:
        who = f"thermal demand {needs_heat[0]} needs" if len(needs_heat) == 1 else (
            f"thermal demands {', '.join(needs_heat[:-1])} and {needs_heat[-1]} need")
        reasons.append(f"no heat source: {who} heat but the case has no CSP and the HPA is off; "
                       "enable the HPA or add a CSP")
    paper = case.budgets.mode == "paper"

    def first_break(name: str, sign: float, breaks) -> tuple[int, float, str] | None:
        """``(period index, bound, note)`` where every plan breaks the limit, or ``None``.

        ``breaks(bound)`` marks the periods whose bound breaks the limit; a deviation
        (``sign``: +1 for consumptions, −1 for availabilities) only makes a bound worse.
        """
        src = problem.sources[name]
        sure, tied, count = budget_split(src.deviation, src.gamma if paper else 0, case.budgets.ties)
        deviated = src.nominal + sign * src.deviation
        bound = np.where(sure, deviated, src.nominal)
        if (broken := breaks(bound)).any():
            t = int(np.flatnonzero(broken)[0])
            return t, float(bound[t]), ""
        spoiled = tied & breaks(deviated)
        if int((tied & ~spoiled).sum()) < count:
            t = int(np.flatnonzero(spoiled)[0])
            return t, float(deviated[t]), (f" in every choice of the {count} deviating periods among the "
                                           f"{int(tied.sum())} tied at a deviation of {src.deviation[t]:.2f}")
        return None

    demands = [(f'ed "{d.name}"', d.name, "consumption", d.p_max_mw, "p_max_mw", d.e_min_mwh, "e_min_mwh", "MW")
               for d in case.ed]
    demands += [(f'td "{k.name}"', k.name, "heat", k.h_max_mw_th, "h_max_mw_th", k.q_min_mwh_th,
                 "q_min_mwh_th", "MW_th") for k in case.td]
    for label, name, what, cap, cap_field, energy, energy_field, unit in demands:
        if found := first_break(name, +1, lambda need, cap=cap: need > cap + MARGIN):
            t, need, note = found
            reasons.append(f"{label}: required {what} {need:.2f} {unit} at {labels[t]} exceeds {cap_field}={cap:g}"
                           + note)
        if energy > cap * hours + MARGIN:
            reasons.append(f"{label}: {energy_field}={energy:g} exceeds {cap_field} x {hours:g} h = "
                           f"{cap * hours:g} {unit.replace('MW', 'MWh')}")
    for unit in case.ndres:
        if found := first_break(unit.name, -1, lambda avail, floor=unit.p_min_mw: avail < floor - MARGIN):
            t, avail, note = found
            reasons.append(f'{unit.kind} "{unit.name}": available power {avail:.2f} MW at {labels[t]} is '
                           f"below p_min_mw={unit.p_min_mw:g}" + note)
    return reasons
