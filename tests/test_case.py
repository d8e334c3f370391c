"""Case validation: every bad input is refused with unit, field, value and rule named."""

from __future__ import annotations

import copy
import datetime as dt
import gzip
import shutil

import numpy as np
import pandas as pd
import pytest
import yaml

from rvpp import CaseError, load_case, prepare, save_case, with_options
from rvpp.errors import CaseFileError
from rvpp.data.case import parse_case

from tests.factories import PAPER


@pytest.fixture(scope="module")
def raw():
    return yaml.safe_load((PAPER / "case.yaml").read_text())


def problems_of(raw_data, history, edit):
    data = copy.deepcopy(raw_data)
    edit(data)
    with pytest.raises(CaseError) as info:
        parse_case(data, history)
    return info.value.problems


def unit(data, kind, name):
    return next(u for u in data["units"][kind] if u["name"] == name)


BAD_INPUTS = {
    "negative capacity": (
        lambda d: unit(d, "wind", "WF1").update(p_max_mw=-5),
        'wind "WF1": p_max_mw=-5 must be > 0'),
    "minimum above maximum": (
        lambda d: unit(d, "ed", "ED_service").update(p_min_mw=90),
        'ed "ED_service": p_min_mw=90 must be <= p_max_mw=80'),
    "efficiency above one": (
        lambda d: d["units"]["csp"][0]["storage"].update(eta_ch=1.2),
        'csp "CSP1": storage.eta_ch=1.2 must be <= 1'),
    "breakpoint efficiency above one": (
        lambda d: d["units"]["csp"][0]["power_block"].update(
            breakpoints=[[0, 0], [19, 0.27], [40, 1.4], [140, 0.395]]),
        "efficiency 1.4 at 40 MW_th (point 3) must be a fraction in [0, 1]"),
    "breakpoints not increasing": (
        lambda d: d["units"]["csp"][0]["power_block"].update(
            breakpoints=[[0, 0], [19, 0.27], [70, 0.34], [40, 0.38], [140, 0.395]]),
        "input 40 (point 4) must be greater than the previous input 70"),
    "storage minimum above maximum": (
        lambda d: d["units"]["csp"][0]["storage"].update(e_min_mwh_th=1200),
        'csp "CSP1": storage.e_min_mwh_th=1200 must be < storage.e_max_mwh_th=1100'),
    "duplicate names": (
        lambda d: unit(d, "pv", "PV2").update(name="PV1"),
        'pv "PV1": name is used by more than one unit; names must be unique'),
    "unknown unit in a budget": (
        lambda d: d["budgets"].update(overrides={"WF9": 3}),
        "budgets.overrides: unknown source 'WF9'"),
    "negative budget": (
        lambda d: d["budgets"].update(overrides={"WF1": -1}),
        "budgets: overrides.WF1=-1 must be >= 0 [periods]"),
    "unknown field": (
        lambda d: unit(d, "pv", "PV3").update(p_max_mv=50),
        'pv "PV3": unknown field "p_max_mv"'),
    "share outside [0, 1]": (
        lambda d: unit(d, "pv", "PV3").update(reserve_share=10),
        'pv "PV3": reserve_share=10 must be <= 1'),
    "text where a number belongs": (
        lambda d: unit(d, "td", "TD_industry").update(h_max_mw_th="lots"),
        "td \"TD_industry\": h_max_mw_th='lots' must be a number"),
    "missing field": (
        lambda d: unit(d, "ed", "ED_residential").pop("e_min_mwh"),
        'ed "ED_residential": e_min_mwh is required'),
    "invalid period length": (
        lambda d: d.update(dt_h=0.3),
        "dt_h=0.3 must be one of 1, 0.5, 0.25 [h]"),
    "unknown time zone": (
        lambda d: d.update(timezone="Europe/Atlantis"),
        "timezone='Europe/Atlantis' is not an IANA time zone"),
    "tariff with the wrong length": (
        lambda d: d["markets"].update(hpa_tariff_eur_per_mwh=[70] * 23),
        "markets: hpa_tariff_eur_per_mwh has 23 values; give 24, one per clock hour 00:00 to 23:00"),
    "percentiles swapped": (
        lambda d: d["uncertainty"].update(q_lo=0.8, q_hi=0.2),
        "uncertainty: q_lo=0.8 must be < 0.5"),
    "unit named like a price": (
        lambda d: unit(d, "wind", "WF2").update(name="price_da", series="WF2"),
        'wind "price_da": name is reserved for a price series'),
    "missing history column": (
        lambda d: unit(d, "wind", "WF2").update(series="WF7"),
        "wind \"WF2\": history column 'WF7' is missing from history.csv"),
    "minimum up time not a whole number of periods": (
        lambda d: d["units"]["csp"][0]["power_block"].update(min_up_h=2.5),
        'csp "CSP1": power_block.min_up_h=2.5 must be a multiple of dt_h=1'),
    "a unit of another kind in a list": (
        lambda d: unit(d, "wind", "WF2").update(kind="pv"),
        "wind \"WF2\": kind='pv' must be 'wind' in the wind list"),
    "a turbine minimum up time longer than the day": (
        lambda d: d["units"]["csp"][0]["power_block"].update(min_up_h=30),
        'csp "CSP1": power_block.min_up_h=30 must be <= 24'),
    "a turbine minimum down time longer than the day": (
        lambda d: d["units"]["csp"][0]["power_block"].update(min_down_h=25),
        'csp "CSP1": power_block.min_down_h=25 must be <= 24'),
    "a delivery date no history can reach": (
        lambda d: d.update(delivery_date="9999-12-31"),
        "delivery_date=9999-12-31 must lie between 1900-01-01 and 2199-12-31"),
    "a start-up shorter than one period": (
        lambda d: d["units"]["csp"][0]["power_block"].update(startup_duration_h=1e-300),
        'csp "CSP1": power_block.startup_duration_h=1e-300 must be at least one period, dt_h=1'),
    "a capacity beyond any plant": (
        lambda d: unit(d, "wind", "WF1").update(p_max_mw=1e308),
        'wind "WF1": p_max_mw=1e+308 must be <= 1e+06'),
    "unknown unit kind": (
        lambda d: d["units"].update(boiler=[{"name": "B1"}]),
        'units: unknown unit kind "boiler"'),
    "the DAM switched off": (
        lambda d: d["markets"].update(dam=False),
        "markets: dam=False must be True"),
}


