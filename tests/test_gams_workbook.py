"""The authors' tool workbook: its import as a case, and rvpp's accounting of its stored result.

The workbook (never committed) is read from ``shared/data/gams-tool`` beside the project; the
tests that need it skip when it is absent. Bad inputs are copies of it changed with openpyxl in a
temporary folder.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
from pathlib import Path

import numpy as np
import openpyxl
import pytest

from rvpp import load_case, solve
from rvpp.cli import main
from rvpp.data.importers.gams_import import import_workbook
from rvpp.data.importers.gams_workbook import WorkbookError, read_workbook
from rvpp.errors import DataImportError
from rvpp.settle.audit import audit_day, audit_result, price_exposures, protection_exact

ROOT = Path(__file__).resolve().parents[1]
WORKBOOK = Path(os.environ.get("RVPP_GAMS_WORKBOOK", ROOT.parent / "shared" / "data" / "gams-tool" / "RVPP_data.xlsx"))
needs_workbook = pytest.mark.skipif(not WORKBOOK.is_file(), reason="the authors' tool workbook (shared/data/gams-tool/"
                                    "RVPP_data.xlsx, or RVPP_GAMS_WORKBOOK) is not available")
DATE = dt.date(2025, 6, 1)
# The tool's stored day-ahead result (sheet DAM, column W) [EUR], as the issue quotes it.
STORED = {"profit": -10_665.93, "revenue_dam": 17_604.31, "revenue_srm": 22_934.13, "operating_cost": 38_245.37,
          "protection_dam": 6_140.49, "protection_srm": 6_818.52}


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    folder = tmp_path_factory.mktemp("gams") / "case"
    made = import_workbook(WORKBOOK, folder, DATE)
    return made, load_case(folder), read_workbook(WORKBOOK)


@needs_workbook
def test_the_imported_case_holds_the_workbooks_bands_exactly(imported):
    _, case, book = imported
    day = audit_day(case)  # the audit's own percentiles of the written history
    prices = book.prices
    np.testing.assert_allclose(day.sources["price_da"].nominal, prices.price_da, atol=1e-9)
    np.testing.assert_allclose(day.sources["price_da"].deviation, prices.price_da_dev_dn, atol=1e-9)
    np.testing.assert_allclose(day.sources["price_da"].deviation_up, prices.price_da_dev_up, atol=1e-9)
    np.testing.assert_allclose(day.sources["price_sr_up"].nominal, prices.price_sr_up, atol=1e-9)
    np.testing.assert_allclose(day.sources["price_sr_up"].deviation, prices.price_sr_up_dev_dn, atol=1e-9)
    np.testing.assert_allclose(day.sources["price_sr_dn"].deviation, prices.price_sr_dn_dev_dn, atol=1e-9)
    for unit in (*book.non_dispatchable, *book.solar_thermal):
        np.testing.assert_allclose(day.sources[unit.name].nominal, unit.forecast.available_mw, atol=1e-9)
        np.testing.assert_allclose(day.sources[unit.name].deviation, unit.forecast.deviation_mw, atol=1e-9)
        assert day.sources[unit.name].gamma == book.budgets.units[unit.name]
    (demand,) = book.demands
    assert book.result.demand_profiles[demand.name] == "lp2"
    np.testing.assert_allclose(day.sources[demand.name].nominal, demand.profiles["lp2"], atol=1e-9)
    np.testing.assert_allclose(day.sources[demand.name].deviation, demand.deviations["lp2"], atol=1e-9)
    assert {n: day.sources[n].gamma for n in ("price_da", "price_sr_up", "price_sr_dn")} == \
        {"price_da": 12, "price_sr_up": 12, "price_sr_dn": 12}


@needs_workbook
def test_rvpps_accounting_of_the_stored_schedule_gives_the_tools_six_numbers(imported):
    _, case, book = imported
    day = audit_day(case)
    stored = book.result
    market = stored.market.rename(columns={"r_up_mw": "r_sr_up_mw", "r_dn_mw": "r_sr_dn_mw"}).reset_index(drop=True)
    p_da, r_up, r_dn = (market[c].to_numpy(float) for c in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw"))
    dt_h = day.dt_h

    revenue_dam = float(np.sum(day.sources["price_da"].nominal * p_da * dt_h))
    revenue_srm = float(np.sum((day.sources["price_sr_up"].nominal * r_up
                                + day.sources["price_sr_dn"].nominal * r_dn) * dt_h))
    exposures = price_exposures(day, market)
    protection_dam = protection_exact(exposures["price_da"], day.sources["price_da"].gamma)
    protection_srm = sum(protection_exact(exposures[n], day.sources[n].gamma) for n in ("price_sr_up", "price_sr_dn"))

    def power(name: str) -> np.ndarray:
        return stored.units.loc[name, "power_mw"].to_numpy(float)

    # every unit's cost from the imported case: c·p·dt, and for hydro and biomass the start-up and
    # shut-down costs counted from the stored commitment and the status before the day
    cost = sum(unit.om_eur_per_mwh * power(unit.name).sum() * dt_h for unit in (*case.ndres, *case.csp))
    starts = {}
    for unit in (*case.hydro, *case.biomass):
        online = np.concatenate([[float(unit.initial_online)], np.round(stored.units.loc[unit.name, "online"])])
        starts[unit.name] = int((np.diff(online) > 0).sum())
        cost += (unit.marginal_cost_eur_per_mwh * power(unit.name).sum() * dt_h
                 + unit.startup_cost_eur * starts[unit.name]
                 + unit.shutdown_cost_eur * int((np.diff(online) < 0).sum()))
    assert starts == {"U1": 1, "U2": 1}
    (battery,) = case.battery
    assert not battery.enabled  # switched off in the workbook: it costs nothing
    cost += sum(d.profile_costs[stored.demand_profiles[d.name]] for d in book.demands)

    ours = {"revenue_dam": revenue_dam, "revenue_srm": revenue_srm, "operating_cost": cost,
            "protection_dam": protection_dam, "protection_srm": protection_srm,
            "profit": revenue_dam + revenue_srm - cost - protection_dam - protection_srm}
    for term, value in STORED.items():
        assert value == pytest.approx(ours[term], abs=0.005), term
    workbook_totals = {"profit": stored.profit_eur, "revenue_dam": stored.revenue_dam_eur,
                       "revenue_srm": stored.revenue_srm_eur, "operating_cost": stored.operating_cost_eur,
                       "protection_dam": stored.protection_dam_eur, "protection_srm": stored.protection_srm_eur}
    for term, value in workbook_totals.items():
        assert value == pytest.approx(ours[term], abs=1e-6), term


@needs_workbook
def test_the_dam_protection_is_the_asymmetric_form(imported):
    """The stored schedule buys in two hours; pricing those with the downward deviation (the
    symmetric form) misses the tool's number by more than a thousand euros."""
    _, case, book = imported
    day = audit_day(case)
    p_da = book.result.market.p_da_mw.to_numpy(float)
    assert list(np.flatnonzero(p_da < 0) + 1) == [8, 9]
    symmetric = protection_exact(day.sources["price_da"].deviation * np.abs(p_da), 12)
    assert symmetric == pytest.approx(7_667.63, abs=0.005)


