"""Attacks on the upload path of the dashboard and on case folders.

Every upload goes through ``read_case_files``, the function the Home page calls. Each
attack must be refused with a named error whose message says what is wrong in the
user's words and quotes nothing of a file the user did not send.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import struct
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rvpp import load_case
from rvpp.data.files import UploadLimits
from rvpp.errors import CaseError, CaseFileError, CasePathError, UploadError, UploadLimitError
from rvpp.outputs.bundle import read_case_files

from tests.factories import PAPER

CASE_YAML = (PAPER / "case.yaml").read_text(encoding="utf-8")
HISTORY = (PAPER / "history.csv").read_bytes()
HOSTNAME = Path("/etc/hostname")
ENVIRON = Path("/proc/self/environ")


def with_history(path: str) -> bytes:
    """The paper's case.yaml with ``history:`` set to ``path``."""
    assert "history: history.csv" in CASE_YAML
    return CASE_YAML.replace("history: history.csv", f"history: {json.dumps(path)}").encode()


def secrets() -> list[str]:
    """Strings the server holds that no message may show: the host name and the values
    of the process environment (those long enough to be recognisable)."""
    found = []
    if HOSTNAME.is_file():
        found.append(HOSTNAME.read_text().strip())
    if ENVIRON.is_file():
        for entry in ENVIRON.read_bytes().split(b"\0"):
            name, _, value = entry.decode("utf-8", "replace").partition("=")
            found += [text for text in (entry.decode("utf-8", "replace"), value) if len(text) >= 6]
    return [s for s in found if s]


def assert_leaks_nothing(err: CaseError) -> None:
    message = "\n".join(err.problems) + str(err)
    for secret in secrets():
        assert secret not in message, f"message shows a server secret: {message!r}"


def zip_of(members: dict[str, bytes], compression=zipfile.ZIP_DEFLATED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=compression) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def refused(files: dict[str, bytes], error: type[CaseError], limits: UploadLimits | None = None) -> CaseError:
    with pytest.raises(error) as info:
        read_case_files(files, **({"limits": limits} if limits else {}))
    assert_leaks_nothing(info.value)
    return info.value


# ----------------------------------------------------------------------------- history: outside the upload


@pytest.mark.parametrize("path", ["/etc/hostname", "/proc/self/environ", "C:\\Windows\\win.ini", "//server/x.csv"])
def test_an_absolute_history_path_is_refused_before_it_is_opened(path):
    err = refused({"case.yaml": with_history(path), "history.csv": HISTORY}, CasePathError)
    assert err.problems == [f'case.yaml: history "{path}" is an absolute path; name a file inside the case '
                            "folder, relative to case.yaml, e.g. history.csv"]


@pytest.mark.parametrize("path", ["../../../../etc/hostname", "data/../../history.csv", "..\\..\\etc\\hostname",
                                  "./../history.csv"])
def test_a_history_path_that_steps_out_with_dot_dot_is_refused(path):
    err = refused({"case.yaml": with_history(path), "history.csv": HISTORY}, CasePathError)
    assert err.problems == [f'case.yaml: history "{path}" steps out of the case folder with ".."; name a file '
                            "inside the case folder, relative to case.yaml, e.g. history.csv"]


def test_a_history_path_inside_a_zip_may_not_leave_it_either():
    for path, words in (("/proc/self/environ", "is an absolute path"), ("../../etc/hostname", 'with ".."')):
        data = zip_of({"mine/case.yaml": with_history(path), "mine/history.csv": HISTORY})
        err = refused({"mine.zip": data}, CasePathError)
        assert len(err.problems) == 1 and words in err.problems[0] and path in err.problems[0]


def test_a_history_that_names_a_file_not_uploaded_lists_what_was_uploaded():
    err = refused({"case.yaml": with_history("data/prices.csv"), "history.csv": HISTORY}, CaseError)
    assert err.problems == ['history file "data/prices.csv" is not among the uploaded files',
                            "the files uploaded are: case.yaml, history.csv"]


