"""A case built from downloaded files (rvpp.data.build_case).

The always-run tests use an hourly table written here by formula (hour h of day d: wind
1,000 + 100·d + 10·h MW, forecast 50 MW lower, ...); the real-data test builds from the
Spanish files when they are present and skips otherwise.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rvpp import load_case, solve, with_options
from rvpp.cli import main
from rvpp.data.build_case import BuildOptions, build_case
from rvpp.errors import DataImportError, RvppError
from rvpp.settle.audit import audit_result
from tests.factories import PAPER, SPAIN

TZ = "Europe/Madrid"
REAL = [SPAIN / "entsoe_spain_2015_2018.csv", SPAIN / "omie_spain_prices_2018_2025.csv"]


def write_table(path: Path, days: int = 45, start: str = "2021-05-01", blank: str | None = None) -> Path:
    """An hourly ``time_utc`` table in rvpp's normalised layout, every value a formula of (day, hour)."""
    first = pd.Timestamp(start, tz=TZ)
    last = (pd.Timestamp(start) + pd.Timedelta(days=days)).tz_localize(TZ)
    utc = pd.date_range(first.tz_convert("UTC"), last.tz_convert("UTC"), freq="h", inclusive="left")
    local = utc.tz_convert(TZ)
    d = np.asarray((local.normalize().tz_localize(None) - pd.Timestamp(start)).days, float)
    h = np.asarray(local.hour, float)
    solar = np.where((h >= 8) & (h <= 19), 400.0 * (h - 7.0), 0.0)
    table = pd.DataFrame({
        "time_utc": [f"{t:%Y-%m-%dT%H:%M:%SZ}" for t in utc], "time_local": [t.isoformat() for t in local],
        "price_da": np.where((h >= 12) & (h <= 15), -1.0 + 0 * d, 50.0 + h),
        "actual_wind_onshore": 1000.0 + 100.0 * d + 10.0 * h, "forecast_wind_onshore": 950.0 + 100.0 * d + 10.0 * h,
        "actual_solar": solar, "forecast_solar": solar * 0.9})
    text = table.to_csv(index=False)
    if blank:
        lines = text.splitlines()
        lines = [",".join(line.split(",")[:3] + [""] + line.split(",")[4:]) if line.startswith(blank) else line
                 for line in lines]
        text = "\n".join(lines) + "\n"
    path.write_text(text)
    return path


def test_units_take_the_fleet_capacity_factor_and_scaled_forecast_errors(tmp_path):
    source = write_table(tmp_path / "series.csv")
    built = build_case([source], tmp_path / "case", template=PAPER, options=BuildOptions(errors_scale=2.0))
    case = load_case(tmp_path / "case")
    assert case.delivery_date == dt.date(2021, 6, 14)  # the last day by default
    frame = case.history.frame
    capacity = 1000.0 + 100.0 * 44 + 10.0 * 23  # the highest wind output: last day, 23:00
    assert built.capacities_mw["wind"] == capacity
    at = pd.Timestamp("2021-05-11 10:00", tz=TZ).tz_convert("UTC")  # day 10, 10:00
    actual = (1000.0 + 1000.0 + 100.0) / capacity * 50.0
    fleet_forecast = (950.0 + 1000.0 + 100.0) / capacity * 50.0
    assert frame.at[at, "WF1"] == pytest.approx(actual, rel=1e-5)
    assert frame.at[at, "WF1_fc"] == pytest.approx(actual - 2.0 * (actual - fleet_forecast), rel=1e-5)
    assert frame.at[at, "WF2"] == pytest.approx(actual, rel=1e-5)
    # PV: solar 400·(h - 7) MW with capacity 4,800 MW (19:00); 0 while the sun is down.
    assert frame.at[at, "PV1"] == pytest.approx(400.0 * 3 / 4800.0 * 50.0, rel=1e-5)
    assert frame.at[at, "PV1_fc"] == pytest.approx(12.5 - 2.0 * (12.5 - 0.9 * 12.5), rel=1e-5)
    midnight = pd.Timestamp("2021-05-11 00:00", tz=TZ).tz_convert("UTC")
    assert frame.at[midnight, "PV1"] == 0.0 and frame.at[midnight, "PV1_fc"] == 0.0
    # Prices are the data's, negative ones included; reserve prices stay within the synthetic bounds.
    assert frame.at[pd.Timestamp("2021-05-11 13:00", tz=TZ).tz_convert("UTC"), "price_da"] == -1.0
    assert frame["price_sr_up"].between(0.0, 40.0).all() and frame["price_sr_dn"].between(0.0, 30.0).all()
    provenance = case.provenance_map
    assert [c for c, p in provenance.items() if p.origin == "real"] == ["price_da"]
    assert {"WF1", "WF1_fc", "WF2", "WF2_fc", "PV1", "PV1_fc", "PV2", "PV2_fc", "PV3", "PV3_fc"} <= {
        c for c, p in provenance.items() if p.origin == "real-derived"}
    assert {"price_sr_up", "price_sr_dn", "ED_industry", "TD_residential", "TD_residential_fc"} <= {
        c for c, p in provenance.items() if p.origin == "modelled"}  # the table gives no system load
    assert provenance["CSP1"].origin == provenance["CSP1_fc"].origin == "real-derived"
    assert case.csp[0].solar_field.forecast_series == "CSP1_fc"
    assert case.uncertainty.band_method("CSP1", "csp") == "forecast"
    assert "series.csv" in provenance["price_da"].source and "sha256" in provenance["price_da"].source
    assert case.uncertainty.band_method("WF1", "wind") == "forecast"
    assert case.uncertainty.band_method("price_sr_up") == "climatology"


