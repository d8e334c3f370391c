"""Tests of the synthetic history generator (rvpp.data.synth)."""

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pvlib
import pytest

from rvpp.data import synth

HISTORY_CSV = Path(__file__).resolve().parents[1] / "data" / "cases" / "paper" / "history.csv"
TZ = "Europe/Madrid"

EXPECTED_COLUMNS = [
    "timestamp", "price_da", "price_sr_up", "price_sr_dn", "WF1", "WF2",
    "PV1", "PV2", "PV3", "CSP1", "ED_industry", "ED_service", "ED_residential",
    "TD_industry", "TD_residential",
]

# Contract limits of the flexible demands: minimum daily energy [MWh], Pmin, Pmax [MW].
CONTRACTS = {
    "ED_industry": (600.0, 2.0, 70.0),
    "ED_service": (800.0, 10.0, 80.0),
    "ED_residential": (600.0, 5.0, 60.0),
    "TD_industry": (700.0, 10.0, 80.0),
    "TD_residential": (700.0, 5.0, 70.0),
}
PRICE_BOUNDS = {"price_da": (35.0, 167.0), "price_sr_up": (6.0, 29.0),
                "price_sr_dn": (1.0, 22.0)}
CAPACITIES = {"WF1": 50.0, "WF2": 50.0, "PV1": 50.0, "PV2": 50.0, "PV3": 50.0,
              "CSP1": 300.0}
SOLAR = ["PV1", "PV2", "PV3", "CSP1"]
DEMANDS = list(CONTRACTS)

SHORT_SPAN = dict(start="2025-03-01", end="2025-03-15")


@pytest.fixture(scope="module")
def history():
    return synth.build_history()


@pytest.fixture(scope="module")
def march(history):
    """The 30 local days before the default delivery day 2025-03-18."""
    ts = history["timestamp"]
    inside = ((ts >= pd.Timestamp("2025-02-16", tz=TZ))
              & (ts < pd.Timestamp("2025-03-18", tz=TZ)))
    frame = history[inside]
    assert frame["timestamp"].dt.normalize().nunique() == 30
    return frame


def hourly_quantiles(frame, column, q):
    return frame.groupby(frame["timestamp"].dt.hour)[column].quantile(q)


# --- interface -----------------------------------------------------------------

def test_public_constants():
    assert isinstance(synth.DEFAULT_SEED, int)
    assert dataclasses.is_dataclass(synth.SITE)
    assert synth.SITE.timezone == TZ
    assert 37.0 < synth.SITE.latitude < 37.5 and -3.3 < synth.SITE.longitude < -2.8
    assert 1000 <= synth.SITE.altitude_m <= 1200
    with pytest.raises(dataclasses.FrozenInstanceError):
        synth.SITE.latitude = 0.0


def test_columns_and_dtypes(history):
    assert list(history.columns) == EXPECTED_COLUMNS
    assert str(history["timestamp"].dt.tz) == TZ
    for column in EXPECTED_COLUMNS[1:]:
        assert history[column].dtype == np.float64, column


# --- time axis -----------------------------------------------------------------

def test_row_count_and_contiguous_utc_hours(history):
    assert len(history) == 9504
    utc = history["timestamp"].dt.tz_convert("UTC")
    assert utc.is_unique
    assert (utc.diff().iloc[1:] == pd.Timedelta(hours=1)).all()
    assert history["timestamp"].iloc[0] == pd.Timestamp("2024-12-01 00:00", tz=TZ)
    assert history["timestamp"].iloc[-1] == pd.Timestamp("2025-12-31 23:00", tz=TZ)


def test_dst_days_have_23_and_25_hours(history):
    per_day = history.groupby(history["timestamp"].dt.date).size()
    assert per_day[pd.Timestamp("2025-03-30").date()] == 23
    assert per_day[pd.Timestamp("2025-10-26").date()] == 25
    assert set(per_day.drop([pd.Timestamp("2025-03-30").date(),
                             pd.Timestamp("2025-10-26").date()])) == {24}


def test_custom_span_covers_local_days():
    frame = synth.build_history(start="2025-10-25", end="2025-10-28")
    assert len(frame) == 24 + 25 + 24
    assert frame["timestamp"].iloc[0] == pd.Timestamp("2025-10-25 00:00", tz=TZ)


