"""The workbook of the seed paper's authors' tool (``RVPP_data.xlsx``): the inputs of its
day-ahead session (DAM+SRM, energy robustness) and the result it stored for them.

The tool (Nemati et al., GAMS + Excel, Apache-2.0) reads fixed ranges of its workbook: every
table has its header on row 15 and its rows from row 16 on, up to row 1000. The first columns
of a range are its keys (unit, period, profile...), the others its named values. This reader
finds each value column by its header, so a column moved within its range is still read, and
refuses by name a sheet or a column that is missing, a key written twice (a unit named twice)
and a cell that is not a number.

Quirks of the source, each handled here:

* An empty value cell is zero, as the tool reads it (GAMS stores only non-zeros). In the
  result sheets an empty cell is "not applicable" (no commitment for a wind farm) and is
  read as NaN.
* The tool recognises hydro, biomass, wind and PV by fixed unit names: ``U1`` is the hydro
  plant, ``U2`` the biomass unit, ``U3`` the wind farm, ``U4`` the PV plant (its switches
  ``sHydro_exists``... act on those names). The sheets only say DRES (dispatchable) or NDRES
  (non-dispatchable); the kind follows the name.
* The day has 24 hourly periods: the tool closes the tank and battery balances at period 24.
* The blue sheets (Trade_PCC, Trade_Units) are rewritten by every session; after the shipped
  SRM+IDM1 run only the demand profile chosen by the day-ahead session is still its own. The
  day-ahead schedule is read from the red sheet ``DAM``.
* Headers may carry trailing spaces (``Positive fluctuation [pu] ``); they are stripped.
"""

from __future__ import annotations

import math
import re
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import openpyxl
import pandas as pd
from openpyxl.utils import column_index_from_string, get_column_letter
from openpyxl.utils.exceptions import InvalidFileException

from ...errors import DataImportError
from ..history import MAX_QUANTITY

HEADER_ROW = 15  # every range of the tool starts with its header on this row
LAST_ROW = 1000  # and ends on this one
PERIODS = 24  # the tool closes its storage balances at period 24
DISPATCHABLE_KINDS = {"U1": "hydro", "U2": "biomass"}
NON_DISPATCHABLE_KINDS = {"U3": "wind", "U4": "pv"}
UNIT_TYPES = ("DRES", "NDRES", "STH", "D", "TES", "ES")
SELF_DISCHARGE_DIVISOR = 2400  # the tool keeps 1 - coefficient / 2400 of a battery's energy per hour
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,39}")


class WorkbookError(DataImportError, ValueError):
    """The workbook breaks a rule; the message names the sheet, the cell or column and the rule."""

    def __init__(self, sheet: str, where: str, rule: str):
        self.sheet, self.where, self.rule = sheet, where, rule
        super().__init__(f'sheet "{sheet}"{" " + where if where else ""}: {rule}')


# ----------------------------------------------------------------------------- plain results


@dataclass(frozen=True)
class Settings:
    """Global settings of the session (sheet Global_params, columns A:B)."""

    session: int  # sMarket: -1 DAM+SRM, 0 SRM+IDM1, 1-7 IDMk, 8 profit-robust, 9 regret
    reserve_duration_min: float  # sTime_SR: a reserve band <= SR ramp [MW/min] x this
    reserve_call_fraction: float  # sFraction_Time_SR: hours of a band called per hour held
    storage_end_min_pu: float  # sEss_lower_bound (only in commented-out constraints)
    storage_end_max_pu: float  # sEss_upper_bound (idem)
    startup_heat_fraction: float  # sK_theta: start-up heat as a share of the power block's input
    dt_h: float  # sDelta: period length [h]
    reserve_share_vpp: float  # sSReserve_limit: VPP bands <= this x installed generation
    reserve_share_non_dispatchable: float  # sSReserve_Ndres_limit
    reserve_share_solar_thermal: float  # sSReserve_Sth_limit
    reserve_share_dispatchable: float  # sSReserve_Dres_limit


@dataclass(frozen=True)
class Budgets:
    """Uncertainty budgets Γ of the day-ahead session [periods]."""

    price_da: int
    price_sr_up: int
    price_sr_dn: int
    units: Mapping[str, int]  # wind, PV, solar field and demand, by unit name


@dataclass(frozen=True)
class Dispatchable:
    """A hydro plant or biomass unit (sheet DRES)."""

    name: str
    kind: str  # hydro | biomass | dispatchable
    enabled: bool
    p_min_mw: float
    p_max_mw: float
    cost_eur_per_mwh: float
    ramp_up_mw_per_h: float
    ramp_dn_mw_per_h: float
    startup_ramp_mw_per_h: float
    shutdown_ramp_mw_per_h: float
    startup_cost_eur: float
    shutdown_cost_eur: float
    initially_on: bool
    p_init_mw: float
    sr_ramp_up_mw_per_min: float
    sr_ramp_dn_mw_per_min: float
    hours_on_before: float
    hours_off_before: float
    min_up_h: float
    min_down_h: float
    e_max_mwh: float  # daily energy limit (water, fuel), with all up reserve called


@dataclass(frozen=True)
class NonDispatchable:
    """A wind farm or PV plant (sheet NDRES) and its day-ahead forecast (sheet Energy_Forecast)."""

    name: str
    kind: str  # wind | pv
    enabled: bool
    p_min_mw: float
    p_max_mw: float
    cost_eur_per_mwh: float
    sr_ramp_up_mw_per_min: float
    sr_ramp_dn_mw_per_min: float
    forecast: pd.DataFrame  # per period: available_mw, deviation_mw (downward)


