"""Hostile input files: each is refused with a message that names the file, the line (or the
member, column or path) and the rule, and never escapes as a traceback or a hang.

Every input is written here in ``tmp_path``: out-of-range years in each importer's format,
damaged OMIE zips (corrupt, bad CRC, encrypted, unknown compression), a user's own
``history.csv`` where ``data build-case`` would write, history headers with a column twice
or a control character, and a named pipe where a file belongs.
"""

from __future__ import annotations

import datetime as dt
import io
import os
import struct
import threading
import zipfile
from pathlib import Path

import pandas as pd
import pytest

from rvpp.cli import main
from rvpp.data.build_case import BuildOptions, build_case
from rvpp.data.files import read_file
from rvpp.data.history import History
from rvpp.data.importers import detect, import_files
from rvpp.data.importers.report import Rows, assemble
from rvpp.errors import CaseError, CaseFileError, DataImportError, RvppError
from tests.factories import PAPER

RANGE = "dates must lie between 1900 and 2199"
DAY = "MARGINALPDBC;\n" + "".join(f"2018;03;26;{h};{40 + h}.00;{41 + h}.00;\n" for h in range(1, 25)) + "*\n"
MEMBER = "marginalpdbc_20180326.1"


def refused_on_import(path: Path, capsys, *expected: str) -> DataImportError:
    """``data import`` refuses ``path`` (library and command line), each expected text in the message."""
    with pytest.raises(DataImportError) as info:
        import_files([path])
    for text in expected:
        assert text in str(info.value)
    assert main(["data", "import", str(path)]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and all(text in err for text in expected)
    return info.value


# ----------------------------------------------------------------------------- 1. years out of range


@pytest.mark.parametrize("year", ["3000", "0001", "1899", "2200"])
def test_omie_year_out_of_range_names_the_line(tmp_path, capsys, year):
    path = tmp_path / f"marginalpdbc_{year}0325.1"
    path.write_text(f"MARGINALPDBC;\n2018;03;26;1;40.00;40.00;\n{year};03;25;1;11.50;11.50;\n*\n")
    refused_on_import(path, capsys, f"{path.name} line 3", f"YEAR={int(year)}", RANGE)


def test_time_utc_table_year_out_of_range_names_the_line(tmp_path, capsys):
    path = tmp_path / "prices.csv"
    path.write_text("time_utc,time_local,price_es_eur_mwh\n2018-01-01T00:00:00Z,2018-01-01T01:00:00+01:00,30\n"
                    "3000-01-01T00:00:00Z,3000-01-01T01:00:00+01:00,31\n")
    refused_on_import(path, capsys, "prices.csv line 3", "3000-01-01T00:00:00Z", RANGE)


def test_energy_dataset_year_out_of_range_names_the_line(tmp_path, capsys):
    path = tmp_path / "energy_dataset.csv"
    path.write_text("time,generation solar,price day ahead\n3000-10-28 00:00:00+02:00,0.0,60\n"
                    "3000-10-28 01:00:00+02:00,0.0,61\n")
    refused_on_import(path, capsys, "energy_dataset.csv line 2", "3000-10-28 00:00:00+02:00", RANGE)


def test_entsoe_export_year_out_of_range_names_the_line(tmp_path, capsys):
    path = tmp_path / "day_ahead.csv"
    path.write_text('"MTU (CET/CEST)","Day-ahead Price [EUR/MWh]"\n"28.10.3000 00:00 - 28.10.3000 01:00","50.00"\n')
    refused_on_import(path, capsys, "day_ahead.csv line 2", "28.10.3000", RANGE)


def test_a_gap_of_centuries_inside_the_range_is_reported(tmp_path):
    """1900 and 2199 are both allowed; the gap between them is longer than a pandas Timedelta holds."""
    table = tmp_path / "prices.csv"
    table.write_text("time_utc,time_local,price_da\n1900-01-01T00:00:00Z,1900-01-01T00:00:00+00:00,3\n"
                     "2199-12-31T23:00:00Z,2199-12-31T23:00:00+00:00,4\n")
    dataset = tmp_path / "energy_dataset.csv"
    dataset.write_text("time,price day ahead\n1900-01-01 00:00:00+00:00,3\n2199-12-31 23:00:00+00:00,4\n")
    hours = int((dt.datetime(2199, 12, 31, 23) - dt.datetime(1900, 1, 1, 1)).total_seconds() // 3600)
    for path in (table, dataset):
        (item,) = import_files([path])
        assert [gap.periods for gap in item.report.gaps] == [hours]


def test_timeline_of_a_reader_out_of_range_is_refused_by_its_line():
    """The last guard: a reader that let such an instant through still gets a named error."""
    rows = Rows()
    rows.add(pd.Timestamp("2018-01-01", tz="UTC"), pd.Timestamp("2018-01-01 01:00", tz="UTC"), {"price_da": 1.0},
             "a.csv line 2")
    rows.add(pd.Timestamp("3000-01-01", tz="UTC"), pd.Timestamp("3000-01-01 01:00", tz="UTC"), {"price_da": 1.0},
             "a.csv line 3")
    with pytest.raises(DataImportError, match=f"a.csv line 3: .*{RANGE}"):
        assemble(rows, source="test", files=[], timezone="UTC", zone=None, meanings={"price_da": "price"})


# ----------------------------------------------------------------------------- 2. damaged OMIE zips


def omie_zip(compression: int = zipfile.ZIP_STORED) -> bytearray:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=compression) as archive:
        archive.writestr(MEMBER, DAY)
    return bytearray(buffer.getvalue())


def member_data(data: bytearray) -> tuple[int, int]:
    """Start and length of the single member's stored bytes (after its local header)."""
    size, name, extra = struct.unpack_from("<I2xHH", data, 18)[0], *struct.unpack_from("<HH", data, 26)
    return 30 + name + extra, size


def patched(data: bytearray, offset_local: int, offset_central: int, value: int) -> bytearray:
    """Write a 2-byte field into the local header and the central directory entry."""
    central = data.find(b"PK\x01\x02")
    struct.pack_into("<H", data, offset_local, value)
    struct.pack_into("<H", data, central + offset_central, value)
    return data


def corrupt_deflate() -> bytearray:
    data = omie_zip(zipfile.ZIP_DEFLATED)
    start, size = member_data(data)
    data[start:start + size] = b"\xff" * size  # a deflate block of the reserved type
    return data


def bad_crc() -> bytearray:
    data = omie_zip()
    start, _ = member_data(data)
    at = data.index(b"41.00", start)
    data[at:at + 2] = b"99"  # still text, but not the bytes the CRC was computed over
    return data


def encrypted() -> bytearray:
    data = omie_zip()
    return patched(data, 6, 8, struct.unpack_from("<H", data, 6)[0] | 0x1)


def unknown_method() -> bytearray:
    return patched(omie_zip(), 8, 10, 97)


@pytest.mark.parametrize("damage, rule", [
    (corrupt_deflate, "cannot be unpacked (Error -3 while decompressing data: invalid block type)"),
    (bad_crc, "is damaged (its data does not match the zip's records)"),
    (encrypted, "is encrypted; give a zip without a password"),
    (unknown_method, "cannot be unpacked (That compression method is not supported)")])
def test_damaged_omie_zip_member_is_named(tmp_path, capsys, damage, rule):
    path = tmp_path / "omie_2018.zip"
    path.write_bytes(bytes(damage()))
    refused_on_import(path, capsys, f'omie_2018.zip, member "{MEMBER}": {rule}')


def test_sound_omie_zip_still_reads(tmp_path):
    path = tmp_path / "omie_2018.zip"
    path.write_bytes(bytes(omie_zip(zipfile.ZIP_DEFLATED)))
    (item,) = import_files([path])
    assert len(item.values) == 24 and item.report.files[0].name == f"omie_2018.zip:{MEMBER}"


# ----------------------------------------------------------------------------- 3. build-case keeps the user's files


def prices_table(path: Path, days: int = 45) -> Path:
    utc = pd.date_range(pd.Timestamp("2021-05-01", tz="Europe/Madrid").tz_convert("UTC"), periods=24 * days, freq="h")
    pd.DataFrame({"time_utc": [f"{t:%Y-%m-%dT%H:%M:%SZ}" for t in utc],
                  "time_local": [t.isoformat() for t in utc.tz_convert("Europe/Madrid")],
                  "price_da": [50.0 + t.hour for t in utc]}).to_csv(path, index=False)
    return path


MINE = "timestamp,price_da\n2020-01-01T00:00:00+01:00,1\n"  # the user's own history, not a built case


def test_build_case_refuses_to_replace_a_users_history(tmp_path, capsys):
    source = prices_table(tmp_path / "prices.csv", days=2)
    out = tmp_path / "mine"
    out.mkdir()
    (out / "history.csv").write_text(MINE)
    with pytest.raises(RvppError, match=r"mine already holds history.csv; choose another folder or overwrite it "
                                         r"\(--force\)"):
        build_case([source], out, template=PAPER)
    assert main(["data", "build-case", "--from", str(source), "--out", str(out)]) == 1
    assert "already holds history.csv" in capsys.readouterr().err
    assert (out / "history.csv").read_text() == MINE and os.listdir(out) == ["history.csv"]
    assert sorted(os.listdir(tmp_path)) == ["mine", "prices.csv"]  # no temporary folder left


def test_build_case_refuses_a_folder_where_history_belongs_even_with_force(tmp_path):
    source = prices_table(tmp_path / "prices.csv", days=2)
    (tmp_path / "mine" / "history.csv").mkdir(parents=True)
    with pytest.raises(RvppError, match=r"history.csv is a folder"):
        build_case([source], tmp_path / "mine", template=PAPER, overwrite=True)


def test_build_case_replaces_a_history_with_force(tmp_path):
    source = prices_table(tmp_path / "prices.csv")
    out = tmp_path / "mine"
    out.mkdir()
    (out / "history.csv").write_text(MINE)
    build_case([source], out, template=PAPER, overwrite=True, options=BuildOptions(seed=1))
    assert sorted(os.listdir(out)) == ["case.yaml", "history.csv"]
    assert (out / "history.csv").read_text() != MINE


# ----------------------------------------------------------------------------- 4-5. history column names


def history_csv(header: str) -> bytes:
    return (f"{header}\n2025-03-17T00:00:00+01:00,1,2,3\n2025-03-17T01:00:00+01:00,1,2,3\n").encode()


def test_history_csv_with_a_column_twice_is_refused():
    with pytest.raises(CaseFileError, match=r'^history.csv: has the column "WF1" twice \(columns 2 and 4\)'):
        History.from_csv(history_csv("timestamp,WF1,price_da,WF1"), "history.csv")


def test_history_csv_with_a_quoted_column_twice_is_refused(tmp_path):
    path = tmp_path / "history.csv"
    path.write_bytes(history_csv('timestamp,"WF1",price_da,WF1'))
    with pytest.raises(CaseFileError, match=r'has the column "WF1" twice \(columns 2 and 4\)'):
        History.read_csv(path)


def test_history_table_with_a_column_twice_is_refused():
    frame = pd.DataFrame([["2025-03-17T00:00:00+01:00", 1.0, 2.0]], columns=["timestamp", "WF1", "WF1"])
    with pytest.raises(CaseError, match=r'history: has the column "WF1" twice \(columns 2 and 3\)'):
        History(frame)


@pytest.mark.parametrize("name, shown, code", [("TD_res\x02idential", "TD_res?idential", "U+0002"),
                                               ("WF1\x7f", "WF1?", "U+007F"), ("P\tV", "P?V", "U+0009")])
def test_history_column_with_a_control_character_is_refused(name, shown, code):
    data = history_csv(f"timestamp,{name},price_da,price_sr_up")
    with pytest.raises(CaseError) as info:
        History.from_csv(data, "history.csv")
    message = str(info.value)
    assert f'history.csv: column "{shown}" holds a non-printable character ({code})' in message
    assert "\x02" not in message and "\x7f" not in message


# ----------------------------------------------------------------------------- 6. named pipes


@pytest.fixture
def fifo(tmp_path):
    """A named pipe with a writer waiting on it: a reader that opens it gets an empty file at once
    (so a failing test fails instead of hanging); the writer is released at the end."""
    path = tmp_path / "history.csv"
    os.mkfifo(path)

    def write():
        with open(path, "wb"):
            pass

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    yield path
    if writer.is_alive():
        os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))  # lets the writer's open return
    writer.join(10)