@needs_workbook
def test_the_command_writes_a_case_and_refuses_to_overwrite_it(tmp_path, capsys):
    out = tmp_path / "case"
    argv = ["data", "import-workbook", str(WORKBOOK), "--out", str(out), "--date", "2025-06-01"]
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == ["case.yaml", "history.csv"]
    case = load_case(out)
    assert sorted((str(k), u.name) for k, u in case.all_units()) == [
        ("battery", "U10"), ("biomass", "U2"), ("csp", "U5"), ("ed", "U6"), ("hydro", "U1"), ("pv", "U4"),
        ("wind", "U3")]
    assert [u.name for _, u in case.units()] == [n for n in case.unit_names() if n != "U10"]  # disabled
    assert case.markets.kappa == 0.1 and case.markets.reserve_base == "installed" and not case.markets.hpa
    assert case.csp[0].storage.cyclic and case.battery[0].cyclic
    # the tool's 1800 EUR / 60 MWh per MWh charged and per MWh discharged, per MWh discharged on a
    # cyclic day with 0.95 each way: 30 + 30 / 0.9025
    assert case.battery[0].degradation_eur_per_mwh == pytest.approx(30 + 30 / 0.9025, abs=1e-9)
    (hydro,), (biomass,) = case.hydro, case.biomass
    assert (hydro.energy_max_mwh, hydro.initial_online, hydro.initial_hours_in_status, hydro.reserve_share) == \
        (996, False, 1, 0.5)
    assert (biomass.min_up_h, biomass.initial_hours_in_status, biomass.startup_cost_eur, biomass.ramp_mw_per_min) == \
        (3, 3, 300, 0.2)
    assert "battery U10 (disabled), hydro U1, biomass U2" in capsys.readouterr().out
    before = (out / "case.yaml").read_bytes()
    assert main(argv) == 1
    assert "already holds case.yaml" in capsys.readouterr().err
    assert (out / "case.yaml").read_bytes() == before


