"""Forecast-based bands: a point forecast plus the quantiles of its past errors (MODEL_SPEC §6).

The paper's bands (:func:`rvpp.uncertainty.bands.forecast_bands`) are *climatology*: per
clock hour, percentiles of what the window observed. Operators bid on forecasts instead,
so a source may take *forecast* bands (``uncertainty.bands`` of the case):

* the point forecast ``f`` for each period of the delivery day D is the history column
  named by the unit's ``forecast_series`` (e.g. the TSO's day-ahead wind forecast, issued
  the day before), or for prices a naive model on past prices, all known when the bids for
  D are made: ``same_hour_yesterday`` (the price at the same local clock hour of D-1,
  cleared the day before), ``same_hour_last_week`` (D-7), or ``blend`` (their mean);
* the errors ``e = actual - forecast`` of the same forecast over the window of whole days
  before D (D-n .. D-1, never D itself) give the quantiles ``Q_lo(e)``, ``Q_50(e)``,
  ``Q_hi(e)`` **per forecast level**: for a period whose forecast is ``f``, the errors of
  the window hours whose forecasts were nearest to ``f`` (the nearest fifth of the
  window, at least :data:`MIN_NEIGHBOURS` hours), with numpy's linear interpolation;
* ``lo = f + Q_lo(e)``, ``mid = f + Q_50(e)``, ``hi = f + Q_hi(e)``, clipped to the
  series' physical limits (0 and the nameplate for output, 0 below for consumption, none
  for prices). The nominal values and deviations of MODEL_SPEC §6 then follow unchanged.

Why per forecast level rather than per clock hour: the error of a forecast depends on its
level (it cannot push output below 0 or above the nameplate; a solar forecast of 0 at
night is never wrong by much; a naive price forecast errs more at high prices), and a
fifth of a 30-day window holds 144 errors where one clock hour holds 30, so the quantiles
are steadier. Measured on 2018 Spanish wind and solar and on OMIE prices of 2019, 2023
and 2024 (``benchmarks/band_quality.py``), 20-80 % bands per forecast level missed 41.5 to
44.5 % of the hours against the nominal 40 % (per clock hour: 42.2 to 44.9 %) and their
mean shortfall below the lower bound was lower in every case (docs/model.md).
Where a local clock hour does not exist on a day (02:00 on the day clocks go forward), the
naive price models take the hour before it; where it occurs twice, its first occurrence.
"""

from __future__ import annotations

import datetime as dt
import threading
from collections import OrderedDict
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from ..data.case import PRICE_MODELS, Case
from ..data.history import PRICE_COLUMNS, History
from ..data.periods import delivery_periods
from ..errors import CaseError
from .bands import STATS, bands_in_periods, forecast_bands, hour_starts, window_days

PRICE_LAGS_DAYS = {"same_hour_yesterday": (1,), "same_hour_last_week": (7,), "blend": (1, 7)}
assert tuple(PRICE_LAGS_DAYS) == PRICE_MODELS
HOURS = 24
NEIGHBOUR_SHARE = 0.2  # share of the window's hours whose errors set the quantiles at one forecast level
MIN_NEIGHBOURS = 24
# Bands of the most recently drawn days, keyed by everything they depend on, so a day
# solved again under another strategy, budget or market set draws its bands once.
RECENT_BANDS = 32
_recent_bands: OrderedDict[tuple, pd.DataFrame] = OrderedDict()
_recent_lock = threading.Lock()


@dataclass(frozen=True)
class BandSpec:
    """How the band of one source is drawn.

    ``column`` and ``scale``: the history column of the observations and the factor
    applied to it (and to the forecast column). ``method``: ``climatology`` or
    ``forecast``. ``forecast_column``: the history column of the point forecast, or
    ``price_model`` for prices. ``low``/``high``: physical limits the band is clipped to.
    """

    column: str
    scale: float = 1.0
    method: str = "climatology"
    forecast_column: str | None = None
    price_model: str | None = None
    low: float | None = None
    high: float | None = None


def band_specs(case: Case) -> dict[str, BandSpec]:
    """The band of every uncertain source of ``case``, prices first, then units.

    Every spec carries its forecast (the unit's forecast column, or the price model) even
    when its method is climatology, so the other method can be drawn for comparison.
    """
    settings = case.uncertainty
    specs = {}
    for name in PRICE_COLUMNS:
        specs[name] = BandSpec(name, 1.0, settings.band_method(name), price_model=settings.price_forecast)
    for kind, unit in case.uncertain_units():
        specs[unit.name] = BandSpec(unit.column, unit.scale, settings.band_method(unit.name, kind),
                                    forecast_column=unit.forecast_column, low=0.0, high=unit.series_capacity)
    return specs