# Inputs whose every problem is known: the messages must be exactly these lines, named as
# written in case.yaml (no internal index, no second line that is not true).
EXACT = {
    "a negative tariff hour": (
        lambda d: d["markets"]["hpa_tariff_eur_per_mwh"].__setitem__(7, -5),
        ["markets: hpa_tariff_eur_per_mwh hour 07:00 = -5 must be >= 0"]),
    "tariffs that are not numbers": (
        lambda d: d["markets"].update(hpa_tariff_eur_per_mwh=["x", float("nan"), True] + [70] * 21),
        ["markets: hpa_tariff_eur_per_mwh hour 00:00 = 'x' must be a number",
         "markets: hpa_tariff_eur_per_mwh hour 01:00 = nan must be a finite number",
         "markets: hpa_tariff_eur_per_mwh hour 02:00 = True must be a number"]),
    "a tariff that is not a list": (
        lambda d: d["markets"].update(hpa_tariff_eur_per_mwh=70),
        ["markets: hpa_tariff_eur_per_mwh must be a list of 24 tariffs [EUR/MWh_th], one per clock hour 00:00 to "
         "23:00; got a number"]),
    "a budget override named by its source": (
        lambda d: d["budgets"].update(overrides={"WF1": 3, "PV2": -1, "price_da": 2.5}),
        ["budgets: overrides.PV2=-1 must be >= 0 [periods]",
         "budgets: overrides.price_da=2.5 must be a whole number [periods]"]),
    "overrides written as a list": (
        lambda d: d["budgets"].update(overrides=["WF1", 3]),
        ["budgets: overrides must be a mapping of source: Γ [periods], e.g. {price_da: 6, WF1: 3}; got a list"]),
    "no units section": (
        lambda d: d.pop("units"),
        ["units: section is required; list the units of the case under wind, pv, csp, ed, td, battery, hydro, biomass"]),
    "an empty units section": (
        lambda d: d.update(units={}),
        ["units: no unit is listed; a case needs at least one unit under wind, pv, csp, ed, td, battery, hydro, biomass"]),
    "every unit list empty": (
        lambda d: d.update(units={"wind": [], "pv": None, "csp": []}),
        ["units: no unit is listed; a case needs at least one unit under wind, pv, csp, ed, td, battery, hydro, biomass"]),
    "a blank markets section": (
        lambda d: d.update(markets=None),
        ["markets: section is empty; it needs at least hpa_tariff_eur_per_mwh"]),
    "a section that is a list": (
        lambda d: d.update(uncertainty=[1, 2]),
        ["uncertainty: must be a mapping of fields; got a list"]),
    "a breakpoint located by point and coordinate": (
        lambda d: d["units"]["csp"][0]["power_block"].update(breakpoints=[[0, 0], [19, "high"], [140, 0.4]]),
        ['csp "CSP1": power_block.breakpoints point 2 efficiency=\'high\' must be a number']),
    "a unit without a name is located by its place in the list": (
        lambda d: d["units"]["pv"][1].pop("name"),
        ["units.pv item 2: name is required"]),
    "a unit that is not a mapping": (
        lambda d: d["units"]["ed"].append("ED4"),
        ["units.ed item 4: must be a mapping of fields (name: ..., ...); got text"]),
    "a number where text belongs": (
        lambda d: d.update(name=2025),
        ["name=2025 must be text (put it in quotes if it looks like a number or a date)"]),
    "a delivery date written as a number": (
        lambda d: d.update(delivery_date=0),
        ["delivery_date=0 must be a date such as 2025-03-18"]),
    "a delivery date with a time of day": (
        lambda d: d.update(delivery_date=dt.datetime(2025, 5, 5)),
        ["delivery_date=2025-05-05 00:00:00 must be a date such as 2025-03-18, without a time of day"]),
    "a huge number is shown cut short": (
        lambda d: unit(d, "wind", "WF1").update(ramp_up_mw_per_min="9" * 400),
        ['wind "WF1": ramp_up_mw_per_min=\'' + "9" * 39 + '…\' must be a finite number']),
    "threads beyond any machine": (
        lambda d: d["solver"].update(threads=10 ** 30),
        ["solver: threads=" + "1" + "0" * 30 + " must be <= 1024"]),
    "a MIP start written as one name": (
        lambda d: d["solver"].update(mip_start="csp[CSP1].online[3]"),
        ["solver: mip_start='csp[CSP1].online[3]' must be a list"]),
    "a MIP start with a number among its names": (
        lambda d: d["solver"].update(mip_start=["csp[CSP1].online[3]", 7]),
        ["solver: mip_start item 2=7 must be text (put it in quotes if it looks like a number or a date)"]),
    "a MIP start name of a whole page": (
        lambda d: d["solver"].update(mip_start=["x" * 5000]),
        ["solver: mip_start item 1='" + "x" * 39 + "…' must have at most 200 characters"]),
}


