"""Forecast bands of the uncertain series (MODEL_SPEC §6, paper §3.4).

From a window of whole days before the delivery day, per local clock hour: the lower
percentile ``lo`` (default 20th), the median ``mid`` and the upper percentile ``hi``
(default 80th), using numpy's linear interpolation between order statistics. A period
takes the band of the clock hour it starts in, so quarter-hours repeat their hour's
band (the history is hourly).
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

from ..errors import CaseError
from ..data.history import History

STATS = ("lo", "mid", "hi")


def window_days(day: dt.date, n_days: int) -> tuple[dt.date, dt.date]:
    """First and last day of the ``n_days`` window that ends the day before ``day``."""
    return day - dt.timedelta(days=n_days), day - dt.timedelta(days=1)


def forecast_bands(
    history: History,
    day: dt.date,
    periods: pd.DatetimeIndex,
    columns: dict[str, tuple[str, float]],
    *,
    n_days: int,
    q_lo: float,
    q_hi: float,
    timezone: str,
) -> pd.DataFrame:
    """Bands per period for every source.

    ``columns`` maps a source name to ``(history column, scale)``. Returns a frame
    indexed by period number ``t = 1..NT`` with columns ``(source, lo|mid|hi)``.
    """
    first, last = window_days(day, n_days)
    try:
        window = history.days(first, n_days, timezone)
    except CaseError:
        covered = (f"{history.start.tz_convert(timezone).date()} to "
                   f"{(history.end - pd.Timedelta(hours=1)).tz_convert(timezone).date()}")
        raise CaseError(
            f"{history.source}: the {n_days}-day window before {day} ({first} to {last}) is not "
            f"covered; the history runs from {covered}. Choose a later delivery date, a shorter "
            "window or a longer history"
        ) from None
    hours = window.index.hour
    missing = sorted(set(periods.hour) - set(hours))
    if missing:
        raise CaseError(f"{history.source}: the window {first} to {last} has no observation at "
                        f"{missing[0]:02d}:00; use a longer window")
    quantiles = (q_lo, 0.5, q_hi)
    # One quantile call per clock hour over every source at once: [hour][stat, source].
    values = np.column_stack([window[column].to_numpy(dtype=float) * scale for column, scale in columns.values()])
    by_hour = {h: np.quantile(values[hours == h], quantiles, axis=0) for h in sorted(set(hours))}
    table = np.stack([by_hour[h] for h in periods.hour])  # [period, stat, source]
    by_source = table.transpose(0, 2, 1).reshape(len(periods), len(columns) * len(STATS))
    return pd.DataFrame(by_source, index=pd.RangeIndex(1, len(periods) + 1, name="t"),
                        columns=pd.MultiIndex.from_product([list(columns), STATS], names=["source", "stat"]))


def realized_values(
    history: History,
    day: dt.date,
    periods: pd.DatetimeIndex,
    columns: dict[str, tuple[str, float]],
    timezone: str,
) -> pd.DataFrame:
    """Observed values of the delivery day itself, per period [t = 1..NT; one column per source]."""
    observed = history.days(day, 1, timezone)
    by_hour = observed.index.tz_convert("UTC").floor("h")
    out = {}
    for source, (column, scale) in columns.items():
        series = pd.Series(observed[column].to_numpy() * scale, index=by_hour)
        out[source] = series.reindex(periods.tz_convert("UTC").floor("h")).to_numpy()
    return pd.DataFrame(out, index=pd.RangeIndex(1, len(periods) + 1, name="t"))
