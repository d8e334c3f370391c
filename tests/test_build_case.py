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
from rvpp.data import synth
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


def test_the_modelled_sky_and_demands_replace_those_columns_only(tmp_path):
    source = write_table(tmp_path / "series.csv")
    frame = pd.read_csv(source)
    frame["load_actual"] = 30000.0
    frame["load_forecast"] = 30300.0
    frame.to_csv(source, index=False)
    build_case([source], tmp_path / "real", template=PAPER)
    build_case([source], tmp_path / "modelled", template=PAPER, options=BuildOptions(sky="modelled",
                                                                                     demands="modelled"))
    real, modelled = load_case(tmp_path / "real"), load_case(tmp_path / "modelled")
    ours, theirs = modelled.history.frame, real.history.frame
    made = synth.build_history(start="2021-05-01", end="2021-06-15")  # the paper's seed and field of 300 MW_th
    columns = ["CSP1", "ED_industry", "ED_service", "ED_residential"]
    assert np.allclose(ours[columns].to_numpy(), made[columns].to_numpy(), atol=1e-5)  # 6 digits in the file
    assert not np.allclose(theirs["ED_industry"], ours["ED_industry"])  # the real ones differ: a flat load
    assert {"CSP1_fc", "ED_industry_fc"} <= set(theirs.columns)
    assert not {"CSP1_fc", "ED_industry_fc", "ED_service_fc", "ED_residential_fc"} & set(ours.columns)
    kept = [c for c in theirs.columns if c in ours.columns and c not in columns]
    assert {"price_da", "WF1", "WF1_fc", "PV1", "PV1_fc", "price_sr_up", "price_sr_dn", "TD_industry"} <= set(kept)
    assert np.array_equal(ours[kept].to_numpy(), theirs[kept].to_numpy())
    origins = modelled.provenance_map
    assert all(origins[c].origin == "modelled" for c in columns) and origins["WF1"].origin == "real-derived"
    assert modelled.csp[0].solar_field.forecast_series is None and modelled.ed[0].forecast_series is None
    assert modelled.uncertainty.band_method("CSP1", "csp") == modelled.uncertainty.band_method(
        "ED_industry", "ed") == "climatology"
    assert real.uncertainty.band_method("CSP1", "csp") == "forecast"
    assert "clear-sky index" not in modelled.description and "system load" not in modelled.description
    for name, value in (("sky", "cloudy"), ("demands", "Modelled")):
        with pytest.raises(RvppError, match=f"--{name} '{value}' must be real .* or modelled"):
            BuildOptions(**{name: value})


def test_command_line_builds_the_modelled_sky(tmp_path, capsys):
    source = write_table(tmp_path / "series.csv")
    code = main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "case"), "--sky", "modelled"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "CSP1: modelled" in printed.out and "CSP1_fc" not in printed.out
    assert main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "other"), "--sky",
                 "cloudy"]) == 1
    assert "error: --sky: invalid choice: 'cloudy'" in capsys.readouterr().err
    assert not (tmp_path / "other").exists()


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


# ----------------------------------------------------------------------------- thermal demands from a weather file

LEVEL = 1.05 * 700 / 24  # both thermal demands of the paper case: q_min 700 MWh_th, median-day mean 30.625 MW_th
COLD_DAY = dt.date(2021, 5, 20)


def write_weather(path: Path, forecast: bool = True, drop_days: tuple[dt.date, ...] = (), warm: bool = False,
                  blank_forecast: str | None = None, cold_day: bool = True) -> Path:
    """Local naive times (Europe/Madrid), 2021-05-01 to 2021-06-14: 5.5 °C from 00:00 to 05:59, 18 °C the
    rest of the day, and -14.5 °C all day on 2021-05-20 (``cold_day``); the forecast 1 °C warmer.
    ``warm``: 20 °C always."""
    local = pd.date_range("2021-05-01", "2021-06-15", freq="h", inclusive="left")
    temperature = np.where(local.hour < 6, 5.5, 18.0)
    if cold_day:
        temperature[local.date == COLD_DAY] = -14.5
    if warm:
        temperature[:] = 20.0
    keep = ~np.isin(local.date, drop_days)
    table = pd.DataFrame({"Fecha": [f"{t:%Y-%m-%d %H:%M}" for t in local], "TMed": temperature})
    if forecast:
        table["TPrev"] = temperature + 1.0
        if blank_forecast:
            table.loc[table["Fecha"].str.startswith(blank_forecast), "TPrev"] = np.nan
    table[keep].to_csv(path, index=False)
    return path


