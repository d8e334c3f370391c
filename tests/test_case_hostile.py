"""Hostile or careless case inputs found by an audit: each is refused by a named rule, never a traceback.

YAML type tags (``!!float abc``, ``!!set 5``), a ``case.yaml`` that links out of its folder,
control characters in text that is later exported to Excel, a section of the workbook's
``case`` sheet given as one value, true/false where a number belongs and power-block
breakpoints of absurd size.
"""

from __future__ import annotations

import copy
import io
import os
import shutil
import zipfile
from pathlib import Path

import openpyxl
import pandas as pd
import pytest
import yaml

from rvpp import load_case
from rvpp.cli import main
from rvpp.data.case import parse_case
from rvpp.data.case_yaml import read_case_yaml
from rvpp.data.history import History
from rvpp.errors import CaseError, CaseFileError, CasePathError
from rvpp.outputs import workbook
from rvpp.outputs.bundle import case_zip_bytes, read_case_files

from tests.factories import PAPER, click, open_app

CASE_YAML = (PAPER / "case.yaml").read_text(encoding="utf-8")
RAW = yaml.safe_load(CASE_YAML)
NAME_LINE = CASE_YAML.splitlines().index("name: paper") + 1  # line 4 of the shipped case


def with_name(written: str) -> bytes:
    """The paper's case.yaml with its ``name:`` line written as ``name: <written>``."""
    assert CASE_YAML.count("name: paper\n") == 1
    return CASE_YAML.replace("name: paper\n", f"name: {written}\n").encode()


@pytest.fixture(scope="module")
def short_history(paper_case):
    """The paper history around its delivery date: enough for the bands, quick to parse."""
    frame = paper_case.history.frame
    start = pd.Timestamp(paper_case.delivery_date, tz="UTC") - pd.Timedelta(days=35)
    return History(frame[(frame.index >= start) & (frame.index < start + pd.Timedelta(days=40))],
                   source="history.csv")


@pytest.fixture(scope="module")
def short_csv(short_history, tmp_path_factory):
    path = tmp_path_factory.mktemp("history") / "history.csv"
    short_history.to_csv(path, "Europe/Madrid")
    return path.read_bytes()


def refused_upload(text: bytes, csv: bytes, kind: type[CaseError] = CaseError) -> CaseError:
    """The error of uploading ``text`` as case.yaml with ``csv`` (the dashboard's path)."""
    with pytest.raises(kind) as info:
        read_case_files({"case.yaml": text, "history.csv": csv})
    assert "Traceback" not in str(info.value)
    return info.value


def refused_data(data: dict, history: History) -> list[str]:
    with pytest.raises(CaseError) as info:
        parse_case(data, history)
    return info.value.problems


# ----------------------------------------------------------------------------- 1. YAML type tags


@pytest.mark.parametrize("written, problem", [
    ("!!float abc", "'abc' is not a number"),
    ('!!int ""', "'' is not a whole number"),
    ("!!int 0x", "'0x' is not a whole number"),
    ("!!bool maybe", "'maybe' is not true or false"),
    ("!!map 5", "!!map must be a mapping (key: value lines), not a single value"),
    ("!!map [1, 2]", "!!map must be a mapping (key: value lines), not a list"),
])
def test_a_value_its_standard_tag_cannot_build_is_refused_at_its_line(short_csv, written, problem):
    err = refused_upload(with_name(written), short_csv, CaseFileError)
    assert err.problems == [f"case.yaml: not valid YAML at line {NAME_LINE}, column 7 ({problem})"]


@pytest.mark.parametrize("written, shown", [
    ("!!timestamp x", "!!timestamp"), ("!!set 5", "!!set"), ("!!set {a: 1}", "!!set"),
    ('!!binary "aGVsbG8="', "!!binary"), ("!!omap [{a: 1}]", "!!omap"), ("!!pairs [{a: 1}]", "!!pairs"),
    ("!!python/object/apply:os.system [ls]", "!!python/object/apply:os.system"), ("!custom x", "!custom"),
    ("!<tag:example.com,2000:x> y", "tag:example.com,2000:x"),
])
def test_a_tag_that_builds_no_plain_data_is_refused_by_name(short_csv, written, shown):
    err = refused_upload(with_name(written), short_csv, CaseFileError)
    assert err.problems == [f"case.yaml: the YAML tag {shown} at line {NAME_LINE}, column 7 is not allowed in a "
                            "case; remove it (a case holds text, numbers, true/false, dates, lists and mappings; "
                            "put text in quotes)"]