@dataclass(frozen=True)
class Storage:
    """A storage (sheet ESS): the solar thermal plant's tank (TES) or a battery (ES)."""

    name: str
    kind: str  # thermal | electrical
    enabled: bool
    self_discharge: float  # the tool keeps (1 - this/2400) of the energy per hour
    e_max_mwh: float
    e_min_mwh: float
    p_dis_max_mw: float
    p_ch_max_mw: float
    e_init_mwh: float  # unused by the day-ahead session (its balances are cyclic)
    eta_ch: float
    eta_dis: float
    cost_eur: float  # battery cost behind the degradation term
    lifecycle_slope: float
    sr_ramp_up_mw_per_min: float
    sr_ramp_dn_mw_per_min: float


@dataclass(frozen=True)
class SolarThermal:
    """The solar thermal plant (sheet STH), its tank and its solar-field forecast."""

    name: str
    enabled: bool
    cost_eur_per_mwh: float  # on electrical output
    p_in_max_mw_th: float  # power block thermal input ("machine capacity")
    p_el_max_mw: float
    initially_on: bool
    hours_on_before: float
    hours_off_before: float
    min_up_h: float
    min_down_h: float
    breakpoints: tuple[tuple[float, float], ...]  # (thermal input [MW_th], efficiency [-])
    storage: str | None  # the tank's unit name
    forecast: pd.DataFrame  # per period: available_mw (thermal), deviation_mw


@dataclass(frozen=True)
class Demand:
    """A flexible demand (sheet Demand) that picks one of its load profiles for the day."""

    name: str
    enabled: bool
    profiles: pd.DataFrame  # periods x profiles [MW]
    deviations: pd.DataFrame  # periods x profiles, day-ahead upward deviation [MW]
    profile_costs: Mapping[str, float]  # [EUR] for choosing a profile
    flex_dn: pd.Series  # per period: consumption >= (1 - this) x profile [pu]
    flex_up: pd.Series  # per period: consumption <= (1 + this) x profile [pu]
    e_min_mwh: float
    ramp_up_mw_per_h: float
    ramp_dn_mw_per_h: float
    sr_ramp_up_mw_per_min: float
    sr_ramp_dn_mw_per_min: float
    p_init_mw: float
    p_min_mw: float
    p_max_mw: float


@dataclass(frozen=True)
class StoredResult:
    """The day-ahead schedule the tool stored (red sheet DAM) and its totals [EUR]."""

    market: pd.DataFrame  # per period: p_da_mw, r_up_mw, r_dn_mw
    units: pd.DataFrame  # per (unit, period): power_mw, charge_mw, discharge_mw, energy_mwh, online, startup, shutdown
    reserves: pd.DataFrame  # per (unit, period): r_up_mw (scenario up), r_dn_mw (scenario down)
    demand_profiles: Mapping[str, str]  # the profile each demand chose
    profit_eur: float
    revenue_eur: float
    cost_eur: float
    revenue_dam_eur: float
    revenue_srm_eur: float
    operating_cost_eur: float
    protection_dam_eur: float
    protection_srm_eur: float
    status: float  # 1 for an optimal solution
    solve_time_s: float


@dataclass(frozen=True)
class Workbook:
    """Every input of the day-ahead session and its stored result."""

    settings: Settings
    budgets: Budgets
    pcc_capacity_mw: float
    periods: tuple[str, ...]
    prices: pd.DataFrame  # per period, see PRICE_COLUMNS
    dispatchable: tuple[Dispatchable, ...]
    non_dispatchable: tuple[NonDispatchable, ...]
    solar_thermal: tuple[SolarThermal, ...]
    storages: tuple[Storage, ...]
    demands: tuple[Demand, ...]
    result: StoredResult


PRICE_COLUMNS = {  # workbook header -> column of Workbook.prices [EUR/MWh, EUR/MW per h for SR]
    "DAM Price [Euro/MWh]": "price_da",
    "Pos dev DAM Price [Euro/MWh]": "price_da_dev_up",
    "Neg dev DAM Price [Euro/MWh]": "price_da_dev_dn",
    "Up_SRM Price in DAM [Euro/MWh]": "price_sr_up",
    "Dev Up_SRM Price in DAM [Euro/MWh]": "price_sr_up_dev_dn",
    "D_SRM Price in DAM [Euro/MWh]": "price_sr_dn",
    "Dev D_SRM Price in DAM [Euro/MWh]": "price_sr_dn_dev_dn",
}


# ----------------------------------------------------------------------------- reading ranges


