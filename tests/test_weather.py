"""The weather CSV importer (rvpp.data.importers.weather), on small files written here.

Every expected instant is worked out by hand: Europe/Madrid is UTC+01:00 in winter and
UTC+02:00 in summer; on 2018-10-28 local 02:00 occurs first at +02:00 (00:00 UTC), then at
+01:00 (01:00 UTC); on 2018-03-25 local 02:00 does not exist.
"""

from __future__ import annotations

import os
import threading

import numpy as np
import pandas as pd
import pytest

from rvpp.data.importers import weather
from rvpp.data.importers.report import hourly
from rvpp.data.importers.weather import WeatherColumns, read
from rvpp.errors import DataImportError

MADRID = "Europe/Madrid"


def utc(text: str) -> pd.Timestamp:
    return pd.Timestamp(text, tz="UTC")


def write(tmp_path, text: str, name: str = "weather.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def refused(path, *expected: str, columns: WeatherColumns = WeatherColumns(), timezone: str | None = None) -> str:
    with pytest.raises(DataImportError) as info:
        read(path, columns, timezone)
    message = str(info.value)
    for text in expected:
        assert text in message, message
    return message


# ----------------------------------------------------------------------------- what is read


def test_times_with_offsets_are_exact_and_the_columns_found_by_name(tmp_path):
    path = write(tmp_path, "time,temperature,temperature_forecast\n"
                           "2018-01-01T00:00:00+01:00,6.5,6.0\n2018-01-01T01:00:00+01:00,5.5,5.0\n"
                           "2018-01-01T02:00:00+01:00,4.0,\n")
    item = read(path)
    assert list(item.values.index) == [utc("2017-12-31 23:00"), utc("2018-01-01 00:00"), utc("2018-01-01 01:00")]
    assert item.values["temperature"].tolist() == [6.5, 5.5, 4.0]
    assert item.values["temperature_forecast"].tolist()[:2] == [6.0, 5.0]
    assert np.isnan(item.values["temperature_forecast"].iloc[2])  # an empty cell is missing, never filled
    assert item.report.resolutions == ((60, 3),) and item.report.gaps == ()
    series = {s.name: s for s in item.report.series}
    assert series["temperature"].unit == "°C" and 'column "temperature"' in series["temperature"].meaning
    assert len(series["temperature_forecast"].missing) == 1


@pytest.mark.parametrize("header", ["timestamp,temp", "Time,T2M", "datetime,air_temperature", "date,t"])
def test_columns_are_found_from_the_short_list(tmp_path, header):
    path = write(tmp_path, f"{header}\n2018-01-01T00:00Z,1.5\n2018-01-01T01:00Z,2.5\n")
    assert read(path).values["temperature"].tolist() == [1.5, 2.5]


def test_columns_named_by_the_user_and_semicolons_with_decimal_commas(tmp_path):
    path = write(tmp_path, "fecha;ta (ºC);prevista\n2018-01-01 00:00;12,5;11,0\n2018-01-01 01:00;-3,25;-2,0\n")
    columns = WeatherColumns.parse(["time=fecha", "temperature=ta", "forecast=prevista"])
    item = read(path, columns, "UTC")
    assert item.values["temperature"].tolist() == [12.5, -3.25]
    assert item.values["temperature_forecast"].tolist() == [11.0, -2.0]


def test_naive_local_times_on_the_day_clocks_go_back_are_summer_then_winter(tmp_path):
    rows = [("00:00", 10), ("01:00", 11), ("02:00", 12), ("02:00", 13), ("03:00", 14)]
    path = write(tmp_path, "time,temperature\n" + "".join(f"2018-10-28 {h},{t}\n" for h, t in rows))
    item = read(path, timezone=MADRID)
    # 00:00+02:00 = 22:00Z the day before; 02:00 first at +02:00 (00:00Z), then at +01:00 (01:00Z); 03:00+01:00 = 02:00Z
    assert list(item.values.index) == [utc("2018-10-27 22:00"), utc("2018-10-27 23:00"), utc("2018-10-28 00:00"),
                                       utc("2018-10-28 01:00"), utc("2018-10-28 02:00")]
    assert item.values["temperature"].tolist() == [10, 11, 12, 13, 14]
    assert any("2018-10-28: 25-hour day in Europe/Madrid" in line for line in item.report.dst)


def test_quarter_hours_become_hourly_means(tmp_path):
    values = [4.0, 5.0, 6.0, 9.0, 1.0, 2.0, 3.0]  # 00:00..01:30; the hour 01:00 lacks two quarters
    stamps = pd.date_range("2018-01-01", periods=len(values), freq="15min", tz="UTC")
    path = write(tmp_path, "time,temperature\n" + "".join(f"{t:%Y-%m-%dT%H:%M}Z,{v}\n" for t, v in zip(stamps, values)))
    item = read(path)
    assert item.report.resolutions == ((15, 7),)
    table, notes = hourly(item)
    assert table.loc[utc("2018-01-01 00:00"), "temperature"] == pytest.approx((4 + 5 + 6 + 9) / 4)  # 6.0
    assert np.isnan(table.loc[utc("2018-01-01 01:00"), "temperature"])  # not averaged from a part of the hour
    assert any("2018-01-01T01:00Z" in n for n in notes)


def test_gaps_are_listed_and_identical_repeats_dropped(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-01T01:00Z,2\n2018-01-01T01:00Z,2\n"
                           "2018-01-01T05:00Z,3\n")
    item = read(path)
    assert [(g.start, g.end, g.periods) for g in item.report.gaps] == [
        (utc("2018-01-01 02:00"), utc("2018-01-01 05:00"), 3)]
    assert len(item.report.duplicates) == 1 and "weather.csv line 3" in item.report.duplicates[0]


def test_a_kelvin_column_is_converted_when_its_header_says_so(tmp_path):
    path = write(tmp_path, "valid_time,t2m [K]\n2018-01-01T00:00Z,273.15\n2018-01-01T01:00Z,283.65\n")
    item = read(path)
    assert item.values["temperature"].tolist() == pytest.approx([0.0, 10.5])
    assert any("kelvin" in n for n in item.report.notes)


# ----------------------------------------------------------------------------- refusals, each by name


def test_refuses_naive_times_without_a_stated_clock(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01 00:00,1\n2018-01-01 01:00,2\n")
    refused(path, "weather.csv line 2", "has no UTC offset", "--weather-timezone")


def test_refuses_a_time_zone_that_does_not_exist(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01 00:00,1\n2018-01-01 01:00,2\n")
    refused(path, "--weather-timezone 'Mars/Olympus' is not a time zone", timezone="Mars/Olympus")
    refused(path, "is not a time zone", timezone="../../etc/passwd")


def test_refuses_a_missing_time(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n,2\n")
    refused(path, "weather.csv line 3: time '' is not a time")


def test_refuses_an_impossible_date(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-02-30T00:00Z,1\n2018-02-30T01:00Z,2\n")
    refused(path, "weather.csv line 2: time '2018-02-30T00:00Z' is not a valid date")


def test_refuses_a_year_out_of_range(tmp_path):
    path = write(tmp_path, "time,temperature\n3000-01-01T00:00Z,1\n3000-01-01T01:00Z,2\n")
    refused(path, "weather.csv line 2", "dates must lie between 1900 and 2199")


def test_refuses_unsorted_times(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T01:00Z,1\n2018-01-01T00:00Z,2\n2018-01-01T02:00Z,3\n")
    refused(path, "weather.csv line 3", "is before the row above it", "rows must be in time order")


def test_refuses_a_repeated_time_with_other_values(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-01T01:00Z,2\n2018-01-01T01:00Z,2.5\n")
    refused(path, "weather.csv line 4", "also given by weather.csv line 3 with other values")


def test_refuses_a_local_time_that_does_not_exist(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-03-25 01:00,1\n2018-03-25 02:00,2\n2018-03-25 03:00,3\n")
    refused(path, "weather.csv line 3: local time 2018-03-25 02:00 does not exist in Europe/Madrid",
            timezone=MADRID)


def test_refuses_a_repeated_local_hour_given_once(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-10-28 01:00,1\n2018-10-28 02:00,2\n2018-10-28 03:00,3\n")
    refused(path, "weather.csv line 3: local time 2018-10-28 02:00 occurs twice in Europe/Madrid",
            "gives it 1 time(s)", timezone=MADRID)


def test_refuses_offsets_on_some_rows_only(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-01 01:00,2\n")
    refused(path, "weather.csv line 3", "has no UTC offset, unlike the first row", timezone="UTC")


def test_refuses_daily_rows(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-02T00:00Z,2\n")
    refused(path, "the rows are 1440 minutes apart; a weather file must be hourly or finer")


def test_refuses_a_step_that_does_not_divide_the_hour(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-01T00:07Z,2\n2018-01-01T00:14Z,3\n")
    refused(path, "the rows are 7 minutes apart, which does not divide the hour")


def test_refuses_rows_off_the_hour(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:50Z,1\n2018-01-01T01:50Z,2\n")
    refused(path, "weather.csv line 2", "off the file's 60-minute grid of UTC hours")


def test_refuses_a_row_between_the_steps(tmp_path):
    """Hourly rows (the most common spacing) with one row at half past, inside the hour before."""
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,1\n2018-01-01T01:00Z,2\n2018-01-01T02:00Z,3\n"
                           "2018-01-01T03:00Z,4\n2018-01-01T03:30Z,5\n2018-01-01T04:00Z,6\n")
    refused(path, "weather.csv line 6: time 2018-01-01T03:30Z is off the file's 60-minute grid")


def test_refuses_text_where_a_temperature_belongs_by_line_and_column(tmp_path):
    path = write(tmp_path, "time,Temp Out\n2018-01-01T00:00Z,1\n2018-01-01T01:00Z,warm\n")
    refused(path, 'weather.csv line 3: column "Temp Out" value \'warm\' is not a number',
            columns=WeatherColumns(temperature="Temp Out"))


def test_refuses_an_infinite_temperature(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,inf\n2018-01-01T01:00Z,2\n")
    refused(path, 'weather.csv line 2: column "temperature" value \'inf\' is not a finite number')


@pytest.mark.parametrize("value, shown", [("-99", "-99 °C"), ("61", "61 °C")])
def test_refuses_an_impossible_temperature_by_line_and_column(tmp_path, value, shown):
    path = write(tmp_path, f"time,temperature\n2018-01-01T00:00Z,1\n2018-01-01T01:00Z,{value}\n")
    refused(path, f'weather.csv line 3: column "temperature" value \'{value}\' is {shown}, outside -90 to 60 °C')


def test_refuses_an_impossible_forecast_temperature(tmp_path):
    path = write(tmp_path, "time,temperature,temperature_forecast\n2018-01-01T00:00Z,1,-9999\n2018-01-01T01:00Z,2,2\n")
    refused(path, 'weather.csv line 2: column "temperature_forecast" value \'-9999\'')


def test_refuses_kelvin_without_a_unit_with_a_hint(tmp_path):
    path = write(tmp_path, "time,t2m\n2018-01-01T00:00Z,280.1\n2018-01-01T01:00Z,281.0\n")
    refused(path, "weather.csv line 2", "outside -90 to 60 °C", "it looks like kelvin", 't2m [K]')


def test_refuses_a_unit_other_than_celsius_or_kelvin(tmp_path):
    path = write(tmp_path, "time,temperature (°F)\n2018-01-01T00:00Z,40\n2018-01-01T01:00Z,41\n")
    refused(path, 'column "temperature (°F)" is in \'°F\'; rvpp reads °C or K')


def test_refuses_a_file_without_a_temperature_column(tmp_path):
    path = write(tmp_path, "time,wind_speed\n2018-01-01T00:00Z,3\n2018-01-01T01:00Z,4\n")
    refused(path, "weather.csv: no temperature column (looked for temperature, temp, t2m", '"time", "wind_speed"',
            "--weather-columns temperature=COLUMN")


def test_refuses_a_file_without_a_time_column(tmp_path):
    path = write(tmp_path, "hour,temperature\n0,3\n1,4\n")
    refused(path, "weather.csv: no time column")


def test_refuses_a_column_named_by_the_user_that_is_not_there(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,3\n2018-01-01T01:00Z,4\n")
    refused(path, 'weather.csv: no column "tmed" (the temperature column named by --weather-columns)',
            columns=WeatherColumns(temperature="tmed"))


def test_refuses_a_temperature_column_given_twice(tmp_path):
    path = write(tmp_path, "time,temp,Temp\n2018-01-01T00:00Z,3,3\n2018-01-01T01:00Z,4,4\n")
    refused(path, 'the header has "temp" 2 times; keep one temperature column')


def test_refuses_one_column_in_two_roles(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,3\n2018-01-01T01:00Z,4\n")
    refused(path, 'column "temperature" cannot be both the forecast and another column',
            columns=WeatherColumns(forecast="temperature"))


@pytest.mark.parametrize("pairs, rule", [(["temp"], "must be ROLE=COLUMN"), (["wind=ws"], "must be ROLE=COLUMN"),
                                         (["time="], "must be ROLE=COLUMN"),
                                         (["time=a", "time=b"], "names the time column twice")])
def test_refuses_weather_columns_that_are_not_role_pairs(pairs, rule):
    with pytest.raises(DataImportError, match=rule):
        WeatherColumns.parse(pairs)


def test_refuses_a_row_of_another_width(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,3\n2018-01-01T01:00Z,4,5\n")
    refused(path, "weather.csv line 3: 3 cells where the header has 2")


def test_refuses_a_single_time(tmp_path):
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,3\n")
    refused(path, "the file has one time only")


def test_refuses_an_empty_file_and_a_header_alone(tmp_path):
    refused(write(tmp_path, "\n\n"), "weather.csv: the file is empty")
    refused(write(tmp_path, "time,temperature\n", "header.csv"), "header.csv: has a header but no rows of data")


def test_refuses_a_workbook_and_binary_data(tmp_path):
    path = tmp_path / "weather.xlsx"
    path.write_bytes(b"PK\x03\x04" + b"\x00" * 64)
    refused(path, '"weather.xlsx" is a zip archive')
    path = tmp_path / "weather.bin"
    path.write_bytes(b"time,temperature\n\x00\x01\x02")
    refused(path, '"weather.bin" is binary data')


def test_refuses_a_file_above_the_size_limit(tmp_path, monkeypatch):
    path = write(tmp_path, "time,temperature\n" + "2018-01-01T00:00Z,3\n" * 100)
    monkeypatch.setattr(weather, "LIMIT_MB", 0.001)
    refused(path, '"weather.csv" is 0 MB; files above 0.001 MB are refused')


def test_refuses_a_folder_a_missing_file_and_a_named_pipe(tmp_path):
    refused(tmp_path, "is a folder, not a file")
    refused(tmp_path / "none.csv", '"none.csv" does not exist')
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)

    def writer():
        with open(fifo, "wb"):
            pass

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    try:
        refused(fifo, '"pipe.csv": not a regular file (it is a named pipe)')
    finally:
        if thread.is_alive():
            os.close(os.open(fifo, os.O_RDONLY | os.O_NONBLOCK))
        thread.join(10)


def test_messages_quote_only_a_short_excerpt_of_the_file(tmp_path):
    secret = "x" * 30 + "SECRET-TAIL"
    path = write(tmp_path, f"time,temperature\n2018-01-01T00:00Z,{secret}\n2018-01-01T01:00Z,1\n")
    message = refused(path, "weather.csv line 2", "is not a number")
    assert "SECRET-TAIL" not in message and "\n" not in message
    path = write(tmp_path, "time,temperature\n2018-01-01T00:00Z,\x1b[31m1\n2018-01-01T01:00Z,1\n", "escape.csv")
    assert "\x1b" not in refused(path, "escape.csv line 2")


def test_a_description_before_the_header_is_skipped(tmp_path):
    """The layout of an Open-Meteo CSV download: the site, a blank line, then the table (times in the
    chosen time zone, GMT here, without an offset)."""
    path = write(tmp_path, "latitude,longitude,elevation,utc_offset_seconds,timezone,timezone_abbreviation\n"
                           "37.2,-3.1,1100.0,0,GMT,GMT\n\ntime,temperature_2m (°C)\n2018-01-01T00:00,3.1\n"
                           "2018-01-01T01:00,2.7\n")
    item = read(path, timezone="UTC")
    assert list(item.values.index) == [utc("2018-01-01 00:00"), utc("2018-01-01 01:00")]
    assert item.values["temperature"].tolist() == [3.1, 2.7]
    assert any("skipped 2 line(s) before the header" in n for n in item.report.notes)