@pytest.mark.parametrize("label", list(EXACT))
def test_messages_name_what_the_user_wrote_and_nothing_else(raw, paper_case, label):
    edit, expected = EXACT[label]
    assert problems_of(raw, paper_case.history, edit) == expected


def test_a_blank_optional_section_means_its_defaults(raw, paper_case):
    data = copy.deepcopy(raw)
    data["solver"] = None
    assert parse_case(data, paper_case.history).solver == paper_case.solver


@pytest.mark.parametrize("label", list(BAD_INPUTS))
def test_bad_input_is_refused_with_a_precise_message(raw, paper_case, label):
    edit, message = BAD_INPUTS[label]
    problems = problems_of(raw, paper_case.history, edit)
    assert any(message in p for p in problems), problems


def test_every_problem_is_reported_at_once(raw, paper_case):
    def several(d):
        unit(d, "wind", "WF1").update(p_max_mw=-1)
        unit(d, "ed", "ED_industry").update(flex_up=3)
    problems = problems_of(raw, paper_case.history, several)
    assert len(problems) == 2


def test_earliest_ties_are_refused_where_the_model_chooses_the_periods_and_written_only_when_set(paper_case, tmp_path):
    for changes, words in (({"budget_mode": "planner_chosen"}, "here planner_chosen and top_gamma"),
                           ({"budget_encoding": "binary"}, "here paper and binary")):
        with pytest.raises(CaseError, match=rf"budgets.ties=earliest needs budgets.mode=paper and "
                                            rf"solver.budget_encoding=top_gamma \({words}\)"):
            with_options(paper_case, ties="earliest", **changes)
    assert "ties" not in (save_case(paper_case, tmp_path / "choose") / "case.yaml").read_text()
    folder = save_case(with_options(paper_case, ties="earliest"), tmp_path / "earliest")
    assert "ties: earliest" in (folder / "case.yaml").read_text()
    assert load_case(folder).budgets.ties == "earliest"


