"""Importers of downloaded files (rvpp.data.importers), on hand-written fixtures in tests/data.

Every expected instant below is worked out by hand from the published formats: OMIE numbers
periods from local midnight in Madrid, ENTSO-E writes local intervals day first, and on the
day clocks go back 02:00 local is first +02:00 (00:00 UTC), then +01:00 (01:00 UTC).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rvpp.cli import main
from rvpp.data.importers import detect, hourly_table, import_files, write_table
from rvpp.data.importers.report import hourly
from rvpp.errors import DataImportError

DATA = Path(__file__).resolve().parent / "data"
OMIE, ENTSOE, TABLES = DATA / "omie", DATA / "entsoe", DATA / "tables"


def utc(text: str) -> pd.Timestamp:
    return pd.Timestamp(text, tz="UTC")


def one(paths, zone=None):
    imports = import_files([Path(p) for p in paths], zone)
    assert len(imports) == 1
    return imports[0]


def price_at(item, stamp: str) -> float:
    return float(item.values.loc[utc(stamp), "price_da"])


# ----------------------------------------------------------------------------- OMIE


def test_omie_23_hour_day_skips_the_missing_local_hour():
    item = one([OMIE / "marginalpdbc_20180325.1"])
    assert len(item.values) == 23 and item.report.resolutions == ((60, 23),)
    # Period 1 starts at local midnight = 23:00 UTC the day before; period k is (k-1) h later.
    assert item.values.index[0] == utc("2018-03-24 23:00")
    assert price_at(item, "2018-03-24 23:00") == 41.0
    # Period 3 starts two elapsed hours after midnight: 01:00 UTC = 03:00 CEST (02:00 does not exist).
    assert price_at(item, "2018-03-25 01:00") == 43.0
    assert item.values.index[2].tz_convert("Europe/Madrid").strftime("%H:%M%z") == "03:00+0200"
    assert item.values.index[-1] == utc("2018-03-25 21:00")  # period 23 ends at local midnight
    assert item.report.gaps == () and item.report.duplicates == ()
    assert any("23-hour day" in line for line in item.report.dst)
    assert item.report.series[0].unit == "EUR/MWh" and item.report.zone.startswith("ES")


def test_omie_zone_option_reads_the_portuguese_column():
    spain, portugal = one([OMIE / "marginalpdbc_20180325.1"]), one([OMIE / "marginalpdbc_20180325.1"], "PT")
    # Period 5 (03:00 UTC) is the congested hour of the fixture: PT 35.50, ES 45.00.
    assert price_at(spain, "2018-03-25 03:00") == 45.0
    assert price_at(portugal, "2018-03-25 03:00") == 35.5
    assert portugal.report.zone.startswith("PT")
    with pytest.raises(DataImportError, match="ES or PT"):
        one([OMIE / "marginalpdbc_20180325.1"], "FR")


def test_omie_25_hour_day_places_the_repeated_hour_in_summer_then_winter_time():
    item = one([OMIE / "marginalpdbc_20181028.1"])  # CRLF line ends, price 10·k
    assert len(item.values) == 25
    assert price_at(item, "2018-10-28 00:00") == 30.0  # period 3: 02:00+02:00
    assert price_at(item, "2018-10-28 01:00") == 40.0  # period 4: 02:00+01:00
    local = item.values.index[2:4].tz_convert("Europe/Madrid")
    assert [t.strftime("%H:%M%z") for t in local] == ["02:00+0200", "02:00+0100"]
    assert item.values.index[-1] == utc("2018-10-28 22:00")


def test_omie_quarter_hours_from_october_2025_and_their_hourly_average():
    item = one([OMIE / "marginalpdbc_20251026.1"])  # 100 quarter-hours, price = period number, period 40 empty
    assert item.report.resolutions == ((15, 100),)
    assert item.values.index[0] == utc("2025-10-25 22:00")
    assert price_at(item, "2025-10-26 00:00") == 9.0  # period 9: 8 quarter-hours after midnight
    missing = item.report.series[0].missing
    assert len(missing) == 1 and missing[0].start == utc("2025-10-26 07:45") and missing[0].periods == 1
    table, notes = hourly(item)
    assert len(table) == 25
    assert table["price_da"].iloc[0] == pytest.approx((1 + 2 + 3 + 4) / 4)
    assert table["price_da"].iloc[24] == pytest.approx((97 + 98 + 99 + 100) / 4)
    # The hour holding the empty period 40 (periods 37-40, 07:00 UTC) is not averaged from three values.
    assert np.isnan(table.loc[utc("2025-10-26 07:00"), "price_da"])
    assert len(notes) == 1 and "2025-10-26T07:00Z" in notes[0]


def test_omie_files_of_several_days_make_one_series_with_its_gaps_listed():
    item = one(sorted(OMIE.glob("marginalpdbc_2018*")))
    assert len(item.values) == 23 + 24 + 25
    # 2018-03-26 to 2018-10-26 is not given: one gap, from local midnight to local midnight.
    gap = item.report.gaps[0]
    assert gap.start == utc("2018-03-25 22:00") and gap.end == utc("2018-10-26 22:00")
    assert price_at(item, "2018-10-26 22:00") == -1.5  # negative prices are read as they are


def test_omie_identical_duplicates_are_reported_and_conflicting_ones_refused(tmp_path):
    copy = tmp_path / "copy_marginalpdbc_20180325.1"
    copy.write_bytes((OMIE / "marginalpdbc_20180325.1").read_bytes())
    item = one([OMIE / "marginalpdbc_20180325.1", copy])
    assert len(item.values) == 23 and len(item.report.duplicates) == 23
    changed = tmp_path / "marginalpdbc_20180325.2"
    changed.write_text(copy.read_text().replace("2018;03;25;7;47.00;47.00;", "2018;03;25;7;47.00;48.00;"))
    with pytest.raises(DataImportError, match="marginalpdbc_20180325.2 line 8.*2018-03-25T05:00Z"):
        one([OMIE / "marginalpdbc_20180325.1", changed])


@pytest.mark.parametrize("text, message", [
    ("MARGINALPDBC;\n2018;03;25;24;1.00;1.00;\n*\n", "PERIOD=24 does not exist on 2018-03-25, which has 23 periods"),
    ("MARGINALPDBC;\n2018;03;25;1;1.00;1.00;\n", "closing line"),
    ("MARGINALPDBC;\n2018;02;30;1;1.00;1.00;\n*\n", "2018-02-30 is not a date"),
    ("MARGINALPDBC;\n2018;03;25;1;1.00;abc;\n*\n", "price 'abc' is not a number"),
    ("MARGINALPDBC;\n2018;03;25;1;1.00;1.00;\n*\n2018;03;25;2;1.00;1.00;\n", "after the closing"),
    ("MARGINALPDBC;\n2018;03;25;1;1.00\n*\n", "found 5 fields"),
])
def test_omie_refuses_what_it_cannot_place(tmp_path, text, message):
    path = tmp_path / "marginalpdbc_bad.1"
    path.write_text(text)
    with pytest.raises(DataImportError, match=message):
        one([path])


def test_omie_zip_archive_reads_like_its_daily_files(tmp_path):
    archive = tmp_path / "marginalpdbc_2018.zip"
    with zipfile.ZipFile(archive, "w") as out:
        for path in sorted(OMIE.glob("marginalpdbc_2018*")):
            out.write(path, arcname=path.name)
        out.writestr("readme.txt", "not a price file")
    from_zip = one([archive])
    from_files = one(sorted(OMIE.glob("marginalpdbc_2018*")))
    pd.testing.assert_frame_equal(from_zip.values, from_files.values)
    members = [f.name.split(":")[1] for f in from_zip.report.files]
    assert members == [p.name for p in sorted(OMIE.glob("marginalpdbc_2018*"))]


# ----------------------------------------------------------------------------- ENTSO-E


def test_entsoe_prices_fall_back_hour_written_twice_is_summer_then_winter():
    item = one([ENTSOE / "day_ahead_prices_2018-10-28.csv"])
    assert len(item.values) == 25 and item.report.gaps == ()
    assert price_at(item, "2018-10-27 22:00") == 50.0  # 00:00+02:00
    assert price_at(item, "2018-10-28 00:00") == 52.0  # first 02:00: +02:00
    assert price_at(item, "2018-10-28 01:00") == 53.0  # second 02:00: +01:00
    assert price_at(item, "2018-10-28 22:00") == 74.0  # 23:00+01:00


def test_entsoe_prices_spring_gap_row_without_value_is_dropped_and_reported():
    item = one([ENTSOE / "day_ahead_prices_2018-03-25.csv"])
    assert len(item.values) == 23
    assert price_at(item, "2018-03-25 00:00") == 61.0  # 01:00+01:00
    assert price_at(item, "2018-03-25 01:00") == 63.0  # 03:00+02:00
    assert any("non-existent local time 25.03.2018 02:00" in note for note in item.report.notes)


def test_entsoe_spring_gap_row_with_a_value_is_refused(tmp_path):
    path = tmp_path / "prices.csv"
    path.write_text((ENTSOE / "day_ahead_prices_2018-03-25.csv").read_text().replace(
        '"25.03.2018 02:00 - 25.03.2018 03:00",""', '"25.03.2018 02:00 - 25.03.2018 03:00","62.00"'))
    with pytest.raises(DataImportError, match="line 4: local time 25.03.2018 02:00 does not exist"):
        one([path])


def test_entsoe_export_cut_after_its_header_is_refused(tmp_path):
    path = tmp_path / "forecast.csv"
    path.write_text((ENTSOE / "wind_solar_forecast_2018-10-28_15min.csv").read_text().splitlines()[0] + "\n")
    with pytest.raises(DataImportError, match="forecast.csv: has a header but no rows of data"):
        one([path])


def test_entsoe_repeated_hour_given_once_without_marker_is_refused(tmp_path):
    lines = (ENTSOE / "day_ahead_prices_2018-10-28.csv").read_text().splitlines()
    path = tmp_path / "prices.csv"
    path.write_text("\n".join(lines[:4] + lines[5:]) + "\n")
    with pytest.raises(DataImportError, match="occurs twice that day.*1 time"):
        one([path])


def test_entsoe_generation_per_type_with_markers_not_expected_and_missing_values():
    item = one([ENTSOE / "actual_generation_2018-10-28.csv"])
    assert list(item.values.columns) == ["actual_biomass", "actual_solar", "actual_wind_onshore"]
    wind = item.values["actual_wind_onshore"]
    assert wind[utc("2018-10-28 00:00")] == 5200.0  # marked (CEST)
    assert wind[utc("2018-10-28 01:00")] == 5300.0  # marked (CET)
    assert wind[utc("2018-10-28 02:00")] == 5400.0  # 03:00+01:00
    report = item.report
    assert any("actual_wind_offshore" in n and "n/e" in n for n in report.notes)
    assert any("Actual Consumption" in n for n in report.notes)
    solar = next(s for s in report.series if s.name == "actual_solar")
    assert solar.values == 5 and solar.missing[0].start == utc("2018-10-28 03:00")
    assert all(s.unit == "MW" for s in report.series) and report.zone == "BZN|ES"


def test_entsoe_quarter_hour_forecasts_average_to_hours_across_the_repeated_hour():
    item = one([ENTSOE / "wind_solar_forecast_2018-10-28_15min.csv"])
    assert item.report.resolutions == ((15, 20),)
    assert any("Intraday" in n for n in item.report.notes)
    table = hourly_table([item])
    wind = table.frame["forecast_wind_onshore"]
    # Row i holds 1000 + 10·i; hour h averages rows 4h..4h+3: 1015 + 40·h.
    assert list(wind) == [1015.0, 1055.0, 1095.0, 1135.0, 1175.0]
    assert wind.index[0] == utc("2018-10-27 22:00") and wind.index[2] == utc("2018-10-28 00:00")
    assert np.isnan(table.frame["forecast_solar"].iloc[1]) and len(table.notes) == 1


def test_entsoe_dates_are_day_first_and_parenthesised_units_are_read(tmp_path):
    path = tmp_path / "prices.csv"
    path.write_text('"MTU (CET/CEST)","Area","Day-ahead Price (EUR/MWh)"\n'
                    '"01.02.2018 00:00 - 01.02.2018 01:00","BZN|ES","12.50"\n'
                    '"01.02.2018 00:00 - 01.02.2018 01:00","BZN|PT","13.50"\n')
    with pytest.raises(DataImportError, match="several areas"):
        one([path])
    item = one([path], zone="PT")
    assert price_at(item, "2018-01-31 23:00") == 13.5  # 1 February, not 2 January


def test_entsoe_utc_exports_and_wrong_units(tmp_path):
    path = tmp_path / "prices.csv"
    path.write_text('"MTU (UTC)","Day-ahead Price [EUR/MWh]"\n"28.10.2018 01:00 - 28.10.2018 02:00","5"\n')
    assert price_at(one([path]), "2018-10-28 01:00") == 5.0
    path.write_text('"MTU (CET/CEST)","Day-ahead Price [GBP/MWh]"\n"28.10.2018 01:00 - 28.10.2018 02:00","5"\n')
    with pytest.raises(DataImportError, match="GBP/MWh; rvpp reads EUR/MWh"):
        one([path])


# ----------------------------------------------------------------------------- hourly tables


def test_spanish_dataset_with_swapped_day_and_month_is_corrected():
    item = one([TABLES / "energy_dataset_swapped_days.csv"])
    wind = item.values["actual_wind_onshore"]
    # "2018-02-01 00:00+01:00" in the file is really 2 January: wind 2000 on day 2 at 00:00.
    assert wind[utc("2018-01-01 23:00")] == 2000.0
    assert wind[utc("2018-01-02 23:00")] == 3000.0
    assert item.report.gaps == () and len(item.values) == 72
    assert any("swapped on 2 days" in n for n in item.report.notes)
    assert set(item.series) == {"actual_solar", "actual_wind_onshore", "forecast_solar", "forecast_wind_onshore",
                                "load_forecast", "load_actual", "price_da"}


def test_spanish_dataset_fall_back_day_by_written_offsets_and_missing_values():
    item = one([TABLES / "energy_dataset_fall_back.csv"])
    assert len(item.values) == 25
    assert item.values.loc[utc("2018-10-28 00:00"), "price_da"] == 62.25  # 02:00+02:00
    assert item.values.loc[utc("2018-10-28 01:00"), "price_da"] == 63.25  # 02:00+01:00
    wind = next(s for s in item.report.series if s.name == "actual_wind_onshore")
    assert wind.values == 24 and wind.missing[0].start == utc("2018-10-28 05:00")
    assert any("price actual" in n for n in item.report.notes)


def test_time_utc_table_keeps_zero_and_negative_prices():
    item = one([TABLES / "omie_hourly_prices_2024-03-30.csv"])
    prices = item.values["price_da"]
    assert len(prices) == 47 and (prices < 0).any() and (prices == 0).any()
    assert prices[utc("2024-03-31 01:00")] == 33.0  # 03:00+02:00 on the 23-hour day
    with pytest.raises(DataImportError, match="no price column for zone PT"):
        one([TABLES / "omie_hourly_prices_2024-03-30.csv"], "PT")


def test_time_utc_table_with_a_local_time_that_disagrees_is_refused(tmp_path):
    path = tmp_path / "prices.csv"
    path.write_text("time_utc,time_local,price_es_eur_mwh\n2024-03-29T23:00:00Z,2024-03-30T00:00:00+02:00,1\n")
    with pytest.raises(DataImportError, match="line 2: time_local"):
        one([path])


def test_normalised_csv_reads_back_what_was_written(tmp_path):
    imports = import_files([ENTSOE / "day_ahead_prices_2018-10-28.csv", ENTSOE / "actual_generation_2018-10-28.csv"])
    table = hourly_table(imports)
    out = write_table(table.frame, tmp_path / "series.csv")
    again = hourly_table([one([out])]).frame
    pd.testing.assert_frame_equal(again, table.frame, check_freq=False)


def test_sources_that_disagree_on_a_series_are_refused(tmp_path):
    path = tmp_path / "other.csv"
    path.write_text('"MTU (CET/CEST)","Day-ahead Price [EUR/MWh]"\n"28.10.2018 00:00 - 28.10.2018 01:00","50.00"\n'
                    '"28.10.2018 01:00 - 28.10.2018 02:00","99.00"\n')
    agree = hourly_table(import_files([ENTSOE / "day_ahead_prices_2018-10-28.csv", OMIE / "marginalpdbc_20181027.1"]))
    assert agree.frame["price_da"].notna().sum() == 24 + 25
    with pytest.raises(DataImportError, match=r"price_da at 2018-10-27T23:00Z: .* gives 99 but .* gives 51"):
        hourly_table(import_files([ENTSOE / "day_ahead_prices_2018-10-28.csv", path]))


def test_unknown_files_are_refused_by_name(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("hello,world\n1,2\n")
    with pytest.raises(DataImportError, match='"notes.txt": format not recognised'):
        detect(path)
    with pytest.raises(DataImportError, match="does not exist"):
        detect(tmp_path / "missing.csv")


def test_command_line_import_prints_the_report_and_writes_the_hourly_csv(tmp_path, capsys):
    out = tmp_path / "prices.csv"
    code = main(["data", "import", str(OMIE / "marginalpdbc_20181028.1"), "--out", str(out)])
    printed = capsys.readouterr()
    assert code == 0
    assert "25 of 60 min" in printed.out and "25-hour day" in printed.out
    written = pd.read_csv(out)
    assert list(written.columns) == ["time_utc", "time_local", "price_da"]
    assert written["time_local"].iloc[2:4].tolist() == ["2018-10-28T02:00:00+02:00", "2018-10-28T02:00:00+01:00"]
    assert main(["data", "import", str(tmp_path / "nothing.csv")]) == 1
    assert "does not exist" in capsys.readouterr().err


def test_binary_files_are_named_for_what_they_are(tmp_path):
    path = tmp_path / "prices.csv"
    path.write_bytes(b"%PDF-1.7 not a table")
    with pytest.raises(DataImportError, match='"prices.csv" is a PDF document, not a text file'):
        detect(path)
