"""Independent reference implementation of the RVPP robust bidding MILP (test oracle).

Builds MODEL_SPEC §3-§9 for one delivery day directly with HiGHS through highspy's
modelling API and returns its optimal objective [EUR], and settles a fixed bid against
a realized day (MODEL_SPEC §10). It shares no code with the library: :func:`read_case`
reads a case folder itself (``case.yaml`` with ``yaml.safe_load``, the history CSV with
plain pandas, the defaults of docs/case-format.md), and everything derived from the
case is computed here from the specification. (The model also accepts an
:class:`rvpp.data.case.Case`, which has the same attribute names, to compare cases
changed in ways the case format cannot write.) Derived here:

* the delivery day's periods in local time (MODEL_SPEC §1);
* the forecast bands (§6): the window of the ``window_days`` days before the delivery
  day in local time, per local clock hour the ``q_lo`` percentile, the median and the
  ``q_hi`` percentile (numpy's default linear interpolation); a period takes the band of
  the clock hour it starts in. Sources the case puts on forecast bands take the point
  forecast (a history column, or for prices the price at the same clock hour a day and/or
  a week before) plus those percentiles of the forecast's window errors, among the window
  hours whose forecast is nearest (the nearest fifth, at least 24; docs/model.md);
* the nominal values and deviations of §6's table, availabilities clipped to
  ``[0, nameplate]``;
* the budgets of the strategy (paper Table 7, hours scaled by ``1/dt``, at most the
  number of periods) with the case's Γ edits;
* the placement of the budgeted deviations (§5): each availability or consumption
  deviates in its Γ largest-deviation periods; where tied deviations straddle the Γ
  boundary, binaries choose which of the tied periods deviate (ties may be broken either
  way, and the optimum takes the best choice).

Only a caller asking to fix the first-stage bid reads a plan's decisions
(:func:`reference_optimum` with ``market``). The price protection (§4) is the
Bertsimas-Sim dual written here from scratch; the power-block curve (STU5) is encoded
with one binary per segment in multiple-choice form; the turbine's minimum up and down
times follow the paper's Appendix A. A few valid inequalities, each justified where it
is added, speed up the solve without changing the optimum.

Symbols in docstrings follow MODEL_SPEC; labels such as (TS7) or (MILP-STU1) are the
paper's equation labels.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable

import highspy
import numpy as np
import pandas as pd
import yaml

from rvpp.settle.audit import finer_band  # MODEL_SPEC §6 interpolation, the audit's own code (day_data)

SCENARIOS = ("none", "up", "dn")
MIP_REL_GAP = 1e-7
BINARY = highspy.HighsVarType.kInteger
PRICES = ("price_da", "price_sr_up", "price_sr_dn")
# Γ in hours per strategy and source kind (paper Table 7; MODEL_SPEC §6).
TABLE7 = {"deterministic": dict(price=0, wind=0, pv=0, csp=0, ed=0, td=0),
          "optimistic": dict(price=3, wind=3, pv=2, csp=2, ed=3, td=3),
          "balanced": dict(price=6, wind=6, pv=4, csp=4, ed=6, td=6),
          "pessimistic": dict(price=9, wind=9, pv=6, csp=6, ed=9, td=9)}


@dataclass(frozen=True)
class Uncertain:
    """An availability (``sign`` −1) or consumption (+1): nominal and deviation per period [MW], Γ."""

    nominal: np.ndarray
    deviation: np.ndarray
    gamma: int
    sign: float


@dataclass(frozen=True)
class DayData:
    """Data of one delivery day derived from the case and its history.

    ``price``: nominal and deviations per period (``price_da_mid``, ``price_da_pos``,
    ``price_da_neg``, ``price_sr_up_hi``, ``price_sr_up_neg``, ``price_sr_dn_hi``,
    ``price_sr_dn_neg``) [EUR/MWh or EUR/MW per h] and ``tariff_hpa`` [EUR/MWh_th];
    ``gamma``: price budgets Γ [periods]; ``uncertain``: per unit name (the CSP's solar
    field under the CSP's name).
    """

    nt: int
    dt: float
    price: dict[str, np.ndarray]
    gamma: dict[str, int]
    uncertain: dict[str, Uncertain]


# ----------------------------------------------------------------------------- reading a case folder

# Defaults of docs/case-format.md, per section and unit kind.
DEFAULTS = {
    "markets": {"dam": True, "srm": True, "hpa": True, "kappa": 0.3, "reserve_duration_min": 15.0},
    "uncertainty": {"window_days": 30, "q_lo": 0.2, "q_hi": 0.8, "bands": {}, "price_forecast": "same_hour_yesterday"},
    "budgets": {"strategy": "balanced", "overrides": {}, "mode": "paper"},
    "wind": {"p_min_mw": 0.0, "om_eur_per_mwh": 0.0, "reserve_share": 0.1, "series": None, "series_scale": 1.0,
             "forecast_series": None},
    "csp": {"om_eur_per_mwh": 0.0, "heat_efficiency": 1.0, "reserve_share": 0.5},
    "solar_field": {"series": None, "series_scale": 1.0, "forecast_series": None},
    "storage": {"p_ch_min_mw_th": 0.0, "p_dis_min_mw_th": 0.0, "e_init_mwh_th": None, "e_end_min_mwh_th": None},
    "power_block": {"min_up_h": 0.0, "min_down_h": 0.0, "startup_fraction": 0.0, "startup_duration_h": None,
                    "initially_on": False, "initial_status_h": None},
    "ed": {"flex_up": 0.1, "flex_dn": 0.1, "series": None, "series_scale": 1.0, "forecast_series": None},
    "td": {"series": None, "series_scale": 1.0, "forecast_series": None},
}
DEFAULTS["pv"] = DEFAULTS["wind"]
KINDS = ("wind", "pv", "csp", "ed", "td")


def _with_defaults(kind: str, data: dict | None) -> SimpleNamespace:
    return SimpleNamespace(**{**DEFAULTS[kind], **(data or {})})


def _csp(data: dict) -> SimpleNamespace:
    unit = _with_defaults("csp", {k: v for k, v in data.items() if k not in ("solar_field", "storage", "power_block")})
    unit.solar_field = _with_defaults("solar_field", data["solar_field"])
    unit.storage = _with_defaults("storage", data["storage"])
    unit.storage.cyclic = unit.storage.e_init_mwh_th is None
    unit.power_block = _with_defaults("power_block", data["power_block"])
    unit.power_block.breakpoints = [tuple(float(x) for x in point) for point in unit.power_block.breakpoints]
    unit.p_max_mw = unit.power_block.p_el_max_mw  # the turbine's electrical nameplate [MW]
    return unit


class ReferenceCase(SimpleNamespace):
    """A case as this module reads it: sections and units as attribute namespaces."""

    def units(self):
        for kind in KINDS:
            for unit in getattr(self, kind):
                yield kind, unit

    @property
    def ndres(self) -> list:
        return self.wind + self.pv


def read_case(folder: str | Path, edit: Callable[[dict], Any] | None = None) -> ReferenceCase:
    """The case of ``folder`` read here: ``case.yaml`` by ``yaml.safe_load`` (``edit`` may change the
    parsed data first, as a user editing the file would) and its history CSV by ``pandas.read_csv``,
    indexed by the UTC instants of its ``timestamp`` column (written with their UTC offsets)."""
    folder = Path(folder)
    data = yaml.safe_load((folder / "case.yaml").read_text(encoding="utf-8"))
    if edit is not None:
        edit(data)
    table = pd.read_csv(folder / data["history"])
    frame = table.drop(columns="timestamp").set_index(pd.DatetimeIndex(pd.to_datetime(table["timestamp"], utc=True)))
    day = data["delivery_date"]
    units = data.get("units") or {}
    case = ReferenceCase(
        name=data["name"], timezone=data.get("timezone", "Europe/Madrid"), dt_h=float(data.get("dt_h", 1)),
        delivery_date=day if isinstance(day, dt.date) else dt.date.fromisoformat(str(day)),
        history=SimpleNamespace(frame=frame.astype(float)),
        **{section: SimpleNamespace(**{**DEFAULTS[section], **(data.get(section) or {})})
           for section in ("markets", "uncertainty", "budgets")},
        wind=[_with_defaults("wind", u) for u in units.get("wind") or []],
        pv=[_with_defaults("pv", u) for u in units.get("pv") or []],
        csp=[_csp(u) for u in units.get("csp") or []],
        ed=[_with_defaults("ed", u) for u in units.get("ed") or []],
        td=[_with_defaults("td", u) for u in units.get("td") or []],
    )
    case.markets.hpa_tariff_eur_per_mwh = [float(x) for x in case.markets.hpa_tariff_eur_per_mwh]
    return case


class ReferenceNotOptimal(RuntimeError):
    """The reference model ended without a proven optimum; the message is HiGHS' status."""


def local_periods(case) -> pd.DatetimeIndex:
    """Local start times of the delivery day's periods (23 or 25 hours on clock-change days)."""
    day = pd.Timestamp(case.delivery_date)
    first, last = (d.tz_localize(case.timezone).tz_convert("UTC") for d in (day, day + pd.Timedelta(days=1)))
    return pd.date_range(first, last, freq=pd.Timedelta(hours=case.dt_h), inclusive="left").tz_convert(case.timezone)


def band_method(case, source: str, kind: str | None) -> str:
    """How the case draws ``source``'s band: its own entry in ``uncertainty.bands``, else its
    unit kind's, else the ``default`` entry, else climatology (case-format.md)."""
    chosen = dict(case.uncertainty.bands)
    return chosen.get(source) or (chosen.get(kind) if kind else None) or chosen.get("default", "climatology")


def hourly_band(case, column: str, scale: float, hours: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(lo, mid, hi)`` per period of the clock ``hours`` from the window before the day (§6)."""
    frame = case.history.frame
    local = frame.index.tz_convert(case.timezone)
    first = case.delivery_date - dt.timedelta(days=case.uncertainty.window_days)
    days = np.array(local.date)
    window = (days >= first) & (days < case.delivery_date)
    values, clock = frame[column].to_numpy(float)[window] * scale, np.asarray(local.hour)[window]
    quantiles = (case.uncertainty.q_lo, 0.5, case.uncertainty.q_hi)
    by_hour = {h: np.quantile(values[clock == h], quantiles) for h in set(hours)}
    table = np.array([by_hour[h] for h in hours])
    return table[:, 0], table[:, 1], table[:, 2]


def forecast_error_band(case, column: str, scale: float, forecast: str | None,
                        periods: pd.DatetimeIndex) -> tuple[np.ndarray, ...]:
    """``(lo, mid, hi)`` per period: point forecast plus percentiles of its window errors (§6)."""
    frame = case.history.frame
    local = frame.index.tz_convert(case.timezone)
    day = case.delivery_date
    if forecast is not None:
        predicted = frame[forecast] * scale
        point = predicted.reindex(periods.tz_convert("UTC").floor("h")).to_numpy(float)
    else:
        lags = {"same_hour_yesterday": [1], "same_hour_last_week": [7],
                "blend": [1, 7]}[case.uncertainty.price_forecast]
        grid = (pd.DataFrame({"date": local.date, "hour": local.hour, "v": frame[column].to_numpy(float) * scale})
                .drop_duplicates(["date", "hour"]).pivot(index="date", columns="hour", values="v")
                .reindex(columns=range(24)).ffill(axis=1))

        def naive(dates, hours) -> np.ndarray:
            looked = [[grid.at[d - dt.timedelta(days=lag), h] if d - dt.timedelta(days=lag) in grid.index
                       else np.nan for d, h in zip(dates, hours)] for lag in lags]
            return np.mean(np.array(looked, dtype=float), axis=0)

        predicted = pd.Series(naive(local.date, local.hour), index=frame.index)
        point = naive([day] * len(periods), periods.hour)
    in_window = (np.array(local.date) >= day - dt.timedelta(days=case.uncertainty.window_days)) & \
        (np.array(local.date) < day)
    past = predicted.to_numpy(float)[in_window]
    error = frame[column].to_numpy(float)[in_window] * scale - past
    ok = np.isfinite(past) & np.isfinite(error)
    past, error = past[ok], error[ok]
    k = min(len(error), max(24, int(np.ceil(0.2 * len(error)))))
    quantiles = (case.uncertainty.q_lo, 0.5, case.uncertainty.q_hi)
    table = []
    for f in point:
        gap = np.abs(past - f)
        table.append(f + np.quantile(error[gap <= np.partition(gap, k - 1)[k - 1]], quantiles))
    table = np.array(table)
    return table[:, 0], table[:, 1], table[:, 2]


def budgets(case, nt: int) -> dict[str, int]:
    """Γ [periods] per source: Table 7 hours scaled by ``1/dt``, at most ``nt``, then the case's edits."""
    preset, per_hour = TABLE7[case.budgets.strategy], round(1 / case.dt_h)
    gamma = {name: preset["price"] * per_hour for name in PRICES}
    gamma.update({unit.name: preset[kind] * per_hour for kind, unit in case.units()})
    gamma = {name: min(g, nt) for name, g in gamma.items()}
    return {**gamma, **dict(case.budgets.overrides)}


def day_data(case) -> DayData:
    """Bands, budgets and tariffs of the case's delivery day (MODEL_SPEC §1, §6), from its history.

    Bands are drawn per clock hour; at 30 or 15 minutes each hourly band is brought to the
    periods by MODEL_SPEC §6's mean-keeping interpolation, here the plan audit's own
    implementation (``rvpp.settle.audit.finer_band``), which is written apart from the code that
    makes the model's bands and is checked against its defining properties in test_periods.py.
    """
    periods = local_periods(case)
    hours = np.asarray(periods.hour)
    nt = len(hours)
    gamma = budgets(case, nt)
    hourly_periods = periods[::round(1 / case.dt_h)] if case.dt_h < 1 else periods
    steps = nt // len(hourly_periods)

    def band(name, column, scale, kind=None, forecast=None, low=None, high=None):
        if band_method(case, name, kind) == "forecast":
            hourly = forecast_error_band(case, column, scale, forecast, hourly_periods)
        else:
            hourly = hourly_band(case, column, scale, np.asarray(hourly_periods.hour))
        if steps == 1:
            return hourly
        held = (np.clip(x, -np.inf if low is None else low, np.inf if high is None else high) for x in hourly)
        return finer_band(*held, steps, low, high)

    lo, mid, hi = band("price_da", "price_da", 1.0)
    price = {"price_da_mid": mid, "price_da_pos": hi - mid, "price_da_neg": mid - lo}
    for name in ("price_sr_up", "price_sr_dn"):
        lo, _, hi = band(name, name, 1.0)
        price[f"{name}_hi"], price[f"{name}_neg"] = hi, hi - lo
    price["tariff_hpa"] = np.array([case.markets.hpa_tariff_eur_per_mwh[h] for h in hours], dtype=float)
    uncertain = {}
    for kind, unit in case.units():
        if kind == "csp":
            column, scale, cap = unit.solar_field.series or unit.name, unit.solar_field.series_scale, \
                unit.solar_field.p_max_mw_th
            forecast = unit.solar_field.forecast_series
        else:
            column, scale, cap = unit.series or unit.name, unit.series_scale, getattr(unit, "p_max_mw", None)
            forecast = unit.forecast_series
        lo, _, hi = band(unit.name, column, scale, kind, forecast, 0.0, cap if kind in ("wind", "pv", "csp") else None)
        if kind in ("wind", "pv", "csp"):
            top, bottom = np.clip(hi, 0.0, cap), np.clip(lo, 0.0, cap)
            uncertain[unit.name] = Uncertain(top, top - bottom, gamma[unit.name], -1.0)
        else:
            if band_method(case, unit.name, kind) == "forecast":
                lo, hi = np.maximum(lo, 0.0), np.maximum(hi, 0.0)
            uncertain[unit.name] = Uncertain(lo, hi - lo, gamma[unit.name], +1.0)
    return DayData(nt=nt, dt=case.dt_h, price=price, gamma={n: gamma[n] for n in PRICES}, uncertain=uncertain)


def reference_optimum(case, market: pd.DataFrame | None = None) -> float:
    """Optimal objective [EUR] of MODEL_SPEC §3-§9 for ``case``.

    With ``market`` (a plan's market table) the first-stage decisions ``p_da``,
    ``r_sr_up``, ``r_sr_dn`` and ``h_hpa`` are fixed to the plan's values: the result is
    then the best profit the reference physics allows for that bid (it raises if the bid
    is infeasible for the reference model).
    """
    model = ReferenceModel(case, day_data(case))
    if market is not None:
        model.fix_market(market.sort_values("t"))
    return model.solve()


def _act(scenario: str, up, dn):
    """Activation of a reserve pair in a scenario: ``up``, ``-dn`` or nothing (§7)."""
    return {"none": 0.0, "up": up, "dn": -dn}[scenario]


class ReferenceModel:
    """The MILP of MODEL_SPEC §3-§9, one method per constraint family."""

    def __init__(self, case, data: DayData, settlement: dict[str, np.ndarray] | None = None):
        """``settlement``: build the recourse model of MODEL_SPEC §10 instead, with slacks priced per
        period by ``short`` (π_def), ``long`` (π_sur), ``reserve_up``, ``reserve_dn`` (m_sr·λ) and
        ``heat`` (c_heat) [EUR/MWh]; its optimum is minus the net cost."""
        self.case, self.d, self.settlement = case, data, settlement
        self.h = highspy.Highs()
        self.h.silent()
        self.T = range(data.nt)
        self.srm, self.hpa = case.markets.srm, case.markets.hpa
        self.t_sr_min = case.markets.reserve_duration_min  # T_sr [min]
        # Per scenario and period: electrical injection of the units [MW] (§7).
        self.injection = {s: [[] for _ in self.T] for s in SCENARIOS}
        self.heat_supply = [[] for _ in self.T]   # [MW_th]
        self.heat_demand = [[] for _ in self.T]   # [MW_th]
        self.profit = []                           # terms of (MILP-Obj) [EUR]
        self._market()
        self._price_protection()
        for unit in case.ndres:
            self._ndres(unit)
        for unit in case.ed:
            self._electrical_demand(unit)
        for unit in case.td:
            self._thermal_demand(unit)
        for unit in case.csp:
            self._csp(unit)
        self._balances()

    # ----------------------------------------------------------------- helpers

    def _series(self, lb, ub, binary: bool = False) -> list:
        """One variable per period with bounds ``lb``, ``ub`` (scalars or arrays)."""
        lbs = np.broadcast_to(np.asarray(lb, dtype=float), (self.d.nt,))
        ubs = np.broadcast_to(np.asarray(ub, dtype=float), (self.d.nt,))
        kind = BINARY if binary else highspy.HighsVarType.kContinuous
        return [self.h.addVariable(lb=float(lbs[t]), ub=float(ubs[t]), type=kind) for t in self.T]

    def _reserve_series(self, cap: float) -> list:
        """Reserve variables in [0, cap] [MW]; fixed to 0 when the SRM is off (§2)."""
        return self._series(0.0, cap if self.srm else 0.0)

    def _sum(self, items):
        return self.h.qsum(list(items))

    def _series_beyond(self, low: float, high, bounds: list, lower: bool) -> list:
        """Variables in ``[low, high]`` per period that also satisfy ``x[t] ≥ bounds[t]`` (``lower``)
        or ``x[t] ≤ bounds[t]``: a column bound where the bound is a number, a row where it
        holds a budget binary."""
        highs = np.broadcast_to(np.asarray(high, dtype=float), (self.d.nt,))
        columns = []
        for t, bound in enumerate(bounds):
            number = isinstance(bound, float)
            lb = max(low, bound) if number and lower else low
            ub = min(highs[t], bound) if number and not lower else highs[t]
            x = self.h.addVariable(lb=float(lb), ub=float(ub))
            if not number:
                self.h.addConstr(x - bound >= 0) if lower else self.h.addConstr(x - bound <= 0)
            columns.append(x)
        return columns

    def _robust_bound(self, name: str) -> list:
        """Bound per period with the budgeted deviations of MODEL_SPEC §5 [MW] or [MW_th].

        ``nominal + sign·dev`` in the Γ periods of largest deviation, the nominal value
        elsewhere. Deviations above the Γ-th largest deviate for sure; when more periods
        tie at the Γ-th largest than the budget has left, binaries ``χ`` (``Σ χ`` = what is
        left) choose which of them deviate, and a bound there is an expression.
        """
        src = self.d.uncertain[name]
        dev = src.deviation
        bound = list(src.nominal.astype(float))
        if src.gamma <= 0 or dev.max() <= 0.0:
            return bound
        threshold = np.sort(dev)[::-1][min(src.gamma, self.d.nt) - 1]
        sure = [t for t in self.T if dev[t] > threshold]
        tied = [t for t in self.T if dev[t] == threshold] if threshold > 0 else []
        left = min(src.gamma, self.d.nt) - len(sure)
        for t in sure:
            bound[t] += src.sign * dev[t]
        if left >= len(tied):
            for t in tied:
                bound[t] += src.sign * dev[t]
        elif left > 0:
            chi = {t: self.h.addVariable(lb=0, ub=1, type=BINARY) for t in tied}
            self.h.addConstr(self._sum(chi.values()) == left)
            for t in tied:
                bound[t] = bound[t] + src.sign * dev[t] * chi[t]
        return bound

    # ----------------------------------------------------------------- markets

    def _market(self) -> None:
        """First-stage bids, market limits (Power-Traded1-4) and market terms of (MILP-Obj) (§2, §3, §7)."""
        case, d, dt = self.case, self.d, self.d.dt
        gen_cap = sum(u.p_max_mw for u in case.ndres) + sum(c.p_max_mw for c in case.csp)  # [MW]
        dem_cap = sum(u.p_max_mw for u in case.ed)                                          # [MW]
        band_cap = case.markets.kappa * max(0.0, gen_cap - dem_cap)                         # [MW]
        self.p_da = self._series(-np.inf, np.inf)
        self.r_sr_up = self._reserve_series(band_cap)
        self.r_sr_dn = self._reserve_series(band_cap)
        self.h_hpa = self._series(0.0, np.inf if self.hpa else 0.0)
        for t in self.T:
            self.h.addConstr(self.p_da[t] + self.r_sr_up[t] <= gen_cap)
            self.h.addConstr(self.p_da[t] - self.r_sr_dn[t] >= -dem_cap)
            self.profit.append(d.price["price_da_mid"][t] * dt * self.p_da[t]
                               + d.price["price_sr_up_hi"][t] * dt * self.r_sr_up[t]
                               + d.price["price_sr_dn_hi"][t] * dt * self.r_sr_dn[t]
                               - d.price["tariff_hpa"][t] * dt * self.h_hpa[t])

    def fix_market(self, market: pd.DataFrame) -> None:
        """Fix the first-stage decisions to a plan's ``p_da_mw``, ``r_sr_*_mw``, ``h_hpa_mw``."""
        for var, col in ((self.p_da, "p_da_mw"), (self.r_sr_up, "r_sr_up_mw"),
                         (self.r_sr_dn, "r_sr_dn_mw"), (self.h_hpa, "h_hpa_mw")):
            for t, value in enumerate(market[col].to_numpy(dtype=float)):
                self.h.changeColBounds(var[t].index, value, value)

    def _price_protection(self) -> None:
        """Bertsimas-Sim protection of the price terms (§4, MILP-DAMprice, MILP-up/downSRMprice).

        For budget Γ and exposures ``x_t`` the worst loss ``max Σ x_t z_t`` over
        ``Σ z_t ≤ Γ, 0 ≤ z_t ≤ 1`` equals by LP duality ``min Γ·φ + Σ ζ_t`` with
        ``φ + ζ_t ≥ x_t``, ``φ, ζ_t ≥ 0``. DAM exposure [EUR]: selling loses
        ``λda_neg·p·dt``, buying loses ``λda_pos·(-p)·dt``; SR exposure ``λ_neg·r·dt``.
        """
        d, dt = self.d, self.d.dt
        da_exposures = [[d.price["price_da_neg"][t] * dt * self.p_da[t],
                         -d.price["price_da_pos"][t] * dt * self.p_da[t]] for t in self.T]
        up_exposures = [[d.price["price_sr_up_neg"][t] * dt * self.r_sr_up[t]] for t in self.T]
        dn_exposures = [[d.price["price_sr_dn_neg"][t] * dt * self.r_sr_dn[t]] for t in self.T]
        for name, exposures in (("price_da", da_exposures), ("price_sr_up", up_exposures),
                                ("price_sr_dn", dn_exposures)):
            gamma = min(d.gamma[name], d.nt)
            phi = self.h.addVariable(lb=0.0)
            zeta = self._series(0.0, np.inf)
            for t in self.T:
                for exposure in exposures[t]:
                    self.h.addConstr(phi + zeta[t] >= exposure)
            self.profit.append(-(gamma * phi + self._sum(zeta)))

    # ----------------------------------------------------------------- ND-RES and demands

    def _ndres(self, unit) -> None:
        """Wind farm or PV plant (§9; MILP-NDRES1, NDRES2-4 with the share cap).

        ``p + r_up ≤ P_robust[t]``, ``P_min ≤ p - r_dn``, ``r_up ≤ min(T_sr·ramp_up, share·P_max)``,
        ``r_dn ≤ min(T_sr·ramp_dn, share·P_max)`` [MW]; O&M ``C_r·p·dt`` [EUR].
        """
        avail = self._robust_bound(unit.name)
        share_cap = unit.reserve_share * unit.p_max_mw
        p = self._series(0.0, np.inf)
        r_up = self._reserve_series(min(self.t_sr_min * unit.ramp_up_mw_per_min, share_cap))
        r_dn = self._reserve_series(min(self.t_sr_min * unit.ramp_dn_mw_per_min, share_cap))
        for t in self.T:
            self.h.addConstr(p[t] + r_up[t] - avail[t] <= 0)
            self.h.addConstr(p[t] - r_dn[t] >= unit.p_min_mw)
            for s in SCENARIOS:
                self.injection[s][t].append(p[t] + _act(s, r_up[t], r_dn[t]))
        self.profit.append(-unit.om_eur_per_mwh * self.d.dt * self._sum(p))

    def _electrical_demand(self, unit) -> None:
        """Flexible electrical demand (§9; MILP-Demand1, Demand2-8).

        ``p ≥ Pd_robust[t]``, ``P_min ≤ p - r_up``, ``p + r_dn ≤ P_max``, ``r ≤ β·p``,
        ``r ≤ T_sr·ramp`` [MW]; ``E_min ≤ Σt (p - r_up)·dt`` [MWh] (Demand8 with dt on r_up).
        Up reserve is a consumption decrease.
        """
        dt = self.d.dt
        p = self._series_beyond(0.0, np.inf, self._robust_bound(unit.name), lower=True)
        r_up = self._reserve_series(self.t_sr_min * unit.ramp_up_mw_per_min)
        r_dn = self._reserve_series(self.t_sr_min * unit.ramp_dn_mw_per_min)
        for t in self.T:
            self.h.addConstr(p[t] - r_up[t] >= unit.p_min_mw)
            self.h.addConstr(p[t] + r_dn[t] <= unit.p_max_mw)
            self.h.addConstr(r_up[t] <= unit.flex_up * p[t])
            self.h.addConstr(r_dn[t] <= unit.flex_dn * p[t])
            for s in SCENARIOS:
                self.injection[s][t].append(-(p[t] - _act(s, r_up[t], r_dn[t])))
        self.h.addConstr(self._sum(dt * (p[t] - r_up[t]) for t in self.T) >= unit.e_min_mwh)

    def _thermal_demand(self, unit) -> None:
        """Thermal demand (§9; MILP-Demand_Heat1, Demand_Heat2-3).

        ``max(H_robust[t], H_min) ≤ h ≤ H_max`` [MW_th]; ``Q_min ≤ Σt h·dt`` [MWh_th].
        """
        h = self._series_beyond(unit.h_min_mw_th, unit.h_max_mw_th, self._robust_bound(unit.name), lower=True)
        for t in self.T:
            self.heat_demand[t].append(h[t])
        self.h.addConstr(self._sum(self.d.dt * h[t] for t in self.T) >= unit.q_min_mwh_th)

    # ----------------------------------------------------------------- CSP

    def _csp(self, unit) -> None:
        """CSP plant: solar field, storage, power block, turbine commitment (§8)."""
        pb, ts = unit.power_block, unit.storage
        field = self._robust_bound(unit.name)  # [MW_th]
        c = {
            "p_sf": self._series_beyond(0.0, np.inf, field, lower=False),  # (MILP-STU1)
            "h": self._series(0.0, np.inf),                       # heat to thermal demands [MW_th]
            "p_ch": self._series(0.0, np.inf),
            "p_dis": self._series(0.0, np.inf),
            "u_ch": self._series(0, 1, binary=True),              # 1 = charging (TS12)
            "r_ch_up": self._reserve_series(np.inf),
            "r_ch_dn": self._reserve_series(np.inf),
            "r_dis_up": self._reserve_series(np.inf),
            "r_dis_dn": self._reserve_series(np.inf),
            "u": self._series(0, 1, binary=True),
            "v_su": self._series(0, 1, binary=True),
            "v_sd": self._series(0, 1, binary=True),
        }
        c["r_ts_up"] = [c["r_ch_up"][t] + c["r_dis_up"][t] for t in self.T]  # (TS5)
        c["r_ts_dn"] = [c["r_ch_dn"][t] + c["r_dis_dn"][t] for t in self.T]  # (TS6)
        self._commitment(pb, c)
        self._power_block(unit, c)
        curves = {s: self._conversion(pb, c, s) for s in SCENARIOS}
        e = {s: curves[s][0] for s in SCENARIOS}
        self._segment_order({s: curves[s][1] for s in SCENARIOS})
        self._turbine_output(unit, c, e)
        self._storage(ts, c)
        nominal = self.d.uncertain[unit.name].nominal
        self._charge_from_field(c, [b if isinstance(b, float) else nominal[t] for t, b in enumerate(field)])
        for t in self.T:
            self.heat_supply[t].append(c["h"][t])
        dt = self.d.dt
        self.profit.append(-unit.om_eur_per_mwh * dt * self._sum(e["none"][t] + c["h"][t] for t in self.T))

    def _commitment(self, pb, c) -> None:
        """Turbine commitment with minimum up and down times (paper Appendix A, STU10-17).

        ``u[t] - u[t-1] = v_su - v_sd`` with ``u[0]`` = ``initially_on`` and no time carried
        over from the previous day (``N_ON = N_OFF = 0``). Durations [h] become periods.
        """
        u, v_su, v_sd = c["u"], c["v_su"], c["v_sd"]
        nt = self.d.nt
        u0 = 1.0 if pb.initially_on else 0.0

        def prev(t):
            return u[t - 1] if t > 0 else u0

        for t in self.T:
            self.h.addConstr(u[t] - prev(t) == v_su[t] - v_sd[t])   # (STU10)
            self.h.addConstr(v_su[t] + v_sd[t] <= 1)                  # (STU11)
        up = int(round(pb.min_up_h / self.d.dt))
        down = int(round(pb.min_down_h / self.d.dt))
        if up > 1:
            for t in range(0, nt - up + 1):                           # (STU13)
                self.h.addConstr(up * (u[t] - prev(t)) <= self._sum(u[t:t + up]))
            for t in range(max(0, nt - up + 1), nt):                  # (STU14)
                self.h.addConstr(self._sum(u[k] - (u[t] - prev(t)) for k in range(t, nt)) >= 0)
        if down > 1:
            for t in range(0, nt - down + 1):                         # (STU16)
                self.h.addConstr(down * (prev(t) - u[t]) <= self._sum(1 - u[k] for k in range(t, t + down)))
            for t in range(max(0, nt - down + 1), nt):                # (STU17)
                self.h.addConstr(self._sum(1 - u[k] - (prev(t) - u[t]) for k in range(t, nt)) >= 0)

    def _power_block(self, unit, c) -> None:
        """Power-block thermal input and its limits (STU2-4) [MW_th].

        ``p_pb = p_sf - h/η_heat + p_dis - p_ch - K_su·Ppb_max·(starts within the start-up
        duration)``; ``p_pb + r_ts_up ≤ Ppb_max·u``; ``Ppb_min·u ≤ p_pb - r_ts_dn``.
        The start-up heat is drawn in the start-up period, or during
        ``startup_duration_h`` after the start when given.
        """
        pb = unit.power_block
        # A start draws its heat in its own period, or for startup_duration_h after it when given.
        startup_len = 1 if pb.startup_duration_h is None else int(round(pb.startup_duration_h / self.d.dt))
        startup_heat = pb.startup_fraction * pb.p_in_max_mw_th
        c["p_pb"] = []
        for t in self.T:
            starts = self._sum(c["v_su"][k] for k in range(max(0, t - startup_len + 1), t + 1))
            p_pb = (c["p_sf"][t] - (1.0 / unit.heat_efficiency) * c["h"][t] + c["p_dis"][t] - c["p_ch"][t]
                    - startup_heat * starts)
            c["p_pb"].append(p_pb)
            self.h.addConstr(p_pb + c["r_ts_up"][t] <= pb.p_in_max_mw_th * c["u"][t])
            self.h.addConstr(p_pb - c["r_ts_dn"][t] >= pb.p_in_min_mw_th * c["u"][t])

    def _conversion(self, pb, c, scenario: str) -> tuple[list, list]:
        """Piecewise thermal-to-electric curve in one activation scenario (STU5, STU_SOS).

        Exact MILP encoding with one binary ``z_k`` per segment ``k`` (between breakpoints
        ``P_k`` and ``P_{k+1}``, outputs ``O_k = η_k·P_k``), in multiple-choice form: the
        input share ``w_k`` of the selected segment lies in ``[P_k·z_k, P_{k+1}·z_k]``,
        ``Σk z_k = 1``, input ``p_pb + act_s(r_ts_up, r_ts_dn) = Σk w_k`` and output
        ``e_s = Σk [(O_k - m_k·P_k)·z_k + m_k·w_k]`` with slope ``m_k``.

        Tightening, valid because an offline turbine has input 0 (STU3-4) and an online
        one at least ``Ppb_min``: when the first segment ends below ``Ppb_min``, it is
        selected exactly when the turbine is off (``z_0 = 1 - u``) and the other segments
        ending below ``Ppb_min`` are never needed. Returns ``e_s`` [MW] and the segment
        binaries per period.
        """
        inputs = [p for p, _ in pb.breakpoints]
        outputs = [p * eta for p, eta in pb.breakpoints]
        n_segments = len(inputs) - 1
        slopes = [(outputs[k + 1] - outputs[k]) / (inputs[k + 1] - inputs[k]) for k in range(n_segments)]
        off_segment_only = inputs[1] < pb.p_in_min_mw_th
        out = self._series(0.0, np.inf)
        segments = []
        for t in self.T:
            z = [self.h.addVariable(lb=0, ub=1, type=BINARY) for _ in range(n_segments)]
            w = [self.h.addVariable(lb=0.0, ub=inputs[k + 1]) for k in range(n_segments)]
            for k in range(n_segments):
                self.h.addConstr(w[k] >= inputs[k] * z[k])
                self.h.addConstr(w[k] <= inputs[k + 1] * z[k])
            self.h.addConstr(self._sum(z) == 1)
            flow = c["p_pb"][t] + _act(scenario, c["r_ts_up"][t], c["r_ts_dn"][t])
            self.h.addConstr(flow == self._sum(w))
            self.h.addConstr(out[t] == self._sum((outputs[k] - slopes[k] * inputs[k]) * z[k] + slopes[k] * w[k]
                                                 for k in range(n_segments)))
            if off_segment_only:
                self.h.addConstr(z[0] == 1 - c["u"][t])
                for k in range(1, n_segments):
                    if inputs[k + 1] < pb.p_in_min_mw_th:
                        self.h.changeColBounds(z[k].index, 0, 0)
            segments.append(z)
        return out, segments

    def _segment_order(self, segments) -> None:
        """Valid ordering of the selected segments across scenarios [-].

        Inputs satisfy ``in_dn ≤ in_none ≤ in_up``, so choosing for each input the
        leftmost segment containing it gives ``seg_dn ≤ seg_none ≤ seg_up``; in
        cumulative form ``Σ_{k≤j} z_up ≤ Σ_{k≤j} z_none ≤ Σ_{k≤j} z_dn`` for every ``j``.
        """
        for t in self.T:
            n_segments = len(segments["none"][t])
            for j in range(n_segments - 1):
                below = {s: self._sum(segments[s][t][: j + 1]) for s in SCENARIOS}
                self.h.addConstr(below["up"] <= below["none"])
                self.h.addConstr(below["none"] <= below["dn"])

    def _turbine_output(self, unit, c, e) -> None:
        """Turbine cap, CSP electrical reserves and injection (§8, STU6-7).

        ``e_s ≤ Pmax_θ·u`` in every scenario; ``p_θ = e_none``, ``r_up = e_up - e_none``,
        ``r_dn = e_none - e_dn``, both ``≤ min(T_sr·ramp, share·Pmax_θ)`` (0 without SRM) [MW].
        """
        cap = min(self.t_sr_min * unit.ramp_mw_per_min, unit.reserve_share * unit.p_max_mw)
        cap = cap if self.srm else 0.0
        for t in self.T:
            for s in SCENARIOS:
                self.h.addConstr(e[s][t] <= unit.p_max_mw * c["u"][t])
                self.injection[s][t].append(e[s][t])
            self.h.addConstr(e["up"][t] - e["none"][t] >= 0)
            self.h.addConstr(e["up"][t] - e["none"][t] <= cap)
            self.h.addConstr(e["none"][t] - e["dn"][t] >= 0)
            self.h.addConstr(e["none"][t] - e["dn"][t] <= cap)

    def _storage(self, ts, c) -> None:
        """Two-tank thermal storage (TS1-TS11, §8).

        Mode limits (TS1-4); energy ``e[t] = e[t-1] + η_ch·p_ch·dt - p_dis·dt/η_dis`` [MWh_th]
        for every t, cyclic ``e[0] = e[NT]`` or fixed ``e[0] = e_init`` with ``e[NT] ≥ e_init``;
        reserve energy shares (TS9-10) and margins (TS11 corrected: ``E_min + σ_up·span ≤ e ≤
        E_max - σ_dn·span``), ``σ ∈ [0, 1]``.
        """
        dt, span = self.d.dt, ts.e_max_mwh_th - ts.e_min_mwh_th
        u_ch = c["u_ch"]
        for t in self.T:
            self.h.addConstr(c["p_ch"][t] - c["r_ch_up"][t] >= ts.p_ch_min_mw_th * u_ch[t])            # (TS1)
            self.h.addConstr(c["p_ch"][t] + c["r_ch_dn"][t] <= ts.p_ch_max_mw_th * u_ch[t])            # (TS2)
            self.h.addConstr(c["p_dis"][t] + c["r_dis_up"][t] <= ts.p_dis_max_mw_th * (1 - u_ch[t]))  # (TS3)
            self.h.addConstr(c["p_dis"][t] - c["r_dis_dn"][t] >= ts.p_dis_min_mw_th * (1 - u_ch[t]))  # (TS4)
        energy = self._series(ts.e_min_mwh_th, ts.e_max_mwh_th)
        for t in self.T:
            before = energy[t - 1] if t > 0 else (energy[-1] if ts.cyclic else ts.e_init_mwh_th)
            self.h.addConstr(energy[t] == before + ts.eta_ch * dt * c["p_ch"][t]
                             - (dt / ts.eta_dis) * c["p_dis"][t])                                       # (TS7)
        if not ts.cyclic:
            self.h.addConstr(energy[-1] >= ts.e_init_mwh_th)
        sigma_up = self.h.addVariable(lb=0.0, ub=1.0)
        sigma_dn = self.h.addVariable(lb=0.0, ub=1.0)
        self.h.addConstr(self._sum((dt / ts.eta_dis) * r for r in c["r_ts_up"]) <= span * sigma_up)   # (TS9)
        self.h.addConstr(self._sum(ts.eta_ch * dt * r for r in c["r_ts_dn"]) <= span * sigma_dn)      # (TS10)
        for t in self.T:
            self.h.addConstr(energy[t] >= ts.e_min_mwh_th + span * sigma_up)                           # (TS11)
            self.h.addConstr(energy[t] <= ts.e_max_mwh_th - span * sigma_dn)

    def _charge_from_field(self, c, avail) -> None:
        """Valid tightening: the storage charges only from the solar field [MW_th].

        ``p_pb ≥ r_ts_dn + Ppb_min·u ≥ 0`` (STU4), and in charging mode ``p_dis = 0`` (TS3),
        so (STU2) gives ``p_ch ≤ p_sf``; in discharging mode ``p_ch = 0`` (TS2). Hence
        ``p_ch ≤ p_sf`` and ``p_ch ≤ avail[t]·u_ch`` hold in every feasible point, with
        ``avail`` the robust availability (the nominal one where a budget binary decides).
        """
        for t in self.T:
            self.h.addConstr(c["p_ch"][t] <= c["p_sf"][t])
            self.h.addConstr(c["p_ch"][t] <= avail[t] * c["u_ch"][t])

    # ----------------------------------------------------------------- balances and solve

    def _balances(self) -> None:
        """Electrical balance in the scenarios none/up/dn and heat balance (§7, Supply-Demand1).

        Settling (§10): ``injection_s = p_da − s_neg + s_pos + act_s(r_sr_up − q_up, r_sr_dn − q_dn)``
        with ``q ≤ r_sr``, heat ``supply + h_hpa + g = demand``, and the penalty
        ``Σt dt·[π_def·s_neg − π_sur·s_pos + m_sr·λup·q_up + m_sr·λdn·q_dn + c_heat·g]`` subtracted
        from the profit.
        """
        zero = [0.0] * self.d.nt
        s_neg = s_pos = q_up = q_dn = g = zero
        if self.settlement is not None:
            s_neg, s_pos, q_up, q_dn, g = (self._series(0.0, np.inf) for _ in range(5))
            self.slacks = {"s_neg": s_neg, "s_pos": s_pos, "q_up": q_up, "q_dn": q_dn, "g": g}
            prices = self.settlement
            for t in self.T:
                self.h.addConstr(q_up[t] - self.r_sr_up[t] <= 0)
                self.h.addConstr(q_dn[t] - self.r_sr_dn[t] <= 0)
                self.profit.append(-self.d.dt * (prices["short"][t] * s_neg[t] - prices["long"][t] * s_pos[t]
                                                 + prices["reserve_up"][t] * q_up[t]
                                                 + prices["reserve_dn"][t] * q_dn[t] + prices["heat"][t] * g[t]))
        for t in self.T:
            for s in SCENARIOS:
                market = self.p_da[t] - s_neg[t] + s_pos[t] + _act(s, self.r_sr_up[t] - q_up[t],
                                                                   self.r_sr_dn[t] - q_dn[t])
                self.h.addConstr(self._sum(self.injection[s][t]) - market == 0)
            supply = self._sum(self.heat_supply[t]) + self.h_hpa[t] + g[t]
            self.h.addConstr(supply - self._sum(self.heat_demand[t]) == 0)

    def solve(self) -> float:
        """Maximize (MILP-Obj) to a relative gap of 1e-7; return the optimal profit [EUR].

        The RINS and RENS sub-MIP heuristics are off: on these small models they cost
        more time than they save. Raises :class:`ReferenceNotOptimal` otherwise.
        """
        self.h.setOptionValue("mip_rel_gap", MIP_REL_GAP)
        self.h.setOptionValue("mip_heuristic_run_rins", False)
        self.h.setOptionValue("mip_heuristic_run_rens", False)
        self.h.maximize(self._sum(self.profit))
        status = self.h.getModelStatus()
        if status != highspy.HighsModelStatus.kOptimal:
            raise ReferenceNotOptimal(self.h.modelStatusToString(status))
        return float(self.h.getInfo().objective_function_value)


# ----------------------------------------------------------------------------- settling a fixed bid (§10)


def realized_day(case, day: dt.date) -> tuple[pd.DatetimeIndex, dict[str, np.ndarray]]:
    """The local periods of ``day`` and what the history observed in each, per price and unit
    (a unit's series times its scale; availabilities clipped to ``[0, nameplate]``, consumptions
    to the demand's limits)."""
    periods = local_periods(ReferenceCase(**{**vars(case), "delivery_date": day}))
    rows = case.history.frame.reindex(periods.tz_convert("UTC").floor("h"))
    values = {name: rows[name].to_numpy(float) for name in PRICES}
    for kind, unit in case.units():
        if kind == "csp":
            column, scale, low, high = (unit.solar_field.series or unit.name, unit.solar_field.series_scale, 0.0,
                                        unit.solar_field.p_max_mw_th)
        else:
            column, scale = unit.series or unit.name, unit.series_scale
            low, high = {"wind": (0.0, getattr(unit, "p_max_mw", None)), "pv": (0.0, getattr(unit, "p_max_mw", None)),
                         "ed": (getattr(unit, "p_min_mw", None), getattr(unit, "p_max_mw", None)),
                         "td": (getattr(unit, "h_min_mw_th", None), getattr(unit, "h_max_mw_th", None))}[kind]
        values[unit.name] = np.clip(rows[column].to_numpy(float) * scale, low, high)
    return periods, values


def reference_settlement(case, day: dt.date, market: pd.DataFrame, m_def: float = 2.0, m_sur: float = 0.5,
                         m_sr: float = 2.0, c_heat: float | None = None) -> dict[str, float]:
    """Settle the bid ``market`` (columns ``p_da_mw``, ``r_sr_up_mw``, ``r_sr_dn_mw``, ``h_hpa_mw`` per
    period) against what ``day`` observed (MODEL_SPEC §10): every unit re-dispatched at the realized
    values, imbalances priced at ``π_def = λ + (m_def − 1)·|λ|``, ``π_sur = λ − (1 − m_sur)·|λ|``,
    undelivered reserve at ``m_sr`` times its price, unserved heat at ``c_heat`` (default twice the
    highest HPA tariff). Returns the net cost [EUR] and the deficit and surplus energies [MWh]."""
    periods, values = realized_day(case, day)
    nt, zero = len(periods), np.zeros(len(periods))
    tariff = np.array([case.markets.hpa_tariff_eur_per_mwh[h] for h in periods.hour], dtype=float)
    price = {"price_da_mid": values["price_da"], "price_da_pos": zero, "price_da_neg": zero,
             "price_sr_up_hi": values["price_sr_up"], "price_sr_up_neg": zero,
             "price_sr_dn_hi": values["price_sr_dn"], "price_sr_dn_neg": zero, "tariff_hpa": tariff}
    uncertain = {unit.name: Uncertain(values[unit.name], zero, 0, -1.0 if kind in ("wind", "pv", "csp") else 1.0)
                 for kind, unit in case.units()}
    data = DayData(nt=nt, dt=case.dt_h, price=price, gamma={name: 0 for name in PRICES}, uncertain=uncertain)
    lam = values["price_da"]
    heat = max(case.markets.hpa_tariff_eur_per_mwh) * 2.0 if c_heat is None else c_heat
    prices = {"short": lam + (m_def - 1.0) * np.abs(lam), "long": lam - (1.0 - m_sur) * np.abs(lam),
              "reserve_up": m_sr * values["price_sr_up"], "reserve_dn": m_sr * values["price_sr_dn"],
              "heat": np.full(nt, heat)}
    model = ReferenceModel(ReferenceCase(**{**vars(case), "delivery_date": day}), data, settlement=prices)
    model.fix_market(market.sort_values("t") if "t" in market else market)
    profit = model.solve()
    solution = model.h.getSolution().col_value
    energy = {name: sum(solution[v.index] for v in series) * case.dt_h for name, series in model.slacks.items()}
    return {"net_cost_eur": -profit, "deficit_mwh": energy["s_neg"], "surplus_mwh": energy["s_pos"],
            "reserve_short_mwh": energy["q_up"] + energy["q_dn"], "unserved_heat_mwh": energy["g"]}