def test_budget_above_the_number_of_periods_is_refused(paper_case):
    with pytest.raises(CaseError, match=r"Γ for 'WF1'=30 exceeds the 24 periods of 2025-05-05"):
        prepare(with_options(paper_case, gammas={"WF1": 30}))
    with pytest.raises(CaseError, match=r"exceeds the 23 periods"):
        prepare(with_options(paper_case, date="2025-03-30", gammas={"price_da": 24}))


def test_history_shorter_than_the_window_is_refused(paper_case):
    with pytest.raises(CaseError, match=r"the 30-day window before 2024-12-20 \(2024-11-20 to 2024-12-19\) "
                                        r"is not covered; the history runs from 2024-12-01"):
        prepare(with_options(paper_case, date="2024-12-20"))


def _write_history_case(tmp_path, change):
    """Copy the paper case with ``change(history frame) -> frame`` applied to its CSV."""
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    frame = change(pd.read_csv(folder / "history.csv"))
    frame.to_csv(folder / "history.csv", index=False)
    return folder


def test_nan_in_a_csv_names_column_and_hour(tmp_path):
    def blank(frame):
        frame.loc[[100, 101], "PV2"] = np.nan
        return frame

    folder = _write_history_case(tmp_path, blank)
    with pytest.raises(CaseError, match=r'history.csv: column "PV2" is empty \(NaN\) at 2024-12-05T04:00:00\+01:00 '
                                        r"and 1 more hours"):
        load_case(folder)


def test_a_value_beyond_any_plant_in_a_csv_names_column_and_hour(tmp_path):
    def huge(frame):
        frame.loc[[100, 101, 102], "price_da"] = [1e300, -2e7, 80.0]
        return frame

    folder = _write_history_case(tmp_path, huge)
    with pytest.raises(CaseError, match=r'history.csv: column "price_da" = 1e\+300 at 2024-12-05T04:00:00\+01:00 '
                                        r"must lie within ±1e\+06 and 1 more hours"):
        load_case(folder)


def test_missing_hours_in_a_csv_are_named(tmp_path):
    folder = _write_history_case(tmp_path, lambda f: f.drop(index=[500, 501, 502]))
    with pytest.raises(CaseError, match=r"history.csv: hour 2024-12-21T20:00:00\+01:00 is missing "
                                        r"\(3 missing hours in all\)"):
        load_case(folder)