WEATHER_COLUMNS = ("time=Fecha", "temperature=TMed", "forecast=TPrev")


def weather_options(path: Path, **more) -> BuildOptions:
    return BuildOptions(weather=path, weather_columns=WEATHER_COLUMNS, weather_timezone=TZ, **more)


def at(day: str, hour: int) -> pd.Timestamp:
    return pd.Timestamp(f"{day} {hour:02d}:00", tz=TZ).tz_convert("UTC")


def test_thermal_demands_follow_the_heating_degree_hours_mapped_by_hand(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv")
    build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather, errors_scale=2.0))
    case = load_case(tmp_path / "case")
    history = case.history.frame
    # Heating degree-hours below 15.5 °C: 10 K in the six cold hours of a normal day, 30 K all day on the cold
    # day, 0 otherwise. Their mean over the 44·6 + 24 = 288 hours that need heat is 3,360 / 288 = 35/3 K.
    # Signal S = 0.5 + 0.5·HDH/(35/3): 13/14 in a cold hour, 1/2 in a warm one, 25/14 on the cold day.
    # The median day is a normal one: S̃ = (6·13/14 + 18·1/2)/24 = 17/28, so S/S̃ is 26/17, 14/17 and 50/17.
    # Swings of ±level·(S/S̃ − 1) would reach 30.625·50/17 = 90 MW_th on the cold day, above 0.9·h_max, so the
    # spread narrows until the cold day sits on the ceiling: spread = (0.9·h_max − level)/(50/17 − 1).
    # (Narrowed, the demand no longer depends on HDH̄ or the base share: the test below pins those.)
    for unit, h_max in (("TD_industry", 80.0), ("TD_residential", 70.0)):
        ceiling = 0.9 * h_max  # 72 and 63 MW_th
        spread = (ceiling - LEVEL) / (33 / 17)  # 21.3144 and 16.6780 MW_th
        series = history[unit]
        assert series[at("2021-05-20", 12)] == pytest.approx(ceiling, rel=1e-5)
        assert series[at("2021-05-11", 3)] == pytest.approx(LEVEL + spread * 9 / 17, rel=1e-5)
        assert series[at("2021-05-11", 15)] == pytest.approx(LEVEL - spread * 3 / 17, rel=1e-5)
        # The forecast, 1 °C warmer: 9 K in a cold hour, S = 0.5 + 0.5·9·3/35 = 31/35, on the actual's map,
        # its error doubled (K = 2).
        guess = LEVEL + spread * ((31 / 35) / (17 / 28) - 1)
        actual = LEVEL + spread * 9 / 17
        assert history[unit + "_fc"][at("2021-05-11", 3)] == pytest.approx(actual - 2 * (actual - guess), rel=1e-5)
        assert history[unit + "_fc"][at("2021-05-11", 15)] == pytest.approx(series[at("2021-05-11", 15)], rel=1e-5)
    assert history["TD_industry"][at("2021-05-11", 15)] == pytest.approx(26.8636, abs=1e-4)
    assert history["TD_residential"][at("2021-05-11", 15)] == pytest.approx(27.6818, abs=1e-4)
    # A median (normal) day holds the median-day energy 1.05·q_min whatever the narrowing.
    day = history.loc[at("2021-05-11", 0):at("2021-05-11", 23), "TD_residential"]
    assert day.sum() == pytest.approx(1.05 * 700, rel=1e-5)