@needs_workbook
def test_the_two_documented_commands_print_the_tools_six_numbers(tmp_path, capsys):
    # a newcomer's route: import, solve, read the printed parts; the SR protection is up + down
    case, out = tmp_path / "case", tmp_path / "plan"
    assert main(["data", "import-workbook", str(WORKBOOK), "--out", str(case), "--date", "2025-06-01"]) == 0
    capsys.readouterr()
    assert main(["solve", "--case", str(case), "--out", str(out)]) == 0
    (line,) = [x for x in capsys.readouterr().err.splitlines() if x.strip().startswith("parts [EUR]:")]
    printed = {}
    for name, number in re.findall(r"([A-Za-z][A-Za-z ]*?) (-?[\d,]+\.\d\d)", line.split(":", 1)[1]):
        printed[name.removeprefix("price protection ")] = float(number.replace(",", ""))
    assert printed == pytest.approx({
        "DAM revenue": STORED["revenue_dam"], "SR revenue": STORED["revenue_srm"], "HPA cost": 0.0,
        "operating cost": STORED["operating_cost"], "DAM": STORED["protection_dam"], "SR up": printed["SR up"],
        "SR down": printed["SR down"], "profit": STORED["profit"]}, abs=0.006)
    assert printed["SR up"] + printed["SR down"] == pytest.approx(STORED["protection_srm"], abs=0.011)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "optimal"
    assert summary["objective_eur"] == pytest.approx(STORED["profit"], abs=0.006)


# ----------------------------------------------------------------------------- bad workbooks


@needs_workbook
def test_the_copy_of_the_read_sheets_imports_as_the_workbook_does(small_copy, imported, tmp_path):
    """The copy the bad inputs start from is itself good: it gives the same case."""
    made = import_workbook(small_copy, tmp_path / "case", DATE)
    assert made.case.to_data() == imported[0].case.to_data()
    assert made.case.history == imported[0].case.history


@pytest.fixture(scope="module")
def small_copy(tmp_path_factory) -> Path:
    """The values of the sheets the import reads, rows 1 to 1000, in a workbook of their own
    (the shipped file is large and slow to open for editing)."""
    source = openpyxl.load_workbook(WORKBOOK, read_only=True, data_only=True)
    book = openpyxl.Workbook()
    book.remove(book.active)
    for name in ("Global_params", "Buses", "VPP_Units", "NDRES", "STH", "DRES", "ESS", "Demand", "Energy_Forecast",
                 "Price_Forecast", "Trade_Units", "DAM"):
        sheet = book.create_sheet(name)
        for row in source[name].iter_rows(min_row=1, max_row=1000, max_col=60, values_only=True):
            sheet.append(row)
    source.close()
    path = tmp_path_factory.mktemp("workbook") / "RVPP_data.xlsx"
    book.save(path)
    return path


def _copy(small_copy: Path, tmp_path: Path, change) -> Path:
    book = openpyxl.load_workbook(small_copy)
    change(book)
    path = tmp_path / "changed.xlsx"
    book.save(path)
    return path


def _header_column(sheet, header: str) -> int:
    return next(c.column for c in sheet[15] if isinstance(c.value, str) and c.value.strip() == header)


def _row_of(sheet, column: int, key: str) -> int:
    return next(r for r in range(16, 1001) if sheet.cell(r, column).value == key)


def _without_column(book):
    sheet = book["NDRES"]
    sheet.cell(15, _header_column(sheet, "Max power [MW]")).value = None


def _unit_named_twice(book):
    sheet = book["VPP_Units"]
    sheet.cell(_row_of(sheet, 1, "U4"), 1).value = "U3"


def _row_named_twice(book):
    sheet = book["NDRES"]
    sheet.cell(_row_of(sheet, 1, "U4"), 1).value = "U3"


