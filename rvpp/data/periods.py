"""Market periods of a delivery day.

A delivery day is a market day in local time (Europe/Madrid by default): it runs
from local midnight to the next local midnight, so the days when clocks change
have 23 or 25 hours, i.e. 92 or 100 quarter-hours (MODEL_SPEC §1).
"""

from __future__ import annotations

import datetime as dt

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