def has_forecast(spec: BandSpec) -> bool:
    """True when forecast bands can be drawn for the source (a forecast column or a price model)."""
    return spec.forecast_column is not None or spec.price_model is not None


def case_bands(case: Case, periods: pd.DatetimeIndex, methods: dict[str, str] | None = None) -> pd.DataFrame:
    """Bands per period of every source of ``case``, each by its method [t = 1..NT; (source, lo|mid|hi)].

    ``methods`` draws the named sources by another method (e.g. to compare the two). The
    bands of the last :data:`RECENT_BANDS` distinct requests are kept, keyed by the history's
    content fingerprint (no history is held) and every setting they depend on; each call
    returns its own copy.
    """
    specs = band_specs(case)
    if methods:
        specs = {name: replace(specs[name], method=method) for name, method in methods.items()}
    settings = case.uncertainty
    key = (case.history.fingerprint, case.delivery_date, case.timezone, str(periods.tz), periods.asi8.tobytes(),
           tuple(specs.items()), settings.window_days, settings.q_lo, settings.q_hi)
    with _recent_lock:
        bands = _recent_bands.get(key)
        if bands is not None:
            _recent_bands.move_to_end(key)
    if bands is None:
        bands = _draw_bands(case, periods, specs)
        with _recent_lock:
            _recent_bands[key] = bands
            while len(_recent_bands) > RECENT_BANDS:
                _recent_bands.popitem(last=False)
    return bands.copy()


def _draw_bands(case: Case, periods: pd.DatetimeIndex, specs: dict[str, BandSpec]) -> pd.DataFrame:
    settings = case.uncertainty
    common = dict(n_days=settings.window_days, q_lo=settings.q_lo, q_hi=settings.q_hi, timezone=case.timezone)
    parts = []
    climatology = {name: (s.column, s.scale) for name, s in specs.items() if s.method == "climatology"}
    if climatology:
        limits = {name: (specs[name].low, specs[name].high) for name in climatology}
        parts.append(forecast_bands(case.history, case.delivery_date, periods, climatology, limits=limits, **common))
    forecast = {name: s for name, s in specs.items() if s.method == "forecast"}
    if forecast:
        parts.append(forecast_error_bands(case.history, case.delivery_date, periods, forecast, **common))
    bands = pd.concat(parts, axis=1)
    return bands[[(name, stat) for name in specs for stat in STATS]]


def forecast_error_bands(history: History, day: dt.date, periods: pd.DatetimeIndex, specs: dict[str, BandSpec],
                         *, n_days: int, q_lo: float, q_hi: float, timezone: str) -> pd.DataFrame:
    """Forecast-error bands per period for the sources in ``specs`` (all of method ``forecast``).

    The bands are drawn per hour of the day (the forecasts are hourly), then brought to
    shorter periods keeping each hour's means (:func:`rvpp.uncertainty.bands.bands_in_periods`).
    Returns a frame indexed by ``t = 1..NT`` with columns ``(source, lo|mid|hi)``.
    """
    first, last = window_days(day, n_days)
    hours = hour_starts(periods)
    pieces = {}
    for source, spec in specs.items():
        point, errors = forecast_and_errors(history, day, spec, n_days=n_days, timezone=timezone)
        errors = errors.dropna()
        if errors.empty:
            raise CaseError(f"{history.source}: no forecast error of {source} can be computed in the window "
                            f"{first} to {last}")
        f = point.reindex(hours.tz_convert("UTC")).to_numpy(float)
        if np.isnan(f).any():
            t = int(np.flatnonzero(np.isnan(f))[0])
            raise CaseError(f"{history.source}: no point forecast of {source} for {hours[t]:%Y-%m-%d %H:%M}")
        offsets = level_quantiles(errors["forecast"].to_numpy(), errors["error"].to_numpy(), f, (q_lo, 0.5, q_hi))
        for i, stat in enumerate(STATS):
            pieces[(source, stat)] = _clip(f + offsets[:, i], spec)
    bands = pd.DataFrame(pieces, index=pd.RangeIndex(1, len(hours) + 1, name="t"))
    bands.columns = pd.MultiIndex.from_tuples(bands.columns, names=["source", "stat"])
    return bands_in_periods(bands, periods, {name: (spec.low, spec.high) for name, spec in specs.items()})