# --- physical bounds -----------------------------------------------------------

def test_no_missing_values(history):
    assert np.isfinite(history[EXPECTED_COLUMNS[1:]].to_numpy()).all()


def test_prices_within_bounds(history):
    for column, (low, high) in PRICE_BOUNDS.items():
        assert history[column].between(low, high).all(), column


def test_generation_within_capacity(history):
    for column, capacity in CAPACITIES.items():
        assert history[column].between(0.0, capacity).all(), column


def test_demands_within_contract_limits(history):
    for column, (_, p_min, p_max) in CONTRACTS.items():
        assert history[column].between(1.2 * p_min, 0.9 * p_max).all(), column


def test_solar_output_zero_when_sun_below_horizon(history):
    mid_hour = pd.DatetimeIndex(history["timestamp"]) + pd.Timedelta(minutes=30)
    solpos = pvlib.solarposition.get_solarposition(
        mid_hour, synth.SITE.latitude, synth.SITE.longitude, synth.SITE.altitude_m)
    night = solpos["apparent_elevation"].to_numpy() <= 0.0
    assert 0.4 < night.mean() < 0.6
    for column in SOLAR:
        assert (history.loc[night, column] == 0.0).all(), column
        assert history.loc[~night, column].mean() > 0.1 * CAPACITIES[column], column


def test_pv_inverters_clip_at_ac_rating(history):
    for column in ["PV1", "PV2", "PV3"]:
        assert history[column].max() == pytest.approx(50.0, abs=0.01)
        assert (history[column] > 49.9).sum() > 50, column


def test_csp_clear_march_noon_near_design_point():
    times = synth.hourly_index("2025-03-18", "2025-03-19")
    cal = synth.make_calendar(times)
    solpos = synth.solar_position(times)
    turbidity = (pvlib.clearsky.lookup_linke_turbidity(
        times + pd.Timedelta(minutes=30), synth.SITE.latitude, synth.SITE.longitude)
        + synth.TURBIDITY_EXCESS_MEAN)
    sky = synth.clear_sky(times, solpos, turbidity.to_numpy())
    clear = synth.all_sky_irradiance(sky, np.zeros(len(times)))
    daylight = solpos["apparent_elevation"].to_numpy() > 0
    thermal = synth.csp_field_thermal_power(solpos, clear, np.full(len(times), 12.0),
                                            daylight)
    noon = thermal[np.flatnonzero(cal.hour == 13.5)[0]]
    assert 280.0 <= noon <= 300.0


# --- randomness ----------------------------------------------------------------

def test_same_seed_gives_identical_frame():
    pd.testing.assert_frame_equal(synth.build_history(7, **SHORT_SPAN),
                                  synth.build_history(7, **SHORT_SPAN))


def test_different_seed_gives_different_frame():
    first = synth.build_history(7, **SHORT_SPAN)
    second = synth.build_history(8, **SHORT_SPAN)
    for column in EXPECTED_COLUMNS[1:]:
        assert not np.allclose(first[column], second[column]), column


def test_components_have_independent_streams(monkeypatch):
    before = synth.build_history(7, **SHORT_SPAN)
    monkeypatch.setitem(synth.DEMAND_MODELS, "ED_residential",
                        (synth.residential_power_shape, (0.0, 0.0)))
    after = synth.build_history(7, **SHORT_SPAN)
    changed = [c for c in EXPECTED_COLUMNS[1:] if not before[c].equals(after[c])]
    assert changed == ["ED_residential"]


def test_noise_is_persistent_and_bands_plausible(march):
    hour_of_week = [march["timestamp"].dt.day_of_week, march["timestamp"].dt.hour]
    for column in DEMANDS + ["price_da"]:
        residual = march[column] - march.groupby(hour_of_week)[column].transform("median")
        assert residual.autocorr() > 0.5, column
        p20, p50, p80 = (hourly_quantiles(march, column, q) for q in (0.2, 0.5, 0.8))
        width = (p80 - p20) / p50
        assert (width > 0.02).all() and (width < 0.6).all(), column


# --- committed data ------------------------------------------------------------

