"""Forecast bands (MODEL_SPEC §6) and market-day periods (§1)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pytest

from rvpp.data.history import History
from rvpp.data.periods import delivery_periods, period_labels
from rvpp.uncertainty.bands import forecast_bands, realized_values

TZ = "Europe/Madrid"


@pytest.mark.parametrize("day, dt_h, count", [
    ("2025-03-18", 1.0, 24), ("2025-03-30", 1.0, 23), ("2025-10-26", 1.0, 25),
    ("2025-03-18", 0.25, 96), ("2025-03-30", 0.25, 92), ("2025-10-26", 0.25, 100), ("2025-10-26", 0.5, 50),
])
def test_delivery_days_follow_local_clock_changes(day, dt_h, count):
    periods = delivery_periods(day, TZ, dt_h)
    assert len(periods) == count
    assert periods[0].strftime("%H:%M") == "00:00"
    assert (periods[-1] + pd.Timedelta(hours=dt_h)).strftime("%Y-%m-%d %H:%M") == (
        (pd.Timestamp(day) + pd.Timedelta(days=1)).strftime("%Y-%m-%d 00:00"))


def test_repeated_autumn_hour_is_labelled_with_its_offset():
    labels = period_labels(delivery_periods("2025-10-26", TZ, 1.0))
    assert labels[:4] == ["00:00", "01:00", "02:00 (+02)", "02:00 (+01)"]


def _ramp_history(start="2025-02-01", days=60):
    """Value on local day d (0-based) at local hour h: d + 100·h, for every column."""
    first = pd.Timestamp(start, tz=TZ)
    last = (pd.Timestamp(start) + pd.Timedelta(days=days)).tz_localize(TZ)
    utc = pd.date_range(first.tz_convert("UTC"), last.tz_convert("UTC"), freq="1h", inclusive="left")
    local = utc.tz_convert(TZ)
    day_index = (local.normalize().tz_localize(None) - pd.Timestamp(start)).days
    values = np.asarray(day_index, float) + 100.0 * local.hour
    return History(pd.DataFrame({"timestamp": utc, "x": values, "y": 2 * values}))


def test_bands_are_hourly_percentiles_of_the_window():
    history = _ramp_history()
    day = dt.date(2025, 3, 18)  # local day 45; window = days 15..44
    periods = delivery_periods(day, TZ, 1.0)
    bands = forecast_bands(history, day, periods, {"x": ("x", 1.0), "y2": ("y", 0.5)},
                           n_days=30, q_lo=0.2, q_hi=0.8, timezone=TZ)
    hours = np.arange(24)
    # Sorted window values 15..44 (+100h): 20th percentile at rank 5.8 -> 20.8, median 29.5, 80th 38.2.
    assert np.allclose(bands[("x", "lo")], 20.8 + 100 * hours)
    assert np.allclose(bands[("x", "mid")], 29.5 + 100 * hours)
    assert np.allclose(bands[("x", "hi")], 38.2 + 100 * hours)
    assert np.allclose(bands[("y2", "mid")], bands[("x", "mid")])  # y = 2x scaled by 0.5


def test_quarter_hours_keep_their_hour_band_mean_without_steps_and_the_short_day_skips_two_oclock():
    history = _ramp_history()
    quarters = delivery_periods("2025-03-18", TZ, 0.25)
    bands = forecast_bands(history, dt.date(2025, 3, 18), quarters, {"x": ("x", 1.0)},
                           n_days=30, q_lo=0.2, q_hi=0.8, timezone=TZ)
    mid = bands[("x", "mid")].to_numpy().reshape(24, 4)
    assert np.allclose(mid.mean(axis=1), 29.5 + 100 * np.arange(24), atol=1e-9)
    assert (np.diff(mid[1:-1], axis=1) > 0).all()  # the ramp rises inside each inner hour, no step
    lo, hi = bands[("x", "lo")].to_numpy(), bands[("x", "hi")].to_numpy()
    assert (lo <= mid.ravel() + 1e-12).all() and (mid.ravel() <= hi + 1e-12).all()
    short = delivery_periods("2025-03-30", TZ, 1.0)
    band = forecast_bands(history, dt.date(2025, 3, 30), short, {"x": ("x", 1.0)},
                          n_days=30, q_lo=0.2, q_hi=0.8, timezone=TZ)
    assert list((band[("x", "mid")] // 100).astype(int)) == [0, 1, *range(3, 24)]


def test_realized_values_are_the_day_itself():
    long_day = delivery_periods("2025-10-26", TZ, 1.0)
    assert len(long_day) == 25
    history = _ramp_history(start="2025-10-01", days=40)
    values = realized_values(history, dt.date(2025, 10, 26), long_day, {"x": ("x", 1.0)}, TZ)["x"].to_numpy()
    assert list(values[:4]) == [25, 125, 225, 225] and values[-1] == 25 + 2300
