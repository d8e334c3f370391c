"""Cases as tables and files: unit tables, case workbooks and uploads round-trip exactly."""

from __future__ import annotations

import io
import zipfile

import pandas as pd
import pytest

import rvpp
from rvpp.outputs import bundle, workbook
from rvpp.data.history import History

CASE = "data/cases/paper"


@pytest.fixture(scope="module")
def case():
    """The paper case on a history just long enough for its delivery day (fast to write)."""
    full = rvpp.load_case(CASE)
    frame = full.history.frame.loc["2025-02-10":"2025-03-20"]
    return full.replace(history=History(frame, source="history.csv"))


@pytest.mark.parametrize("kind", ["wind", "pv", "csp", "ed", "td"])
def test_unit_table_round_trips(case, kind):
    table = workbook.unit_table(case, kind)
    assert list(table["name"]) == [u.name for u in getattr(case, kind)]
    assert list(table.columns) == workbook.unit_columns(kind)
    assert workbook.with_unit_table(case, kind, table) == case


def test_a_csps_start_status_and_end_of_day_storage_survive_the_table_and_the_workbook(case):
    """Fields a table leaves out are lost on the first edit: every field of the CSP is a column."""
    csp = case.csp[0]
    kept = case.replace(csp=[csp.model_copy(update={
        "storage": csp.storage.model_copy(update={"e_end_min_mwh_th": 300.0, "end_value_eur_per_mwh_th": 66.5}),
        "power_block": csp.power_block.model_copy(update={"initial_status_h": 2.0})})])
    table = workbook.unit_table(kept, "csp")
    assert (table.loc[0, "storage.e_end_min_mwh_th"], table.loc[0, "storage.end_value_eur_per_mwh_th"],
            table.loc[0, "power_block.initial_status_h"]) == (300.0, 66.5, 2.0)
    table.loc[0, "om_eur_per_mwh"] = 30.0  # an edit of another cell
    edited = workbook.with_unit_table(kept, "csp", table).csp[0]
    assert (edited.om_eur_per_mwh, edited.storage.e_end_min_mwh_th, edited.storage.end_value_eur_per_mwh_th,
            edited.power_block.initial_status_h) == (30.0, 300.0, 66.5, 2.0)
    assert workbook.read_case_workbook(workbook.case_workbook_bytes(kept)) == kept


def test_a_batterys_end_target_survives_the_table_and_the_workbook(case):
    battery = {"name": "BAT", "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 20.0, "p_dis_max_mw": 20.0,
               "e_init_mwh": 30.0, "ramp_mw_per_min": 4.0}
    kept = case.replace(battery=[battery, {**battery, "name": "BAT2", "e_end_min_mwh": 22.0}])
    table = workbook.unit_table(kept, "battery")
    assert pd.isna(table.loc[0, "e_end_min_mwh"]) and table.loc[1, "e_end_min_mwh"] == 22.0
    table.loc[0, "e_end_min_mwh"] = 13.0  # set in the table
    edited = workbook.with_unit_table(kept, "battery", table)
    assert [u.e_end_min_mwh for u in edited.battery] == [13.0, 22.0]
    assert workbook.read_case_workbook(workbook.case_workbook_bytes(kept)) == kept


def test_unit_table_shows_the_history_column_of_each_unit(case):
    renamed = workbook.unit_table(case, "wind")
    assert list(renamed["series"]) == ["WF1", "WF2"]
    renamed.loc[0, "name"] = "North"
    edited = workbook.with_unit_table(case, "wind", renamed)
    assert edited.wind[0].name == "North" and edited.wind[0].column == "WF1"
    assert case.wind[0].series is None and edited.wind[1].series is None


def test_an_edit_changes_the_case_and_an_invalid_one_names_the_rule(case):
    table = workbook.unit_table(case, "csp")
    table.loc[0, "storage.e_min_mwh_th"] = 1200.0
    with pytest.raises(rvpp.CaseError) as err:
        workbook.with_unit_table(case, "csp", table)
    assert err.value.problems == ['csp "CSP1": storage.e_min_mwh_th=1200 must be < storage.e_max_mwh_th=1100']
    table.loc[0, "storage.e_min_mwh_th"] = 100.0  # below the case's initial energy of 110 MWh_th
    assert workbook.with_unit_table(case, "csp", table).csp[0].storage.e_min_mwh_th == 100.0
    table.loc[0, "storage.e_min_mwh_th"] = 200.0
    with pytest.raises(rvpp.CaseError) as err:
        workbook.with_unit_table(case, "csp", table)
    assert err.value.problems == ['csp "CSP1": storage.e_init_mwh_th=110 must lie in '
                                  '[storage.e_min_mwh_th=200, storage.e_max_mwh_th=1100]']