def _type_disagrees(book):
    sheet = book["VPP_Units"]
    sheet.cell(_row_of(sheet, 5, "U3"), 6).value = "DRES"  # E:F, the tool's second list of unit types


def _type_left_out(book):
    sheet = book["VPP_Units"]
    row = _row_of(sheet, 5, "U4")
    sheet.cell(row, 5).value = sheet.cell(row, 6).value = None


def _dispatchable_renamed(book):
    for sheet, column in (("VPP_Units", 1), ("VPP_Units", 5), ("DRES", 6)):
        book[sheet].cell(_row_of(book[sheet], column, "U1"), column).value = "U7"


def _dispatchable_value(unit: str, header: str, value: float):
    def change(book):
        sheet = book["DRES"]
        sheet.cell(_row_of(sheet, 6, unit), _header_column(sheet, header)).value = value
    return change


def _unit_value(sheet_name: str, key_column: int, unit: str, header: str, value: float):
    def change(book):
        sheet = book[sheet_name]
        sheet.cell(_row_of(sheet, key_column, unit), _header_column(sheet, header)).value = value
    return change


def _without_sheet(book):
    del book["Energy_Forecast"]


def _storage_value(unit: str, header: str, value: float):
    def change(book):
        sheet = book["ESS"]
        sheet.cell(_row_of(sheet, 1, unit), _header_column(sheet, header)).value = value
    return change


def _first_dam_price(value: float):
    def change(book):
        sheet = book["Price_Forecast"]
        sheet.cell(_row_of(sheet, 1, "T1"), _header_column(sheet, "DAM Price [Euro/MWh]")).value = value
    return change


def _huge_availability(book):
    sheet = book["Energy_Forecast"]
    sheet.cell(16, _header_column(sheet, "Pavailable DAM [MW]")).value = 1e300


def _not_a_number(book):
    sheet = book["DRES"]
    sheet.cell(_row_of(sheet, 6, "U1"), _header_column(sheet, "Max energy [MWh]")).value = "lots"


@needs_workbook
@pytest.mark.parametrize(("change", "message"), [
    (_without_column, r'sheet "NDRES" range A15:F1000: column "Max power \[MW\]" is missing \(header row 15\)'),
    (_unit_named_twice, r'sheet "VPP_Units" cell A\d+: U3 B5 NDRES is written twice \(first on row \d+\)'),
    (_row_named_twice, r'sheet "NDRES" cell A\d+: U3 is written twice \(first on row \d+\)'),
    (_type_disagrees, r'sheet "VPP_Units" cell E\d+: unit "U3" of type "DRES" is of type "NDRES" in column C'),
    (_type_left_out, r'sheet "VPP_Units" column E: lists no type for unit "U4" of column A'),
    (_without_sheet, r'sheet "Energy_Forecast": is missing; the tool\'s workbook has it'),
    (_dispatchable_renamed, r'sheet "VPP_Units" unit "U7": the tool knows a dispatchable unit as hydro \(U1\)'),
    (_not_a_number, r'sheet "DRES" row \d+ column "Max energy \[MWh\]": \'lots\' is not a finite number'),
    # biomass U2 runs at least 2 MW for its 3 h minimum up time: 6 MWh of fuel
    (_dispatchable_value("U2", "Max energy [MWh]", 5), r'sheet "DRES" unit "U2" column "Max energy \[MWh\]": 5 is '
     r"below Min power production x Min up time = 2 MW x 3 h = 6 MWh: once started, the unit could not run"),
    (_dispatchable_value("U1", "Min down time [hour]", 30),
     r'sheet "DRES" unit "U1" column "Min down time \[hour\]": 30 must lie in 0..24 h'),
    (_dispatchable_value("U1", "Min power production [MW]", 60),
     r'sheet "DRES" unit "U1": Min power production 60 MW must be <= Max power production 50 MW'),
    # refused in the workbook's words, not in the case's (battery "U10": self_discharge_per_h=-0.00208333)
    (_dispatchable_value("U1", "Startup cost [Euro]", -100),
     r'sheet "DRES" unit "U1" column "Startup cost \[Euro\]": -100 must be >= 0'),
    (_storage_value("U10", "Self degradation coefficient [-]", -5),
     r'sheet "ESS" unit "U10" column "Self degradation coefficient \[-\]": -5 must be >= 0'),
    (_storage_value("U10", "Self degradation coefficient [-]", 3000),
     r'sheet "ESS" unit "U10" column "Self degradation coefficient \[-\]": 3000 must be < 2400'),
    (_unit_value("NDRES", 1, "U3", "Max power [MW]", -5),
     r'sheet "NDRES" unit "U3" column "Max power \[MW\]": -5 must be >= 0'),
    (_unit_value("STH", 6, "U5", "Machine capacity [MW]", -1),
     r'sheet "STH" unit "U5" column "Machine capacity \[MW\]": -1 must be >= 0'),
    (_unit_value("Demand", 15, "U6", "Max Demand [MW]", -2),
     r'sheet "Demand" unit "U6" column "Max Demand \[MW\]": -2 must be >= 0'),
    # not in history.csv's words, nor as the band's end 999999987.8
    (_dispatchable_value("U1", "Max power production [MW]", 1e12),
     r'sheet "DRES" row \d+ column "Max power production \[MW\]": 1e\+12 must lie within ±1e\+06'),
    (_first_dam_price(1e9), r'sheet "Price_Forecast" row \d+ column "DAM Price \[Euro/MWh\]": 1e\+09 must lie '
                            r"within ±1e\+06"),
    (_huge_availability, r'sheet "Energy_Forecast" row 16 column "Pavailable DAM \[MW\]": 1e\+300 must lie within'),
    # the period and the band's end are named, and the number written as one, not as np.float64(32.9234567)
    (_first_dam_price(45.1234567), r'sheet "Price_Forecast" column "DAM Price \[Euro/MWh\]" period T1: the band\'s '
                                   r"lower end 32.9234567 needs more than 6 significant digits"),
], ids=["missing column", "unit named twice", "row named twice", "types disagree", "type left out", "missing sheet",
        "unknown dispatchable",
        "not a number", "fuel short of the minimum run", "minimum time longer than the day", "minimum above maximum",
        "negative cost", "negative self-discharge", "self-discharge above the tool's divisor", "negative wind power",
        "negative turbine input", "negative demand", "huge power", "huge price", "huge availability", "too many digits"])