@dataclass(frozen=True)
class _Table:
    """Rows of one range: keys (tuple of text) -> {header: value}, in sheet order."""

    sheet: str
    rows: Mapping[tuple[str, ...], Mapping[str, object]]
    cells: Mapping[tuple[str, ...], int]  # the sheet row of each key

    def number(self, key: tuple[str, ...], column: str, *, blank: float = 0.0,
               limit: float | None = MAX_QUANTITY) -> float:
        """The cell's number; ``limit`` bounds its size (None: a sum of money, which may be larger)."""
        value = self.rows[key][column]
        if value is None:
            return blank
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise WorkbookError(self.sheet, f'row {self.cells[key]} column "{column}"',
                                f"{value!r} is not a finite number")
        if limit is not None and abs(value) > limit:
            raise WorkbookError(self.sheet, f'row {self.cells[key]} column "{column}"',
                                f"{value:g} must lie within ±{limit:g}: no quantity of a virtual power plant comes "
                                "near, so it is a typo")
        return float(value)

    def unit_numbers(self, key: tuple[str, ...], columns: tuple[str, ...], unit: str, *,
                     unlimited: tuple[str, ...] = ()) -> list[float]:
        """The numbers of ``unit``'s row in ``columns`` (``unlimited``: sums of money, of any size): costs,
        powers, energies, ramps, hours and coefficients, never below 0."""
        values = [self.number(key, c, limit=None if c in unlimited else MAX_QUANTITY) for c in columns]
        for column, value in zip(columns, values):
            if value < 0:
                raise WorkbookError(self.sheet, f'unit "{unit}" column "{column}"', f"{value:g} must be >= 0")
        return values


class _Sheets:
    """The cell values of the sheets read so far (one pass per sheet, values only)."""

    def __init__(self, book: openpyxl.Workbook):
        self.book = book
        self.grids: dict[str, list[tuple]] = {}
        self.tables: dict[tuple, _Table] = {}

    def grid(self, sheet: str) -> list[tuple]:
        if sheet not in self.grids:
            if sheet not in self.book.sheetnames:
                raise WorkbookError(sheet, "", "is missing; the tool's workbook has it")
            rows = self.book[sheet].iter_rows(min_row=1, max_row=LAST_ROW, values_only=True)
            self.grids[sheet] = [tuple(row) for row in rows]
        return self.grids[sheet]

    def cell(self, sheet: str, row: int, col: int) -> object:
        grid = self.grid(sheet)
        if row > len(grid) or col > len(grid[row - 1]):
            return None
        value = grid[row - 1][col - 1]
        return value.strip() if isinstance(value, str) else value

    def table(self, sheet: str, first: str, last: str, n_keys: int, columns: tuple[str, ...]) -> _Table:
        """Read range ``first15:last1000``: the first ``n_keys`` columns are keys, the rest
        are found by their headers, each of ``columns`` required."""
        memo = (sheet, first, last, n_keys, columns)
        if memo not in self.tables:
            self.tables[memo] = self._read_table(sheet, first, last, n_keys, columns)
        return self.tables[memo]

    def _read_table(self, sheet: str, first: str, last: str, n_keys: int, columns: tuple[str, ...]) -> _Table:
        c0, c1 = column_index_from_string(first), column_index_from_string(last)
        headers: dict[str, int] = {}
        for col in range(c0 + n_keys, c1 + 1):
            header = self.cell(sheet, HEADER_ROW, col)
            if header not in (None, ""):
                headers.setdefault(str(header), col)
        for column in columns:
            if column not in headers:
                where = f"range {first}{HEADER_ROW}:{last}{LAST_ROW}"
                raise WorkbookError(sheet, where, f'column "{column}" is missing (header row {HEADER_ROW})')
        rows: dict[tuple[str, ...], dict[str, object]] = {}
        cells: dict[tuple[str, ...], int] = {}
        for row in range(HEADER_ROW + 1, LAST_ROW + 1):
            keys = [self.cell(sheet, row, c0 + k) for k in range(n_keys)]
            values = {column: self.cell(sheet, row, headers[column]) for column in columns}
            if keys[0] in (None, ""):  # a row without its first key is not data (the tool keeps lists of choices there)
                if any(v not in (None, "") for v in values.values()):
                    raise WorkbookError(sheet, f"row {row}", f"has values but no key in column {get_column_letter(c0)}")
                continue
            if any(k in (None, "") for k in keys):
                raise WorkbookError(sheet, f"row {row}", f"key cells {_letters(c0, n_keys)} must all be filled")
            key = tuple(str(k).strip() for k in keys)
            if key in rows:
                raise WorkbookError(sheet, f"cell {get_column_letter(c0)}{row}",
                                    f"{' '.join(key)} is written twice (first on row {cells[key]})")
            rows[key], cells[key] = values, row
        return _Table(sheet, MappingProxyType(rows), MappingProxyType(cells))

    def pairs(self, sheet: str, first: str, start_row: int) -> dict[str, tuple[object, int]]:
        """A name/value list: names in column ``first``, values in the column right of it."""
        col = column_index_from_string(first)
        out: dict[str, tuple[object, int]] = {}
        for row in range(start_row, LAST_ROW + 1):
            name = self.cell(sheet, row, col)
            if name in (None, ""):
                continue
            name = str(name)
            if name in out:
                raise WorkbookError(sheet, f"cell {first}{row}",
                                    f'"{name}" is written twice (first on row {out[name][1]})')
            out[name] = (self.cell(sheet, row, col + 1), row)
        return out


def _letters(c0: int, n: int) -> str:
    return ", ".join(get_column_letter(c0 + k) for k in range(n))


def _value(pairs: dict[str, tuple[object, int]], sheet: str, column: str, name: str) -> float:
    if name not in pairs:
        raise WorkbookError(sheet, f"column {column}", f'parameter "{name}" is missing')
    value, row = pairs[name]
    if value is None:
        return 0.0
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise WorkbookError(sheet, f"cell {get_column_letter(column_index_from_string(column) + 1)}{row}",
                            f'"{name}" = {value!r} is not a finite number')
    return float(value)