def test_without_narrowing_the_demand_is_its_level_times_the_signal_over_its_median_day(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv", cold_day=False)
    build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather))
    history = load_case(tmp_path / "case").history.frame
    # Every day alike: 10 K in six hours, so HDH̄ = 10 K (the mean over the hours that need heat, not over
    # all hours, which is 2.5 K). S = 0.5 + 0.5·HDH/10: 1 in a cold hour, 1/2 in a warm one; S̃ = 15/24 = 5/8.
    # The swings level·(S/S̃ − 1) stay in [1.2·h_min, 0.9·h_max], so the demand is level·S/S̃.
    for unit in ("TD_industry", "TD_residential"):
        assert history[unit][at("2021-05-11", 3)] == pytest.approx(LEVEL * 8 / 5, rel=1e-5)  # 49.0 MW_th
        assert history[unit][at("2021-05-11", 15)] == pytest.approx(LEVEL * 4 / 5, rel=1e-5)  # 24.5 MW_th
        # The forecast, 1 °C warmer: S = 0.5 + 0.5·9/10 = 0.95 in a cold hour.
        assert history[unit + "_fc"][at("2021-05-11", 3)] == pytest.approx(LEVEL * 0.95 * 8 / 5, rel=1e-5)
    assert history["TD_industry"][at("2021-06-01", 0)] == pytest.approx(49.0, rel=1e-5)


def test_the_base_temperature_and_share_are_the_users(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv")
    build_case([source], tmp_path / "case", template=PAPER,
               options=weather_options(weather, heating_base_c=20.0, heat_base_share=0.8))
    history = load_case(tmp_path / "case").history.frame
    # Below 20 °C: 14.5 K in a cold hour, 2 K in a warm one, 34.5 K on the cold day; every hour needs heat.
    # Mean over all 1,080 hours: (44·(6·14.5 + 18·2) + 24·34.5)/1080 = 6240/1080 = 52/9 K.
    # S = 0.8 + 0.2·HDH·9/52; a normal day's mean: 0.8 + 0.2·(123/24)·9/52.
    mean = 52 / 9
    typical = 0.8 + 0.2 * (123 / 24) / mean
    cold = (0.8 + 0.2 * 34.5 / mean) / typical
    night = (0.8 + 0.2 * 14.5 / mean) / typical
    spread = min(LEVEL, (0.9 * 70 - LEVEL) / (cold - 1))
    assert history["TD_residential"][at("2021-05-11", 3)] == pytest.approx(LEVEL + spread * (night - 1), rel=1e-5)
    with pytest.raises(RvppError, match=r"--heat-base-share 0 must be > 0 and <= 1"):
        BuildOptions(heat_base_share=0.0)
    with pytest.raises(RvppError, match=r"--heating-base 99 °C must lie in -90 to 60 °C"):
        BuildOptions(heating_base_c=99.0)


def test_provenance_says_real_derived_or_modelled_per_thermal_series(tmp_path):
    source = write_table(tmp_path / "series.csv")
    with_forecast = write_weather(tmp_path / "weather.csv")
    build_case([source], tmp_path / "both", template=PAPER, options=weather_options(with_forecast))
    origins = load_case(tmp_path / "both").provenance_map
    for unit in ("TD_industry", "TD_residential"):
        assert origins[unit].origin == origins[unit + "_fc"].origin == "real-derived"
        assert "weather.csv" in origins[unit].source and "sha256" in origins[unit].source
        assert "heating degree-hours max(0, 15.5 °C − temperature)" in origins[unit].note
        assert "temperature_forecast on the same map" in origins[unit + "_fc"].note
    assert origins["ED_industry"].origin == "modelled"  # no system load in the table
    actual_only = write_weather(tmp_path / "actual.csv", forecast=False)
    build_case([source], tmp_path / "actual", template=PAPER,
               options=BuildOptions(weather=actual_only, weather_columns=WEATHER_COLUMNS[:2], weather_timezone=TZ))
    case = load_case(tmp_path / "actual")
    origins = case.provenance_map
    assert origins["TD_industry"].origin == "real-derived" and origins["TD_industry_fc"].origin == "modelled"
    assert "from the actual temperature; the weather file gives no forecast of it" in origins["TD_industry_fc"].note
    assert case.td[0].forecast_series == "TD_industry_fc"
    assert case.uncertainty.band_method("TD_industry", "td") == "forecast"
    error = case.history.frame["TD_industry_fc"] / case.history.frame["TD_industry"] - 1.0
    assert 0.02 < error.std() < 0.08  # the stated 5 % modelled error
    build_case([source], tmp_path / "none", template=PAPER)
    origins = load_case(tmp_path / "none").provenance_map
    assert origins["TD_industry"].origin == origins["TD_industry_fc"].origin == "modelled"


def test_the_weather_must_cover_the_period_and_the_missing_days_are_named(tmp_path):
    source = write_table(tmp_path / "series.csv")
    short = write_weather(tmp_path / "weather.csv", drop_days=(dt.date(2021, 5, 2), dt.date(2021, 5, 3),
                                                                dt.date(2021, 5, 4), dt.date(2021, 5, 7)))
    with pytest.raises(DataImportError, match=r"weather.csv: the weather does not cover the case's period 2021-05-01 "
                                              r"to 2021-06-14: no temperature in 96 hour\(s\) of 4 day\(s\): "
                                              r"2021-05-02 to 2021-05-04, 2021-05-07"):
        build_case([source], tmp_path / "case", template=PAPER, options=weather_options(short))
    assert not (tmp_path / "case").exists()
    build_case([source], tmp_path / "case", template=PAPER,
               options=weather_options(short, start="2021-05-08"))
    assert load_case(tmp_path / "case").provenance_map["TD_industry"].origin == "real-derived"
    with pytest.raises(DataImportError, match=r"no temperature in 96 hour\(s\) of 4 day\(s\).*--fill-gaps "
                                              r"interpolates runs of at most 3 hours"):
        build_case([source], tmp_path / "filled", template=PAPER, options=weather_options(short, fill_gaps_h=3))


def test_short_weather_gaps_are_interpolated_only_on_request(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv")
    lines = weather.read_text().splitlines()
    lines = [line for line in lines if not line.startswith(("2021-05-15 10:00", "2021-05-15 11:00"))]
    weather.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataImportError, match=r"no temperature in 2 hour\(s\) of 1 day\(s\): 2021-05-15.*--fill-gaps"):
        build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather))
    built = build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather, fill_gaps_h=2))
    assert any(n.startswith("temperature: 2 hour(s) from 2021-05-15T08:00Z") for n in built.notes)
    assert "interpolated" in built.case.provenance_map["TD_industry"].note
    assert built.case.history.frame["TD_industry"][at("2021-05-15", 10)] == pytest.approx(
        built.case.history.frame["TD_industry"][at("2021-05-15", 9)], rel=1e-5)  # 18 °C either side