def test_a_bad_workbook_is_refused_by_name_and_nothing_is_written(small_copy, tmp_path, change, message):
    path = _copy(small_copy, tmp_path, change)
    out = tmp_path / "case"
    with pytest.raises(WorkbookError, match=message):
        import_workbook(path, out, DATE)
    assert not out.exists()
    assert main(["data", "import-workbook", str(path), "--out", str(out), "--date", "2025-06-01"]) == 1
    assert not out.exists()


def test_a_file_that_is_not_a_workbook_is_refused(tmp_path):
    path = tmp_path / "RVPP_data.xlsx"
    path.write_text("timestamp,price_da\n")
    with pytest.raises(DataImportError, match='"RVPP_data.xlsx" cannot be read as an Excel workbook'):
        import_workbook(path, tmp_path / "case", DATE)
    assert not (tmp_path / "case").exists()


@needs_workbook
@pytest.mark.slow
def test_rvpp_solves_the_imported_case_to_the_tools_optimum(imported):
    """docs/gams-tool.md's reconciliation: with the tool's conventions set by the import (the demand's
    window, ramps and energy floor; the tank's per-band limit, reserve energy factor and share limit;
    the uncapped power-block curve) rvpp's optimum is the tool's stored one, term by term.

    Facts checked on the way: the installed reserve base is 0.1 x (50 + 10 + 50 + 50 + 55) = 21.5 MW
    (the switched-off battery does not count) and both sell the whole down band in every hour; the
    demand sits at the foot of its window, 0.9 x the chosen profile plus its deviation in the Γ = 12
    largest hours (0.9 x 1684 + 239.3 = 1754.9 MWh), as the tool's does."""
    _, case, book = imported
    (ed,), (csp,) = case.ed, case.csp
    assert ed.profile_window and not ed.energy_net_of_up_band and (ed.ramp_up_mw_per_h, ed.ramp_dn_mw_per_h) == \
        (180, 180) and (ed.flex_up, ed.flex_dn) == (0.1, 0.1)
    # 15 min x 2 MW_th/min; the workbook's sFraction_Time_SR is 1; the tool's σ <= 0.5
    assert (csp.storage.reserve_band_max_mw_th, csp.storage.reserve_energy_factor, csp.storage.reserve_share_max,
            csp.power_block.output_capped) == (30, 2, 0.5, False)
    result = solve(case)
    assert result.status == "optimal"
    assert audit_result(result) == []
    terms = {"profit": result.objective_eur, "revenue_dam": result.parts["revenue_dam_eur"],
             "revenue_srm": result.parts["revenue_sr_eur"], "operating_cost": result.parts["cost_opex_eur"],
             "protection_dam": result.protection_eur["price_da"],
             "protection_srm": result.protection_eur["price_sr_up"] + result.protection_eur["price_sr_dn"]}
    for term, value in STORED.items():
        assert terms[term] == pytest.approx(value, abs=0.01), term
    assert result.objective_eur == pytest.approx(book.result.profit_eur, abs=0.01)
    # each unit's energy over the day and the tank's flows are the stored schedule's (the bands'
    # split among the units is not: optimal plans tie there)
    stored = book.result.units
    ours = result.units.groupby("unit")["p_mw"].sum() * case.dt_h
    for name in ("U1", "U2", "U3", "U4", "U5", "U6"):
        assert ours[name] == pytest.approx(stored.loc[name, "power_mw"].sum(), abs=0.01), name
    assert result.csp["ts_charge_mw"].sum() == pytest.approx(stored.loc["U9", "charge_mw"].sum(), abs=0.01)
    assert result.csp["ts_discharge_mw"].sum() == pytest.approx(stored.loc["U9", "discharge_mw"].sum(), abs=0.01)
    market = result.market
    np.testing.assert_allclose(market.r_sr_dn_mw, 21.5, atol=1e-6)
    np.testing.assert_allclose(book.result.market.r_dn_mw, 21.5, atol=1e-9)
    assert market.r_sr_up_mw.max() <= 21.5 + 1e-6
    (demand,) = book.demands
    profile = demand.profiles["lp2"].to_numpy()
    foot = 0.9 * profile.sum() + np.sort(demand.deviations["lp2"].to_numpy())[::-1][:12].sum()
    served = result.units.loc[result.units.unit == "U6", "p_mw"].sum() * case.dt_h
    assert profile.sum() == pytest.approx(1684, abs=1e-9) and foot == pytest.approx(1754.9, abs=1e-9)
    assert served == pytest.approx(foot, abs=1e-4)
    assert book.result.units.loc["U6", "power_mw"].sum() == pytest.approx(1754.9, abs=1e-9)