def _whole(value: float, sheet: str, where: str, low: int, high: int) -> int:
    if value != int(value) or not low <= value <= high:
        raise WorkbookError(sheet, where, f"{value:g} must be a whole number in {low}..{high}")
    return int(value)


# ----------------------------------------------------------------------------- the reader


def read_workbook(path: str | Path) -> Workbook:
    """Read the tool's workbook: the inputs of its day-ahead session and the stored result.

    Refuses (:class:`WorkbookError`) a missing sheet or column, a unit named twice, a unit
    without its data, a period set other than T1..T24 and a cell that is not a number.
    """
    path = Path(path)
    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except (zipfile.BadZipFile, InvalidFileException, KeyError) as exc:
        raise DataImportError(f'"{path.name}" cannot be read as an Excel workbook (.xlsx): {exc}') from None
    try:
        sheets = _Sheets(book)
        units = _unit_list(sheets)
        periods = _periods(sheets)
        settings = _settings(sheets)
        switches = _switches(sheets)
        return Workbook(
            settings=settings,
            budgets=_budgets(sheets, units),
            pcc_capacity_mw=_pcc_capacity(sheets),
            periods=periods,
            prices=_prices(sheets, periods),
            dispatchable=_dispatchable(sheets, units, switches),
            non_dispatchable=_non_dispatchable(sheets, units, switches, periods),
            solar_thermal=_solar_thermal(sheets, units, switches, periods),
            storages=_storages(sheets, units, switches),
            demands=_demands(sheets, units, switches, periods),
            result=_result(sheets, periods),
        )
    finally:
        book.close()


def _unit_list(sheets: _Sheets) -> dict[str, str]:
    """Unit name -> type from VPP_Units (A: unit, B: bus, C: type)."""
    table = sheets.table("VPP_Units", "A", "C", 3, ())
    units: dict[str, str] = {}
    for (name, _bus, kind), row in table.cells.items():
        if name in units:
            raise WorkbookError("VPP_Units", f"cell A{row}", f'unit "{name}" is named twice')
        if not NAME.fullmatch(name):
            raise WorkbookError("VPP_Units", f"cell A{row}",
                                f'unit name "{name}" must be 1 to 40 letters, digits, _, . or -')
        if kind not in UNIT_TYPES:
            raise WorkbookError("VPP_Units", f"cell C{row}",
                                f'unit type "{kind}" must be one of {", ".join(UNIT_TYPES)}')
        units[name] = kind
    if not units:
        raise WorkbookError("VPP_Units", "column A", "lists no unit")
    # The tool reads each unit's type a second time from E:F (its set uy): both tables must say the same
    typed = sheets.table("VPP_Units", "E", "F", 2, ())
    seen: set[str] = set()
    for (name, kind), row in typed.cells.items():
        if name in seen:
            raise WorkbookError("VPP_Units", f"cell E{row}", f'unit "{name}" is named twice')
        seen.add(name)
        if units.get(name) != kind:
            said = f'is of type "{units[name]}" in column C' if name in units else "is not listed in column A"
            raise WorkbookError("VPP_Units", f"cell E{row}", f'unit "{name}" of type "{kind}" {said}')
    missing = [name for name in units if name not in seen]
    if missing:
        raise WorkbookError("VPP_Units", "column E", f'lists no type for unit "{missing[0]}" of column A')
    return units


def _of_type(units: dict[str, str], kind: str) -> list[str]:
    return [name for name, k in units.items() if k == kind]


def _periods(sheets: _Sheets) -> tuple[str, ...]:
    table = sheets.table("Price_Forecast", "A", "A", 1, ())
    periods = tuple(key[0] for key in table.rows)
    expected = tuple(f"T{t}" for t in range(1, PERIODS + 1))
    if periods != expected:
        found = f"{', '.join(periods[:4])}... ({len(periods)} periods)"
        raise WorkbookError("Price_Forecast", "column A",
                            f"periods must be T1..T{PERIODS} in order (the tool closes its "
                                                           f"storage balances at period {PERIODS}); found {found}")
    return periods


def _settings(sheets: _Sheets) -> Settings:
    pairs = sheets.pairs("Global_params", "A", 2)

    def get(name: str) -> float:
        return _value(pairs, "Global_params", "A", name)

    settings = Settings(
        session=int(get("sMarket")),
        reserve_duration_min=get("sTime_SR"),
        reserve_call_fraction=get("sFraction_Time_SR"),
        storage_end_min_pu=get("sEss_lower_bound"),
        storage_end_max_pu=get("sEss_upper_bound"),
        startup_heat_fraction=get("sK_theta"),
        dt_h=get("sDelta"),
        reserve_share_vpp=get("sSReserve_limit"),
        reserve_share_non_dispatchable=get("sSReserve_Ndres_limit"),
        reserve_share_solar_thermal=get("sSReserve_Sth_limit"),
        reserve_share_dispatchable=get("sSReserve_Dres_limit"),
    )
    if settings.dt_h != 1:
        raise WorkbookError("Global_params", "parameter sDelta",
                            f"{settings.dt_h:g} must be 1: the tool's day is 24 hourly periods")
    return settings