def test_forecast_errors_scale_zero_is_a_perfect_forecast_and_clipping_holds(tmp_path):
    source = write_table(tmp_path / "series.csv")
    build_case([source], tmp_path / "case", template=PAPER, options=BuildOptions(errors_scale=0.0))
    frame = load_case(tmp_path / "case").history.frame
    assert np.allclose(frame["WF1_fc"], frame["WF1"])
    assert np.allclose(frame["CSP1_fc"], frame["CSP1"])
    build_case([source], tmp_path / "big", template=PAPER, options=BuildOptions(errors_scale=60.0))
    frame = load_case(tmp_path / "big").history.frame
    assert frame["WF1_fc"].min() >= 0.0 and frame["WF1_fc"].max() <= 50.0
    assert frame["CSP1_fc"].min() >= 0.0 and frame["CSP1_fc"].max() <= 300.0


def _clear_sky_ghi(index: pd.DatetimeIndex) -> np.ndarray:
    """The site's clear-sky GHI [W/m2] at mid-hour, straight from pvlib (the oracle's own call)."""
    import pvlib

    site = pvlib.location.Location(37.23, -3.07, TZ, 1100.0)
    middle = index.tz_convert(TZ) + pd.Timedelta(minutes=30)
    turbidity = pvlib.clearsky.lookup_linke_turbidity(middle, site.latitude, site.longitude)
    return site.get_clearsky(middle, model="ineichen", linke_turbidity=turbidity)["ghi"].to_numpy()


def test_the_clear_sky_index_reads_clear_days_as_one_and_a_half_fleet_as_one_half():
    from rvpp.data import synth
    from rvpp.data.build_case import clear_sky_index

    assert (synth.SITE.latitude, synth.SITE.longitude) == pytest.approx((37.23, -3.07), abs=0.01)
    index = pd.date_range("2021-04-30 22:00", periods=24 * 20, freq="h", tz="UTC")
    ghi = _clear_sky_ghi(index)
    growing = 0.7 + 0.01 * np.arange(len(index)) / 24  # the fleet grows by 1 % of its output a day
    cf = growing * ghi / 1000.0
    cloudy = index.tz_convert(TZ).date == dt.date(2021, 5, 15)
    cf[cloudy] *= 0.5
    k = clear_sky_index(cf, index)
    elevated = ghi > 200.0
    later = index.tz_convert(TZ).date >= dt.date(2021, 5, 8)  # a week of envelope behind it
    clear = later & ~cloudy & elevated
    # The envelope is the 0.9 quantile of 7..30 days before: growth of 1 %/day reads as at most a few per cent.
    assert np.all(k[clear] > 0.95) and np.all(k <= 1.0)
    assert np.allclose(k[cloudy & elevated], 0.5, atol=0.03)


def test_the_fields_heat_rises_with_the_clear_sky_index_and_stays_within_the_field():
    from rvpp.data import synth

    times = synth.hourly_index("2018-04-05", "2018-04-06")
    heats = [synth.field_heat_from_clear_sky_index(times, np.full(24, k)) for k in (0.2, 0.5, 0.8, 1.0)]
    for lower, higher in zip(heats, heats[1:]):
        assert np.all(higher >= lower - 1e-9)
    assert heats[0].max() == 0.0 and heats[-1].max() == pytest.approx(300.0)  # no beam under overcast; defocused
    assert heats[-1][:6].max() == 0.0 and heats[-1][21:].max() == 0.0  # night