def test_added_and_removed_rows(case):
    table = workbook.unit_table(case, "pv")
    row = workbook.new_unit_row(case, "pv")
    assert row["name"] == "PV4" and row["series"] == "PV1"
    grown = workbook.with_unit_table(case, "pv", pd.concat([table, pd.DataFrame([row])], ignore_index=True))
    assert [u.name for u in grown.pv] == ["PV1", "PV2", "PV3", "PV4"]
    assert grown.pv[3].column == "PV1" and grown.pv[3].p_max_mw == 50.0
    with_override = rvpp.with_options(case, gammas={"PV3": 7})
    shrunk = workbook.with_unit_table(with_override, "pv", table.iloc[:2])
    assert [u.name for u in shrunk.pv] == ["PV1", "PV2"]
    assert "PV3" not in shrunk.budgets.override_map


def test_a_new_csp_gets_a_curve_and_an_empty_required_cell_is_reported(case):
    table = workbook.unit_table(case, "csp")
    row = workbook.new_unit_row(case, "csp")
    grown = workbook.with_unit_table(case, "csp", pd.concat([table, pd.DataFrame([row])], ignore_index=True))
    assert grown.csp[1].name == "CSP2"
    assert grown.csp[1].power_block.breakpoints == case.csp[0].power_block.breakpoints
    table.loc[0, "power_block.p_el_max_mw"] = None
    with pytest.raises(rvpp.CaseError, match=r'csp "CSP1": power_block.p_el_max_mw is required'):
        workbook.with_unit_table(case, "csp", table)


def test_breakpoints_are_edited_through_the_case_model(case):
    table = workbook.breakpoint_table(case, "CSP1")
    assert len(table) == len(case.csp[0].power_block.breakpoints)
    table.loc[3, "efficiency"] = 0.36
    assert workbook.with_breakpoints(case, "CSP1", table).csp[0].power_block.breakpoints[3] == (40.0, 0.36)
    table.loc[3, "input_mw_th"] = 10.0
    with pytest.raises(rvpp.CaseError, match="strictly increasing"):
        workbook.with_breakpoints(case, "CSP1", table)


def test_case_workbook_round_trips(case):
    data = workbook.case_workbook_bytes(case)
    sheets = pd.read_excel(io.BytesIO(data), sheet_name=None)
    assert list(sheets) == ["case", "hpa_tariff", "budgets", "wind", "pv", "csp", "ed", "td", "breakpoints",
                            "history"]
    assert list(sheets["case"].columns) == ["field", "value"]
    edited = rvpp.with_options(case, gammas={"WF1": 5}, markets="DAM,HPA", strategy="pessimistic")
    back = workbook.read_case_workbook(workbook.case_workbook_bytes(edited))
    assert back == edited
    assert back.history.fingerprint == case.history.fingerprint


def test_a_broken_workbook_is_explained(case):
    with pytest.raises(rvpp.CaseError, match=r"cannot be read as an Excel workbook \(.xlsx\) \(it seems to be text"):
        workbook.read_case_workbook(b"not a workbook", label="plan.xlsx")
    buffer = io.BytesIO()
    with pd.ExcelWriter(buffer, engine="openpyxl") as writer:
        pd.DataFrame({"field": ["name"], "value": ["x"]}).to_excel(writer, sheet_name="case", index=False)
    with pytest.raises(rvpp.CaseError, match="sheet 'hpa_tariff' is missing"):
        workbook.read_case_workbook(buffer.getvalue())


def test_zip_upload_round_trips(case):
    data = bundle.case_zip_bytes(case)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        assert sorted(archive.namelist()) == ["paper/case.yaml", "paper/history.csv"]
    assert bundle.read_case_files({"paper.zip": data}) == case