def test_duplicated_and_naive_timestamps_are_refused(tmp_path):
    folder = _write_history_case(tmp_path, lambda f: f.assign(
        timestamp=f["timestamp"].where(f.index != 10, f["timestamp"].iloc[9])))
    with pytest.raises(CaseError, match="appears more than once"):
        load_case(folder)
    folder2 = _write_history_case(tmp_path / "b", lambda f: f.assign(timestamp=f["timestamp"].str.slice(0, 19)))
    with pytest.raises(CaseError, match="has no UTC offset"):
        load_case(folder2)


def test_invalid_yaml_is_reported_with_its_line(tmp_path):
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    (folder / "case.yaml").write_text("name: x\nunits: [unclosed\n")
    with pytest.raises(CaseError, match=r"case.yaml: not valid YAML at line \d+"):
        load_case(folder)


def test_a_case_round_trips_through_its_folder(paper_case, tmp_path):
    edited = paper_case.replace(markets={"kappa": 0.25}, wind=[paper_case.wind[0]])
    save_case(edited, tmp_path / "saved")
    again = load_case(tmp_path / "saved")
    assert again == edited
    assert hash(again) == hash(edited)
    assert again.history.fingerprint == paper_case.history.fingerprint


def test_a_mip_start_is_written_only_when_a_case_carries_one(paper_case, tmp_path):
    started = paper_case.replace(solver={"mip_start": ("csp[CSP1].online[12]", "csp[CSP1].startup[12]")})
    save_case(started, tmp_path / "started")
    assert load_case(tmp_path / "started") == started
    save_case(paper_case, tmp_path / "plain")
    assert "mip_start" not in (tmp_path / "plain" / "case.yaml").read_text(encoding="utf-8")
    assert load_case(tmp_path / "plain").solver.mip_start == ()


def test_cases_are_immutable_and_hash_by_content(paper_case):
    with pytest.raises(Exception):
        paper_case.dt_h = 0.25
    assert with_options(paper_case, strategy="balanced") == paper_case
    assert hash(with_options(paper_case, strategy="pessimistic")) != hash(paper_case)


def test_markets_option_requires_the_dam(paper_case):
    with pytest.raises(CaseError, match="must include DAM"):
        with_options(paper_case, markets="SRM,HPA")
    with pytest.raises(CaseError, match="unknown market 'IDM'"):
        with_options(paper_case, markets="DAM,IDM")


def test_a_case_survives_pickling_for_worker_processes(paper_case):
    import pickle

    again = pickle.loads(pickle.dumps(paper_case))
    assert again == paper_case and hash(again) == hash(paper_case)
    assert again.history.frame.equals(paper_case.history.frame)
    assert again.history.source == paper_case.history.source


# ----------------------------------------------------------------------------- files that are not what they should be


def _folder(tmp_path, case_yaml: bytes | None = None, history: bytes | None = None):
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    if case_yaml is not None:
        (folder / "case.yaml").write_bytes(case_yaml)
    if history is not None:
        (folder / "history.csv").write_bytes(history)
    return folder


def _message(folder) -> list[str]:
    with pytest.raises(CaseFileError) as info:
        load_case(folder)
    return info.value.problems


YAML_BYTES = (PAPER / "case.yaml").read_bytes()
HISTORY_BYTES = (PAPER / "history.csv").read_bytes()


def test_latin1_text_is_named_with_its_byte_and_line(tmp_path):
    text = YAML_BYTES.replace(b"description: >-", "description: >-\n  Sevilla, año 2025".encode("latin-1"), 1)
    at = text.index(b"\xf1")
    lines = text[:at].split(b"\n")
    assert lines[-1] == b"  Sevilla, a"
    assert _message(_folder(tmp_path, case_yaml=text)) == [
        f"case.yaml: not UTF-8 text: byte {at + 1} (line {len(lines)}, column 13) is 0xF1, which looks like Latin-1/Windows-1252; "
        "save the file as UTF-8"]