def test_committed_csv_matches_generator(history):
    text = HISTORY_CSV.read_text().splitlines()
    assert text[0] == ",".join(EXPECTED_COLUMNS)
    assert any(line.startswith("2025-03-30T01:00:00+01:00,") for line in text)
    assert any(line.startswith("2025-03-30T03:00:00+02:00,") for line in text)
    stored = pd.read_csv(HISTORY_CSV, parse_dates=False)
    instants = pd.to_datetime(stored["timestamp"], utc=True)
    assert (instants == history["timestamp"].dt.tz_convert("UTC")).all()
    values = stored[EXPECTED_COLUMNS[1:]].to_numpy()
    assert np.abs(values - history[EXPECTED_COLUMNS[1:]].to_numpy()).max() <= 5e-4 + 1e-9


def test_write_history_round_trip(tmp_path):
    path = tmp_path / "nested" / "history.csv"
    written = synth.write_history(path)
    stored = pd.read_csv(path, parse_dates=False)
    assert list(stored.columns) == EXPECTED_COLUMNS
    instants = pd.to_datetime(stored["timestamp"], utc=True)
    assert (instants == written["timestamp"].dt.tz_convert("UTC")).all()
    np.testing.assert_array_equal(stored[EXPECTED_COLUMNS[1:]].to_numpy(),
                                  written[EXPECTED_COLUMNS[1:]].to_numpy())


# --- calibration on the March window ---------------------------------------------

@pytest.mark.parametrize("column", DEMANDS)
def test_median_day_energy_close_above_minimum(march, column):
    min_energy = CONTRACTS[column][0]
    median_day = hourly_quantiles(march, column, 0.5).sum() / min_energy
    low_day = hourly_quantiles(march, column, 0.2).sum() / min_energy
    assert 1.0 <= median_day <= 1.1
    assert 0.9 <= low_day <= 1.0


def test_price_has_midday_dip_and_evening_peak(march):
    median = hourly_quantiles(march, "price_da", 0.5)
    midday = median.loc[12:16].min()
    morning = median.loc[6:9].max()
    evening = median.loc[19:22].max()
    assert median.idxmax() in range(19, 23)
    assert evening > 1.3 * midday
    assert morning > 1.1 * midday
    assert evening > morning


def test_price_ranges(history):
    p = history["price_da"].quantile([0.05, 0.5, 0.95])
    assert 35 < p[0.05] < 50 and 55 < p[0.5] < 90 and 100 < p[0.95] < 160
    assert 8 < history["price_sr_up"].median() < 20
    assert 3 < history["price_sr_dn"].median() < 15
    assert np.corrcoef(history["price_sr_up"], history["price_da"])[0, 1] > 0.3


def test_price_falls_with_wind_and_sun(history):
    daily = history.set_index("timestamp").resample("D").mean()
    wind = (daily["WF1"] + daily["WF2"]) / 2
    solar = daily[["PV1", "PV2", "PV3"]].mean(axis=1)
    assert np.corrcoef(daily["price_da"], wind)[0, 1] < -0.2
    assert np.corrcoef(daily["price_da"], solar)[0, 1] < -0.2


def test_wind_farms_correlated(history, march):
    for frame in (history, march):
        corr = np.corrcoef(frame["WF1"], frame["WF2"])[0, 1]
        assert 0.5 < corr < 0.9


def test_capacity_factors_and_seasons(history):
    year = history[history["timestamp"].dt.year == 2025]
    month = year["timestamp"].dt.month
    cf = {c: year[c].mean() / CAPACITIES[c] for c in CAPACITIES}
    assert 0.18 < cf["WF1"] < 0.35 and 0.18 < cf["WF2"] < 0.35
    assert 0.20 < cf["PV1"] < 0.30 and 0.20 < cf["PV3"] < 0.30
    assert cf["PV1"] < cf["PV2"] < 0.35
    assert 0.20 < cf["CSP1"] < 0.35
    summer, winter, spring = month.isin([6, 7, 8]), month.isin([12, 1, 2]), month.isin([4, 5])

    def mean(column, months):
        return year.loc[months, column].mean()

    assert mean("CSP1", summer) > 2.5 * mean("CSP1", winter)
    assert mean("TD_residential", winter) > 2 * mean("TD_residential", summer)
    assert mean("ED_residential", winter) > mean("ED_residential", spring)