def _budgets(sheets: _Sheets, units: dict[str, str]) -> Budgets:
    pairs = sheets.pairs("Global_params", "A", 2)
    prices = {name: _whole(_value(pairs, "Global_params", "A", name), "Global_params", f'parameter "{name}"', 0,
                           PERIODS)
              for name in ("pGamma_Price_DAM [-]", "pGamma_Price_SRM_up [-]", "pGamma_Price_SRM_down [-]")}
    per_unit: dict[str, int] = {}
    ranges = (("F", "O", "Gamma DAM [-]", ("NDRES", "STH")), ("Q", "Z", "Gamma Dem DAM [-]", ("D",)))
    for first, last, column, kinds in ranges:
        table = sheets.table("Global_params", first, last, 1, (column,))
        for (name,) in table.rows:
            if units.get(name) not in kinds:
                raise WorkbookError("Global_params", f"cell {first}{table.cells[(name,)]}",
                                    f'"{name}" is not a unit of type {" or ".join(kinds)} in VPP_Units')
            per_unit[name] = _whole(table.number((name,), column), "Global_params", f'"{column}" of {name}', 0, PERIODS)
    for name, kind in units.items():
        if kind in ("NDRES", "STH", "D") and name not in per_unit:
            raise WorkbookError("Global_params", "columns F:Z", f'unit "{name}" ({kind}) has no day-ahead budget')
    return Budgets(prices["pGamma_Price_DAM [-]"], prices["pGamma_Price_SRM_up [-]"],
                   prices["pGamma_Price_SRM_down [-]"],
                   MappingProxyType(per_unit))


def _switches(sheets: _Sheets) -> dict[str, bool]:
    pairs = sheets.pairs("VPP_Units", "K", HEADER_ROW)
    names = ("sDRES_exists", "sHydro_exists", "sBiomass_exists", "sNDRES_exists", "sWF_exists", "sPV_exists",
             "sSTH_exists", "sTS_exists", "sDem_exists", "sES_exists")
    out = {}
    for name in names:
        value = _value(pairs, "VPP_Units", "K", f"{name} [-]")
        if value not in (0, 1):
            raise WorkbookError("VPP_Units", f'parameter "{name} [-]"', f"{value:g} must be 0 or 1")
        out[name] = value == 1
    return out


def _pcc_capacity(sheets: _Sheets) -> float:
    table = sheets.table("Buses", "E", "F", 1, ("PCC capacity [MW]",))
    if len(table.rows) != 1:
        raise WorkbookError("Buses", "column E", f"must list one connection point (PCC), found {len(table.rows)}")
    (key,) = table.rows
    return table.number(key, "PCC capacity [MW]")


def _prices(sheets: _Sheets, periods: tuple[str, ...]) -> pd.DataFrame:
    table = sheets.table("Price_Forecast", "A", "AJ", 1, tuple(PRICE_COLUMNS))
    data = {new: [table.number((t,), old) for t in periods] for old, new in PRICE_COLUMNS.items()}
    return pd.DataFrame(data, index=pd.Index(periods, name="period"))


def _row_of(table: _Table, name: str, sheet: str, what: str) -> tuple[str, ...]:
    if (name,) not in table.rows:
        raise WorkbookError(sheet, "key column", f'{what} "{name}" listed in VPP_Units has no row')
    return (name,)


def _forecast(sheets: _Sheets, name: str, periods: tuple[str, ...]) -> pd.DataFrame:
    columns = ("Pavailable DAM [MW]", "Dev Pavailable DAM [MW]")
    table = sheets.table("Energy_Forecast", "A", "T", 2, columns)
    missing = [t for t in periods if (name, t) not in table.rows]
    if missing:
        raise WorkbookError("Energy_Forecast", "columns A:B",
                            f'unit "{name}" has no forecast for {", ".join(missing[:3])}')
    frame = pd.DataFrame({"available_mw": [table.number((name, t), columns[0]) for t in periods],
                          "deviation_mw": [table.number((name, t), columns[1]) for t in periods]},
                         index=pd.Index(periods, name="period"))
    bad = frame.index[(frame.deviation_mw < 0) | (frame.deviation_mw > frame.available_mw + 1e-9)]
    if len(bad):
        raise WorkbookError("Energy_Forecast", f'unit "{name}" period {bad[0]}',
                            "the deviation must lie in [0, available power]")
    return frame


def _dispatchable(sheets: _Sheets, units: dict[str, str], switches: dict[str, bool]) -> tuple[Dispatchable, ...]:
    names = _of_type(units, "DRES")
    columns = ("Production cost [Euro/MWh]", "Max power production [MW]", "Min power production [MW]", "Ramp up [MW/h]",
               "Ramp down [MW/h]", "Startup ramp up [MW/h]", "Shutdown ramp down [MW/h]", "Startup cost [Euro]",
               "Shutdown cost [Euro]", "Commit status t=0 [-]", "power production t=0 [MW]", "SR ramp up [MW/min]",
               "SR ramp down [MW/min]", "Online periods prior t=1 [hour]", "Offline periods prior t=1 [hour]",
               "Min up time [hour]", "Min down time [hour]", "Max energy [MWh]")
    table = sheets.table("DRES", "F", "X", 1, columns) if names else None
    out = []
    for name in names:
        key = _row_of(table, name, "DRES", "dispatchable unit")
        v = table.unit_numbers(key, columns, name)
        _check_dispatchable(name, dict(zip(columns, v)))
        kind = DISPATCHABLE_KINDS.get(name, "dispatchable")
        switch = {"hydro": "sHydro_exists", "biomass": "sBiomass_exists"}.get(kind)
        enabled = switches["sDRES_exists"] and (switch is None or switches[switch])
        out.append(Dispatchable(name, kind, enabled, p_min_mw=v[2], p_max_mw=v[1], cost_eur_per_mwh=v[0],
                                ramp_up_mw_per_h=v[3], ramp_dn_mw_per_h=v[4], startup_ramp_mw_per_h=v[5],
                                shutdown_ramp_mw_per_h=v[6], startup_cost_eur=v[7], shutdown_cost_eur=v[8],
                                initially_on=_binary(v[9], "DRES", name, columns[9]), p_init_mw=v[10],
                                sr_ramp_up_mw_per_min=v[11], sr_ramp_dn_mw_per_min=v[12], hours_on_before=v[13],
                                hours_off_before=v[14], min_up_h=v[15], min_down_h=v[16], e_max_mwh=v[17]))
    return tuple(out)