def test_a_forecast_with_gaps_leaves_the_forecast_modelled_and_says_so(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv", blank_forecast="2021-05-15 10:00")
    built = build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather))
    assert any(n.startswith("thermal demand forecasts stay modelled: the weather's temperature_forecast has no "
                            "value on 1 day(s) of the case (2021-05-15)") for n in built.notes)
    origins = built.case.provenance_map
    assert origins["TD_industry"].origin == "real-derived" and origins["TD_industry_fc"].origin == "modelled"


def test_a_period_without_heating_gives_flat_demands_at_their_median_day_level(tmp_path):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv", warm=True)
    built = build_case([source], tmp_path / "case", template=PAPER, options=weather_options(weather))
    history = built.case.history.frame
    assert np.allclose(history["TD_industry"], LEVEL) and np.allclose(history["TD_residential"], LEVEL)
    assert built.case.provenance_map["TD_industry_fc"].origin == "modelled"
    assert any('td "TD_industry": no hour of the period is below 15.5 °C' in n for n in built.notes)


def test_command_line_builds_thermal_demands_from_a_weather_file(tmp_path, capsys):
    source = write_table(tmp_path / "series.csv")
    weather = write_weather(tmp_path / "weather.csv")
    code = main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "case"), "--weather",
                 str(weather), "--weather-columns", *WEATHER_COLUMNS, "--weather-timezone", TZ,
                 "--heating-base", "15.5", "--heat-base-share", "0.5"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "TD_industry: real-derived" in printed.out and "TD_residential_fc: real-derived" in printed.out
    assert "  Weather table (time, air temperature): weather.csv" in printed.out  # its report: span, gaps...
    assert '  series temperature [°C]: air temperature, column "TMed"' in printed.out
    code = main(["data", "build-case", "--from", str(source), "--out", str(tmp_path / "other"), "--weather",
                 str(weather), "--weather-columns", *WEATHER_COLUMNS])
    assert code == 1
    err = capsys.readouterr().err
    assert "has no UTC offset" in err and "--weather-timezone" in err and "Traceback" not in err


