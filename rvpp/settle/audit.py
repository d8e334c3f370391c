"""Independent audit of a plan against MODEL_SPEC §4-§9.

The audit reads only the exported tables (``market``, ``units``, ``csp``), the summary
and the case; it never touches the optimisation model nor the preparation of the day
(:mod:`rvpp.uncertainty.problem`, :mod:`rvpp.uncertainty`). What the plan had to respect
is derived here from the case and its history with the audit's own arithmetic
(:func:`audit_day`): the bands of MODEL_SPEC §6 (:func:`band` for the paper's climatology,
:func:`forecast_band` for a point forecast and its past errors), the nominal
values and deviations, the budgets of paper Table 7, and the power-block curve as a
piecewise-linear interpolation of the breakpoints. It re-checks every balance in all
three activation scenarios, the market limits, every unit's bounds, the power-block
curve, the storage energy recursion and reserve margins, the turbine commitment and
minimum up/down times, the budgets Γ and the placement of χ, the price protection (sum
of the Γ largest exposures) and the objective.

Use :func:`audit_result` on a :class:`~rvpp.solving.results.Result`, or :func:`audit_export`
on a folder written by ``python -m rvpp solve``.
"""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..data.case import STRATEGY_BUDGETS_H, Case
from ..data.kinds import KINDS, NDRES_KINDS, Role, UnitKind
from ..data.scenarios import Scenario
from ..data.history import PRICE_COLUMNS
from ..data.periods import delivery_periods

TOLERANCE = 1e-4  # [MW], [MWh]: exported values carry 6 decimals
NEAREST_SHARE, NEAREST_MIN = 0.2, 24  # forecast bands: errors of the nearest fifth of the window, >= 24 hours
PRICE_LAGS = {"same_hour_yesterday": (1,), "same_hour_last_week": (7,), "blend": (1, 7)}  # [days]
MONEY_TOLERANCE = 1e-2  # [EUR]: one cent on any objective part


@dataclass(frozen=True)
class Violation:
    """One broken rule: which check, where, and by how much."""

    check: str
    unit: str | None
    t: int | None
    excess: float
    detail: str = ""

    def __str__(self) -> str:
        where = " ".join(x for x in (self.unit or "", f"t={self.t}" if self.t is not None else "") if x)
        return f"{self.check} [{where}] broken by {self.excess:.6g}" + (f": {self.detail}" if self.detail else "")


# ----------------------------------------------------------------------------- what the plan had to respect


@dataclass(frozen=True, eq=False)
class Series:
    """One uncertain series as the audit derives it (MODEL_SPEC §6 table).

    ``kind``: ``price_da``, ``price_sr``, ``production`` (bad direction down) or
    ``consumption`` (up); ``deviation``: the adverse deviation (for the DAM price the
    downward one), ``deviation_up``: the DAM price's upward deviation; ``gamma`` [periods].
    """

    kind: str
    unit_kind: str | None
    nominal: np.ndarray
    deviation: np.ndarray
    gamma: int
    deviation_up: np.ndarray | None = None

    @property
    def is_price(self) -> bool:
        return self.unit_kind is None


@dataclass(frozen=True, eq=False)
class AuditDay:
    """The delivery day of ``case``: periods, every uncertain series, the HPA tariff."""

    case: Case
    nt: int
    dt_h: float
    sources: dict[str, Series]
    tariff_hpa: np.ndarray

    def periods_for_hours(self, hours: float) -> int:
        return int(round(hours / self.dt_h))