def _check_dispatchable(name: str, values: dict[str, float]) -> None:
    """The rules of rvpp's case model for a hydro or biomass unit, in the words of sheet DRES."""
    low, high = values["Min power production [MW]"], values["Max power production [MW]"]
    if low > high:
        raise WorkbookError("DRES", f'unit "{name}"', f"Min power production {low:g} MW must be <= Max power "
                                                       f"production {high:g} MW")
    for column in ("Min up time [hour]", "Min down time [hour]"):
        if not 0 <= values[column] <= PERIODS:
            raise WorkbookError("DRES", f'unit "{name}" column "{column}"',
                                f"{values[column]:g} must lie in 0..{PERIODS} h: a minimum time is at most the day")
    hours = max(values["Min up time [hour]"], 1.0)  # the workbook's periods are of 1 h (sDelta)
    energy = values["Max energy [MWh]"]
    if energy < low * hours:
        raise WorkbookError("DRES", f'unit "{name}" column "Max energy [MWh]"',
                            f"{energy:g} is below Min power production x Min up time = {low:g} MW x {hours:g} h = "
                            f"{low * hours:g} MWh: once started, the unit could not run its minimum up time at its "
                            "minimum output")


def _binary(value: float, sheet: str, name: str, column: str) -> bool:
    if value not in (0, 1):
        raise WorkbookError(sheet, f'unit "{name}" column "{column}"', f"{value:g} must be 0 or 1")
    return value == 1


def _non_dispatchable(sheets: _Sheets, units: dict[str, str], switches: dict[str, bool],
                      periods: tuple[str, ...]) -> tuple[NonDispatchable, ...]:
    names = _of_type(units, "NDRES")
    columns = ("Min power [MW]", "Operation Cost [Euro/MWh]", "SR Ramp Up [MW/min]", "SR Ramp Down [MW/min]",
               "Max power [MW]")
    table = sheets.table("NDRES", "A", "F", 1, columns) if names else None
    out = []
    for name in names:
        key = _row_of(table, name, "NDRES", "non-dispatchable unit")
        if name not in NON_DISPATCHABLE_KINDS:
            raise WorkbookError("VPP_Units", f'unit "{name}"',
                                "the tool knows a non-dispatchable unit as wind (U3) or PV (U4) only by these names")
        kind = NON_DISPATCHABLE_KINDS[name]
        enabled = switches["sNDRES_exists"] and switches["sWF_exists" if kind == "wind" else "sPV_exists"]
        v = table.unit_numbers(key, columns, name)
        out.append(NonDispatchable(name, kind, enabled, p_min_mw=v[0], p_max_mw=v[4], cost_eur_per_mwh=v[1],
                                   sr_ramp_up_mw_per_min=v[2], sr_ramp_dn_mw_per_min=v[3],
                                   forecast=_forecast(sheets, name, periods)))
    return tuple(out)


def _solar_thermal(sheets: _Sheets, units: dict[str, str], switches: dict[str, bool],
                   periods: tuple[str, ...]) -> tuple[SolarThermal, ...]:
    names = _of_type(units, "STH")
    columns = ("Operation cost [Euro/MWh]", "Machine capacity [MW]", "Max electrical output [MW]",
               "Commit status t=0 [-]", "Online periods prior t=1 [hour]", "Offline periods prior t=1 [hour]",
               "Min up time [hour]", "Min down time [hour]")
    if not names:
        return ()
    table = sheets.table("STH", "F", "N", 1, columns)
    curve = sheets.table("STH", "P", "S", 2, ("Powerblock breakpoint [MW]", "Piecewise bounds [pu]"))
    tanks = sheets.table("VPP_Units", "H", "I", 2, ())
    out = []
    for name in names:
        key = _row_of(table, name, "STH", "solar thermal plant")
        v = table.unit_numbers(key, columns, name)
        # The tool's names are swapped: "breakpoint" holds the thermal input, "bounds" the efficiency.
        points = tuple((curve.number(k, "Powerblock breakpoint [MW]"), curve.number(k, "Piecewise bounds [pu]"))
                       for k in curve.rows if k[0] == name)
        if len(points) < 2:
            raise WorkbookError("STH", "columns P:S", f'plant "{name}" needs at least two power-block breakpoints')
        linked = [tank for (plant, tank) in tanks.rows if plant == name]
        if len(linked) > 1:
            raise WorkbookError("VPP_Units", "columns H:I",
                                f'plant "{name}" has {len(linked)} tanks; the tool links one')
        for tank in linked:
            if units.get(tank) != "TES":
                raise WorkbookError("VPP_Units", "columns H:I", f'tank "{tank}" of plant "{name}" is not a TES unit')
        out.append(SolarThermal(name, switches["sSTH_exists"], cost_eur_per_mwh=v[0], p_in_max_mw_th=v[1],
                                p_el_max_mw=v[2],
                                initially_on=_binary(v[3], "STH", name, columns[3]), hours_on_before=v[4],
                                hours_off_before=v[5], min_up_h=v[6], min_down_h=v[7], breakpoints=points,
                                storage=linked[0] if linked else None, forecast=_forecast(sheets, name, periods)))
    return tuple(out)