REAL_WEATHER_DAYS = ("2018-01-01", "2018-02-14")


def spain_slice(tmp_path: Path) -> Path:
    """The Spanish dataset's rows of January and February 2018 (a copy in tmp_path, never committed)."""
    raw = pd.read_csv(REAL[0], dtype=str)
    stamps = pd.to_datetime(raw["time"], utc=True)
    keep = (stamps >= pd.Timestamp("2017-12-31 23:00", tz="UTC")) & (stamps < pd.Timestamp("2018-03-01", tz="UTC"))
    path = tmp_path / "energy_dataset.csv"
    raw[keep.to_numpy()].to_csv(path, index=False)
    return path


@pytest.mark.slow
@pytest.mark.skipif(not REAL[0].is_file(), reason="real Spanish data not present")
def test_real_spanish_slice_with_and_without_a_weather_file(tmp_path):
    source = spain_slice(tmp_path)
    span = {"start": REAL_WEATHER_DAYS[0], "end": REAL_WEATHER_DAYS[1]}
    without = build_case([source], tmp_path / "modelled", template=PAPER, options=BuildOptions(**span))
    origins = without.case.provenance_map
    assert origins["TD_industry"].origin == origins["TD_industry_fc"].origin == "modelled"
    assert origins["ED_industry"].origin == "real-derived"  # the dataset gives the system load
    # A winter day: 7 + 5·cos(2π(h − 15)/24) °C, 12 °C at 15:00 local and 2 °C at 03:00; the forecast 0.5 °C
    # colder. Hand-written: there is no temperature in the shared data.
    local = pd.date_range("2018-01-01", "2018-02-15", freq="h", inclusive="left", tz=TZ)
    temperature = 7.0 + 5.0 * np.cos(2 * np.pi * (np.asarray(local.hour) - 15) / 24.0)
    weather = tmp_path / "weather.csv"
    pd.DataFrame({"time": [t.isoformat() for t in local], "temperature": temperature,
                  "temperature_forecast": temperature - 0.5}).to_csv(weather, index=False)
    built = build_case([source], tmp_path / "weather", template=PAPER, options=BuildOptions(weather=weather, **span))
    case = load_case(tmp_path / "weather")
    origins = case.provenance_map
    assert origins["TD_industry"].origin == origins["TD_industry_fc"].origin == "real-derived"
    assert origins["ED_industry"].origin == "real-derived" and origins["price_da"].origin == "real"
    assert origins["WF1"].origin == "real-derived"
    history = case.history.frame
    # Colder at night than in the afternoon: more heat at 05:00 than at 15:00 on every day.
    night = history.loc[history.index.tz_convert(TZ).hour == 5, "TD_residential"].to_numpy()
    afternoon = history.loc[history.index.tz_convert(TZ).hour == 15, "TD_residential"].to_numpy()
    assert (night > afternoon).all()
    # The forecast is colder, so it expects more heat in every hour that needs heat.
    assert (history["TD_residential_fc"] >= history["TD_residential"] - 1e-6).all()
    assert history["TD_residential"].between(1.2 * 5, 0.9 * 70).all()
    daily = history["TD_residential"].groupby(history.index.tz_convert(TZ).date).sum()
    assert float(np.median(daily)) == pytest.approx(1.05 * 700, rel=1e-4)
    assert built.case.delivery_date == dt.date(2018, 2, 14)
    result = solve(with_options(case, date="2018-02-10"))
    assert result.status == "optimal"
    assert audit_result(result) == []