@pytest.mark.parametrize("where, data, seems", [
    ("case.yaml", YAML_BYTES.decode().encode("utf-16"), "UTF-16 text"),
    ("case.yaml", b"%PDF-1.7\n%\xe2\xe3", "a PDF document"),
    ("history.csv", b"PK\x03\x04" + b"\0" * 40, "a zip archive (an Excel .xlsx workbook is one too)"),
    ("history.csv", gzip.compress(HISTORY_BYTES[:1000]), "a gzip archive"),
    ("history.csv", HISTORY_BYTES[:200] + b"\0\0\0" + HISTORY_BYTES[200:400], "binary data (it holds NUL bytes)"),
])
def test_a_file_that_is_not_text_is_named_for_what_it_seems(tmp_path, where, data, seems):
    folder = _folder(tmp_path, **{"case_yaml" if where == "case.yaml" else "history": data})
    assert _message(folder) == [f"{where}: is {seems}, not UTF-8 text"]


def test_a_workbook_given_as_the_case_file_is_named(tmp_path, paper_case):
    from rvpp.outputs.workbook import write_case_workbook

    book = tmp_path / "case.xlsx"
    write_case_workbook(paper_case.replace(history=paper_case.history), book)
    assert _message(book) == ["case.xlsx: is a zip archive (an Excel .xlsx workbook is one too), not UTF-8 text"]


def test_a_byte_order_mark_and_windows_line_ends_just_work(tmp_path, paper_case):
    bom = b"\xef\xbb\xbf"
    folder = _folder(tmp_path, case_yaml=bom + YAML_BYTES.replace(b"\n", b"\r\n"),
                     history=bom + HISTORY_BYTES.replace(b"\n", b"\r\n"))
    assert load_case(folder) == paper_case


def test_a_key_written_twice_is_refused_with_both_lines(tmp_path):
    text = YAML_BYTES.decode()
    first = text.index("  kappa: 0.3")
    twice = text.replace("  kappa: 0.3\n", "  kappa: 0.3\n  kappa: 0.5\n", 1)
    line = text[:first].count("\n") + 1
    assert _message(_folder(tmp_path, case_yaml=twice.encode())) == [
        f'case.yaml: key "kappa" is written twice in one mapping (lines {line} and {line + 1}); keep one']
    deep = text.replace("        e_min_mwh_th: 110\n", "        e_min_mwh_th: 110\n        e_min_mwh_th: 120\n", 1)
    line = text[:text.index("        e_min_mwh_th: 110")].count("\n") + 1
    assert _message(_folder(tmp_path / "deep", case_yaml=deep.encode())) == [
        f'case.yaml: key "e_min_mwh_th" is written twice in one mapping (lines {line} and {line + 1}); keep one']


def test_a_yaml_merge_key_may_be_overridden_on_purpose(tmp_path):
    text = YAML_BYTES.decode().replace("solver:\n", "solver:\n  <<: &base {time_limit_s: 60, threads: 2}\n", 1)
    assert "  time_limit_s: 120\n" in text
    solver = load_case(_folder(tmp_path, case_yaml=text.encode())).solver
    assert (solver.time_limit_s, solver.threads) == (120, 0)


@pytest.mark.parametrize("case_yaml, history, expected", [
    (b"", None, "case.yaml: the top level must be a mapping of settings (name:, markets:, units:, ...); "
                "the file is empty"),
    (b"- a\n- b\n", None, "case.yaml: the top level must be a mapping of settings (name:, markets:, units:, ...); "
                          "it holds a list"),
    (None, b"", "history.csv: is empty; a history CSV starts with a header row such as "
                "timestamp,price_da,price_sr_up,price_sr_dn,..."),
])
def test_empty_and_shapeless_files_are_named(tmp_path, case_yaml, history, expected):
    assert _message(_folder(tmp_path, case_yaml=case_yaml, history=history)) == [expected]


def test_a_history_that_is_a_folder_is_named(tmp_path):
    folder = _folder(tmp_path, case_yaml=YAML_BYTES.replace(b"history: history.csv", b"history: data"))
    (folder / "data").mkdir()
    assert _message(folder) == ["data: is a folder, not a file"]