def _storages(sheets: _Sheets, units: dict[str, str], switches: dict[str, bool]) -> tuple[Storage, ...]:
    names = [n for n, k in units.items() if k in ("TES", "ES")]
    columns = ("Self degradation coefficient [-]", "Max energy [MWh]", "Min energy [MWh]", "Discharging power [MW]",
               "Charging power [MW]", "Initial energy [MWh]", "Charging efficiency [%]", "Discharging efficiency [%]",
               "ESS cost [Euro]", "lifecycle slope [-]", "SR ramp up [MW/min]", "SR ramp down [MW/min]")
    table = sheets.table("ESS", "A", "M", 1, columns) if names else None
    out = []
    for name in names:
        key = _row_of(table, name, "ESS", "storage")
        v = table.unit_numbers(key, columns, name, unlimited=("ESS cost [Euro]",))
        thermal = units[name] == "TES"
        if not thermal and v[0] >= SELF_DISCHARGE_DIVISOR:
            raise WorkbookError("ESS", f'unit "{name}" column "{columns[0]}"',
                                f"{v[0]:g} must be < {SELF_DISCHARGE_DIVISOR:g}: the tool keeps 1 - coefficient / "
                                f"{SELF_DISCHARGE_DIVISOR:g} of the energy each hour")
        for column, eta in ((columns[6], v[6]), (columns[7], v[7])):
            if not 0 < eta <= 1:  # the header says [%] but the tool divides by it as a fraction
                raise WorkbookError("ESS", f'unit "{name}" column "{column}"', f"{eta:g} must be a fraction in (0, 1]")
        if not v[2] < v[1]:
            raise WorkbookError("ESS", f'unit "{name}"', f"Min energy {v[2]:g} must be < Max energy {v[1]:g}")
        out.append(Storage(name, "thermal" if thermal else "electrical",
                           switches["sTS_exists" if thermal else "sES_exists"], self_discharge=v[0], e_max_mwh=v[1],
                           e_min_mwh=v[2], p_dis_max_mw=v[3], p_ch_max_mw=v[4], e_init_mwh=v[5], eta_ch=v[6],
                           eta_dis=v[7], cost_eur=v[8], lifecycle_slope=v[9], sr_ramp_up_mw_per_min=v[10],
                           sr_ramp_dn_mw_per_min=v[11]))
    return tuple(out)


def _demands(sheets: _Sheets, units: dict[str, str], switches: dict[str, bool],
             periods: tuple[str, ...]) -> tuple[Demand, ...]:
    names = _of_type(units, "D")
    if not names:
        return ()
    profiles = sheets.table("Demand", "A", "D", 3, ("Demand [MW]",))
    costs = sheets.table("Demand", "F", "H", 2, ("Cost [Euro]",))
    flex = sheets.table("Demand", "J", "M", 2, ("Negative fluctuation [pu]", "Positive fluctuation [pu]"))
    columns = ("Min Energy [MWh]", "Ramp Up [MW/h]", "Ramp Down [MW/h]", "SR Ramp Up [MW/min]", "SR Ramp Down [MW/min]",
               "Initial load level [MW]", "Min Demand [MW]", "Max Demand [MW]")
    table = sheets.table("Demand", "O", "W", 1, columns)
    deviations = sheets.table("Demand", "AD", "AO", 3, ("Dev Demand DAM [MW]",))
    out = []
    for name in names:
        key = _row_of(table, name, "Demand", "demand")
        v = table.unit_numbers(key, columns, name)
        chosen = [lp for (u, lp) in costs.rows if u == name]
        if not chosen:
            raise WorkbookError("Demand", "columns F:H", f'demand "{name}" has no load profile')
        shape, dev = {}, {}
        for lp in chosen:
            for t in periods:
                if (name, lp, t) not in profiles.rows:
                    raise WorkbookError("Demand", "columns A:D", f'demand "{name}" profile {lp} has no value for {t}')
            shape[lp] = [profiles.number((name, lp, t), "Demand [MW]") for t in periods]
            dev[lp] = [deviations.number((name, lp, t), "Dev Demand DAM [MW]") if (name, lp,
                                                                                   t) in deviations.rows else 0.0
                       for t in periods]
        for t in periods:
            if (name, t) not in flex.rows:
                raise WorkbookError("Demand", "columns J:M", f'demand "{name}" has no fluctuation for {t}')
        index = pd.Index(periods, name="period")
        out.append(Demand(name, switches["sDem_exists"], profiles=pd.DataFrame(shape, index=index),
                          deviations=pd.DataFrame(dev, index=index),
                          profile_costs=MappingProxyType({lp: costs.number((name, lp),
                                                                           "Cost [Euro]") for lp in chosen}),
                          flex_dn=pd.Series([flex.number((name, t), "Negative fluctuation [pu]") for t in periods],
                                            index=index),
                          flex_up=pd.Series([flex.number((name, t), "Positive fluctuation [pu]") for t in periods],
                                            index=index),
                          e_min_mwh=v[0], ramp_up_mw_per_h=v[1], ramp_dn_mw_per_h=v[2], sr_ramp_up_mw_per_min=v[3],
                          sr_ramp_dn_mw_per_min=v[4], p_init_mw=v[5], p_min_mw=v[6], p_max_mw=v[7]))
    return tuple(out)


