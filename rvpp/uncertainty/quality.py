"""How good a band is: width, miss rate and shortfall below its lower bound, day by day.

For every delivery day of a period, the bands are drawn exactly as a plan for that day
would draw them (the window of days before it; the forecast issued for it) and scored
against what the day then brought:

* **width**: mean of ``hi - lo`` over the hours;
* **miss rate**: share of hours whose actual value lies outside ``[lo, hi]`` (split into
  below and above); a 20-80 % band that is well calibrated misses 40 % of the hours;
* **shortfall**: mean over all hours of ``max(0, lo - actual)``, what the lower bound a
  producer plans on over-promises.

Output series are divided by a capacity so numbers read as % of capacity.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pandas as pd

from ..data.history import History
from ..data.periods import delivery_periods
from ..errors import RvppError
from .bands import forecast_bands
from .forecast import BandSpec, forecast_error_bands
from ..data.importers import fill_gaps, hourly_table, import_files

SERIES = {  # --series: (actual column, forecast column or None for prices, normalised by capacity)
    "wind_onshore": ("actual_wind_onshore", "forecast_wind_onshore", True),
    "solar": ("actual_solar", "forecast_solar", True),
    "price_da": ("price_da", None, False),
}
MAX_FILLED_GAP_H = 3  # a gap of at most this many hours is interpolated for scoring, and counted


def score(lo: np.ndarray, hi: np.ndarray, actual: np.ndarray) -> dict[str, float]:
    """Width, miss rates and mean shortfall of bands ``[lo, hi]`` against ``actual`` (same units)."""
    below, above = actual < lo, actual > hi
    return {"width": float(np.mean(hi - lo)), "miss_rate": float(np.mean(below | above)),
            "below_rate": float(np.mean(below)), "above_rate": float(np.mean(above)),
            "shortfall": float(np.mean(np.maximum(0.0, lo - actual)))}


def band_quality(history: History, days: list[dt.date], spec: BandSpec, *, window_days: int, q_lo: float,
                 q_hi: float, timezone: str) -> dict:
    """Score climatology and forecast bands of one series over ``days``.

    ``spec`` describes the forecast (a forecast column or a price model) and the scale
    and limits; the climatology uses the same column and scale.
    """
    collected: dict[str, list] = {"climatology": [], "forecast": []}
    actual_all = []
    for day in days:
        periods = delivery_periods(day, timezone, 1.0)
        common = dict(n_days=window_days, q_lo=q_lo, q_hi=q_hi, timezone=timezone)
        clim = forecast_bands(history, day, periods, {"s": (spec.column, spec.scale)}, **common)
        fc = forecast_error_bands(history, day, periods, {"s": spec}, **common)
        observed = history.days(day, 1, timezone)[spec.column].to_numpy(float) * spec.scale
        actual_all.append(observed)
        for name, bands in (("climatology", clim), ("forecast", fc)):
            collected[name].append((bands[("s", "lo")].to_numpy(), bands[("s", "hi")].to_numpy()))
    actual = np.concatenate(actual_all)
    methods = {}
    for name, parts in collected.items():
        lo = np.concatenate([p[0] for p in parts])
        hi = np.concatenate([p[1] for p in parts])
        methods[name] = score(lo, hi, actual)
    return {"days": len(days), "hours": int(len(actual)), "methods": methods}


def band_quality_from_files(paths: list[str | Path], *, series: str = "wind_onshore", year: int | None = None,
                            window_days: int = 30, q_lo: float = 0.2, q_hi: float = 0.8,
                            price_model: str = "same_hour_yesterday", zone: str | None = None,
                            timezone: str = "Europe/Madrid") -> dict:
    """:func:`band_quality` on imported files, for one year of days (default: the last whole year).

    Output series are normalised by the year's highest output and reported in % of it.
    Gaps of at most three hours are interpolated for scoring and counted in ``filled_hours``;
    longer gaps are refused.
    """

    if series not in SERIES:
        raise RvppError(f"--series {series!r} must be one of {', '.join(SERIES)}")
    column, forecast, normalised = SERIES[series]
    table = hourly_table(import_files(list(paths), zone)).frame
    needed = [c for c in (column, forecast) if c]
    missing = [c for c in needed if c not in table.columns]
    if missing:
        raise RvppError(f"the files give no {missing[0]} (they give {', '.join(table.columns)})")
    local_years = table.index.tz_convert(timezone).year
    whole = [y for y in sorted(set(local_years)) if _covers_year(table.index, y, timezone)]
    if year is None:
        if not whole:
            raise RvppError("the files cover no whole year; choose one with --year")
        year = whole[-1]
    first, last = dt.date(year, 1, 1), dt.date(year, 12, 31)
    start = pd.Timestamp(first - dt.timedelta(days=window_days + 7)).tz_localize(timezone)
    end = pd.Timestamp(last + dt.timedelta(days=1)).tz_localize(timezone)
    part = table.loc[(table.index >= start) & (table.index < end), needed]
    if part.index.min() > start or part.index.max() + pd.Timedelta(hours=1) < end:
        raise RvppError(f"the files do not cover {year} and the {window_days + 7} days before it")
    part, filled = fill_gaps(part, MAX_FILLED_GAP_H)
    capacity = float(part.loc[part.index >= pd.Timestamp(first).tz_localize(timezone), column].max()) \
        if normalised else None
    scale = 100.0 / capacity if normalised else 1.0
    spec = BandSpec(column, scale, "forecast", forecast_column=forecast,
                    price_model=None if forecast else price_model,
                    low=0.0 if normalised else None, high=100.0 if normalised else None)
    history = History(part.reset_index(names="timestamp"), source=f"{series} {year}")
    days = [first + dt.timedelta(days=k) for k in range((last - first).days + 1)]
    result = band_quality(history, days, spec, window_days=window_days, q_lo=q_lo, q_hi=q_hi, timezone=timezone)
    return {"series": series, "year": year, "unit": "% of capacity" if normalised else "EUR/MWh",
            "capacity": capacity, "window_days": window_days, "q_lo": q_lo, "q_hi": q_hi,
            "forecast": forecast or price_model, "filled_hours": filled, **result}


def _covers_year(index: pd.DatetimeIndex, year: int, timezone: str) -> bool:
    first = pd.Timestamp(dt.date(year, 1, 1)).tz_localize(timezone)
    last = pd.Timestamp(dt.date(year + 1, 1, 1)).tz_localize(timezone)
    return index.min() <= first and index.max() + pd.Timedelta(hours=1) >= last