def test_a_tag_is_refused_on_a_key_and_inside_a_unit_too():
    text = CASE_YAML.replace("  kappa: 0.3\n", "  !!set kappa: 0.3\n").encode()
    with pytest.raises(CaseFileError, match=r"^case\.yaml: the YAML tag !!set at line \d+, column 3 is not allowed"):
        read_case_yaml(text, "case.yaml")
    text = CASE_YAML.replace("{name: WF1, p_max_mw: 50,", "{name: WF1, p_max_mw: !!float fifty,").encode()
    line, row = next((i, row) for i, row in enumerate(text.decode().splitlines(), start=1) if "name: WF1" in row)
    with pytest.raises(CaseFileError) as info:
        read_case_yaml(text, "case.yaml")
    assert info.value.problems == [f"case.yaml: not valid YAML at line {line}, column {row.index('!!float') + 1} "
                                   "('fifty' is not a number)"]


def test_an_impossible_date_written_plainly_is_refused_at_its_line(short_csv):
    text = CASE_YAML.replace("delivery_date: 2025-05-05", "delivery_date: 2025-02-30").encode()
    line = CASE_YAML.splitlines().index("delivery_date: 2025-05-05") + 1
    err = refused_upload(text, short_csv, CaseFileError)
    assert err.problems == [f"case.yaml: not valid YAML at line {line}, column 16 ('2025-02-30' is not a valid date "
                            "or time (a date is written 2025-03-18))"]


def test_tags_of_plain_data_still_work(short_csv):
    case = read_case_files({"case.yaml": with_name("!!str 2025"), "history.csv": short_csv})
    assert case.name == "2025"