# ----------------------------------------------------------------------------- stored result

RESULT_TOTALS = {  # label in DAM!V -> field of StoredResult
    "Profit DAM+SRM [Euro]": "profit_eur",
    "Revenue DAM+SRM [Euro]": "revenue_eur",
    "Cost DAM+SRM [Euro]": "cost_eur",
    "Revenue DAM [Euro]": "revenue_dam_eur",
    "Revenue SRM [Euro]": "revenue_srm_eur",
    "Cost Operation DAM [Euro]": "operating_cost_eur",
    "Robust cost DAM [Euro]": "protection_dam_eur",
    "Robust cost SRM [Euro]": "protection_srm_eur",
    "State DAM+SRM [-]": "status",
    "Time DAM+SRM [s]": "solve_time_s",
}
UNIT_RESULT_COLUMNS = {
    "Generation DAM [MW]": "power_mw",
    "Ess charge DAM [MW]": "charge_mw",
    "Ess discharge DAM [MW]": "discharge_mw",
    "Ess energy DAM [MW]": "energy_mwh",  # the header says MW; the value is the stored energy [MWh]
    "Commitment DAM [-]": "online",
    "Start Up DAM [-]": "startup",
    "Shut Down DAM [-]": "shutdown",
}


def _result(sheets: _Sheets, periods: tuple[str, ...]) -> StoredResult:
    market_columns = ("Traded power DAM [MW]", "UP SR offer DAM [MW]", "Down SR offer DAM [MW]")
    market = sheets.table("DAM", "A", "D", 1, market_columns)
    missing = [t for t in periods if (t,) not in market.rows]
    if missing:
        raise WorkbookError("DAM", "columns A:D", f"the stored schedule has no row for {', '.join(missing[:3])}")
    market_frame = pd.DataFrame({new: [market.number((t,), old, blank=math.nan) for t in periods]
                                 for old, new in zip(market_columns, ("p_da_mw", "r_up_mw", "r_dn_mw"), strict=True)},
                                index=pd.Index(periods, name="period"))
    units = sheets.table("DAM", "F", "N", 2, tuple(UNIT_RESULT_COLUMNS))
    unit_frame = pd.DataFrame([{new: units.number(key, old, blank=math.nan) for old, new in UNIT_RESULT_COLUMNS.items()}
                               for key in units.rows],
                              index=pd.MultiIndex.from_tuples(list(units.rows), names=["unit", "period"]))
    reserves = sheets.table("DAM", "P", "T", 3, ("UP SR DAM [MW]", "Down SR DAM [MW]"))
    up = {(u, t): reserves.number((v, u, t), "UP SR DAM [MW]") for (v, u, t) in reserves.rows if v == "V1"}
    dn = {(u, t): reserves.number((v, u, t), "Down SR DAM [MW]") for (v, u, t) in reserves.rows if v == "V2"}
    keys = list(dict.fromkeys([*up, *dn]))
    reserve_frame = pd.DataFrame({"r_up_mw": [up.get(k, 0.0) for k in keys], "r_dn_mw": [dn.get(k, 0.0) for k in keys]},
                                 index=pd.MultiIndex.from_tuples(keys, names=["unit", "period"]))
    pairs = sheets.pairs("DAM", "V", HEADER_ROW)
    totals = {field: _value(pairs, "DAM", "V", label) for label, field in RESULT_TOTALS.items()}
    return StoredResult(market_frame, unit_frame, reserve_frame, _chosen_profiles(sheets, periods), **totals)


def _chosen_profiles(sheets: _Sheets, periods: tuple[str, ...]) -> Mapping[str, str]:
    """The profile each demand chose: the one whose values the day-ahead session wrote to
    Trade_Units (the session that follows keeps that profile)."""
    written = sheets.table("Trade_Units", "AZ", "BB", 2, ("Demand profile DAM [MW]",))
    profiles = sheets.table("Demand", "A", "D", 3, ("Demand [MW]",))
    chosen: dict[str, str] = {}
    for name in dict.fromkeys(u for (u, _t) in written.rows):
        values = [written.number((name, t), "Demand profile DAM [MW]") if (name, t) in written.rows else math.nan
                  for t in periods]
        candidates = dict.fromkeys(lp for (u, lp, _t) in profiles.rows if u == name)
        matches = sorted(lp for lp in candidates
                         if all(profiles.number((name, lp, t), "Demand [MW]") == v
                                for t, v in zip(periods, values, strict=True)))
        if len(matches) != 1:
            raise WorkbookError("Trade_Units", "columns AZ:BB",
                                f'the stored profile of demand "{name}" matches {len(matches)} of its load '
                                "profiles, not one")
        chosen[name] = matches[0]
    return MappingProxyType(chosen)