def test_read_file_refuses_a_named_pipe(fifo):
    with pytest.raises(CaseFileError, match=r"^history.csv: not a regular file \(it is a named pipe\)"):
        read_file(fifo, "history.csv")


def test_read_file_refuses_a_device():
    with pytest.raises(CaseFileError, match=r"^zero: not a regular file \(it is a device\)"):
        read_file(Path("/dev/zero"), "zero", max_bytes=16)  # bounded, so a failing test cannot fill memory


def test_solve_refuses_a_named_pipe_as_history(tmp_path, fifo, capsys):
    (tmp_path / "case.yaml").write_bytes((PAPER / "case.yaml").read_bytes())
    assert main(["solve", "--case", str(tmp_path), "--out", str(tmp_path / "out")]) == 1
    assert "history.csv: not a regular file" in capsys.readouterr().err


def test_importers_refuse_a_named_pipe(fifo, capsys):
    with pytest.raises(DataImportError, match=r'"history.csv": not a regular file \(it is a named pipe\)'):
        detect(fifo)
    assert main(["data", "import", str(fifo)]) == 1
    assert "not a regular file" in capsys.readouterr().err


def test_read_file_still_names_missing_files_and_folders(tmp_path):
    with pytest.raises(CaseFileError, match=r"^x.csv: cannot be read \("):
        read_file(tmp_path / "x.csv", "x.csv")
    with pytest.raises(CaseFileError, match=r"^x: is a folder, not a file"):
        read_file(tmp_path, "x")