def test_yaml_and_csv_upload(case):
    with zipfile.ZipFile(io.BytesIO(bundle.case_zip_bytes(case))) as archive:
        files = {name.split("/")[-1]: archive.read(name) for name in archive.namelist()}
    assert bundle.read_case_files(files) == case
    with pytest.raises(rvpp.CaseError) as err:
        bundle.read_case_files({"case.yaml": files["case.yaml"]})
    assert err.value.problems[0] == 'history file "history.csv" is not among the uploaded files'
    assert err.value.problems[-1] == "the files uploaded are: case.yaml"


def test_broken_uploads_are_explained(case):
    with pytest.raises(rvpp.CaseError, match="cannot be read as a zip archive"):
        bundle.read_case_files({"case.zip": b"PK-not-really"})
    with pytest.raises(rvpp.CaseError, match="no case found in notes.txt"):
        bundle.read_case_files({"notes.txt": b"hello"})
    with zipfile.ZipFile(io.BytesIO(bundle.case_zip_bytes(case))) as archive:
        text = archive.read("paper/case.yaml").decode().replace("p_max_mw: 50", "p_max_mw: -50", 1)
        history = archive.read("paper/history.csv")
    with pytest.raises(rvpp.CaseError) as err:
        bundle.read_case_files({"case.yaml": text.encode(), "history.csv": history})
    assert err.value.problems == ['wind "WF1": p_max_mw=-50 must be > 0']
    with pytest.raises(rvpp.CaseError, match="not valid YAML"):
        bundle.read_case_files({"case.yaml": b"name: [unclosed", "history.csv": history})


@pytest.mark.parametrize("files, expected", [
    ({"case.yaml": "name: Añón\n".encode("latin-1")},
     "case.yaml: not UTF-8 text: byte 8 (line 1, column 8) is 0xF1, which looks like Latin-1/Windows-1252; save the file as UTF-8"),
    ({"case.yaml": "name: x\n".encode("utf-16")}, "case.yaml: is UTF-16 text, not UTF-8 text"),
    ({"case.yaml": b"history: history.csv\n", "history.csv": b"PK\x05\x06" + b"\0" * 18},
     "history.csv: is an empty zip archive, not UTF-8 text"),
    ({"case.yaml": b"name: a\nname: b\n"}, 'case.yaml: key "name" is written twice in one mapping (lines 1 and 2); '
                                         "keep one"),
])
def test_uploaded_files_that_are_not_utf8_text_are_named(files, expected):
    with pytest.raises(rvpp.CaseError) as err:
        bundle.read_case_files(files)
    assert err.value.problems == [expected]


def test_an_uploaded_workbook_names_a_field_given_twice(case):
    import openpyxl

    book = openpyxl.load_workbook(io.BytesIO(workbook.case_workbook_bytes(case)))
    book["case"].append(["name", "again"])
    rows = book["case"].max_row
    buffer = io.BytesIO()
    book.save(buffer)
    with pytest.raises(rvpp.CaseError) as err:
        bundle.read_case_files({"case.xlsx": buffer.getvalue()})
    assert err.value.problems == [f"case.xlsx: sheet 'case' gives the field 'name' twice (rows 2 and {rows}); keep one"]


def test_a_workbook_of_another_kind_is_refused_for_its_missing_sheets_not_for_its_contents():
    # The authors' tool workbook was refused for "sheet 'Global_params' has the column 'Global parameters' twice":
    # true, but not why it is no case workbook.
    import openpyxl

    book = openpyxl.Workbook()
    book.active.title = "Global_params"
    book.active.append(["Global parameters", "value", None, None, None, "Global parameters"])
    book.create_sheet("hpa_tariff")
    buffer = io.BytesIO()
    book.save(buffer)
    with pytest.raises(rvpp.CaseError) as err:
        bundle.read_case_files({"RVPP_data.xlsx": buffer.getvalue()})
    [message] = err.value.problems
    assert message.startswith("RVPP_data.xlsx: sheet 'case' is missing (a case workbook has the sheets case, "
                              "hpa_tariff, budgets, "), message
    assert "authors' RVPP tool" in message and "python -m rvpp data import-workbook" in message
    assert "twice" not in message