def test_history_from_the_servers_disk_is_never_read_even_where_the_upload_would_land(tmp_path, monkeypatch):
    """The upload is read in memory: a relative history that exists in the working folder
    of the server but was not uploaded is not found."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "secret.csv").write_bytes(HISTORY)
    err = refused({"case.yaml": with_history("secret.csv")}, CaseError)
    assert err.problems[0] == 'history file "secret.csv" is not among the uploaded files'


# ----------------------------------------------------------------------------- names of uploaded files and zip members


@pytest.mark.parametrize("member, words", [
    ("../history.csv", 'steps out of the upload with ".."'),
    ("mine/../../history.csv", 'steps out of the upload with ".."'),
    ("/etc/hostname", "an absolute path"),
    ("C:/Windows/win.ini", "an absolute path"),
])
def test_a_zip_member_outside_the_upload_is_refused(member, words):
    data = zip_of({"mine/case.yaml": CASE_YAML.encode(), "mine/history.csv": HISTORY, member: b"x"})
    err = refused({"mine.zip": data}, CasePathError)
    assert err.problems == [f'mine.zip: member "{member}": {"the name " if ".." in member else ""}{words}'
                            + ("; an upload may only hold files inside its own folder" if "absolute" in words else "")]


def test_an_uploaded_file_name_may_not_step_out_either():
    err = refused({"../../case.yaml": CASE_YAML.encode(), "history.csv": HISTORY}, CasePathError)
    assert err.problems == ['uploaded file "../../case.yaml": the name steps out of the upload with ".."']


def test_a_symbolic_link_in_a_zip_is_refused():
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("mine/case.yaml", CASE_YAML)
        link = zipfile.ZipInfo("mine/history.csv")
        link.external_attr = (0o120777 << 16)  # a symbolic link whose target is the member's data
        archive.writestr(link, "/etc/hostname")
    err = refused({"mine.zip": buffer.getvalue()}, CasePathError)
    assert err.problems == ['mine.zip: member "mine/history.csv" is a symbolic link; an upload may only hold '
                            "plain files"]


def test_a_workbook_is_a_zip_and_its_members_are_checked_the_same_way():
    data = zip_of({"[Content_Types].xml": b"<x/>", "../../etc/evil.xml": b"<x/>"})
    err = refused({"case.xlsx": data}, CasePathError)
    assert err.problems == ['case.xlsx: member "../../etc/evil.xml": the name steps out of the upload with ".."']


# ----------------------------------------------------------------------------- what an upload may cost


def _patch_sizes(data: bytes, member: str, size: int) -> bytes:
    """Rewrite the uncompressed size of ``member`` in its local header and in the central
    directory (the sizes a zip reader is told, not the data it holds)."""
    out = bytearray(data)
    name = member.encode()
    for signature, size_at, name_at in ((b"PK\x03\x04", 22, 30), (b"PK\x01\x02", 24, 46)):
        start = out.find(signature)
        patched = 0
        while start != -1:
            length = struct.unpack_from("<H", out, start + name_at - (4 if signature == b"PK\x03\x04" else 18))[0]
            if bytes(out[start + name_at:start + name_at + length]) == name:
                struct.pack_into("<I", out, start + size_at, size)
                patched += 1
            start = out.find(signature, start + 4)
        assert patched == 1, (signature, member)
    return bytes(out)


def test_the_patched_sizes_are_what_a_zip_reader_sees():
    data = _patch_sizes(zip_of({"a.csv": b"0" * 5000}), "a.csv", 7)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        assert archive.getinfo("a.csv").file_size == 7


def test_a_zip_that_claims_small_sizes_is_refused_and_never_inflated_past_its_claim():
    big = b"0," * (3 * 1024 ** 2)  # 6 MiB of data behind a header claiming 100 bytes
    data = _patch_sizes(zip_of({"mine/case.yaml": CASE_YAML.encode(), "mine/history.csv": big}),
                        "mine/history.csv", 100)
    err = refused({"mine.zip": data}, UploadError, UploadLimits(unzipped_bytes=1024 ** 2))
    assert err.problems == ['mine.zip, member "mine/history.csv": is damaged (its data does not match the '
                            "zip's records)"]


def test_a_zip_that_claims_huge_sizes_still_loads_what_it_really_holds():
    """The old check added up the sizes the zip claims; the sizes are now counted while inflating."""
    data = _patch_sizes(zip_of({"mine/case.yaml": CASE_YAML.encode(), "mine/history.csv": HISTORY}),
                        "mine/history.csv", 2 ** 32 - 1)
    assert read_case_files({"mine.zip": data}) == load_case(PAPER)


def _bomb(n_bytes: int) -> bytes:
    """A zip whose history.csv inflates to ``n_bytes`` of zeros (about 1 KiB per MiB)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("bomb/case.yaml", CASE_YAML)
        with archive.open("bomb/history.csv", "w", force_zip64=True) as member:
            chunk = b"0" * 1024 ** 2
            for _ in range(n_bytes // len(chunk)):
                member.write(chunk)
    return buffer.getvalue()


@pytest.fixture
def inflated(monkeypatch) -> list[int]:
    """The bytes every zip member read hands out, counted at the zipfile module itself."""
    counted = [0]
    read = zipfile.ZipExtFile.read

    def counting(self, n=-1):
        data = read(self, n)
        counted[0] += len(data)
        return data

    monkeypatch.setattr(zipfile.ZipExtFile, "read", counting)
    return counted


# How far past the limit inflating may go: the chunk that crosses it (64 KiB) and the small case.yaml.
OVERSHOOT = 64 * 1024 + len(CASE_YAML.encode())


def test_a_zip_bomb_is_stopped_while_it_inflates(inflated):
    limit = UploadLimits().unzipped_bytes
    data = _bomb(limit + 16 * 1024 ** 2)
    assert len(data) < limit / 500
    err = refused({"bomb.zip": data}, UploadLimitError)
    assert err.problems == [f"bomb.zip: unpacks to more than {limit // 1024 ** 2} MiB; a case is usually a few MiB"]
    # Inflating went up to the limit and stopped there, 16 MiB short of the member's end.
    assert limit < inflated[0] <= limit + OVERSHOOT


def test_a_zip_bomb_inside_a_workbook_is_stopped_too(inflated):
    data = zip_of({"xl/worksheets/sheet1.xml": b"0" * (2 * 1024 ** 2)})
    err = refused({"case.xlsx": data}, UploadLimitError, UploadLimits(unzipped_bytes=1024 ** 2))
    assert err.problems == ["case.xlsx: unpacks to more than 1 MiB; a case is usually a few MiB"]
    assert 1024 ** 2 < inflated[0] <= 1024 ** 2 + OVERSHOOT


def test_an_oversized_upload_is_refused_before_it_is_read():
    limits = UploadLimits(upload_bytes=len(HISTORY) // 2)
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": HISTORY}, UploadLimitError, limits)
    size = (len(HISTORY) + len(CASE_YAML.encode())) / 1024 ** 2
    assert err.problems == [f"the upload is {size:.1f} MiB; an upload may be at most "
                            f"{limits.upload_bytes / 1024 ** 2:g} MiB"]
    default = UploadLimits().upload_bytes
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": b"0" * default}, UploadLimitError)
    assert err.problems[0].endswith(f"an upload may be at most {default // 1024 ** 2} MiB")


def test_too_many_rows_or_columns_of_history_are_refused():
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": HISTORY}, UploadLimitError,
                  UploadLimits(history_rows=1000))
    assert err.problems == ["history.csv: has more than 1,000 rows; an upload may have at most 1,000 "
                            "(about 0 years of hours)"]
    wide = b"timestamp," + b",".join(b"c%d" % i for i in range(600)) + b"\n"
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": wide}, UploadLimitError)
    assert err.problems == ["history.csv: has 601 columns; an upload may have at most 500"]


def test_a_workbook_with_too_many_rows_is_refused_while_streaming():
    import openpyxl

    book = openpyxl.Workbook()
    book.active.title = "case"
    book.create_sheet("hpa_tariff")  # every sheet a case workbook needs: a workbook without one is refused first
    sheet = book.create_sheet("history")
    for row in range(50):
        sheet.append([f"2025-01-01T{row % 24:02d}:00:00+00:00", 1.0])
    buffer = io.BytesIO()
    book.save(buffer)
    err = refused({"case.xlsx": buffer.getvalue()}, UploadLimitError, UploadLimits(history_rows=20))
    assert err.problems == ["case.xlsx: sheet 'history' has more than 20 rows; an upload may have at most 20"]


def test_reading_that_takes_too_long_is_stopped():
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": HISTORY}, UploadLimitError,
                  UploadLimits(parse_s=0.0))
    assert err.problems == ["the upload took longer than 0 s to read (stopped while reading case.yaml); "
                            "upload a smaller case"]


