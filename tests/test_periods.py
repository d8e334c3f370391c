"""Hourly series brought to 30- and 15-minute periods (MODEL_SPEC §6, finer periods)."""

import numpy as np
import pytest

from rvpp.data.periods import band_to_periods, delivery_periods, hourly_to_periods


def _day_of_wind(seed: int = 7, hours: int = 24) -> np.ndarray:
    rng = np.random.default_rng(seed)
    values = np.clip(np.cumsum(rng.normal(0.0, 12.0, hours)) + 40.0, 0.0, 80.0)
    values[5:8] = 0.0  # a calm
    values[15:17] = 80.0  # at the nameplate
    return values


@pytest.mark.parametrize("per_hour", [2, 4])
def test_every_hour_keeps_its_mean_and_the_output_stays_between_zero_and_the_nameplate(per_hour):
    hourly = _day_of_wind()
    fine = hourly_to_periods(hourly, per_hour, 0.0, 80.0)
    assert fine.shape == (24 * per_hour,)
    means = np.array([fine[h * per_hour:(h + 1) * per_hour].sum() / per_hour for h in range(24)])
    assert np.max(np.abs(means - hourly)) < 1e-9
    assert fine.min() >= 0.0 and fine.max() <= 80.0
    assert (fine[5 * per_hour:8 * per_hour] == 0.0).all()  # a calm hour has no energy to spread
    assert np.allclose(fine[15 * per_hour:17 * per_hour], 80.0)  # nor room above the nameplate


def test_the_nameplate_cut_moves_the_surplus_inside_its_hour():
    # 0 then 9 then 10 (nameplate 10): the cubic would overshoot 10 in the middle hour.
    hourly = np.array([0.0, 0.0, 9.0, 10.0, 10.0])
    free = hourly_to_periods(hourly, 4, 0.0, None)
    assert free.max() > 10.0  # what the limit has to correct
    held = hourly_to_periods(hourly, 4, 0.0, 10.0)
    assert held.max() <= 10.0 and abs(held[8:12].mean() - 9.0) < 1e-9
    assert abs(held[8:12].sum() - 36.0) < 1e-9


def test_a_step_becomes_a_ramp():
    hourly = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    fine = hourly_to_periods(hourly, 4, 0.0, None)
    jumps = np.abs(np.diff(fine))
    assert jumps.max() < 0.5  # repeating the hours jumps by the whole step (1.0) at once
    assert len(np.unique(np.round(fine[8:16], 9))) == 8  # the two hours at the step are not flat
    assert abs(fine[12:16].mean() - 2.0) < 1e-9 and abs(fine[8:12].mean() - 1.0) < 1e-9


def test_prices_may_be_negative_and_hourly_periods_are_unchanged():
    prices = np.array([30.0, -5.0, -12.0, 4.0, 60.0, 55.0])
    fine = hourly_to_periods(prices, 4)
    assert np.max(np.abs(fine.reshape(6, 4).mean(axis=1) - prices)) < 1e-9
    assert fine.min() < -12.0 or fine.max() > 60.0 or len(np.unique(fine)) > 6
    assert np.array_equal(hourly_to_periods(prices, 1), prices)


def test_a_band_stays_ordered_and_keeps_each_hours_three_means():
    rng = np.random.default_rng(3)
    mid = np.clip(rng.uniform(0, 100, 25), 0, 100)
    lo = np.maximum(mid - rng.uniform(0, 40, 25), 0.0)
    hi = np.minimum(mid + rng.uniform(0, 40, 25), 100.0)
    fine = band_to_periods(lo, mid, hi, 4, 0.0, 100.0)
    for hourly, values in zip((lo, mid, hi), fine):
        assert np.max(np.abs(values.reshape(25, 4).mean(axis=1) - hourly)) < 1e-9
    f_lo, f_mid, f_hi = fine
    assert (f_lo <= f_mid + 1e-12).all() and (f_mid <= f_hi + 1e-12).all()
    assert f_lo.min() >= 0.0 and f_hi.max() <= 100.0 + 1e-12


def test_the_long_day_has_one_hundred_quarter_hours():
    assert len(delivery_periods("2025-10-26", "Europe/Madrid", 0.25)) == 100
    fine = hourly_to_periods(np.arange(25.0), 4, 0.0, None)
    assert len(fine) == 100 and abs(fine[96:].mean() - 24.0) < 1e-9
