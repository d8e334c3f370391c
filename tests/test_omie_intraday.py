"""OMIE intraday auction price files (rvpp.data.importers.omie_intraday and rvpp.data.intraday_prices).

Files are written here by hand in OMIE's layout. Every expected instant is worked out by hand:
periods count elapsed time from local midnight in Madrid; on 27 October 2024 (25 hours) local
midnight is 2024-10-26T22:00Z and 12:00 local is winter time, 11:00Z, thirteen hours later, so
IDA3's first period is 14; on 25 March 2018 (23 hours) local midnight is 2018-03-24T23:00Z and
20:00 local is summer time, 18:00Z, nineteen hours later, so IDM7's first period is 20. In a file
line the Portuguese price comes first, then the Spanish one.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import pandas as pd
import pytest
import yaml

from rvpp import load_case
from rvpp.cli import main
from rvpp.data.case import parse_case
from rvpp.data.history import History
from rvpp.data.importers import import_files
from rvpp.data.importers.omie_intraday import read
from rvpp.errors import DataImportError
from tests.factories import PAPER


def utc(text: str) -> pd.Timestamp:
    return pd.Timestamp(text, tz="UTC")


def pibc(folder: Path, name: str, lines: list[str], header: str = "MARGINALPIBC;", end: str = "*") -> Path:
    path = folder / name
    path.write_text("\n".join([header, *lines, end]) + "\n", encoding="latin-1")
    return path


def day_lines(day: str, periods, es=lambda p: 100 + p, pt=lambda p: 90 + p) -> list[str]:
    """Lines of ``day`` (``YYYY;MM;DD``) for ``periods``: ES price 100 + period, PT 90 + period."""
    return [f"{day};{p};{pt(p):.2f};{es(p):.2f};" for p in periods]


def only(imports, column: str) -> pd.Series:
    found = [i for i in imports if i.series == (column,)]
    assert len(found) == 1
    return found[0].values[column]


# ----------------------------------------------------------------------------- reading


def test_a_session_file_is_one_series_named_after_its_session(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2024070102.1", day_lines("2024;07;01", range(1, 25)))
    (item,) = read([path])
    assert item.series == ("price_ida2",)
    prices = item.values["price_ida2"]
    # 1 July: local midnight is 2024-06-30T22:00Z (+02:00); period k starts k-1 hours later
    assert prices.index[0] == utc("2024-06-30 22:00") and prices.iloc[0] == 101.0
    assert prices[utc("2024-07-01 09:00")] == 112.0  # period 12
    assert item.ends[-1] == utc("2024-07-01 22:00")
    assert item.report.gaps == () and item.report.resolutions == ((60, 24),)
    assert item.report.zone == "ES (Spain)"
    (portugal,) = read([path], zone="PT")
    assert portugal.values["price_ida2"][utc("2024-07-01 09:00")] == 102.0


def test_ida3_starts_at_noon_and_an_earlier_period_is_refused(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2024070103.1", day_lines("2024;07;01", range(13, 25)))
    prices = only(read([path]), "price_ida3")
    assert len(prices) == 12 and prices.index[0] == utc("2024-07-01 10:00") and prices.iloc[0] == 113.0
    (tmp_path / "early").mkdir()
    early = pibc(tmp_path / "early", "marginalpibc_2024070103.1", day_lines("2024;07;01", range(12, 25)))
    with pytest.raises(DataImportError, match=r"line 2: PERIOD=12 starts at 11:00 local, before IDA3's window opens "
                                              r"at 12:00; is the file of another session\?"):
        read([early])


def test_the_25_hour_day_moves_ida3_to_period_14(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2024102703.1", day_lines("2024;10;27", range(14, 26)))
    (item,) = read([path])
    prices = item.values["price_ida3"]
    assert prices.index[0] == utc("2024-10-27 11:00") and prices.iloc[0] == 114.0
    assert prices.index[-1] == utc("2024-10-27 22:00") and prices.iloc[-1] == 125.0  # 23:00 local, +01:00
    assert any("25-hour day" in line for line in item.report.dst)
    (tmp_path / "early").mkdir()
    one_early = pibc(tmp_path / "early", "marginalpibc_2024102703.1", ["2024;10;27;13;1.00;1.00;"])
    with pytest.raises(DataImportError, match="PERIOD=13 starts at 11:00 local, before IDA3's window"):
        read([one_early])


def test_the_23_hour_day_of_the_seven_session_preset(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2018032507.1", day_lines("2018;03;25", range(20, 24)))
    prices = only(read([path], "tool_seven"), "price_idm7")
    assert list(prices.index) == [utc("2018-03-25 18:00"), utc("2018-03-25 19:00"), utc("2018-03-25 20:00"),
                                  utc("2018-03-25 21:00")]
    assert list(prices) == [120.0, 121.0, 122.0, 123.0]
    beyond = pibc(tmp_path, "marginalpibc_2018032506.1", day_lines("2018;03;25", [24]))
    with pytest.raises(DataImportError, match="PERIOD=24 does not exist on 2018-03-25, which has 23 periods of 60"):
        read([beyond], "tool_seven")


def test_quarter_hours_from_march_2025_average_to_the_hour(tmp_path):
    # 20 March 2025: local midnight is 2025-03-19T23:00Z (+01:00); 96 quarter-hours
    es = {1: 40.0, 2: 44.0, 3: 52.0, 4: 64.0}
    lines = day_lines("2025;03;20", range(1, 97), es=lambda p: es.get(p, 100 + p))
    path = pibc(tmp_path, "marginalpibc_2025032001.1", lines)
    (item,) = read([path])
    assert item.report.resolutions == ((15, 96),)
    assert item.values["price_ida1"][utc("2025-03-20 00:00")] == 105.0  # period 5
    out = tmp_path / "ida.csv"
    assert main(["data", "import-omie-intraday", str(path), "--out", str(out)]) == 0
    table = pd.read_csv(out)
    assert len(table) == 24
    assert table.loc[0, "time_utc"] == "2025-03-19T23:00:00Z"
    assert table.loc[0, "price_ida1"] == pytest.approx(50.0)  # (40 + 44 + 52 + 64) / 4


def test_an_hourly_file_on_a_quarter_hour_day_is_refused(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2025032002.1", day_lines("2025;03;20", range(1, 25)))
    with pytest.raises(DataImportError, match="periods stop at 24, within the 24 hours of the day, but from "
                                              "2025-03-19 the intraday auctions have 96 quarter-hourly periods"):
        read([path])
    hourly_day = pibc(tmp_path, "marginalpibc_2025031802.1", day_lines("2025;03;18", range(1, 26)))
    with pytest.raises(DataImportError, match="PERIOD=25 does not exist on 2025-03-18, which has 24 periods"):
        read([hourly_day])


def test_versions_identical_are_kept_once_and_different_ones_refused(tmp_path):
    first = pibc(tmp_path, "marginalpibc_2024070101.1", day_lines("2024;07;01", range(1, 25)))
    same = pibc(tmp_path, "marginalpibc_2024070101.2", day_lines("2024;07;01", range(1, 25)))
    (item,) = read([first, same])
    assert len(item.values) == 24 and len(item.report.duplicates) == 24
    other = pibc(tmp_path, "marginalpibc_2024070101.3",
                 day_lines("2024;07;01", range(1, 25), es=lambda p: 100 + p + (5 if p == 7 else 0)))
    with pytest.raises(DataImportError, match="marginalpibc_2024070101.3 line 8: the period starting "
                                              "2024-07-01T04:00Z is also given by"):
        read([first, other])


def test_sessions_of_several_days_and_their_gaps(tmp_path):
    files = [pibc(tmp_path, "marginalpibc_2024070101.1", day_lines("2024;07;01", range(1, 25))),
             pibc(tmp_path, "marginalpibc_2024070201.1", day_lines("2024;07;02", [p for p in range(1, 25) if p != 5])),
             pibc(tmp_path, "marginalpibc_2024070102.1", day_lines("2024;07;01", range(1, 25)))]
    ida1, ida2 = read(files)
    assert ida1.series == ("price_ida1",) and ida2.series == ("price_ida2",)
    assert len(ida1.values) == 47
    (gap,) = ida1.report.gaps
    assert (gap.start, gap.end, gap.periods) == (utc("2024-07-02 02:00"), utc("2024-07-02 03:00"), 1)


def test_a_yearly_zip_reads_like_its_daily_files(tmp_path):
    archive = tmp_path / "marginalpibc_2024.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("marginalpibc_2024070101.1", "\n".join(["MARGINALPIBC;", *day_lines("2024;07;01", range(1, 25)),
                                                          "*"]))
        z.writestr("marginalpibc_2024070103.1", "\n".join(["MARGINALPIBC;", *day_lines("2024;07;01", range(13, 25)),
                                                          "*"]))
        z.writestr("readme.txt", "not a price file")
    ida1, ida3 = read([archive])
    assert ida1.report.files[0].name == "marginalpibc_2024.zip:marginalpibc_2024070101.1"
    assert ida3.values["price_ida3"][utc("2024-07-01 21:00")] == 124.0


def test_zip_limits(tmp_path):
    empty = tmp_path / "other.zip"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("marginalpdbc_20240701.1", "MARGINALPDBC;\n*\n")
    with pytest.raises(DataImportError, match='"other.zip" holds no marginalpibc file'):
        read([empty])
    big = tmp_path / "big.zip"
    with zipfile.ZipFile(big, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("marginalpibc_2024070101.1", "MARGINALPIBC;\n" + " " * 1_100_000 + "\n*\n")
    with pytest.raises(DataImportError, match="marginalpibc_2024070101.1 is 1.1 MB unpacked"):
        read([big])


# ----------------------------------------------------------------------------- refusals by name


@pytest.mark.parametrize("name, preset, message", [
    ("prices.txt", "iberian_2024", r'"prices.txt": an OMIE intraday price file is named marginalpibc_YYYYMMDDSS.V'),
    ("marginalpibc_20240701.1", "iberian_2024", "is named marginalpibc_YYYYMMDDSS.V"),
    ("marginalpibc_2024070104.1", "iberian_2024",
     r"session 04 is not one of the 3 sessions of iberian_2024 \(IDA1 to IDA3, numbered 01 to 03\)"),
    ("marginalpibc_2024070100.1", "iberian_2024", "session 00 is not one of the 3 sessions"),
    ("marginalpibc_2024070108.1", "tool_seven", r"session 08 is not one of the 7 sessions of tool_seven \(IDM1 to IDM7"),
    ("marginalpibc_2024023001.1", "iberian_2024", "2024-02-30 in its name is not a date"),
    ("marginalpibc_3024070101.1", "iberian_2024", "the year 3024 of its name is out of range"),
])
def test_a_file_name_that_does_not_fit_is_refused(tmp_path, name, preset, message):
    path = pibc(tmp_path, name, day_lines("2024;07;01", range(1, 25)))
    with pytest.raises(DataImportError, match=message):
        read([path], preset)


def test_a_session_four_is_read_by_the_seven_session_preset(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2018040204.1", day_lines("2018;04;02", range(8, 25)))
    prices = only(read([path], "tool_seven"), "price_idm4")
    assert prices.index[0] == utc("2018-04-02 05:00") and prices.iloc[0] == 108.0  # 07:00 local, +02:00


def test_files_of_another_day_or_zone_are_refused_by_name(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2024070301.1", day_lines("2024;07;03", range(1, 25)))
    with pytest.raises(DataImportError, match=r'"marginalpibc_2024070301.1" is for delivery day 2024-07-03, outside '
                                              r"the days asked \(2024-07-01 to 2024-07-02\)"):
        read([path], days=(pd.Timestamp("2024-07-01").date(), pd.Timestamp("2024-07-02").date()))
    dated = pibc(tmp_path, "marginalpibc_2024070401.1", day_lines("2024;07;05", range(1, 25)))
    with pytest.raises(DataImportError, match="line 2: the line is dated 2024-07-05 but the file's name is for "
                                              "2024-07-04"):
        read([dated])
    portugal_only = pibc(tmp_path, "marginalpibc_2024070601.1",
                         [f"2024;07;06;{p};{90 + p:.2f};;" for p in range(1, 25)])
    with pytest.raises(DataImportError, match=r"no line gives a price for Spain \(ES\); the file may be for another "
                                              "zone"):
        read([portugal_only])
    assert only(read([portugal_only], zone="PT"), "price_ida1").iloc[0] == 91.0
    with pytest.raises(DataImportError, match="zone='FR' is not an OMIE zone"):
        read([path], zone="FR")
    with pytest.raises(DataImportError, match="--sessions 'xbid' is not a preset of intraday sessions; choose "
                                              "iberian_2024 or tool_seven"):
        read([path], "xbid")


# ----------------------------------------------------------------------------- hostile contents and paths


@pytest.mark.parametrize("text, message", [
    ("MARGINALPDBC;\n2024;07;01;1;1;1;\n*\n", r'line 1 must be "MARGINALPIBC;".*\(a day-ahead file\)'),
    ("MARGINALPIBC;\n2024;07;01;1;1;1;\n", "the closing line '\\*' is missing"),
    ("MARGINALPIBC;\n2024;07;01;1;1;1;\n*\n2024;07;01;2;1;1;\n", "line 4: data after the closing"),
    ("MARGINALPIBC;\n2024;07;01;1;1;\n*\n", "line 2: expected YEAR;MONTH;DAY;PERIOD;PRICE_PT;PRICE_ES; but found 5"),
    ("MARGINALPIBC;\n2024;07;01;1;1;abc;\n*\n", "line 2: price 'abc' is not a number"),
    ("MARGINALPIBC;\n2024;07;01;1;1;inf;\n*\n", "line 2: price 'inf' is not a finite number"),
    ("MARGINALPIBC;\n2024;07;01;x;1;1;\n*\n", "line 2: PERIOD='x' must be a whole number"),
    ("MARGINALPIBC;\n2024;07;01;0;1;1;\n*\n", "PERIOD=0 does not exist"),
    ("MARGINALPIBC;\n*\n", "no data lines"),
    ("", 'line 1 must be "MARGINALPIBC;"'),
])
def test_hostile_contents_are_refused_with_the_line(tmp_path, text, message):
    path = tmp_path / "marginalpibc_2024070101.1"
    path.write_text(text)
    with pytest.raises(DataImportError, match=message):
        read([path])


def test_hostile_paths_are_refused_by_name(tmp_path):
    folder = tmp_path / "marginalpibc_2024070101.1"
    folder.mkdir()
    with pytest.raises(DataImportError, match="marginalpibc_2024070101.1"):
        read([folder])
    with pytest.raises(DataImportError, match='"marginalpibc_2024070201.1" does not exist'):
        read([tmp_path / "marginalpibc_2024070201.1"])
    image = tmp_path / "marginalpibc_2024070301.1"
    image.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(64))
    with pytest.raises(DataImportError, match="not a text file"):
        read([image])
    with pytest.raises(DataImportError, match="no intraday price file given"):
        read([])


def test_the_general_import_points_to_the_intraday_command(tmp_path):
    path = pibc(tmp_path, "marginalpibc_2024070101.1", day_lines("2024;07;01", range(1, 25)))
    with pytest.raises(DataImportError, match='an OMIE intraday auction price file .*"rvpp data '
                                              'import-omie-intraday"'):
        import_files([path])


# ----------------------------------------------------------------------------- into a case's history


@pytest.fixture
def two_day_case(tmp_path):
    """The paper case on 1-2 December 2024 (hourly, no clock change), written as a folder."""
    from rvpp.data.case_yaml import save_case

    paper = load_case(PAPER)
    frame = paper.history.frame
    rows = frame[(frame.index >= utc("2024-11-30 23:00")) & (frame.index < utc("2024-12-02 23:00"))]
    data = paper.to_data()
    data["delivery_date"] = "2024-12-02"
    folder = tmp_path / "case"
    save_case(parse_case(data, History(rows)), folder)
    return folder


def december_files(folder: Path, sessions=(1, 2, 3)) -> list[Path]:
    folder.mkdir(exist_ok=True)
    files = []
    for day in ("01", "02"):
        for number in sessions:
            first = 13 if number == 3 else 1
            files.append(pibc(folder, f"marginalpibc_202412{day}0{number}.1",
                              day_lines(f"2024;12;{day}", range(first, 25),
                                        es=lambda p, n=number, d=int(day): 10 * n + p + d / 100)))
    return files


def test_prices_join_the_history_of_a_case(tmp_path, two_day_case, capsys):
    before = pd.read_csv(two_day_case / "history.csv")
    files = december_files(tmp_path / "files")
    assert main(["data", "import-omie-intraday", *map(str, files), "--case", str(two_day_case)]) == 0
    after = pd.read_csv(two_day_case / "history.csv")
    assert list(after.columns) == [*before.columns, "price_ida1", "price_ida2", "price_ida3"]
    pd.testing.assert_frame_equal(after[before.columns], before)
    # 2 December 05:00 local is period 6: IDA1 10·1 + 6 + 0.02, IDA2 10·2 + 6 + 0.02
    row = after.index[after["timestamp"] == "2024-12-02T05:00:00+01:00"][0]
    assert after.loc[row, "price_ida1"] == pytest.approx(16.02)
    assert after.loc[row, "price_ida2"] == pytest.approx(26.02)
    # before noon IDA3 trades nothing: the day-ahead price of the hour stands in
    assert after.loc[row, "price_ida3"] == before.loc[row, "price_da"]
    noon = after.index[after["timestamp"] == "2024-12-01T12:00:00+01:00"][0]
    assert after.loc[noon, "price_ida3"] == pytest.approx(43.01)  # period 13: 30 + 13 + 0.01
    case = yaml.safe_load((two_day_case / "case.yaml").read_text())
    assert case["provenance"]["price_ida3"]["origin"] == "real"
    assert "before 12:00 local, outside IDA3's window, the day-ahead price" in case["provenance"]["price_ida3"]["note"]
    assert load_case(two_day_case).history.columns[-3:] == ("price_ida1", "price_ida2", "price_ida3")
    assert "added price_ida1, price_ida2, price_ida3" in capsys.readouterr().out


def test_a_case_refuses_missing_days_other_days_and_held_columns(tmp_path, two_day_case, capsys):
    original = (two_day_case / "history.csv").read_bytes()
    files = december_files(tmp_path / "files")
    without = [f for f in files if f.name != "marginalpibc_2024120203.1"]
    assert main(["data", "import-omie-intraday", *map(str, without), "--case", str(two_day_case)]) == 1
    assert ("price_ida3: no IDA3 price for 12 hour(s) of its window (2024-12-02 12:00, 2024-12-02 13:00, "
            "2024-12-02 14:00 and 9 more, local time)") in capsys.readouterr().err
    later = pibc(tmp_path / "files", "marginalpibc_2024120301.1", day_lines("2024;12;03", range(1, 25)))
    assert main(["data", "import-omie-intraday", *map(str, files), str(later), "--case", str(two_day_case)]) == 1
    assert "is for delivery day 2024-12-03, outside the days asked (2024-12-01 to 2024-12-02)" in \
        capsys.readouterr().err
    assert (two_day_case / "history.csv").read_bytes() == original  # nothing written by a refusal
    assert main(["data", "import-omie-intraday", *map(str, files), "--case", str(two_day_case)]) == 0
    capsys.readouterr()
    assert main(["data", "import-omie-intraday", *map(str, files), "--case", str(two_day_case)]) == 1
    assert "already holds price_ida1, price_ida2, price_ida3; replace them (--force)" in capsys.readouterr().err
    assert main(["data", "import-omie-intraday", *map(str, files), "--case", str(two_day_case), "--force"]) == 0
    assert main(["data", "import-omie-intraday", *map(str, files), "--case", str(two_day_case),
                 "--start", "2024-12-01"]) == 1
    assert "--start and --end cannot be given with --case" in capsys.readouterr().err
    assert not list(tmp_path.glob(".case.*.tmp"))  # no temporary folder left behind


def test_the_hours_before_a_window_are_no_gap(tmp_path):
    files = [pibc(tmp_path, f"marginalpibc_2024070{d}03.1", day_lines(f"2024;07;0{d}", range(13, 25)))
             for d in (1, 2)]
    assert read(files)[0].report.gaps == ()
    holed = pibc(tmp_path, "marginalpibc_2024070303.1", day_lines("2024;07;03", [p for p in range(13, 25) if p != 20]))
    (gap,) = read([*files, holed])[0].report.gaps
    assert (gap.start, gap.end) == (utc("2024-07-03 17:00"), utc("2024-07-03 18:00"))  # period 20: 19:00 local


def test_the_days_asked_on_the_command_line(tmp_path, capsys):
    files = [pibc(tmp_path, f"marginalpibc_2024070{d}01.1", day_lines(f"2024;07;0{d}", range(1, 25))) for d in (1, 2)]
    assert main(["data", "import-omie-intraday", *map(str, files), "--start", "2024-07-02"]) == 1
    assert ('"marginalpibc_2024070101.1" is for delivery day 2024-07-01, outside the days asked (from 2024-07-02)'
            in capsys.readouterr().err)
    assert main(["data", "import-omie-intraday", *map(str, files), "--end", "2024-07-01"]) == 1
    assert "2024-07-02, outside the days asked (up to 2024-07-01)" in capsys.readouterr().err
    assert main(["data", "import-omie-intraday", *map(str, files), "--start", "2024-07-02", "--end", "2024-07-01"]) == 1
    assert "--start 2024-07-02 is after --end 2024-07-01" in capsys.readouterr().err
    assert main(["data", "import-omie-intraday", *map(str, files), "--start", "2024-07-01", "--end", "2024-07-02"]) == 0
    assert "series price_ida1 [EUR/MWh]: IDA1 marginal price, Spain; 48 values, 101 to 124" in capsys.readouterr().out