def band(case: Case, column: str, scale: float, hours: np.ndarray,
         window: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lo, mid, hi)`` of one history column per period, the period's clock hour in ``hours``.

    MODEL_SPEC §6 (the paper's climatology): over the ``window_days`` whole local days
    before the delivery day, per local clock hour, the ``q_lo`` percentile, the median and
    the ``q_hi`` percentile (numpy's linear interpolation) of ``scale`` x the column. Other
    ways to draw a band (e.g. from a point forecast and its past errors) belong here.
    ``window``: :func:`climatology_window` of the case (found once per day, shared by its sources).
    """
    rows, clock = window
    values = case.history.frame[column].to_numpy(float)[rows] * scale
    quantiles = (case.uncertainty.q_lo, 0.5, case.uncertainty.q_hi)
    wanted = sorted(set(hours.tolist()))
    groups = [values[clock == h] for h in wanted]
    if len({len(group) for group in groups}) == 1:  # one call for all hours (as many days in each)
        per_hour = dict(zip(wanted, np.quantile(np.column_stack(groups), quantiles, axis=0).T))
    else:
        per_hour = {h: np.quantile(group, quantiles) for h, group in zip(wanted, groups)}
    lo, mid, hi = np.array([per_hour[h] for h in hours.tolist()]).T
    return lo, mid, hi


def climatology_window(case: Case) -> tuple[np.ndarray, np.ndarray]:
    """The history rows of the ``window_days`` whole local days before the delivery day (a mask)
    and their local clock hours."""
    local = case.history.frame.index.tz_convert(case.timezone)
    days = np.array(local.date)
    first = case.delivery_date - dt.timedelta(days=case.uncertainty.window_days)
    rows = (days >= first) & (days < case.delivery_date)
    return rows, np.asarray(local.hour)[rows]


def forecast_band(case: Case, column: str, scale: float, forecast: str | None,
                  periods: pd.DatetimeIndex) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lo, mid, hi)`` per period from a point forecast and its past errors (MODEL_SPEC §6).

    The forecast ``f`` is the history column ``forecast`` (rows of the delivery day), or for
    prices (``forecast`` None) the case's naive model: the price at the same local clock hour
    one day and/or a week before (the first of a repeated hour; the hour before a skipped
    one). Over the window's hours, errors ``e = actual - f``; for each period, the errors of
    the window hours whose ``f`` lies nearest (the nearest fifth, at least 24, ties kept)
    give ``f + (q_lo percentile, median, q_hi percentile)``. Not clipped here.
    """
    frame = case.history.frame
    local = frame.index.tz_convert(case.timezone)
    dates, clock = np.array(local.date), np.asarray(local.hour)
    day = case.delivery_date
    window = (dates >= day - dt.timedelta(days=case.uncertainty.window_days)) & (dates < day)
    actual = frame[column].to_numpy(float) * scale
    if forecast is not None:
        guess = frame[forecast].to_numpy(float) * scale
        by_instant = dict(zip(frame.index, guess))
        point = np.array([by_instant[t] for t in periods.tz_convert("UTC").floor("h")])
    else:
        seen: dict = {}
        for d, h, v in zip(dates, clock, actual):
            seen.setdefault((d, h), v)

        def value(d: dt.date, h: int) -> float:
            while (d, h) not in seen and h > 0:
                h -= 1
            return seen.get((d, h), np.nan)

        def naive(d: dt.date, h: int) -> float:
            return float(np.mean([value(d - dt.timedelta(days=lag), h)
                                  for lag in PRICE_LAGS[case.uncertainty.price_forecast]]))

        guess = np.array([naive(d, h) if w else np.nan for d, h, w in zip(dates, clock, window)])
        point = np.array([naive(day, h) for h in periods.hour])
    past, error = guess[window], (actual - guess)[window]
    known = ~np.isnan(past) & ~np.isnan(error)
    past, error = past[known], error[known]
    count = min(len(error), max(NEAREST_MIN, int(np.ceil(NEAREST_SHARE * len(error)))))
    quantiles = (case.uncertainty.q_lo, 0.5, case.uncertainty.q_hi)
    rows = []
    for level in point:
        distance = np.abs(past - level)
        rows.append(level + np.quantile(error[distance <= np.sort(distance)[count - 1]], quantiles))
    lo, mid, hi = np.array(rows).T
    return lo, mid, hi


def finer_series(hourly: np.ndarray, steps: int, low: float | None, high) -> np.ndarray:
    """Hourly means at ``steps`` periods per hour (MODEL_SPEC §6, finer periods): each period is
    the mean slope over its span of a monotone cubic (PCHIP) through the cumulative energy at
    the hour boundaries (above ``low``), then held within ``[low, high]`` (``high`` a number or
    one per period) hour by hour, the hour's mean restored by moving the difference onto its
    periods in proportion to their room to the limit on that side."""
    n = len(hourly)
    top = np.full(n * steps, np.inf) if high is None else np.broadcast_to(np.asarray(high, float), (n * steps,))
    bottom = -np.inf if low is None else low
    hourly = np.array([min(max(v, bottom), top[h * steps:(h + 1) * steps].mean()) for h, v in enumerate(hourly)])
    shift = 0.0 if low is None else low
    energy = np.concatenate([[0.0], np.cumsum(hourly - shift)])
    if n > 1:
        # heavy: SciPy's interpolation takes seconds to import, and only quarter-hour audits need it
        from scipy.interpolate import PchipInterpolator

        curve = PchipInterpolator(np.arange(n + 1), energy)(np.linspace(0.0, n, n * steps + 1))
    else:
        curve = np.linspace(0.0, energy[-1], steps + 1)
    out = np.empty(n * steps)
    for h in range(n):
        edges = curve[h * steps:(h + 1) * steps + 1].copy()
        edges[0], edges[-1] = energy[h], energy[h + 1]
        part = np.diff(edges) * steps + shift
        cap = top[h * steps:(h + 1) * steps]
        part = np.minimum(np.maximum(part, bottom), cap)
        gap = hourly[h] * steps - part.sum()
        room = (cap - part) if gap > 0 else (part - bottom)
        room = np.where(np.isinf(room), 1.0, room)
        if room.sum() > 0:
            part = part + gap * room / room.sum()
        out[h * steps:(h + 1) * steps] = np.minimum(np.maximum(part, bottom), cap)
    return out


def finer_band(lo: np.ndarray, mid: np.ndarray, hi: np.ndarray, steps: int, low: float | None,
               high: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An hourly band at ``steps`` periods per hour, ordered in every period: ``lo`` by
    :func:`finer_series`, then ``mid - lo`` and ``hi - mid`` as series >= 0 within the room below ``high``."""
    fine_lo = finer_series(lo, steps, low, high)
    fine_mid = fine_lo + finer_series(np.maximum(mid - lo, 0.0), steps, 0.0, None if high is None else high - fine_lo)
    fine_hi = fine_mid + finer_series(np.maximum(hi - mid, 0.0), steps, 0.0, None if high is None else high - fine_mid)
    return fine_lo, fine_mid, fine_hi


def budgets(case: Case, nt: int) -> dict[str, int]:
    """Γ [periods] per source: the strategy's Table 7 hours scaled by ``1/dt`` (at most ``nt``), or
    ``budgets.fraction`` of the ``nt`` periods rounded half up for every source; then the case's edits."""
    names = [*PRICE_COLUMNS, *(unit.name for _, unit in case.units())]
    if case.budgets.fraction is not None:
        share = case.budgets.fraction * nt
        gamma = int(share) + (1 if share - int(share) >= 0.5 else 0)
        return {**{name: min(gamma, nt) for name in names}, **case.budgets.override_map}
    preset, per_hour = STRATEGY_BUDGETS_H[case.budgets.strategy], int(round(1.0 / case.dt_h))
    gammas = {name: min(preset["price"] * per_hour, nt) for name in PRICE_COLUMNS}
    gammas.update({unit.name: min(preset[KINDS[kind].budget] * per_hour, nt)
                   for kind, unit in case.uncertain_units()})
    return {**gammas, **case.budgets.override_map}


def audit_day(case: Case, bands: pd.DataFrame | None = None) -> AuditDay:
    """What a plan of the case's delivery day must respect (MODEL_SPEC §1, §6).

    ``bands``: ``(source, lo|mid|hi)`` per period, to audit a plan made from given
    bands instead of those of the history (:func:`band`).
    """
    periods = delivery_periods(case.delivery_date, case.timezone, case.dt_h)
    hours, nt = np.asarray(periods.hour), len(periods)
    whole = delivery_periods(case.delivery_date, case.timezone, 1.0)  # the history's hours of the day
    steps = nt // len(whole)
    gammas = budgets(case, nt)

    window = None

    def lo_mid_hi(name: str, column: str, scale: float, kind: str | None = None, forecast: str | None = None,
                  low: float | None = None, high: float | None = None):
        nonlocal window
        if bands is not None:
            return tuple(bands[(name, stat)].to_numpy(float) for stat in ("lo", "mid", "hi"))
        if case.uncertainty.band_method(name, kind) == "forecast":
            hourly = forecast_band(case, column, scale, forecast, whole)
        else:
            if window is None:
                window = climatology_window(case)
            hourly = band(case, column, scale, np.asarray(whole.hour), window)
        if steps == 1:
            return hourly
        held = (np.clip(x, -np.inf if low is None else low, np.inf if high is None else high) for x in hourly)
        return finer_band(*held, steps, low, high)

    sources = {}
    lo, mid, hi = lo_mid_hi("price_da", "price_da", 1.0)
    sources["price_da"] = Series("price_da", None, mid, mid - lo, gammas["price_da"], deviation_up=hi - mid)
    for name in ("price_sr_up", "price_sr_dn"):
        lo, _, hi = lo_mid_hi(name, name, 1.0)
        sources[name] = Series("price_sr", None, hi, hi - lo, gammas[name])
    for kind, unit in case.uncertain_units():
        if kind == UnitKind.CSP:
            field = unit.solar_field
            lo, _, hi = lo_mid_hi(unit.name, field.series or unit.name, field.series_scale, kind, field.forecast_series,
                                  0.0, field.p_max_mw_th)
            top, bottom = np.clip(hi, 0.0, field.p_max_mw_th), np.clip(lo, 0.0, field.p_max_mw_th)
        else:
            lo, _, hi = lo_mid_hi(unit.name, unit.series or unit.name, unit.series_scale, kind, unit.forecast_series,
                                  0.0, unit.p_max_mw if kind in NDRES_KINDS else None)
        if kind in NDRES_KINDS:
            top, bottom = np.clip(hi, 0.0, unit.p_max_mw), np.clip(lo, 0.0, unit.p_max_mw)
        if KINDS[kind].role is Role.PRODUCTION:
            sources[unit.name] = Series("production", kind, top, top - bottom, gammas[unit.name])
        else:
            if case.uncertainty.band_method(unit.name, kind) == "forecast" and bands is None:
                lo, hi = np.maximum(lo, 0.0), np.maximum(hi, 0.0)  # a forecast consumption band stays >= 0
            sources[unit.name] = Series("consumption", kind, lo, hi - lo, gammas[unit.name])
    tariff = np.array([case.markets.hpa_tariff_eur_per_mwh[h] for h in hours], dtype=float)
    return AuditDay(case=case, nt=nt, dt_h=case.dt_h, sources=sources, tariff_hpa=tariff)


def curve_output_mw(pb, thermal_mw: np.ndarray) -> np.ndarray:
    """Electrical output [MW] of an online power block at thermal input [MW_th] (paper STU5).

    Linear interpolation between the breakpoints ``(P_n, η_n·P_n)``, the input held to
    ``[p_in_min, p_in_max]``.
    """
    inputs = np.array([p for p, _ in pb.breakpoints], dtype=float)
    outputs = np.array([p * eta for p, eta in pb.breakpoints], dtype=float)
    return np.interp(np.clip(thermal_mw, pb.p_in_min_mw_th, pb.p_in_max_mw_th), inputs, outputs)


# ----------------------------------------------------------------------------- entry points


class _Auditor:
    def __init__(self, tol: float):
        self.tol = tol
        self.violations: list[Violation] = []

    def leq(self, check: str, lhs, rhs, unit: str | None = None, scale: float = 1.0) -> None:
        """Record every period where ``lhs <= rhs`` fails beyond the tolerance."""
        lhs, rhs = np.broadcast_arrays(np.asarray(lhs, float), np.asarray(rhs, float))
        excess = lhs - rhs
        limit = self.tol * max(1.0, scale)
        for i in np.flatnonzero(excess > limit):
            t = int(i) + 1 if lhs.ndim else None
            self.violations.append(Violation(check, unit, t, float(excess.flat[i]),
                                             f"{lhs.flat[i]:.6g} > {rhs.flat[i]:.6g}"))

    def eq(self, check: str, lhs, rhs, unit: str | None = None, scale: float = 1.0) -> None:
        self.leq(check, lhs, rhs, unit, scale)
        self.leq(check, rhs, lhs, unit, scale)

    def fail(self, check: str, detail: str, unit: str | None = None, t: int | None = None,
             excess: float = float("nan")) -> None:
        self.violations.append(Violation(check, unit, t, excess, detail))


def _activation(s: str, up, dn):
    return up if s == Scenario.UP else (-dn if s == Scenario.DN else 0.0 * up)


def audit_result(result, tol: float = TOLERANCE, bands: pd.DataFrame | None = None) -> list[Violation]:
    """Audit a solved :class:`~rvpp.solving.results.Result` (empty list: every rule holds).

    ``bands``: audit against these ``(source, lo|mid|hi)`` bands instead of the history's
    (for a plan solved from given bands, e.g. ``result.problem.bands`` of a hand-made problem).
    """
    if not result.has_plan:
        return [Violation("plan", None, None, float("nan"), f"no plan to audit ({result.status})")]
    return audit_tables(audit_day(result.case, bands), result.market, result.units, result.csp, result.summary(),
                        tol, dispatch=result.dispatch)


def audit_export(case: Case, folder: str | Path, tol: float = TOLERANCE) -> list[Violation]:
    """Audit a folder written by ``python -m rvpp solve`` against ``case``.

    The run (date, period length, strategy, budgets, budget mode, markets and their
    settings, the CSPs kept) is read back from ``summary.json``.
    """
    folder = Path(folder)
    summary = json.loads((folder / "summary.json").read_text())
    settings = summary["settings"]
    kept = set(summary["csp"])
    run = case.replace(
        delivery_date=summary["date"], dt_h=summary["dt_h"], markets=settings["markets"],
        uncertainty=settings["uncertainty"], csp=[c for c in case.csp if c.name in kept],
        budgets={"strategy": summary["strategy"], "mode": summary["budget_mode"],
                 "ties": summary.get("budget_ties", "choose"), "overrides": summary["budgets"]})
    tables = {name: _read_table(folder / f"{name}.csv") for name in ("market", "units", "csp", "dispatch")}
    return audit_tables(audit_day(run), tables["market"], tables["units"], tables["csp"], summary, tol,
                        dispatch=tables["dispatch"])


def _read_table(path: Path) -> pd.DataFrame:
    """An exported table; an empty file (e.g. no CSP) or none (a plan written before the table
    existed) reads as an empty frame."""
    if not path.exists():
        return pd.DataFrame()
    try:
        return pd.read_csv(path)
    except pd.errors.EmptyDataError:
        return pd.DataFrame()


def audit_tables(day: AuditDay, market: pd.DataFrame, units: pd.DataFrame, csp: pd.DataFrame,
                 summary: dict | None = None, tol: float = TOLERANCE,
                 dispatch: pd.DataFrame | None = None, heat_short: np.ndarray | None = None) -> list[Violation]:
    """Audit plan tables against the day of :func:`audit_day`; with ``summary`` also the
    budgets it states and the objective. ``dispatch`` holds the batteries', hydro and biomass
    units' rows (MODEL_SPEC §13); ``heat_short``: heat an intraday session plans short [MW_th],
    on the supply side of the heat balance (MODEL_SPEC §14)."""
    a = _Auditor(tol)
    case, nt = day.case, day.nt
    if len(market) != nt:
        a.fail("market.rows", f"{len(market)} rows for {nt} periods")
        return a.violations
    by_unit = {name: part.sort_values("t").reset_index(drop=True) for name, part in units.groupby("unit")} \
        if len(units) else {}
    by_csp = {name: part.sort_values("t").reset_index(drop=True) for name, part in csp.groupby("unit")} \
        if len(csp) else {}
    for kind, unit in case.units():
        if unit.name not in by_unit or len(by_unit[unit.name]) != nt:
            a.fail("units.rows", f"missing or incomplete rows for {kind} {unit.name}", unit.name)
        if kind == UnitKind.CSP and (unit.name not in by_csp or len(by_csp[unit.name]) != nt):
            a.fail("csp.rows", "missing or incomplete csp rows", unit.name)
    dispatch = pd.DataFrame() if dispatch is None else dispatch
    by_dispatch = {name: part.sort_values("t").reset_index(drop=True) for name, part in dispatch.groupby("unit")} \
        if len(dispatch) else {}
    for kind, unit in _certain_units(case):
        if unit.name not in by_dispatch or len(by_dispatch[unit.name]) != nt:
            a.fail("dispatch.rows", f"missing or incomplete dispatch rows for {kind} {unit.name}", unit.name)
    if a.violations:
        return a.violations

    _audit_market(a, day, market)
    _audit_balances(a, day, market, by_unit, by_csp, heat_short)
    _audit_ndres(a, day, by_unit)
    _audit_demands(a, day, by_unit)
    for unit in case.csp:
        _audit_csp(a, day, unit, by_unit[unit.name], by_csp[unit.name])
    for kind, unit in _certain_units(case):
        a.eq("dispatch.units_p", by_unit[unit.name]["p_mw"].to_numpy(float),
             by_dispatch[unit.name]["p_mw"].to_numpy(float), unit.name)
        if kind == UnitKind.BATTERY:
            _audit_battery(a, day, unit, by_dispatch[unit.name])
        else:
            _audit_dispatchable(a, day, unit, by_dispatch[unit.name])
    _audit_budgets(a, day, by_unit, by_csp)
    if summary is not None:
        for name, gamma in summary["budgets"].items():
            if name not in day.sources or gamma != day.sources[name].gamma:
                expected = day.sources[name].gamma if name in day.sources else "no such source"
                a.fail("budget.gamma", f"summary states Γ={gamma}, the case gives {expected}", name)
        _audit_objective(a, day, market, by_unit, by_csp, summary, by_dispatch)
    return a.violations


def _certain_units(case: Case) -> list:
    """``(kind, unit)`` of the batteries, hydro and biomass units in the plan (enabled ones)."""
    return [(kind, unit) for kind, unit in case.units()
            if kind in (UnitKind.BATTERY, UnitKind.HYDRO, UnitKind.BIOMASS)]


def _audit_market(a: _Auditor, day: AuditDay, market: pd.DataFrame) -> None:
    case = day.case
    batteries = [u for k, u in _certain_units(case) if k == UnitKind.BATTERY]
    plants = [u for k, u in _certain_units(case) if k != UnitKind.BATTERY]
    generation = (sum(u.p_max_mw for u in case.ndres) + sum(c.p_max_mw for c in case.csp)
                  + sum(b.p_dis_max_mw for b in batteries) + sum(g.p_max_mw for g in plants))
    demand = sum(d.p_max_mw for d in case.ed) + sum(b.p_ch_max_mw for b in batteries)
    base = generation if case.markets.reserve_base == "installed" else max(0.0, generation - demand)
    cap = case.markets.kappa * base if case.markets.srm else 0.0
    p, up, dn, hpa = (market[c].to_numpy(float) for c in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw"))
    a.leq("market.trade_upper", p + up, generation)
    a.leq("market.trade_lower", -demand, p - dn)
    for name, band in (("market.sr_up", up), ("market.sr_dn", dn)):
        a.leq(f"{name}_cap", band, cap)
        a.leq(f"{name}_nonnegative", -band, 0.0)
    a.leq("market.hpa_nonnegative", -hpa, 0.0)
    if not case.markets.hpa:
        a.eq("market.hpa_off", hpa, 0.0)
    da, sr_up, sr_dn = (day.sources[n] for n in ("price_da", "price_sr_up", "price_sr_dn"))
    for column, expected in (("price_da_mid", da.nominal), ("price_da_neg", da.deviation),
                             ("price_da_pos", da.deviation_up), ("price_sr_up_hi", sr_up.nominal),
                             ("price_sr_up_neg", sr_up.deviation), ("price_sr_dn_hi", sr_dn.nominal),
                             ("price_sr_dn_neg", sr_dn.deviation), ("tariff_hpa", day.tariff_hpa)):
        a.eq(f"market.{column}", market[column].to_numpy(float), expected)


def _audit_balances(a: _Auditor, day: AuditDay, market: pd.DataFrame, by_unit: dict, by_csp: dict,
                    heat_short: np.ndarray | None = None) -> None:
    case = day.case
    p_da, sr_up, sr_dn = (market[c].to_numpy(float) for c in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw"))
    for s in Scenario:
        supply = np.zeros(day.nt)
        for unit in case.ndres:
            u = by_unit[unit.name]
            supply += u["p_mw"].to_numpy() + _activation(s, u["r_up_mw"].to_numpy(), u["r_dn_mw"].to_numpy())
        for unit in case.csp:
            supply += by_csp[unit.name][f"e_{s}_mw"].to_numpy()
        for unit in case.ed:
            u = by_unit[unit.name]
            supply -= u["p_mw"].to_numpy() - _activation(s, u["r_up_mw"].to_numpy(), u["r_dn_mw"].to_numpy())
        for _, unit in _certain_units(case):  # a battery's p is its discharge less its charge
            u = by_unit[unit.name]
            supply += u["p_mw"].to_numpy() + _activation(s, u["r_up_mw"].to_numpy(), u["r_dn_mw"].to_numpy())
        a.eq(f"electric_balance[{s}]", supply, p_da + _activation(s, sr_up, sr_dn))
    heat = market["h_hpa_mw"].to_numpy(float).copy()
    if heat_short is not None:
        heat += np.asarray(heat_short, dtype=float)
    for unit in case.csp:
        heat += by_csp[unit.name]["heat_to_td_mw"].to_numpy()
    need = sum((by_unit[k.name]["p_mw"].to_numpy() for k in case.td), np.zeros(day.nt))
    a.eq("heat_balance", heat, need)


def _reserve_cap(day: AuditDay, ramp: float, share_cap: float = float("inf")) -> float:
    markets = day.case.markets
    return min(markets.reserve_duration_min * ramp, share_cap) if markets.srm else 0.0


def _audit_battery(a: _Auditor, day: AuditDay, bat, d: pd.DataFrame) -> None:
    """A battery's limits re-derived from MODEL_SPEC §13: modes, reserves by mode, the energy
    recursion with self-discharge, the day's boundary and the σ-margins behind the reserve."""
    n, dt = bat.name, day.dt_h
    ch, dis, e = (d[c].to_numpy(float) for c in ("charge_mw", "discharge_mw", "energy_mwh"))
    mode = d["charging"].to_numpy(float)
    ch_up, ch_dn, dis_up, dis_dn = (d[c].to_numpy(float) for c in ("r_ch_up_mw", "r_ch_dn_mw", "r_dis_up_mw",
                                                                    "r_dis_dn_mw"))
    up, dn = ch_up + dis_up, ch_dn + dis_dn
    a.leq("battery.nonnegative", -np.minimum.reduce([ch, dis, ch_up, ch_dn, dis_up, dis_dn]), 0.0, n)
    a.leq("battery.mode_binary", np.abs(mode * (1 - mode)), 0.0, n)
    a.leq("battery.charge_ceiling", ch + ch_dn, bat.p_ch_max_mw * mode, n)
    a.leq("battery.charge_up", ch_up, ch, n)
    a.leq("battery.discharge_ceiling", dis + dis_up, bat.p_dis_max_mw * (1 - mode), n)
    a.leq("battery.discharge_dn", dis_dn, dis, n)
    a.eq("battery.reserve_up_sum", d["r_up_mw"].to_numpy(float), up, n)
    a.eq("battery.reserve_dn_sum", d["r_dn_mw"].to_numpy(float), dn, n)
    cap = _reserve_cap(day, bat.ramp_mw_per_min, bat.reserve_share * max(bat.p_ch_max_mw, bat.p_dis_max_mw))
    a.leq("battery.reserve_up_cap", up, cap, n)
    a.leq("battery.reserve_dn_cap", dn, cap, n)
    a.eq("battery.net_output", d["p_mw"].to_numpy(float), dis - ch, n)
    start = e[-1] if bat.e_init_mwh is None else bat.e_init_mwh
    before = np.concatenate([[start], e[:-1]])
    expected = (1 - bat.self_discharge_per_h * dt) * before + bat.eta_ch * ch * dt - dis * dt / bat.eta_dis
    a.eq("battery.energy_balance", e, expected, n, scale=bat.e_max_mwh)
    if bat.e_init_mwh is not None:
        floor = bat.e_init_mwh if bat.e_end_min_mwh is None else min(bat.e_end_min_mwh, bat.e_init_mwh)
        a.leq("battery.energy_end", floor, e[-1], n)
    span = bat.e_max_mwh - bat.e_min_mwh
    sigma_up, sigma_dn = float(d["sigma_up"].iloc[0]), float(d["sigma_dn"].iloc[0])
    a.leq("battery.sigma_range", -min(sigma_up, sigma_dn), 0.0, n)
    a.leq("battery.sigma_range", max(sigma_up, sigma_dn), 1.0, n)
    a.leq("battery.reserve_energy_up", float(np.sum(up * dt / bat.eta_dis)), sigma_up * span, n, scale=span)
    a.leq("battery.reserve_energy_dn", float(np.sum(dn * bat.eta_ch * dt)), sigma_dn * span, n, scale=span)
    a.leq("battery.margin_low", bat.e_min_mwh + sigma_up * span, e, n, scale=bat.e_max_mwh)
    a.leq("battery.margin_high", e, bat.e_max_mwh - sigma_dn * span, n, scale=bat.e_max_mwh)


def _audit_dispatchable(a: _Auditor, day: AuditDay, unit, d: pd.DataFrame) -> None:
    """A hydro or biomass unit's limits re-derived from MODEL_SPEC §13: output and reserve within
    commitment, reserve caps, ramps in every activation scenario, minimum up and down times with
    what carries over, and the day's energy with all up reserve called."""
    n, dt, nt = unit.name, day.dt_h, day.nt
    p, up, dn = (d[c].to_numpy(float) for c in ("p_mw", "r_up_mw", "r_dn_mw"))
    on, start, stop = (d[c].to_numpy(float) for c in ("online", "startup", "shutdown"))
    a.leq("dispatchable.nonnegative", -np.minimum.reduce([p, up, dn]), 0.0, n)
    a.leq("dispatchable.floor", unit.p_min_mw * on, p - dn, n)
    a.leq("dispatchable.ceiling", p + up, unit.p_max_mw * on, n)
    cap = _reserve_cap(day, unit.ramp_mw_per_min, unit.reserve_share * unit.p_max_mw)
    a.leq("dispatchable.reserve_up_cap", up, cap, n)
    a.leq("dispatchable.reserve_dn_cap", dn, cap, n)
    initial = 1.0 if unit.initial_online else 0.0
    was_on = np.concatenate([[initial], on[:-1]])
    a.eq("dispatchable.transition", on - was_on, start - stop, n)
    a.leq("dispatchable.one_transition", start + stop, 1.0, n)

    def limit(ramp):
        return unit.p_max_mw if ramp is None else min(ramp * dt, unit.p_max_mw)

    low_before = np.concatenate([[np.nan], (p - dn)[:-1]])
    high_before = np.concatenate([[np.nan], (p + up)[:-1]])
    if unit.p_init_mw is not None:
        low_before[0] = high_before[0] = unit.p_init_mw
    rows = ~np.isnan(low_before)
    a.leq("dispatchable.ramp_up", ((p + up) - low_before)[rows],
          (limit(unit.ramp_up_mw_per_h) * was_on + limit(unit.startup_ramp_mw_per_h) * start)[rows], n)
    a.leq("dispatchable.ramp_dn", (high_before - (p - dn))[rows],
          (limit(unit.ramp_dn_mw_per_h) * on + limit(unit.shutdown_ramp_mw_per_h) * stop)[rows], n)
    up_periods = max(1, int(round(unit.min_up_h / dt)))  # a start is online in its own period
    down_periods = max(1, int(round(unit.min_down_h / dt)))
    for t in range(nt):  # every run and every rest lasts its minimum, or reaches the day's end
        if start[t] > 0.5:
            a.leq("dispatchable.min_up", 1.0 - on[t:t + up_periods].min(), 0.0, n)
        if stop[t] > 0.5:
            a.leq("dispatchable.min_down", on[t:t + down_periods].max(), 0.0, n)
    if unit.initial_hours_in_status is not None:
        needed = unit.min_up_h if unit.initial_online else unit.min_down_h
        held = int(round(max(0.0, needed - unit.initial_hours_in_status) / dt))
        a.eq("dispatchable.initial_status", on[:held], initial, n)
    if unit.energy_max_mwh is not None:
        a.leq("dispatchable.energy", float(np.sum((p + up) * dt)), unit.energy_max_mwh, n,
              scale=unit.energy_max_mwh)


def _certain_cost(kind, unit, d: pd.DataFrame, dt: float) -> float:
    """A battery's wear, or a hydro or biomass unit's marginal, start-up and shut-down costs [EUR]."""
    if kind == UnitKind.BATTERY:
        return float(np.sum(unit.degradation_eur_per_mwh * d["discharge_mw"].to_numpy(float) * dt))
    return float(np.sum(unit.marginal_cost_eur_per_mwh * d["p_mw"].to_numpy(float) * dt)
                 + unit.startup_cost_eur * d["startup"].to_numpy(float).sum()
                 + unit.shutdown_cost_eur * d["shutdown"].to_numpy(float).sum())


def _audit_ndres(a: _Auditor, day: AuditDay, by_unit: dict) -> None:
    for unit in day.case.ndres:
        u, n = by_unit[unit.name], unit.name
        p, up, dn, bound = (u[c].to_numpy(float) for c in ("p_mw", "r_up_mw", "r_dn_mw", "bound_mw"))
        share = unit.reserve_share * unit.p_max_mw
        a.leq("ndres.available", p + up, bound, n)
        a.leq("ndres.minimum", unit.p_min_mw, p - dn, n)
        a.leq("ndres.nonnegative", -np.minimum.reduce([p, up, dn]), 0.0, n)
        a.leq("ndres.reserve_up_cap", up, _reserve_cap(day, unit.ramp_up_mw_per_min, share), n)
        a.leq("ndres.reserve_dn_cap", dn, _reserve_cap(day, unit.ramp_dn_mw_per_min, share), n)


def _audit_demands(a: _Auditor, day: AuditDay, by_unit: dict) -> None:
    dt = day.dt_h
    for ed in day.case.ed:
        u, n = by_unit[ed.name], ed.name
        p, up, dn, bound = (u[c].to_numpy(float) for c in ("p_mw", "r_up_mw", "r_dn_mw", "bound_mw"))
        if ed.profile_window:  # the tool's window around the nominal profile (bound = profile + deviation)
            profile = day.sources[ed.name].nominal
            a.leq("ed.window_low", bound - ed.flex_up * profile, p - up, n)
            a.leq("ed.window_high", p + dn, bound + ed.flex_dn * profile, n)
            a.leq("ed.flex_up", up, ed.flex_up * profile, n)
            a.leq("ed.flex_dn", dn, ed.flex_dn * profile, n)
        else:
            a.leq("ed.required", bound, p, n)
            a.leq("ed.flex_up", up, ed.flex_up * p, n)
            a.leq("ed.flex_dn", dn, ed.flex_dn * p, n)
        a.leq("ed.floor", ed.p_min_mw, p - up, n)
        a.leq("ed.ceiling", p + dn, ed.p_max_mw, n)
        # ramps between periods: highest consumption of a period against the lowest of the one before
        # and the reverse; the first period from p_init_mw when given
        start = np.nan if ed.p_init_mw is None else ed.p_init_mw  # no bands before the day; nan: no limit
        low, high = p - up, p + dn
        low_before, high_before = np.concatenate([[start], low[:-1]]), np.concatenate([[start], high[:-1]])
        if ed.ramp_up_mw_per_h is not None:
            a.leq("ed.ramp_up", high - low_before, ed.ramp_up_mw_per_h * dt, n)
        if ed.ramp_dn_mw_per_h is not None:
            a.leq("ed.ramp_dn", high_before - low, ed.ramp_dn_mw_per_h * dt, n)
        a.leq("ed.reserve_up_cap", up, _reserve_cap(day, ed.ramp_up_mw_per_min), n)
        a.leq("ed.reserve_dn_cap", dn, _reserve_cap(day, ed.ramp_dn_mw_per_min), n)
        a.leq("ed.nonnegative", -np.minimum(up, dn), 0.0, n)
        served = p - up if ed.energy_net_of_up_band else p
        a.leq("ed.energy", ed.e_min_mwh, float(np.sum(served * dt)), n, scale=ed.e_min_mwh)
    for td in day.case.td:
        u, n = by_unit[td.name], td.name
        h, bound = u["p_mw"].to_numpy(float), u["bound_mw"].to_numpy(float)
        a.leq("td.required", bound, h, n)
        a.leq("td.minimum", td.h_min_mw_th, h, n)
        a.leq("td.maximum", h, td.h_max_mw_th, n)
        a.leq("td.energy", td.q_min_mwh_th, float(np.sum(h * dt)), n, scale=td.q_min_mwh_th)


def _audit_csp(a: _Auditor, day: AuditDay, unit, rows: pd.DataFrame, c: pd.DataFrame) -> None:
    n, ts, pb, dt = unit.name, unit.storage, unit.power_block, day.dt_h
    col = {name: c[name].to_numpy(float) for name in c.columns if name not in ("start", "clock", "unit")}
    u, v_su, v_sd, mode = col["online"], col["startup"], col["shutdown"], col["charging"]
    for name, values in (("online", u), ("startup", v_su), ("shutdown", v_sd), ("charging", mode)):
        a.leq(f"csp.{name}_binary", np.abs(values - np.round(values)), 0.0, n)
        a.leq(f"csp.{name}_binary", np.abs(np.round(values) - 0.5), 0.5, n)
    # Solar field (STU1, MILP-STU1).
    a.leq("csp.sf_available", col["p_sf_mw"], col["sf_bound_mw"], n)
    a.leq("csp.sf_nonnegative", -col["p_sf_mw"], 0.0, n)
    # Power-block thermal input (STU2), with the start-up heat of the periods after a start.
    startup_periods = pb.startup_periods(day.dt_h)
    starting = np.array([v_su[max(0, t - startup_periods + 1): t + 1].sum() for t in range(day.nt)])
    heat_in = (col["p_sf_mw"] - col["heat_to_td_mw"] / unit.heat_efficiency + col["ts_discharge_mw"]
               - col["ts_charge_mw"] - pb.startup_fraction * pb.p_in_max_mw_th * starting)
    a.eq("csp.heat_split", col["p_pb_mw"], heat_in, n)
    a.leq("csp.heat_nonnegative", -col["heat_to_td_mw"], 0.0, n)
    r_up, r_dn = col["ts_r_up_mw"], col["ts_r_dn_mw"]
    a.eq("csp.ts_r_up_sum", r_up, col["ts_r_ch_up_mw"] + col["ts_r_dis_up_mw"], n)
    a.eq("csp.ts_r_dn_sum", r_dn, col["ts_r_ch_dn_mw"] + col["ts_r_dis_dn_mw"], n)
    a.leq("csp.input_ceiling", col["p_pb_mw"] + r_up, pb.p_in_max_mw_th * u, n)
    a.leq("csp.input_floor", pb.p_in_min_mw_th * u, col["p_pb_mw"] - r_dn, n)
    # Conversion curve in each activation scenario (STU5) and the turbine nameplate.
    for s in Scenario:
        x = col["p_pb_mw"] + _activation(s, r_up, r_dn)
        e = col[f"e_{s}_mw"]
        expected = np.where(u > 0.5, curve_output_mw(pb, x), 0.0)
        a.eq(f"csp.pb_curve[{s}]", e, expected, n)
        a.leq(f"csp.pb_input_range[{s}]", x, pb.p_in_max_mw_th * u, n)
        a.leq(f"csp.pb_input_range[{s}]", pb.p_in_min_mw_th * u, x, n)
        if pb.output_capped:  # otherwise the curve alone limits the output (the tool's convention)
            a.leq(f"csp.turbine_cap[{s}]", e, pb.p_el_max_mw * u, n)
    # Electrical reserves (STU6-STU7) and the unit rows of units.csv.
    cap = _reserve_cap(day, unit.ramp_mw_per_min, unit.reserve_share * unit.p_max_mw)
    a.leq("csp.reserve_up_cap", col["e_up_mw"] - col["e_none_mw"], cap, n)
    a.leq("csp.reserve_dn_cap", col["e_none_mw"] - col["e_dn_mw"], cap, n)
    a.eq("csp.units_p", rows["p_mw"].to_numpy(float), col["e_none_mw"], n)
    a.eq("csp.units_r_up", rows["r_up_mw"].to_numpy(float), col["e_up_mw"] - col["e_none_mw"], n)
    a.eq("csp.units_r_dn", rows["r_dn_mw"].to_numpy(float), col["e_none_mw"] - col["e_dn_mw"], n)
    # Storage power limits by mode (TS1-TS4).
    a.leq("csp.ts_charge_floor", ts.p_ch_min_mw_th * mode, col["ts_charge_mw"] - col["ts_r_ch_up_mw"], n)
    a.leq("csp.ts_charge_ceiling", col["ts_charge_mw"] + col["ts_r_ch_dn_mw"], ts.p_ch_max_mw_th * mode, n)
    a.leq("csp.ts_discharge_ceiling", col["ts_discharge_mw"] + col["ts_r_dis_up_mw"],
          ts.p_dis_max_mw_th * (1 - mode), n)
    a.leq("csp.ts_discharge_floor", ts.p_dis_min_mw_th * (1 - mode), col["ts_discharge_mw"] - col["ts_r_dis_dn_mw"],
          n)
    for name in ("ts_charge_mw", "ts_discharge_mw", "ts_r_ch_up_mw", "ts_r_ch_dn_mw", "ts_r_dis_up_mw",
                 "ts_r_dis_dn_mw"):
        a.leq(f"csp.{name}_nonnegative", -col[name], 0.0, n)
    if ts.reserve_band_max_mw_th is not None:
        for name in ("ts_r_ch_up_mw", "ts_r_ch_dn_mw", "ts_r_dis_up_mw", "ts_r_dis_dn_mw"):
            a.leq("csp.ts_band_max", col[name], ts.reserve_band_max_mw_th, n)
    # Energy recursion, cyclic or from a fixed initial energy (TS7-TS8 as corrected).
    energy = col["ts_energy_mwh"]
    previous = np.roll(energy, 1)
    if not ts.cyclic:
        previous[0] = ts.e_init_mwh_th
        floor = ts.e_init_mwh_th if ts.e_end_min_mwh_th is None else min(ts.e_end_min_mwh_th, ts.e_init_mwh_th)
        a.leq("csp.ts_energy_end", floor, energy[-1], n)
    a.eq("csp.ts_energy_balance", energy,
         previous + ts.eta_ch * col["ts_charge_mw"] * dt - col["ts_discharge_mw"] * dt / ts.eta_dis, n)
    # Reserve energy shares and margins (TS9-TS11, corrected).
    span = ts.e_max_mwh_th - ts.e_min_mwh_th
    sigma_up, sigma_dn = float(col["sigma_up"][0]), float(col["sigma_dn"][0])
    top = ts.reserve_share_max
    a.leq("csp.sigma_range", np.array([-sigma_up, -sigma_dn, sigma_up - top, sigma_dn - top]), 0.0, n)
    held = ts.reserve_energy_factor * span
    a.leq("csp.ts_reserve_energy_up", float(np.sum(r_up * dt / ts.eta_dis)), sigma_up * held, n, scale=span)
    a.leq("csp.ts_reserve_energy_dn", float(np.sum(r_dn * ts.eta_ch * dt)), sigma_dn * held, n, scale=span)
    a.leq("csp.ts_margin_low", ts.e_min_mwh_th + sigma_up * span, energy, n, scale=span)
    a.leq("csp.ts_margin_high", energy, ts.e_max_mwh_th - sigma_dn * span, n, scale=span)
    _audit_commitment(a, day, unit, u, v_su, v_sd)


def _audit_commitment(a: _Auditor, day: AuditDay, unit, u, v_su, v_sd) -> None:
    """Transitions and minimum up/down times by run lengths (Appendix A)."""
    n, pb = unit.name, unit.power_block
    state = np.round(u).astype(int)
    previous = np.concatenate([[1 if pb.initially_on else 0], state[:-1]])
    a.eq("csp.commitment_transition", state - previous, np.round(v_su) - np.round(v_sd), n)
    if pb.initial_status_h is not None:  # a minimum time begun the day before is completed first (STU12, STU15)
        need_h = pb.min_up_h if pb.initially_on else pb.min_down_h
        held = state[:day.periods_for_hours(max(0.0, need_h - pb.initial_status_h))]
        a.eq("csp.initial_status_held", held, np.full(len(held), previous[0]), n)
    for name, value, need in (("min_up", 1, day.periods_for_hours(pb.min_up_h)),
                              ("min_down", 0, day.periods_for_hours(pb.min_down_h))):
        t = 0
        while t < day.nt:
            if state[t] != value:
                t += 1
                continue
            end = t
            while end < day.nt and state[end] == value:
                end += 1
            started_today = previous[t] != value
            if started_today and end < day.nt and end - t < need:
                a.fail(f"csp.{name}", f"run of {end - t} periods from t={t + 1} is shorter than {need}",
                       n, t + 1, float(need - (end - t)))
            t = end


def _audit_budgets(a: _Auditor, day: AuditDay, by_unit: dict, by_csp: dict) -> None:
    """χ sums to Γ, lands on the largest deviations (paper mode; among tied ones on the earliest
    under ``budgets.ties: earliest``), and bounds follow."""
    paper = day.case.budgets.mode == "paper"
    earliest = paper and day.case.budgets.ties == "earliest"
    for name, src in day.sources.items():
        if src.is_price:
            continue
        table = by_csp[name] if src.unit_kind == UnitKind.CSP else by_unit[name]
        prefix = "sf_" if src.unit_kind == UnitKind.CSP else ""
        nominal = table[f"{prefix}nominal_mw"].to_numpy(float)
        deviation = table[f"{prefix}deviation_mw"].to_numpy(float)
        bound = table[f"{prefix}bound_mw"].to_numpy(float)
        chi = table["chi"].to_numpy(float)
        a.eq("budget.nominal", nominal, src.nominal, name)
        a.eq("budget.deviation", deviation, src.deviation, name)
        if abs(chi.sum() - src.gamma) > 0.5 and deviation.max() > 0:
            a.fail("budget.count", f"Σχ={chi.sum():g} but Γ={src.gamma}", name)
        sign = -1.0 if src.kind == "production" else 1.0
        a.eq("budget.bound", bound, nominal + sign * deviation * chi, name)
        if paper and 0 < chi.sum() < len(chi):
            chosen, other = deviation[chi > 0.5], deviation[chi < 0.5]
            a.leq("budget.largest_deviations", other.max(), chosen.min(), name)
            boundary = np.flatnonzero(deviation == chosen.min())
            if earliest and chosen.min() > 0 and (chi[boundary] > 0.5).any() and (chi[boundary] < 0.5).any():
                last_chosen = boundary[chi[boundary] > 0.5].max()
                first_skipped = boundary[chi[boundary] < 0.5].min()
                if last_chosen > first_skipped:
                    a.fail("budget.earliest_ties", f"a tied deviation of {chosen.min():g} deviates at period "
                           f"{last_chosen + 1} but not at the earlier period {first_skipped + 1}", name,
                           t=int(last_chosen) + 1)


def protection_exact(exposure: np.ndarray, gamma: int) -> float:
    """Worst-case loss: the sum of the Γ largest exposures [EUR] (Bertsimas–Sim)."""
    if gamma <= 0:
        return 0.0
    return float(np.sort(np.asarray(exposure, float))[::-1][:gamma].sum())


def price_exposures(day, market: pd.DataFrame) -> dict[str, np.ndarray]:
    """Per-period loss [EUR] if each price moves adversely by its full deviation (MODEL_SPEC §4).

    DAM ``λ_neg·p_da·dt`` where the plan sells, ``λ_pos·(−p_da)·dt`` where it buys; SR
    ``λ_neg·r_sr·dt``. ``day``: an :class:`AuditDay` or any object with the same
    ``dt_h`` and ``sources`` (e.g. a :class:`~rvpp.uncertainty.problem.Problem`, to draw a
    plan's exposures); ``market``: the columns ``p_da_mw``, ``r_sr_up_mw``, ``r_sr_dn_mw``.
    """
    dt = day.dt_h
    p = market["p_da_mw"].to_numpy(float)
    da = day.sources["price_da"]
    return {
        "price_da": np.maximum.reduce([da.deviation * p * dt, -da.deviation_up * p * dt, np.zeros_like(p)]),
        "price_sr_up": day.sources["price_sr_up"].deviation * market["r_sr_up_mw"].to_numpy(float) * dt,
        "price_sr_dn": day.sources["price_sr_dn"].deviation * market["r_sr_dn_mw"].to_numpy(float) * dt,
    }


def _audit_objective(a: _Auditor, day: AuditDay, market: pd.DataFrame, by_unit: dict, by_csp: dict,
                     summary: dict, by_dispatch: dict) -> None:
    case, dt = day.case, day.dt_h
    da, up, dn = (day.sources[n].nominal for n in ("price_da", "price_sr_up", "price_sr_dn"))
    revenue_dam = float(np.sum(da * market["p_da_mw"].to_numpy(float) * dt))
    revenue_sr = float(np.sum((up * market["r_sr_up_mw"].to_numpy(float) + dn * market["r_sr_dn_mw"].to_numpy(float))
                              * dt))
    cost_hpa = float(np.sum(day.tariff_hpa * market["h_hpa_mw"].to_numpy(float) * dt))
    opex = sum(float(np.sum(u.om_eur_per_mwh * by_unit[u.name]["p_mw"].to_numpy(float) * dt)) for u in case.ndres)
    opex += sum(float(np.sum(c.om_eur_per_mwh * (by_csp[c.name]["e_none_mw"].to_numpy(float)
                                                 + by_csp[c.name]["heat_to_td_mw"].to_numpy(float)) * dt))
                for c in case.csp)
    opex += sum(_certain_cost(kind, unit, by_dispatch[unit.name], dt) for kind, unit in _certain_units(case))
    exposures = price_exposures(day, market)
    protection = {name: protection_exact(exposures[name], day.sources[name].gamma) for name in exposures}
    keys = {"price_da": "da", "price_sr_up": "sr_up", "price_sr_dn": "sr_dn"}
    scale = MONEY_TOLERANCE / a.tol
    for name, key in keys.items():
        a.eq(f"objective.protection_{key}", summary["protection_eur"][key], protection[name], scale=scale)
    for field, value in (("revenue_dam_eur", revenue_dam), ("revenue_sr_eur", revenue_sr),
                         ("cost_hpa_eur", cost_hpa), ("cost_opex_eur", opex)):
        a.eq(f"objective.{field}", summary[field], value, scale=scale)
    kept = 0.0
    for c in case.csp:
        ts = c.storage
        if ts.e_init_mwh_th is not None and ts.end_value_eur_per_mwh_th > 0.0:
            kept += ts.end_value_eur_per_mwh_th * (float(by_csp[c.name]["ts_energy_mwh"].to_numpy(float)[-1])
                                                    - ts.e_init_mwh_th)
    a.eq("objective.value_heat_kept_eur", summary.get("value_heat_kept_eur", 0.0), kept, scale=scale)
    total = revenue_dam + revenue_sr - cost_hpa - opex - sum(protection.values()) + kept
    a.eq("objective.total", summary["objective_eur"], total, scale=scale)


# ----------------------------------------------------------------------------- intraday sessions


def audit_session(result, commitments, previous_units: pd.DataFrame, tol: float = TOLERANCE) -> list[Violation]:
    """Audit a solved intraday session (:class:`~rvpp.solving.results.SessionResult`) against what
    was fixed before it (:class:`~rvpp.model.session.Commitments`; MODEL_SPEC §14).

    Checked from the session's tables: the day-ahead bids unchanged; no trade before the window;
    the position equal to ``p_da`` plus every trade so far; every unit's output and reserves
    before the window equal to ``previous_units`` (the schedule of the step before); then every
    rule of :func:`audit_tables` with the total position in place of ``p_da``, against the
    session's bands and its budgets derived here (``⌊Γ_da·f_k·|W|/NT + ½⌋``); the intraday price
    protection as the sum of the Γ largest exposures of the trade; and the trade's revenue.
    """
    if not result.has_plan:
        return [Violation("plan", None, None, float("nan"), f"no session plan to audit ({result.status})")]
    a = _Auditor(tol)
    case, market, first = result.case, result.market, commitments.first
    nt, dt = len(market), case.dt_h
    for column, name in (("p_da_mw", "p_da"), ("r_sr_up_mw", "r_sr_up"), ("r_sr_dn_mw", "r_sr_dn"),
                         ("h_hpa_mw", "h_hpa")):
        a.eq(f"session.fixed_{name}", market[column].to_numpy(float), np.asarray(getattr(commitments, name), float))
    traded = market["traded_mw"].to_numpy(float)
    a.eq("session.no_trade_before_window", traded[:first], 0.0)
    a.eq("session.position", market["position_mw"].to_numpy(float),
         np.asarray(commitments.p_da, float) + np.asarray(commitments.traded, float) + traded)
    if first:
        for name, part in result.units.groupby("unit"):
            before = previous_units[previous_units["unit"] == name].sort_values("t")
            part = part.sort_values("t")
            for column in ("p_mw", "r_up_mw", "r_dn_mw"):
                a.eq(f"session.kept_{column}", part[column].to_numpy(float)[:first],
                     before[column].to_numpy(float)[:first], name)
    day = audit_day(case, bands=result.problem.bands)
    k = [s.name for s in case.intraday.resolved].index(result.session) + 1
    own = case.intraday.resolved[k - 1].gamma_factor
    factor = own if own is not None else case.intraday.gamma_shrink ** k
    window = nt - first
    gammas = {}
    for name, series in day.sources.items():
        share = series.gamma * factor * window / nt
        gammas[name] = min(window, int(share) + (1 if share - int(share) >= 0.5 else 0))
    day = AuditDay(case=day.case, nt=day.nt, dt_h=day.dt_h, tariff_hpa=day.tariff_hpa,
                   sources={name: Series(s.kind, s.unit_kind, s.nominal, s.deviation, gammas[name], s.deviation_up)
                            for name, s in day.sources.items()})
    frame = market.copy()
    frame["p_da_mw"] = market["position_mw"]
    a.violations += audit_tables(day, frame, result.units, result.csp, None, tol, dispatch=result.dispatch,
                                 heat_short=market["heat_short_mw"].to_numpy(float))
    price = day.sources["price_da"]
    exposure = np.maximum.reduce([price.deviation * traded * dt, -price.deviation_up * traded * dt,
                                  np.zeros(nt)])
    for check, expected, stated in (
            ("session.protection", protection_exact(exposure, price.gamma), result.parts["protection_intraday_eur"]),
            ("session.revenue", float(np.sum(price.nominal * traded * dt)), result.parts["revenue_intraday_eur"])):
        if abs(expected - stated) > MONEY_TOLERANCE:
            a.fail(check, f"the session states {stated:.2f} EUR, derived {expected:.2f} EUR",
                   excess=abs(expected - stated))
    return a.violations