def test_the_command_line_names_a_bad_tag_without_a_traceback(tmp_path, capsys):
    folder = tmp_path / "case"
    folder.mkdir()
    (folder / "case.yaml").write_bytes(with_name("!!set 5"))
    shutil.copy(PAPER / "history.csv", folder / "history.csv")
    code = main(["solve", "--case", str(folder), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0
    assert err.strip() == (f"error: case.yaml: the YAML tag !!set at line {NAME_LINE}, column 7 is not allowed in a "
                           "case; remove it (a case holds text, numbers, true/false, dates, lists and mappings; "
                           "put text in quotes)")
    assert not (tmp_path / "out").exists()


# ----------------------------------------------------------------------------- 2. case.yaml linked out of the folder

SECRET = "s3cr3t-token-0123456789"
OUTSIDE = f"api_token: {SECRET}\npassword: hunter2-hunter2\n"


@pytest.fixture
def linked_out(tmp_path):
    """A case folder whose case.yaml is a link to a YAML file outside it."""
    outside = tmp_path / "private" / "settings.yaml"
    outside.parent.mkdir()
    outside.write_text(OUTSIDE, encoding="utf-8")
    folder = tmp_path / "case"
    folder.mkdir()
    shutil.copy(PAPER / "history.csv", folder / "history.csv")
    (folder / "case.yaml").symlink_to(outside)
    return folder


@pytest.mark.parametrize("given", ["folder", "file"])
def test_a_case_yaml_linked_out_of_its_folder_is_refused_and_nothing_of_it_is_shown(linked_out, given):
    with pytest.raises(CasePathError) as info:
        load_case(linked_out if given == "folder" else linked_out / "case.yaml")
    message = "\n".join(info.value.problems) + str(info.value)
    assert info.value.problems == ["case.yaml: is a link to a file outside the case folder; copy the file into the "
                                   "folder"]
    for leaked in ("api_token", SECRET, "password", "hunter2", "private", "settings.yaml"):
        assert leaked not in message


def test_the_command_line_refuses_a_linked_case_yaml(linked_out, tmp_path, capsys):
    code = main(["solve", "--case", str(linked_out), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0 and "is a link to a file outside the case folder" in err
    assert "api_token" not in err and SECRET not in err


def test_a_case_yaml_linked_inside_its_folder_and_a_linked_folder_still_load(tmp_path, paper_case):
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    (folder / "settings").mkdir()
    os.replace(folder / "case.yaml", folder / "settings" / "case.yaml")
    (folder / "case.yaml").symlink_to(Path("settings") / "case.yaml")
    assert load_case(folder) == paper_case
    (tmp_path / "alias").symlink_to(folder, target_is_directory=True)
    assert load_case(tmp_path / "alias") == paper_case


# ----------------------------------------------------------------------------- 3. control characters in text


@pytest.mark.parametrize("field, value, problem", [
    ("name", "paper\x01", "name: must not contain control characters (found U+0001)"),
    ("name", "paper\x1b[31m", "name: must not contain control characters (found U+001B)"),
    ("name", "line\nbreak", "name: must not contain control characters (found U+000A)"),
    ("name", "nel\x85", "name: must not contain control characters (found U+0085)"),
    ("description", "a case\x07", "description: must not contain control characters (found U+0007)"),
    ("description", "\x9b2J", "description: must not contain control characters (found U+009B)"),
])
def test_control_characters_in_the_case_text_are_refused(short_history, field, value, problem):
    data = copy.deepcopy(RAW)
    data[field] = value
    assert refused_data(data, short_history) == [problem]


def test_control_characters_in_a_mip_start_series_or_provenance_are_refused(short_history):
    data = copy.deepcopy(RAW)
    data["solver"]["mip_start"] = ["online[CSP1,1]", "online[CSP1,2]\x00"]
    assert refused_data(data, short_history) == [
        "solver: mip_start item 2: must not contain control characters (found U+0000)"]
    data = copy.deepcopy(RAW)
    data["units"]["wind"][0]["series"] = "WF1\x7f"
    assert refused_data(data, short_history) == [
        'wind "WF1": series: must not contain control characters (found U+007F)']
    data = copy.deepcopy(RAW)
    data["provenance"] = {"WF1": {"origin": "synthetic", "source": "made\x0c", "note": "ok"}}
    [problem] = refused_data(data, short_history)
    assert problem.startswith("provenance") and problem.endswith(
        "source: must not contain control characters (found U+000C)")


def test_a_control_character_written_as_a_yaml_escape_is_refused_on_upload(short_csv):
    err = refused_upload(with_name('"paper\\x01"'), short_csv)
    assert err.problems == ["name: must not contain control characters (found U+0001)"]


def test_ordinary_unicode_text_spaces_and_line_breaks_in_a_description_are_fine(short_history):
    data = copy.deepcopy(RAW)
    data["name"] = "Planta solar Écija – 日本 ‍ test"
    data["description"] = "Written on Windows,\r\nwith a line break."
    assert parse_case(data, short_history).description == data["description"]
    data["description"] = "First line,\twith a tab.\nSecond line."
    data["solver"]["mip_start"] = ["online[CSP1,1]"]
    case = parse_case(data, short_history)
    assert case.name == data["name"] and case.description == data["description"]
    back = workbook.read_case_workbook(workbook.case_workbook_bytes(case))  # Excel takes them
    assert back.name == case.name and back.description == case.description


# ----------------------------------------------------------------------------- 4. workbook sections as values


def edited_workbook(case, rows: list[tuple[str, object]], drop_prefix: str | None) -> tuple[bytes, int]:
    """The case workbook of ``case`` with the rows of its ``case`` sheet under ``drop_prefix`` removed
    and ``rows`` appended; and the row number of the first appended row."""
    book = openpyxl.load_workbook(io.BytesIO(workbook.case_workbook_bytes(case)))
    sheet = book["case"]
    kept = [(f, v) for f, v in sheet.iter_rows(min_row=2, values_only=True)
            if drop_prefix is None or not str(f).startswith(drop_prefix + ".")]
    sheet.delete_rows(2, sheet.max_row)
    for row in kept + rows:
        sheet.append(row)
    buffer = io.BytesIO()
    book.save(buffer)
    return buffer.getvalue(), len(kept) + 2


@pytest.fixture(scope="module")
def small_case(paper_case, short_history):
    return paper_case.replace(history=short_history)


@pytest.mark.parametrize("section, example", [("markets", "markets.kappa"), ("budgets", "budgets.strategy"),
                                              ("uncertainty", "uncertainty.window_days"),
                                              ("solver", "solver.time_limit_s")])
def test_a_section_given_as_one_value_in_the_case_sheet_is_refused(small_case, section, example):
    data, row = edited_workbook(small_case, [(section, "x")], drop_prefix=section)
    with pytest.raises(CaseError) as info:
        read_case_files({"case.xlsx": data})
    assert info.value.problems == [f"case.xlsx: sheet 'case': {section} must be a section of fields ({example}, ...), "
                                   f"not a value (row {row})"]


@pytest.mark.parametrize("field, sheets", [("units", "the sheets wind, pv, csp, ed, td, battery, hydro and biomass"),
                                           ("units.wind", "the sheets wind, pv, csp, ed, td, battery, hydro and biomass"),
                                           ("markets.hpa_tariff_eur_per_mwh", "the sheet 'hpa_tariff'")])
def test_a_row_for_what_another_sheet_holds_is_refused_not_overwritten(small_case, field, sheets):
    data, row = edited_workbook(small_case, [(field, 5)], drop_prefix=None)
    with pytest.raises(CaseError) as info:
        workbook.read_case_workbook(data, label="case.xlsx")
    assert info.value.problems == [f"case.xlsx: sheet 'case': {field} is read from {sheets}, not from a row of this "
                                   f"sheet (row {row}); remove the row"]


# ----------------------------------------------------------------------------- 5. loose numbers


@pytest.mark.parametrize("edit, problem", [
    (lambda d: d["units"]["wind"][0].update(p_max_mw=True), 'wind "WF1": p_max_mw=True must be a number'),
    (lambda d: d["units"]["ed"][0].update(p_init_mw=False), 'ed "ED_industry": p_init_mw=False must be a number'),
    (lambda d: d["units"]["csp"][0]["storage"].update(eta_ch=True),
     'csp "CSP1": storage.eta_ch=True must be a number'),
    (lambda d: d["units"]["csp"][0]["power_block"]["breakpoints"][2].__setitem__(1, True),
     'csp "CSP1": power_block.breakpoints point 3 efficiency=True must be a number'),
    (lambda d: d["uncertainty"].update(window_days=True), "uncertainty: window_days=True must be a whole number"),
    (lambda d: d["solver"].update(threads=True), "solver: threads=True must be a whole number"),
    (lambda d: d["budgets"].update(fraction=True), "budgets: fraction=True must be a number"),
    (lambda d: d.update(dt_h=True), "dt_h=True must be a number"),
])
def test_true_or_false_is_not_a_number(short_history, edit, problem):
    data = copy.deepcopy(RAW)
    edit(data)
    assert refused_data(data, short_history) == [problem]


def test_breakpoint_inputs_are_bounded_like_every_quantity(short_history):
    data = copy.deepcopy(RAW)
    data["units"]["csp"][0]["power_block"]["breakpoints"][-1] = [1e300, 0.395]
    assert refused_data(data, short_history) == [
        'csp "CSP1": power_block.breakpoints point 6 input=1e+300 must be <= 1e+06']
    data["units"]["csp"][0]["power_block"]["breakpoints"][-1] = [1e6, 0.395]
    assert parse_case(data, short_history).csp[0].power_block.breakpoints[-1] == (1e6, 0.395)


def test_numbers_written_as_text_still_count(short_history):
    data = copy.deepcopy(RAW)
    data["units"]["wind"][0]["p_max_mw"] = "50"
    data["uncertainty"]["window_days"] = "30"
    case = parse_case(data, short_history)
    assert case.wind[0].p_max_mw == 50.0 and case.uncertainty.window_days == 30


# ----------------------------------------------------------------------------- the dashboard's upload


def test_the_home_page_explains_a_bad_tag_and_a_section_given_as_a_value(small_case, short_csv, data_dir):
    from tests.test_app import errors

    at = open_app()
    before = at.session_state["case"]
    at.file_uploader(key="home_upload").set_value([("case.yaml", with_name("!!float abc"), "text/yaml"),
                                                   ("history.csv", short_csv, "text/csv")]).run()
    click(at, "home_load_upload")
    assert f"not valid YAML at line {NAME_LINE}, column 7 ('abc' is not a number)" in errors(at)
    data, _ = edited_workbook(small_case, [("markets", "x")], drop_prefix="markets")
    at.file_uploader(key="home_upload").set_value([("case.xlsx", data, "application/octet-stream")]).run()
    click(at, "home_load_upload")
    assert "sheet 'case': markets must be a section of fields (markets.kappa, ...), not a value" in errors(at)
    assert at.session_state["case"] == before


@pytest.mark.parametrize("name, folder", [("../../evil", "_.._evil"), ("/etc/cron.d/x", "_etc_cron.d_x"),
                                          ("año 2025", "a_o_2025"), ("...", "case")])
def test_a_case_downloaded_as_a_zip_stays_in_one_folder_whatever_its_name(paper_case, name, folder):
    with zipfile.ZipFile(io.BytesIO(case_zip_bytes(paper_case.replace(name=name)))) as archive:
        assert sorted(archive.namelist()) == [f"{folder}/case.yaml", f"{folder}/history.csv"]


@pytest.mark.parametrize("field", ["series", "forecast_series"])
def test_a_unit_cannot_follow_a_price_column(paper_case, field):
    wind = [unit.model_dump() for unit in paper_case.wind]
    wind[0][field] = "price_da"
    with pytest.raises(CaseError, match="^wind \"WF1\": follows the price column 'price_da'; a unit follows a "
                                        "column of output, demand or heat"):
        paper_case.replace(wind=wind)


def test_a_case_folder_with_a_bad_history_cell_names_the_case_files_problems_first(tmp_path):
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    settings = (folder / "case.yaml").read_text()
    (folder / "case.yaml").write_text(settings.replace("kappa: 0.3", "kappa: 1.5"))
    history = (folder / "history.csv").read_text().splitlines()
    history[3] = history[3].replace(",", ",x", 1)  # the day-ahead price of the file's third hour, 02:00
    (folder / "history.csv").write_text("\n".join(history) + "\n")
    with pytest.raises(CaseError) as refused:
        load_case(folder)
    problems = refused.value.problems
    assert problems == ["markets: kappa=1.5 must be <= 1", 'history.csv: column "price_da" has a non-numeric value '
                        f"'x{history[3].split(',')[1][1:]}' at 2024-12-01T02:00:00+01:00"], problems