def test_a_year_of_quarter_hours_for_fifty_units_is_within_the_limits(paper_case):
    """35,136 rows (a leap year of 15-minute periods) and 53 series pass every limit.

    The history is hourly, so the rows span four years; the limits count rows and bytes.
    """
    rows = 366 * 96
    start = pd.Timestamp("2021-06-01", tz="Europe/Madrid")
    stamps = pd.date_range(start.tz_convert("UTC"), periods=rows, freq="1h").tz_convert("Europe/Madrid")
    frame = paper_case.history.frame.iloc[:0]
    rng = np.random.default_rng(1)
    columns = list(frame.columns) + [f"EXTRA{i}" for i in range(53 - len(frame.columns))]
    table = pd.DataFrame(rng.uniform(1, 50, (rows, len(columns))).round(3), columns=columns)
    table.insert(0, "timestamp", [t.isoformat() for t in stamps])
    csv = table.to_csv(index=False).encode()
    case = read_case_files({"case.yaml": CASE_YAML.encode(), "history.csv": csv})
    assert len(case.history.frame) == rows and len(case.history.columns) == 53


# ----------------------------------------------------------------------------- YAML that costs too much


def test_a_yaml_alias_bomb_is_refused_before_it_is_expanded():
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, "
              f"*a{i - 1}, *a{i - 1}, *a{i - 1}]" for i in range(1, 9)]
    err = refused({"case.yaml": "\n".join(lines).encode(), "history.csv": HISTORY}, CaseFileError)
    assert err.problems == ["case.yaml: holds more than 100,000 values once its aliases (*name) are expanded; "
                            "a case holds a few thousand"]


