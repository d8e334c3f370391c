"""Forecast-error bands (rvpp.uncertainty.forecast, MODEL_SPEC §6) and the case fields that select them.

Expected quantiles are worked out by hand with numpy's linear rule: for n sorted values the
q-quantile lies at position q·(n - 1).
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pytest

from rvpp.data.case import parse_case
from rvpp.data.history import History
from rvpp.data.periods import delivery_periods
from rvpp.errors import CaseError
from rvpp.uncertainty.problem import prepare
from rvpp.uncertainty.forecast import BandSpec, forecast_and_errors, forecast_error_bands, level_quantiles
from rvpp.uncertainty.quality import score
from tests.factories import SPAIN, demand, wind

TZ = "Europe/Madrid"
DAY = dt.date(2025, 3, 18)


def history(columns: dict, start: str = "2025-03-01", days: int = 20) -> History:
    """Hourly history; each column is a function of (local day index from ``start``, local hour)."""
    first = pd.Timestamp(start, tz=TZ)
    last = (pd.Timestamp(start) + pd.Timedelta(days=days)).tz_localize(TZ)
    utc = pd.date_range(first.tz_convert("UTC"), last.tz_convert("UTC"), freq="1h", inclusive="left")
    local = utc.tz_convert(TZ)
    index = np.asarray((local.normalize().tz_localize(None) - pd.Timestamp(start)).days)
    hour = np.asarray(local.hour)
    return History(pd.DataFrame({"timestamp": utc, **{n: f(index, hour).astype(float) for n, f in columns.items()}}))


def day_index(day: dt.date, start: str = "2025-03-01") -> int:
    return (day - dt.date.fromisoformat(start)).days


def bands_for(hist: History, spec: BandSpec, day=DAY, n_days=5, dt_h=1.0):
    periods = delivery_periods(day, TZ, dt_h)
    return forecast_error_bands(hist, day, periods, {"s": spec}, n_days=n_days, q_lo=0.2, q_hi=0.8, timezone=TZ)


def test_constant_forecast_takes_every_window_error():
    # Window D-5..D-1 (day indices 12..16): errors -2, -1, 0, 1, 2 in every hour; forecast 10.
    d = day_index(DAY)
    hist = history({"x": lambda i, h: 10.0 + np.clip(i - d + 3, -2, 2), "x_fc": lambda i, h: 10.0 + 0 * i})
    bands = bands_for(hist, BandSpec("x", forecast_column="x_fc", method="forecast"))
    # 120 errors, 24 of each value: Q20 at position 23.8 -> -2 + 0.8 = -1.2; median 0; Q80 at 95.2 -> 1.2.
    assert np.allclose(bands[("s", "lo")], 8.8)
    assert np.allclose(bands[("s", "mid")], 10.0)
    assert np.allclose(bands[("s", "hi")], 11.2)


def test_quantiles_follow_the_forecast_level():
    # Night hours (0-5) are forecast 0 and err by 0 or +1; day hours are forecast 40 and err by -6 or +6.
    forecast = lambda i, h: np.where(h < 6, 0.0, 40.0)  # noqa: E731
    error = lambda i, h: np.where(h < 6, (i % 2).astype(float), np.where(i % 2 == 0, -6.0, 6.0))  # noqa: E731
    hist = history({"x": lambda i, h: forecast(i, h) + error(i, h), "x_fc": forecast})
    bands = bands_for(hist, BandSpec("x", forecast_column="x_fc", method="forecast", low=0.0, high=50.0))
    d = day_index(DAY)
    window = np.arange(d - 5, d)
    night = np.sort(np.repeat(window % 2, 6).astype(float))  # 30 errors at level 0 (all nearest: distance 0)
    day = np.sort(np.repeat(np.where(window % 2 == 0, -6.0, 6.0), 18))
    lo_n, mid_n, hi_n = np.quantile(night, [0.2, 0.5, 0.8])
    lo_d, mid_d, hi_d = np.quantile(day, [0.2, 0.5, 0.8])
    assert np.allclose(bands[("s", "lo")][:6], lo_n) and np.allclose(bands[("s", "hi")][:6], hi_n)
    assert np.allclose(bands[("s", "lo")][6:], 40 + lo_d) and np.allclose(bands[("s", "hi")][6:], 40 + hi_d)
    # By hand: window days 12..16 -> parities 0,1,0,1,0: 18 zeros and 12 ones at night.
    assert (lo_n, hi_n) == (0.0, 1.0) and (lo_d, hi_d) == (-6.0, 6.0)


def test_output_bands_are_clipped_to_zero_and_the_nameplate():
    hist = history({"x": lambda i, h: 52.0 + 0 * i, "x_fc": lambda i, h: np.where(h < 12, 49.0, 1.0)})
    bands = bands_for(hist, BandSpec("x", forecast_column="x_fc", method="forecast", low=0.0, high=50.0))
    assert np.allclose(bands[("s", "hi")], 50.0)  # 49 + 3 and 1 + 51 both above the nameplate
    hist = history({"x": lambda i, h: 0.0 * i, "x_fc": lambda i, h: 10.0 + 0 * i})
    bands = bands_for(hist, BandSpec("x", forecast_column="x_fc", method="forecast", low=0.0, high=50.0))
    assert np.allclose(bands[("s", "lo")], 0.0) and np.allclose(bands[("s", "hi")], 0.0)  # 10 - 10


def test_prices_are_not_clipped_and_keep_their_sign():
    hist = history({"p": lambda i, h: -5.0 - i + 0 * h})  # falls by 1 EUR/MWh a day, below zero
    bands = bands_for(hist, BandSpec("p", method="forecast", price_model="same_hour_yesterday"))
    # Forecast: yesterday's price; every error is -1, so the band is the actual price of the day.
    expected = -5.0 - day_index(DAY)
    for stat in ("lo", "mid", "hi"):
        assert np.allclose(bands[("s", stat)], expected)


def test_bands_use_only_days_before_the_delivery_day_and_its_own_forecast():
    d = day_index(DAY)
    base = {"x": lambda i, h: 20.0 + 3.0 * np.sin(i + h), "x_fc": lambda i, h: 20.0 + 0.5 * h + 0 * i}
    spec = BandSpec("x", forecast_column="x_fc", method="forecast")
    reference = bands_for(history(base), spec)
    # Changing what happens on the delivery day and after, or before the window, changes nothing.
    changed = dict(base, x=lambda i, h: np.where((i >= d) | (i < d - 5), 1e3, 20.0 + 3.0 * np.sin(i + h)))
    pd.testing.assert_frame_equal(bands_for(history(changed), spec), reference)
    # The forecast issued for the day moves the band with it (a constant window forecast makes every
    # window hour equally near, so the error quantiles stay the same).
    flat = dict(base, x_fc=lambda i, h: 20.0 + 0 * i)
    moved = dict(base, x_fc=lambda i, h: 20.0 + np.where(i == d, 4.0, 0.0))
    before, after = bands_for(history(flat), spec), bands_for(history(moved), spec)
    assert np.allclose(after[("s", "mid")], before[("s", "mid")] + 4.0)


def test_naive_price_models_and_the_day_after_clocks_go_forward():
    # Price = 100 * day index + clock hour; 2025-03-30 has no 02:00.
    hist = history({"p": lambda i, h: 100.0 * i + h}, days=31)  # up to 2025-03-31, the delivery day
    day = dt.date(2025, 4, 1)
    i = day_index(day)
    point, _ = forecast_and_errors(hist, day, BandSpec("p", method="forecast", price_model="same_hour_yesterday"),
                                   n_days=5, timezone=TZ)
    clock = point.index.tz_convert(TZ).hour
    # The history ends the day before: a naive price forecast needs nothing of the delivery day.
    assert len(point) == 24
    assert (point.to_numpy() == 100.0 * (i - 1) + clock).all()
    day = dt.date(2025, 3, 31)
    i = day_index(day)
    point, _ = forecast_and_errors(hist, day, BandSpec("p", method="forecast", price_model="same_hour_yesterday"),
                                   n_days=5, timezone=TZ)
    clock = point.index.tz_convert(TZ).hour
    # 02:00 of the 31st takes 01:00 of the 30th (the hour before the skipped one); others their own hour.
    assert point[clock == 2].iloc[0] == 100.0 * (i - 1) + 1
    assert point[clock == 5].iloc[0] == 100.0 * (i - 1) + 5
    week, _ = forecast_and_errors(hist, day, BandSpec("p", method="forecast", price_model="same_hour_last_week"),
                                  n_days=5, timezone=TZ)
    blend, _ = forecast_and_errors(hist, day, BandSpec("p", method="forecast", price_model="blend"),
                                   n_days=5, timezone=TZ)
    assert week[clock == 5].iloc[0] == 100.0 * (i - 7) + 5
    assert blend[clock == 5].iloc[0] == pytest.approx(100.0 * (i - 4) + 5)


def test_quarter_hours_keep_the_band_of_their_hour_on_average_and_windows_must_be_covered():
    hist = history({"x": lambda i, h: 10.0 + h + 0 * i, "x_fc": lambda i, h: 10.0 + h + 0 * i})
    spec = BandSpec("x", forecast_column="x_fc", method="forecast")
    hourly, quarter = bands_for(hist, spec), bands_for(hist, spec, dt_h=0.25)
    for stat in ("lo", "mid", "hi"):
        by_hour = quarter[("s", stat)].to_numpy().reshape(24, 4).mean(axis=1)
        assert np.max(np.abs(by_hour - hourly[("s", stat)].to_numpy())) < 1e-9
    mid = quarter[("s", "mid")].to_numpy().reshape(24, 4)
    assert (np.diff(mid[1:-1], axis=1) > 0).all()  # the forecast rises through each hour, no step
    with pytest.raises(CaseError, match="need the days"):
        bands_for(hist, spec, day=dt.date(2025, 3, 3))


def test_level_quantiles_take_the_nearest_fifth():
    forecasts = np.arange(100.0)
    errors = np.arange(100.0)
    # Level 50: the 24 hours nearest (|f - 50| <= 12 reaches 25 values, ties kept: 38..62).
    out = level_quantiles(forecasts, errors, np.array([50.0]), (0.0, 0.5, 1.0))
    assert out.tolist() == [[38.0, 50.0, 62.0]]


# ----------------------------------------------------------------------------- the case fields


def _case(bands=None, forecast_series=None, extra_columns=(), days=20, **uncertainty):
    units = {"wind": [wind("W", p_max=50.0, **({"forecast_series": forecast_series} if forecast_series else {}))],
             "ed": [demand("D", p_max=100.0)]}
    data = {"name": "fc", "delivery_date": DAY.isoformat(),
            "markets": {"srm": False, "hpa": False, "hpa_tariff_eur_per_mwh": [50.0] * 24},
            "uncertainty": {"window_days": 5, **({"bands": bands} if bands is not None else {}), **uncertainty},
            "budgets": {"strategy": "deterministic"}, "units": units}
    columns = {"price_da": lambda i, h: 40.0 + 10.0 * (i % 3) + h, "price_sr_up": lambda i, h: 5.0 + 0 * i,
               "price_sr_dn": lambda i, h: 3.0 + 0 * i, "W": lambda i, h: 30.0 + 5.0 * np.cos(i) + 0 * h,
               "W_fc": lambda i, h: 30.0 + 0 * i, "D": lambda i, h: 20.0 + 0 * i}
    columns.update({c: (lambda i, h: 0 * i) for c in extra_columns})
    return parse_case(data, history(columns, days=days))


def test_case_selects_forecast_bands_per_source_and_prepare_uses_them():
    case = _case(bands={"default": "climatology", "wind": "forecast", "price_da": "forecast"}, forecast_series="W_fc")
    assert case.uncertainty.band_method("W", "wind") == "forecast"
    assert case.uncertainty.band_method("D", "ed") == "climatology"
    problem = prepare(case)
    d = day_index(DAY)
    errors = np.repeat(5.0 * np.cos(np.arange(d - 5, d)), 24)
    lo, hi = np.quantile(errors, [0.2, 0.8])
    wind_source = problem.sources["W"]
    assert np.allclose(wind_source.nominal, min(50.0, 30.0 + hi))  # production planned on the upper bound
    assert np.allclose(wind_source.deviation, (30.0 + hi) - (30.0 + lo))
    # The demand keeps its climatology: a constant 20 MW history gives a zero-width band.
    assert np.allclose(problem.sources["D"].nominal, 20.0) and np.allclose(problem.sources["D"].deviation, 0.0)
    # DAM price by same_hour_yesterday: the price 40 + 10·(i mod 3) + h against the day before's.
    price = problem.sources["price_da"]
    window = np.repeat(np.arange(d - 5, d), 24)
    hours = np.tile(np.arange(24), 5)
    past = 40.0 + 10.0 * ((window - 1) % 3) + hours
    errors = 40.0 + 10.0 * (window % 3) + hours - past
    yesterday = 40.0 + 10.0 * ((d - 1) % 3) + np.arange(24)
    for t, level in enumerate(yesterday):
        # The nearest fifth of the 120 window hours by forecast level (24, ties at the edge kept).
        distance = np.abs(past - level)
        q = np.quantile(errors[distance <= np.sort(distance)[23]], [0.2, 0.5, 0.8])
        assert price.nominal[t] == pytest.approx(level + q[1])
        assert price.deviation[t] == pytest.approx(q[1] - q[0])
        assert price.deviation_up[t] == pytest.approx(q[2] - q[1])


def test_bands_of_a_day_drawn_again_are_fresh_copies_and_follow_every_input():
    # Climatology of W = 30 + 5·cos(i) over the window D-5..D-1, the same in every hour.
    case = _case()
    d = day_index(DAY)
    window = 30.0 + 5.0 * np.cos(np.arange(d - 5, d))
    first = prepare(case).bands
    first[("W", "mid")] = -1.0  # a caller's change never reaches the next caller
    again = prepare(case.replace(budgets={"strategy": "pessimistic"})).bands
    for stat, q in (("lo", 0.2), ("mid", 0.5), ("hi", 0.8)):
        assert np.allclose(again[("W", stat)], np.quantile(window, q))
    # Another quantile, window length or history content gives other bands.
    assert np.allclose(prepare(case.replace(uncertainty={"q_lo": 0.1})).bands[("W", "lo")],
                       np.quantile(window, 0.1))
    longer = np.quantile(30.0 + 5.0 * np.cos(np.arange(d - 7, d)), 0.5)
    assert np.allclose(prepare(case.replace(uncertainty={"window_days": 7})).bands[("W", "mid")], longer)
    doubled = case.history.with_columns({"W": 2.0 * case.history.frame["W"].to_numpy()})
    assert np.allclose(prepare(case.replace(history=doubled)).bands[("W", "mid")], 2.0 * np.quantile(window, 0.5))


def test_case_refuses_forecast_bands_it_cannot_draw():
    with pytest.raises(CaseError, match='wind "W": uncertainty.bands asks for forecast bands but the unit has no '
                                        "forecast_series"):
        _case(bands={"W": "forecast"})
    with pytest.raises(CaseError, match="forecast history column 'W_dayahead' is missing"):
        _case(forecast_series="W_dayahead")
    with pytest.raises(CaseError, match="uncertainty.bands: unknown key 'WX'"):
        _case(bands={"WX": "forecast"})
    with pytest.raises(CaseError, match="uncertainty: bands: W='persistence' must be one of climatology, forecast"):
        _case(bands={"W": "persistence"}, forecast_series="W_fc")
    with pytest.raises(CaseError, match="price_forecast"):
        _case(price_forecast="tomorrow")


def test_case_round_trips_its_new_fields(tmp_path):
    from rvpp.data.case_yaml import load_case, save_case

    case = _case(bands={"wind": "forecast"}, forecast_series="W_fc", price_forecast="blend")
    case = case.replace(provenance={"W": {"origin": "real", "source": "a file, sha256 0123"}})
    again = load_case(save_case(case, tmp_path / "c"))
    assert again.uncertainty == case.uncertainty and again.provenance_map == case.provenance_map
    assert again.wind[0].forecast_series == "W_fc"
    with pytest.raises(CaseError, match="provenance: 'nothing' is not a column"):
        case.replace(provenance={"nothing": {"origin": "real", "source": "x"}})


def test_unit_tables_and_the_workbook_keep_forecast_columns_bands_and_provenance():
    from rvpp.outputs import workbook

    case = _case(bands={"wind": "forecast"}, forecast_series="W_fc", price_forecast="blend")
    case = case.replace(provenance={"W": {"origin": "real", "source": "a file, sha256 0123", "note": "scaled"}})
    table = workbook.unit_table(case, "wind")
    assert table.at[0, "forecast_series"] == "W_fc"
    edited = workbook.with_unit_table(case, "wind", table.assign(p_max_mw=60.0))
    assert edited.wind[0].forecast_series == "W_fc" and edited.wind[0].p_max_mw == 60.0
    again = workbook.read_case_workbook(workbook.case_workbook_bytes(case))
    assert again.uncertainty == case.uncertainty and again.provenance_map == case.provenance_map
    assert again.wind[0].forecast_series == "W_fc"


def test_band_figure_draws_the_model_band_the_other_method_and_the_realized_day():
    from rvpp.outputs.plots import band_overlays, bands_figure

    case = _case(bands={"wind": "forecast"}, forecast_series="W_fc")
    problem = prepare(case)
    overlays = band_overlays(problem, "W")
    label, lo, hi = overlays["compare"]
    # Climatology of W = 30 + 5·cos(i) over the window D-5..D-1, the same in every hour.
    d = day_index(DAY)
    window = 30.0 + 5.0 * np.cos(np.arange(d - 5, d))
    assert label == "Climatology"
    assert np.allclose(lo, np.quantile(window, 0.2)) and np.allclose(hi, np.quantile(window, 0.8))
    assert np.allclose(overlays["realized"], 30.0 + 5.0 * np.cos(day_index(DAY)))
    figure = bands_figure(problem, "W", **overlays)
    names = [trace.name for trace in figure.data]
    assert "Upper bound: forecast + error (80th)" in names and "Realized" in names
    assert "Climatology: upper" in names and "forecast-error band" in figure.layout.title.text
    # Tomorrow: a history that ends the day before the delivery day still gives both price bands.
    tomorrow = prepare(_case(bands={"price_da": "forecast"}, days=17))
    overlays = band_overlays(tomorrow, "price_da")
    assert "realized" not in overlays and overlays["compare"][0] == "Climatology"


def test_score_counts_misses_and_shortfall_by_hand():
    lo, hi = np.array([0.0, 0.0, 10.0, 10.0]), np.array([10.0, 10.0, 20.0, 20.0])
    actual = np.array([5.0, 12.0, 4.0, 15.0])
    result = score(lo, hi, actual)
    assert result == {"width": 10.0, "miss_rate": 0.5, "below_rate": 0.25, "above_rate": 0.25, "shortfall": 1.5}


def test_band_quality_of_a_perfect_forecast_is_a_zero_width_band_that_never_misses():
    from rvpp.uncertainty.quality import band_quality

    hist = history({"x": lambda i, h: 10.0 + 5.0 * np.sin(i + h), "x_fc": lambda i, h: 10.0 + 5.0 * np.sin(i + h)})
    days = [DAY, DAY + dt.timedelta(days=1)]
    result = band_quality(hist, days, BandSpec("x", forecast_column="x_fc", method="forecast"), window_days=5,
                          q_lo=0.2, q_hi=0.8, timezone=TZ)
    assert result["hours"] == 48
    assert result["methods"]["forecast"] == {"width": 0.0, "miss_rate": 0.0, "below_rate": 0.0, "above_rate": 0.0,
                                             "shortfall": 0.0}
    climatology = result["methods"]["climatology"]
    assert climatology["width"] > 1.0 and climatology["miss_rate"] > 0.0


@pytest.mark.slow
@pytest.mark.skipif(not (SPAIN / "entsoe_spain_2015_2018.csv").is_file(), reason="real Spanish data not present")
def test_forecast_bands_beat_climatology_on_real_2018_wind(capsys):
    import json

    from rvpp.cli import main

    assert main(["data", "band-quality", str(SPAIN / "entsoe_spain_2015_2018.csv"), "--year", "2018", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    clim, fc = result["methods"]["climatology"], result["methods"]["forecast"]
    assert result["hours"] == 8760 and result["filled_hours"] == [
        "actual_wind_onshore: 1 hour(s) from 2018-11-07T08:00Z to 2018-11-07T08:00Z interpolated linearly"]
    assert fc["width"] < clim["width"] / 4 and fc["shortfall"] < clim["shortfall"] / 3
    assert 0.40 <= fc["miss_rate"] < clim["miss_rate"]


def test_uncertainty_page_switches_a_source_to_forecast_bands():
    from rvpp import prepare as library_prepare
    from tests.test_app import case_of, figures, open_app, values

    at = open_app("uncertainty")
    assert "Day-ahead price: forecast band" in figures(at)
    assert "Climatology: upper" not in [t["name"] for t in figures(at)["Day-ahead price: forecast band"]["data"]]
    at.multiselect(key="uncertainty_forecast_bands").set_value(["price_da"]).run()
    assert not at.exception, at.exception
    case = case_of(at)
    assert case.uncertainty.band_method("price_da") == "forecast"
    spec = figures(at)["Day-ahead price: forecast-error band"]
    names = [t["name"] for t in spec["data"]]
    assert "Climatology: upper" in names and "Realized" in names
    expected = library_prepare(case).sources["price_da"]
    mid = next(t for t in spec["data"] if t["name"] == "Forecast + median error")
    assert np.allclose(values(mid["y"]), expected.nominal)


def test_the_audit_derives_forecast_bands_on_its_own_and_agrees():
    from rvpp import solve
    from rvpp.settle.audit import audit_day, audit_result

    case = _case(bands={"wind": "forecast", "price_da": "forecast"}, forecast_series="W_fc", price_forecast="blend",
                 days=20)
    problem = prepare(case)
    day = audit_day(case)
    for name in ("W", "price_da", "D"):
        assert np.allclose(day.sources[name].nominal, problem.sources[name].nominal)
        assert np.allclose(day.sources[name].deviation, problem.sources[name].deviation)
    result = solve(case)
    assert result.status == "optimal" and audit_result(result) == []
    # Audited as if the case used climatology, the same plan breaks the band checks.
    flipped = audit_day(case.replace(uncertainty={"bands": {}}))
    assert not np.allclose(flipped.sources["price_da"].nominal, problem.sources["price_da"].nominal)