def forecast_and_errors(history: History, day: dt.date, spec: BandSpec, *, n_days: int,
                        timezone: str) -> tuple[pd.Series, pd.DataFrame]:
    """The point forecast of ``day`` [UTC hour index] and the window's errors.

    Errors are ``actual - forecast`` per observed hour of the ``n_days`` days before ``day``,
    as a frame with columns ``hour`` (local clock hour), ``forecast`` and ``error``.
    """
    first, _ = window_days(day, n_days)
    if not has_forecast(spec):
        raise CaseError(f"{spec.column}: forecast bands need a forecast column or a price model")
    if spec.forecast_column is not None:
        # The forecast issued for the day is a history row of the day itself.
        frame = _local_days(history, first, n_days + 1, timezone, day)
        local = frame.index.tz_convert(timezone)
        actual = frame[spec.column].to_numpy(float) * spec.scale
        forecast = frame[spec.forecast_column].to_numpy(float) * spec.scale
        on_day = local.date == day
        point = pd.Series(forecast[on_day], index=frame.index[on_day])
        in_window = ~on_day
    else:
        # Naive price models need the prices up to the day before only.
        lags = PRICE_LAGS_DAYS[spec.price_model]
        frame = _local_days(history, first - dt.timedelta(days=max(lags)), n_days + max(lags), timezone, day)
        local = frame.index.tz_convert(timezone)
        actual = frame[spec.column].to_numpy(float) * spec.scale
        table = _by_clock_hour(actual, local)
        forecast = _naive(table, local, lags)
        targets = delivery_periods(day, timezone, 1.0)
        point = pd.Series(_naive(table, targets, lags), index=targets.tz_convert("UTC"))
        in_window = np.asarray(local.date >= first)
    errors = pd.DataFrame({"hour": local.hour[in_window], "forecast": forecast[in_window],
                           "error": (actual - forecast)[in_window]})
    return point, errors


def _local_days(history: History, first: dt.date, n_days: int, timezone: str, day: dt.date) -> pd.DataFrame:
    try:
        rows = history.days(first, n_days, timezone)
    except CaseError:
        covered = (f"{history.start.tz_convert(timezone).date()} to "
                   f"{(history.end - pd.Timedelta(hours=1)).tz_convert(timezone).date()}")
        raise CaseError(f"{history.source}: forecast bands for {day} need the days {first} to "
                        f"{first + dt.timedelta(days=n_days - 1)}; the history runs from {covered}. Choose a "
                        "later delivery date, a shorter window or a longer history") from None
    rows.index = rows.index.tz_convert("UTC")
    return rows


def _by_clock_hour(values: np.ndarray, local: pd.DatetimeIndex) -> pd.DataFrame:
    """One row per local date, one column per clock hour 0..23; a repeated hour keeps its first
    value, a skipped hour (clocks forward) takes the hour before it."""
    by_clock = pd.Series(values, index=pd.MultiIndex.from_arrays([local.date, local.hour]))
    table = by_clock.groupby(level=[0, 1]).first().unstack()
    return table.reindex(columns=range(HOURS)).ffill(axis=1)


def _naive(table: pd.DataFrame, targets: pd.DatetimeIndex, lags: tuple[int, ...]) -> np.ndarray:
    """Mean over ``lags`` of the value at the same local clock hour ``lag`` days before each target."""
    guesses = []
    for lag in lags:
        guesses.append(np.array([table.at[d - dt.timedelta(days=lag), h]
                                 if d - dt.timedelta(days=lag) in table.index else np.nan
                                 for d, h in zip(targets.date, targets.hour)], dtype=float))
    return np.mean(guesses, axis=0)


def level_quantiles(forecasts: np.ndarray, errors: np.ndarray, levels: np.ndarray,
                    quantiles: tuple[float, ...]) -> np.ndarray:
    """Quantiles of the errors of the window hours whose forecast is nearest each level.

    For each value in ``levels``, the ``max(MIN_NEIGHBOURS, NEIGHBOUR_SHARE·n)`` window hours
    with the forecasts closest to it give the quantiles; hours as close as the farthest of
    them are included too, so equal forecasts (a constant forecast, solar at night) are
    never split by their order in time. Returns an array ``(len(levels), len(quantiles))``.
    """
    count = min(len(errors), max(MIN_NEIGHBOURS, int(np.ceil(NEIGHBOUR_SHARE * len(errors)))))
    out = np.empty((len(levels), len(quantiles)))
    for i, level in enumerate(levels):
        distance = np.abs(forecasts - level)
        reach = np.partition(distance, count - 1)[count - 1]
        out[i] = np.quantile(errors[distance <= reach], quantiles)
    return out


def _clip(values: np.ndarray, spec: BandSpec) -> np.ndarray:
    low = -np.inf if spec.low is None else spec.low
    high = np.inf if spec.high is None else spec.high
    return np.clip(values, low, high)
