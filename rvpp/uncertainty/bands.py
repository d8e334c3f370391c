"""Forecast bands of the uncertain series (MODEL_SPEC §6, paper §3.4).

From a window of whole days before the delivery day, per local clock hour: the lower
percentile ``lo`` (default 20th), the median ``mid`` and the upper percentile ``hi``
(default 80th), using numpy's linear interpolation between order statistics. The history
is hourly: at 30 or 15 minutes, each of the day's hourly ``lo``, ``mid`` and ``hi`` is
brought to the finer periods by :func:`rvpp.data.periods.band_to_periods` (smooth, each
hour's mean kept, the band still ordered and within the series' limits), never by repeating
the hour (MODEL_SPEC §6).
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

from ..errors import CaseError
from ..data.history import History
from ..data.periods import band_to_periods, hourly_to_periods

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
    limits: dict[str, tuple[float | None, float | None]] | None = None,
) -> pd.DataFrame:
    """Bands per period for every source.

    ``columns`` maps a source name to ``(history column, scale)``; ``limits`` to the
    series' physical ``(low, high)`` (None: open), which periods shorter than an hour keep.
    Returns a frame indexed by period number ``t = 1..NT`` with columns ``(source, lo|mid|hi)``.
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
    day_hours = hour_starts(periods).hour
    missing = sorted(set(day_hours) - set(hours))
    if missing:
        raise CaseError(f"{history.source}: the window {first} to {last} has no observation at "
                        f"{missing[0]:02d}:00; use a longer window")
    quantiles = (q_lo, 0.5, q_hi)
    # One quantile call per clock hour over every source at once: [hour][stat, source].
    values = np.column_stack([window[column].to_numpy(dtype=float) * scale for column, scale in columns.values()])
    by_hour = {h: np.quantile(values[hours == h], quantiles, axis=0) for h in sorted(set(hours))}
    table = np.stack([by_hour[h] for h in day_hours])  # [hour, stat, source]
    by_source = table.transpose(0, 2, 1).reshape(len(day_hours), len(columns) * len(STATS))
    hourly = pd.DataFrame(by_source, index=pd.RangeIndex(1, len(day_hours) + 1, name="t"),
                          columns=pd.MultiIndex.from_product([list(columns), STATS], names=["source", "stat"]))
    return bands_in_periods(hourly, periods, limits or {})


def hour_starts(periods: pd.DatetimeIndex) -> pd.DatetimeIndex:
    """The hours the ``periods`` of a day fall in, in order [local, tz-aware]."""
    return periods.tz_convert("UTC").floor("h").unique().tz_convert(periods.tz)


def per_hour(periods: pd.DatetimeIndex) -> int:
    """How many of the ``periods`` make an hour (1, 2 or 4)."""
    return len(periods) // len(hour_starts(periods))


def bands_in_periods(hourly: pd.DataFrame, periods: pd.DatetimeIndex,
                     limits: dict[str, tuple[float | None, float | None]]) -> pd.DataFrame:
    """Hourly bands ``(source, lo|mid|hi)`` of a day brought to its ``periods`` (each hour's means
    kept, the band ordered and within each source's ``limits``); hourly periods unchanged."""
    steps = per_hour(periods)
    if steps == 1:
        return hourly
    out = {}
    for source in dict.fromkeys(hourly.columns.get_level_values(0)):
        low, high = limits.get(source, (None, None))
        fine = band_to_periods(*(hourly[(source, stat)].to_numpy(float) for stat in STATS), steps, low, high)
        out.update({(source, stat): values for stat, values in zip(STATS, fine)})
    frame = pd.DataFrame(out, index=pd.RangeIndex(1, len(periods) + 1, name="t"))
    frame.columns = pd.MultiIndex.from_tuples(frame.columns, names=["source", "stat"])
    return frame


def realized_values(
    history: History,
    day: dt.date,
    periods: pd.DatetimeIndex,
    columns: dict[str, tuple[str, float]],
    timezone: str,
    limits: dict[str, tuple[float | None, float | None]] | None = None,
) -> pd.DataFrame:
    """Observed values of the delivery day itself, per period [t = 1..NT; one column per source].

    At periods shorter than an hour, each hourly observation is brought to them by
    :func:`rvpp.data.periods.hourly_to_periods` (each hour's mean kept, within the source's
    ``limits`` ``(low, high)``; None: open).
    """
    observed = history.days(day, 1, timezone)
    by_hour = observed.index.tz_convert("UTC").floor("h")
    hours = hour_starts(periods).tz_convert("UTC")
    steps = per_hour(periods)
    limits = limits or {}
    out = {}
    for source, (column, scale) in columns.items():
        series = pd.Series(observed[column].to_numpy() * scale, index=by_hour).reindex(hours).to_numpy(float)
        out[source] = hourly_to_periods(series, steps, *limits.get(source, (None, None)))
    return pd.DataFrame(out, index=pd.RangeIndex(1, len(periods) + 1, name="t"))