@needs_workbook
@pytest.mark.slow
def test_without_the_tools_conventions_rvpp_finds_a_lower_optimum(imported):
    """The gap the conventions close (docs/gams-tool.md): with every option at its default the same case
    solves lower, its demand at its floor, the chosen profile plus its deviation in the Γ = 12 largest
    hours (1684 + 239.3 = 1923.3 MWh)."""
    _, case, book = imported
    (ed,), (csp,) = case.ed, case.csp
    plain = case.replace(
        ed=[ed.model_copy(update={"profile_window": False, "ramp_up_mw_per_h": None, "ramp_dn_mw_per_h": None,
                                  "energy_net_of_up_band": True})],
        csp=[csp.model_copy(update={
            "storage": csp.storage.model_copy(update={"reserve_band_max_mw_th": None, "reserve_energy_factor": 1.0,
                                                      "reserve_share_max": 1.0}),
            "power_block": csp.power_block.model_copy(update={"output_capped": True})})])
    result = solve(plain)
    assert result.status == "optimal"
    assert audit_result(result) == []
    assert result.objective_eur < book.result.profit_eur - 3000
    (demand,) = book.demands
    floor = demand.profiles["lp2"].sum() + np.sort(demand.deviations["lp2"].to_numpy())[::-1][:12].sum()
    served = result.units.loc[result.units.unit == "U6", "p_mw"].sum() * case.dt_h
    assert floor == pytest.approx(1923.3, abs=1e-9)
    assert served == pytest.approx(floor, abs=1e-4)


@needs_workbook
def test_the_authors_workbook_uploaded_as_a_case_says_how_to_import_it():
    from rvpp.errors import CaseError
    from rvpp.outputs.bundle import read_case_files

    with pytest.raises(CaseError) as err:
        read_case_files({"RVPP_data.xlsx": WORKBOOK.read_bytes()})
    [message] = err.value.problems
    assert message.startswith("RVPP_data.xlsx: sheet 'case' is missing"), message
    assert "python -m rvpp data import-workbook RVPP_data.xlsx --out FOLDER --date YYYY-MM-DD" in message