def test_yaml_nested_too_deep_is_refused():
    err = refused({"case.yaml": b"name: " + b"[" * 10_000 + b"]" * 10_000}, CaseFileError)
    assert err.problems == ["case.yaml: nested more than 32 levels deep (line 1); a case needs a few levels"]


def test_an_oversized_case_yaml_is_refused():
    err = refused({"case.yaml": b"# " + b"x" * (1024 ** 2), "history.csv": HISTORY}, CaseFileError)
    assert err.problems == ["case.yaml: is larger than 1024 KiB; a case.yaml is usually a few KiB"]


# ----------------------------------------------------------------------------- case folders on disk


@pytest.fixture
def folder(tmp_path):
    target = tmp_path / "case"
    shutil.copytree(PAPER, target)
    return target


def _refused_on_disk(folder: Path) -> CaseError:
    with pytest.raises(CasePathError) as info:
        load_case(folder)
    assert_leaks_nothing(info.value)
    return info.value


@pytest.mark.parametrize("path, words", [("/etc/hostname", "is an absolute path"),
                                         ("/proc/self/environ", "is an absolute path"),
                                         ("../outside.csv", 'steps out of the case folder with ".."')])
def test_a_case_folder_may_only_read_its_own_files(folder, path, words):
    shutil.copy(folder / "history.csv", folder.parent / "outside.csv")
    (folder / "case.yaml").write_bytes(with_history(path))
    err = _refused_on_disk(folder)
    assert err.problems == [f'case.yaml: history "{path}" {words}; name a file inside the case folder, relative '
                            "to case.yaml, e.g. history.csv"]


def test_a_link_out_of_the_case_folder_is_refused(folder):
    (folder / "history.csv").unlink()
    (folder / "history.csv").symlink_to(HOSTNAME if HOSTNAME.exists() else "/etc/passwd")
    err = _refused_on_disk(folder)
    assert err.problems == ['case.yaml: history "history.csv" is a link to a file outside the case folder; copy '
                            "the file into the folder"]
    (folder / "history.csv").unlink()
    (folder / "data").symlink_to("/etc")
    (folder / "case.yaml").write_bytes(with_history("data/hostname"))
    err = _refused_on_disk(folder)
    assert err.problems[0].startswith('case.yaml: history "data/hostname" is a link to a file outside')


def test_links_that_stay_inside_the_case_folder_are_fine(folder, paper_case):
    (folder / "data").mkdir()
    os.replace(folder / "history.csv", folder / "data" / "prices.csv")
    (folder / "history.csv").symlink_to(Path("data") / "prices.csv")
    assert load_case(folder) == paper_case


def test_the_shipped_case_still_loads(paper_case):
    assert paper_case.name == "paper" and paper_case.history.source == "history.csv"
    assert len(paper_case.history.frame) == 9504


# ----------------------------------------------------------------------------- messages quote nothing from outside


def test_a_csv_header_is_quoted_only_as_a_short_printable_excerpt():
    header = "tim\x1bestamp_" + "x" * 200
    err = refused({"case.yaml": CASE_YAML.encode(), "history.csv": f"{header},price_da\n1,2\n".encode()},
                  CaseError)
    assert err.problems == ['history.csv: no "timestamp" column (found "tim?estamp_xxxxxxxxxxxxxxxxxx…", '
                            '"price_da")']
    assert "\x1b" not in str(err)


def test_server_folders_are_off_unless_the_operator_turns_them_on(monkeypatch):
    from dashboard import state

    monkeypatch.delenv(state.SERVER_FOLDERS, raising=False)
    assert not state.server_folders_allowed()
    with pytest.raises(CasePathError) as info:
        state.load_folder("/etc")
    assert info.value.problems == ["loading a case folder from the server's disk is turned off; upload the case "
                                   "instead (the server's operator can turn folders on by starting it with "
                                   "RVPP_ALLOW_SERVER_FOLDERS=1)"]
    for value, allowed in (("0", False), ("yes", False), ("1", True)):
        monkeypatch.setenv(state.SERVER_FOLDERS, value)
        assert state.server_folders_allowed() is allowed
    with pytest.raises(CaseError, match="no shipped case '/etc'"):
        state.load_shipped("/etc")