def test_the_field_follows_the_fleet_real_derived_from_its_clear_sky_index(tmp_path):
    source = write_table(tmp_path / "series.csv")
    frame = pd.read_csv(source)
    utc = pd.DatetimeIndex(pd.to_datetime(frame["time_utc"], utc=True))
    cf = 0.8 * _clear_sky_ghi(utc) / 1000.0
    dull = (utc.tz_convert(TZ).date == dt.date(2021, 6, 12))
    frame["actual_solar"] = 5000.0 * cf * np.where(dull, 0.3, 1.0)
    frame["forecast_solar"] = 5000.0 * cf  # the forecast missed the dull day
    frame.to_csv(source, index=False)
    build_case([source], tmp_path / "case", template=PAPER)
    heat = load_case(tmp_path / "case").history.frame
    local = heat.index.tz_convert(TZ).date
    daily = heat.groupby(local)[["CSP1", "CSP1_fc"]].sum()
    assert daily.loc[dt.date(2021, 6, 12), "CSP1"] < 0.1 * daily.loc[dt.date(2021, 6, 11), "CSP1"]
    assert daily.loc[dt.date(2021, 6, 12), "CSP1_fc"] > 0.8 * daily.loc[dt.date(2021, 6, 11), "CSP1_fc"]
    assert daily.loc[dt.date(2021, 6, 11), "CSP1"] > 2000.0  # a clear June day fills much of the field's hours


def test_electrical_demands_follow_the_system_load_on_their_energy_and_range(tmp_path):
    source = write_table(tmp_path / "series.csv")
    frame = pd.read_csv(source)
    local = pd.DatetimeIndex(pd.to_datetime(frame["time_utc"], utc=True)).tz_convert(TZ)
    hour = np.asarray(local.hour, float)
    frame["load_actual"] = 30000.0 + 6000.0 * np.sin(np.pi * (hour - 6.0) / 12.0)  # 24,000 to 36,000 MW
    frame["load_forecast"] = frame["load_actual"] + 600.0
    frame.to_csv(source, index=False)
    build_case([source], tmp_path / "case", template=PAPER, options=BuildOptions(errors_scale=2.0))
    case = load_case(tmp_path / "case")
    history = case.history.frame
    # ED_industry: e_min 600 MWh, p in [2, 70] MW: level 1.05·600/24 = 26.25 MW, the load's own swings ±20 %.
    industry = history["ED_industry"].to_numpy()
    assert industry.max() == pytest.approx(26.25 * 1.2, rel=1e-6) and industry.min() == pytest.approx(26.25 * 0.8,
                                                                                                     rel=1e-6)
    # ED_service: level 35 MW in [12, 72] MW: ±20 % fits, so the same relative shape.
    assert np.allclose(history["ED_service"] / 35.0, industry / 26.25, rtol=1e-5)  # 6 digits in the file
    # The forecast is 600 MW (2 % of 30,000) high, its error doubled: 4 % of the level above.
    assert np.allclose(history["ED_industry_fc"] - industry, 2.0 * 0.02 * 26.25, atol=1e-4)
    origins = case.provenance_map
    assert origins["ED_industry"].origin == origins["ED_industry_fc"].origin == "real-derived"
    assert case.ed[0].forecast_series == "ED_industry_fc"
    assert case.uncertainty.band_method("ED_industry", "ed") == "forecast"
    heat = history["TD_industry"].to_numpy()
    error = history["TD_industry_fc"].to_numpy() / heat - 1.0
    assert 0.05 < error.std() < 0.15  # 5 % error, doubled by K = 2: a stated, modelled forecast error
    assert origins["TD_industry_fc"].origin == "modelled"
    assert case.uncertainty.band_method("TD_industry", "td") == "forecast"


def test_a_gap_in_the_system_load_leaves_the_demands_modelled_unless_filled(tmp_path):
    source = write_table(tmp_path / "series.csv")
    frame = pd.read_csv(source)
    frame["load_actual"] = 30000.0
    frame.loc[100, "load_actual"] = np.nan
    frame.to_csv(source, index=False)
    built = build_case([source], tmp_path / "case", template=PAPER)
    assert load_case(tmp_path / "case").provenance_map["ED_industry"].origin == "modelled"
    assert any(n.startswith("electrical demands stay modelled: the data has gaps: load_actual") for n in built.notes)
    build_case([source], tmp_path / "filled", template=PAPER, options=BuildOptions(fill_gaps_h=1))
    case = load_case(tmp_path / "filled")
    assert case.provenance_map["ED_industry"].origin == "real-derived"
    assert "interpolated" in case.provenance_map["ED_industry"].note
    assert np.allclose(case.history.frame["ED_industry"], 1.05 * 600 / 24)  # a flat load: the level itself


