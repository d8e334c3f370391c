"""Market periods of a delivery day.

A delivery day is a market day in local time (Europe/Madrid by default): it runs
from local midnight to the next local midnight, so the days when clocks change
have 23 or 25 hours, i.e. 92 or 100 quarter-hours (MODEL_SPEC §1).
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

ALLOWED_DT_H = (1.0, 0.5, 0.25)


def delivery_periods(day: dt.date | str, timezone: str, dt_h: float) -> pd.DatetimeIndex:
    """Local start times of every market period of ``day`` [tz-aware]."""
    if dt_h not in ALLOWED_DT_H:
        raise ValueError(f"dt_h={dt_h} must be one of {ALLOWED_DT_H}")
    start = pd.Timestamp(day).normalize()
    first = start.tz_localize(timezone)
    last = (start + pd.Timedelta(days=1)).tz_localize(timezone)
    step = pd.Timedelta(hours=dt_h)
    utc = pd.date_range(first.tz_convert("UTC"), last.tz_convert("UTC"), freq=step, inclusive="left")
    return utc.tz_convert(timezone)


def period_labels(periods: pd.DatetimeIndex) -> list[str]:
    """Clock labels ``HH:MM`` of the periods; a repeated hour gets its UTC offset."""
    clock = periods.strftime("%H:%M")
    repeated = clock.duplicated(keep=False)
    offsets = periods.strftime("%z")
    return [f"{c} ({o[:3]})" if rep else c for c, rep, o in zip(clock, repeated, offsets)]


def hourly_to_periods(values: np.ndarray, per_hour: int, low: float | None = None,
                      high: float | np.ndarray | None = None) -> np.ndarray:
    """Hourly means brought to ``per_hour`` periods per hour, smooth and keeping each hour's mean.

    MODEL_SPEC §6 (finer periods from hourly data): the cumulative energy at the hour
    boundaries is interpolated by a monotone cubic (PCHIP, Fritsch and Carlson 1980) and
    each period takes the mean rate of the interpolant over its span, so every hour's mean
    is the hourly value exactly. Where the series is at or above ``low`` the cumulative of
    ``values - low`` rises monotonically, PCHIP keeps it monotone, and no period falls
    below ``low``. Values above ``high`` (a nameplate, a scalar or one limit per period) are
    cut and the surplus goes to the hour's other periods in proportion to their room below
    the limit, which keeps the mean. The input is first held to ``[low, high]`` hour by hour
    (an hour at its limit stays flat there). [same unit as ``values``]
    """
    values = np.asarray(values, dtype=float)
    if per_hour == 1 or len(values) == 0:
        return values.copy()
    n = len(values)
    fine_high = None if high is None else np.broadcast_to(np.asarray(high, dtype=float), (n * per_hour,))
    if low is not None:
        values = np.maximum(values, low)
    if fine_high is not None:
        values = np.minimum(values, fine_high.reshape(n, per_hour).mean(axis=1))
    base = 0.0 if low is None else float(low)
    if n == 1:
        fine = np.repeat(values, per_hour)
    else:
        # heavy: SciPy's interpolation takes seconds to import, and only quarter-hour cases need it
        from scipy.interpolate import PchipInterpolator

        cumulative = np.concatenate([[0.0], np.cumsum(values - base)])
        spline = PchipInterpolator(np.arange(n + 1.0), cumulative)
        at = spline(np.arange(n * per_hour + 1) / per_hour)
        at[::per_hour] = cumulative  # the hour boundaries exactly
        fine = np.diff(at) * per_hour + base
    rows = fine.reshape(n, per_hour)
    floor = np.full(rows.shape, -np.inf if low is None else float(low))
    ceiling = np.full(rows.shape, np.inf) if fine_high is None else fine_high.reshape(n, per_hour)
    return _within_keeping_mean(rows, values, floor, ceiling).ravel()


def _within_keeping_mean(rows: np.ndarray, means: np.ndarray, floor: np.ndarray, ceiling: np.ndarray) -> np.ndarray:
    """``rows`` (one hour per row) held to ``[floor, ceiling]``, each row shifted back to its mean:
    a shortfall is added in proportion to each period's room below the ceiling, a surplus taken
    in proportion to its height above the floor (neither crosses a limit)."""
    held = np.clip(rows, floor, ceiling)
    missing = means * rows.shape[1] - held.sum(axis=1)
    room = np.where(missing[:, None] > 0, ceiling - held, held - floor)
    room = np.where(np.isfinite(room), room, 1.0)  # an open side: spread evenly
    total = room.sum(axis=1)
    share = np.divide(room, total[:, None], out=np.zeros_like(room), where=total[:, None] > 0)
    return np.clip(held + missing[:, None] * share, floor, ceiling)


def band_to_periods(lo: np.ndarray, mid: np.ndarray, hi: np.ndarray, per_hour: int, low: float | None = None,
                    high: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An hourly band ``lo <= mid <= hi`` brought to finer periods by :func:`hourly_to_periods`,
    still ordered in every period: the three held to ``[low, high]``, the lower bound first,
    then the two gaps (each >= 0 and no higher than the room left below ``high``), so every
    hour keeps the means of all three."""
    lo, mid, hi = (np.clip(np.asarray(x, dtype=float), -np.inf if low is None else low,
                           np.inf if high is None else high) for x in (lo, mid, hi))
    fine_lo = hourly_to_periods(lo, per_hour, low, high)
    below = np.maximum(mid - lo, 0.0)
    fine_mid = fine_lo + hourly_to_periods(below, per_hour, 0.0, None if high is None else high - fine_lo)
    above = np.maximum(hi - mid, 0.0)
    fine_hi = fine_mid + hourly_to_periods(above, per_hour, 0.0, None if high is None else high - fine_mid)
    return fine_lo, fine_mid, fine_hi