def test_gaps_are_refused_or_interpolated_on_request(tmp_path):
    source = write_table(tmp_path / "series.csv", blank="2021-05-20T10")
    with pytest.raises(DataImportError, match=r"actual_wind_onshore has no value in 1 hour.*longest span of whole "
                                              r"days with every value is 2021-05-21 to 2021-06-14.*--fill-gaps"):
        build_case([source], tmp_path / "case", template=PAPER)
    built = build_case([source], tmp_path / "case", template=PAPER, options=BuildOptions(fill_gaps_h=1))
    wind = load_case(tmp_path / "case").history.frame["WF1"]
    hour = pd.Timestamp("2021-05-20 10:00", tz="UTC")
    assert wind[hour] == pytest.approx((wind[hour - pd.Timedelta(hours=1)] + wind[hour + pd.Timedelta(hours=1)]) / 2)
    assert any("interpolated" in n for n in built.notes)
    assert "interpolated" in built.case.provenance_map["WF1"].note


def test_build_refuses_what_it_cannot_build(tmp_path):
    source = write_table(tmp_path / "series.csv")
    prices_only = tmp_path / "prices.csv"
    pd.read_csv(source)[["time_utc", "time_local", "price_da"]].to_csv(prices_only, index=False)
    no_prices = tmp_path / "wind.csv"
    pd.read_csv(source).drop(columns="price_da").to_csv(no_prices, index=False)
    with pytest.raises(DataImportError, match="the files give no day-ahead price"):
        build_case([no_prices], tmp_path / "a", template=PAPER)
    with pytest.raises(RvppError, match="--date 2021-05-20 must lie in 2021-06-07 to 2021-06-14"):
        build_case([source], tmp_path / "b", template=PAPER, options=BuildOptions(date="2021-05-20"))
    with pytest.raises(RvppError, match=r"the data cover 5 whole day\(s\), 2021-06-10 to 2021-06-14; a case needs 38"):
        build_case([source], tmp_path / "b", template=PAPER, options=BuildOptions(start="2021-06-10"))
    with pytest.raises(RvppError, match="--errors-scale K=-1 must be"):
        BuildOptions(errors_scale=-1.0)
    build_case([source], tmp_path / "c", template=PAPER)
    with pytest.raises(RvppError, match="already holds a case"):
        build_case([source], tmp_path / "c", template=PAPER)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c", "prices.csv", "series.csv", "wind.csv"]  # no temporary


def test_prices_alone_make_a_case_with_every_unit_synthetic(tmp_path):
    source = write_table(tmp_path / "series.csv")
    prices_only = tmp_path / "prices.csv"
    pd.read_csv(source)[["time_utc", "time_local", "price_da"]].to_csv(prices_only, index=False)
    built = build_case([prices_only], tmp_path / "case", template=PAPER)
    case = load_case(tmp_path / "case")
    assert {c: p.origin for c, p in case.provenance_map.items() if p.origin == "real"} == {"price_da": "real"}
    assert case.provenance_map["CSP1"].origin == "modelled" and "CSP1_fc" not in case.history.columns
    assert case.wind[0].forecast_series is None and case.uncertainty.band_method("WF1", "wind") == "climatology"
    assert case.uncertainty.band_method("price_da") == "forecast"
    assert any("wind units are synthetic" in n for n in built.notes)
    assert "WF1_fc" not in case.history.columns and case.history.frame["WF1"].max() > 0


def test_command_line_builds_a_case(tmp_path, capsys):
    source = write_table(tmp_path / "series.csv")
    code = main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "case"), "--errors-scale", "3",
                 "--start", "2021-05-02", "--date", "2021-06-10"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "WF1: real-derived" in printed.out and "price_sr_up: modelled" in printed.out
    case = load_case(tmp_path / "case")
    assert case.delivery_date == dt.date(2021, 6, 10)
    assert case.history.local_days(TZ)[0] == dt.date(2021, 5, 2)
    assert main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "case")]) == 1
    assert "already holds a case" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.skipif(not all(p.is_file() for p in REAL), reason="real Spanish data not present")
def test_real_spanish_case_solves_a_day_of_2018(tmp_path):
    built = build_case(REAL, tmp_path / "spain", template=PAPER,
                       options=BuildOptions(errors_scale=3.0, start="2018-01-01", end="2018-03-31"))
    case = load_case(tmp_path / "spain")
    raw = pd.read_csv(REAL[0])
    raw.index = pd.to_datetime(raw["time"], utc=True)
    first_quarter = raw.loc["2017-12-31 23:00":"2018-03-31 21:00"]
    capacity = first_quarter["generation wind onshore"].max()
    assert built.capacities_mw["wind"] == capacity
    at = pd.Timestamp("2018-03-10 12:00", tz="UTC")
    assert case.history.frame.at[at, "WF1"] == pytest.approx(
        raw.at[at, "generation wind onshore"] / capacity * 50.0, rel=1e-5)
    assert case.history.frame.at[at, "price_da"] == raw.at[at, "price day ahead"]
    result = solve(with_options(case, date="2018-03-20"))
    assert result.status == "optimal"
    assert audit_result(result) == []
    source = result.problem.sources["WF1"]
    assert (source.nominal <= 50.0).all() and (source.deviation >= 0.0).all()
