"""A case from the workbook of the seed paper's authors' tool (``rvpp data import-workbook``).

:func:`workbook_case` maps what :func:`~rvpp.data.importers.gams_workbook.read_workbook` read
onto rvpp's case model; :func:`import_workbook` also writes the case folder (``case.yaml`` and
``history.csv``) atomically. docs/gams-tool.md gives every mapping and every difference between
the two models.

The workbook holds one day: a point value and a deviation per period for every uncertain
series, not a history. rvpp draws its bands ``lo``/``mid``/``hi`` from a window of days before
the delivery day (MODEL_SPEC §6). The import therefore writes a six-day window whose per-hour
percentiles are the workbook's bands exactly: each hour holds ``lo, lo, mid, mid, hi, hi``, and
with ``q_lo = 0.2``, ``q_hi = 0.8`` and numpy's linear interpolation the 20th percentile of six
values is the second (``lo``), the median the mean of the third and fourth (``mid``) and the 80th
percentile the fifth (``hi``). The window is stated in the case (``uncertainty.window_days: 6``,
the quantiles, ``timezone: UTC`` so no day has a clock change) and the history's provenance says
that it is constructed, not observed.

Bands from the workbook's columns (rvpp's nominal value and adverse deviation, MODEL_SPEC §5-§6):

============================  ===================================  ================================
series                        ``lo`` / ``mid`` / ``hi``            rvpp then uses
============================  ===================================  ================================
DAM price                     price − neg dev / price / + pos dev  nominal mid, deviations both ways
SR up / down price            price − dev / midpoint / price       nominal hi, deviation hi − lo
wind, PV, solar field         avail − dev / midpoint / avail       nominal hi, deviation hi − lo
demand (the chosen profile)   profile / midpoint / profile + dev   nominal lo, deviation hi − lo
============================  ===================================  ================================
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from ...errors import CaseError, DataImportError
from ..case import CASE_FILE, Case, parse_case
from ..case_yaml import check_case_folder, write_case_folder
from ..history import History
from ..kinds import UnitKind
from .gams_workbook import SELF_DISCHARGE_DIVISOR, Workbook, WorkbookError, read_workbook

HISTORY_FILE = "history.csv"
WRITTEN = (CASE_FILE, HISTORY_FILE)
WINDOW_DAYS = 6  # lo, lo, mid, mid, hi, hi per hour
Q_LO, Q_HI = 0.2, 0.8  # on six values: exactly the 2nd and the 5th
TIMEZONE = "UTC"  # the workbook names no place; UTC has no clock change, so every day has 24 hours
SOLVER_REL_GAP = 1e-9  # the imported case is solved to optimality (docs/gams-tool.md)
CSV_DIGITS = 6  # significant digits History.to_csv keeps
SOURCE = "the authors' RVPP tool workbook"
DISPATCHABLE = (UnitKind.HYDRO.value, UnitKind.BIOMASS.value)


class Band(NamedTuple):
    """One series' band per period and where the workbook holds it (for messages)."""

    lo: np.ndarray
    mid: np.ndarray
    hi: np.ndarray
    sheet: str
    where: str


@dataclass(frozen=True)
class WorkbookImport:
    """The case made from a workbook and where it was written."""

    case: Case
    folder: Path | None = None

    def lines(self) -> list[str]:
        units = ", ".join(f"{kind} {unit.name}" + ("" if getattr(unit, "enabled", True) else " (disabled)")
                          for kind, unit in self.case.all_units())
        out = [f"case {self.case.name!r} for {self.case.delivery_date}: {units}"]
        if self.folder is not None:
            out.append(f"wrote {CASE_FILE} and {HISTORY_FILE} to {self.folder}")
        return out


def import_workbook(path: str | Path, out: str | Path, date: dt.date, *, overwrite: bool = False) -> WorkbookImport:
    """Read the workbook at ``path`` and write its case into the folder ``out``.

    Nothing is written unless the whole workbook maps: any :class:`WorkbookError` (or a case
    rule broken by the mapped values) is raised before the folder is touched.
    """
    out = Path(out)
    _check_out(out, overwrite)
    made = workbook_case(read_workbook(path), date)
    _write(made.case, out, overwrite)
    return WorkbookImport(made.case, out)


def workbook_case(book: Workbook, date: dt.date) -> WorkbookImport:
    """The rvpp case of ``book`` delivered on ``date`` (see the module docstring for the bands)."""
    units: dict[str, list[dict[str, Any]]] = {}
    series: dict[str, Band] = {}  # history column -> its band
    for unit in book.non_dispatchable:
        units.setdefault(unit.kind, []).append(_non_dispatchable(book, unit))
        series[unit.name] = _production_band(unit.forecast, f'unit "{unit.name}"')
    for plant in book.solar_thermal:
        units.setdefault(UnitKind.CSP.value, []).append(_solar_thermal(book, plant))
        series[plant.name] = _production_band(plant.forecast, f'unit "{plant.name}"')
    for demand in book.demands:
        units.setdefault(UnitKind.ED.value, []).append(_demand(demand))
        profile = book.result.demand_profiles.get(demand.name)
        if profile is None:
            raise WorkbookError("Trade_Units", "columns AZ:BB", f'demand "{demand.name}" has no chosen profile')
        lo = demand.profiles[profile].to_numpy(float)
        hi = lo + demand.deviations[profile].to_numpy(float)
        series[demand.name] = Band(lo, _middle(lo, hi), hi, "Demand", f'unit "{demand.name}" profile {profile}')
    for unit in book.dispatchable:
        if unit.kind not in DISPATCHABLE:
            raise WorkbookError("VPP_Units", f'unit "{unit.name}"', "the tool knows a dispatchable unit as hydro (U1) "
                                                                    "or biomass (U2) only by these names")
        units.setdefault(unit.kind, []).append(_dispatchable(book, unit))
    for storage in book.storages:
        if storage.kind == "electrical":
            units.setdefault(UnitKind.BATTERY.value, []).append(_battery(storage))
    series.update(_price_bands(book))
    history = _window(series, date)
    data = {
        "name": "gams-tool-workbook",
        "description": ("The day-ahead case of the authors' RVPP tool workbook (Nemati et al., Renewable-based "
                        "Virtual Power Plant, v1.0.0, Apache-2.0), imported by rvpp data import-workbook. "
                        "See docs/gams-tool.md."),
        "delivery_date": date.isoformat(),
        "timezone": TIMEZONE,
        "dt_h": book.settings.dt_h,
        "markets": {"dam": True, "srm": True, "hpa": False, "kappa": book.settings.reserve_share_vpp,
                    "reserve_base": "installed",
                    "reserve_duration_min": book.settings.reserve_duration_min,
                    "hpa_tariff_eur_per_mwh": [0.0] * 24},
        "uncertainty": {"window_days": WINDOW_DAYS, "q_lo": Q_LO, "q_hi": Q_HI, "bands": {"default": "climatology"}},
        "budgets": {"mode": "paper", "overrides": {"price_da": book.budgets.price_da,
                                                   "price_sr_up": book.budgets.price_sr_up,
                                                   "price_sr_dn": book.budgets.price_sr_dn,
                                                   **book.budgets.units}},
        # solved to optimality, not to the default 0.01 % gap (about 1 EUR here): the stored result is optimal
        "solver": {"rel_gap": SOLVER_REL_GAP},
        "units": units,
        "provenance": {column: {"origin": "synthetic", "source": SOURCE,
                                "note": "constructed window: each hour holds lo, lo, mid, mid, hi, hi of the "
                                        "workbook's band, so the case's percentiles are that band"}
                       for column in series},
    }
    try:
        case = parse_case(data, history)
    except CaseError as err:
        raise DataImportError("the workbook's values break a rule of rvpp's case model: "
                              + "; ".join(err.problems)) from None
    return WorkbookImport(case)


def _dispatchable(book: Workbook, unit) -> dict[str, Any]:
    if unit.sr_ramp_up_mw_per_min != unit.sr_ramp_dn_mw_per_min:
        raise WorkbookError("DRES", f'unit "{unit.name}" columns "SR ramp up/down [MW/min]"',
                            "differ; rvpp has one reserve ramp per unit")
    status_h = unit.hours_on_before if unit.initially_on else unit.hours_off_before
    return {"name": unit.name, "enabled": unit.enabled, "p_min_mw": unit.p_min_mw, "p_max_mw": unit.p_max_mw,
            "marginal_cost_eur_per_mwh": unit.cost_eur_per_mwh, "startup_cost_eur": unit.startup_cost_eur,
            "shutdown_cost_eur": unit.shutdown_cost_eur, "ramp_up_mw_per_h": unit.ramp_up_mw_per_h,
            "ramp_dn_mw_per_h": unit.ramp_dn_mw_per_h, "startup_ramp_mw_per_h": unit.startup_ramp_mw_per_h,
            "shutdown_ramp_mw_per_h": unit.shutdown_ramp_mw_per_h, "min_up_h": unit.min_up_h,
            "min_down_h": unit.min_down_h, "initial_online": unit.initially_on, "initial_hours_in_status": status_h,
            "p_init_mw": unit.p_init_mw, "energy_max_mwh": unit.e_max_mwh,
            "ramp_mw_per_min": unit.sr_ramp_up_mw_per_min,
            "reserve_share": book.settings.reserve_share_dispatchable}


def _battery(storage) -> dict[str, Any]:
    if storage.sr_ramp_up_mw_per_min != storage.sr_ramp_dn_mw_per_min:
        raise WorkbookError("ESS", f'unit "{storage.name}" columns "SR ramp up/down [MW/min]"',
                            "differ; rvpp has one reserve ramp per unit")
    throughput = storage.lifecycle_slope * storage.cost_eur / storage.e_max_mwh  # per MWh charged or discharged
    return {"name": storage.name, "enabled": storage.enabled, "e_min_mwh": storage.e_min_mwh,
            "e_max_mwh": storage.e_max_mwh, "p_ch_max_mw": storage.p_ch_max_mw, "p_dis_max_mw": storage.p_dis_max_mw,
            "eta_ch": storage.eta_ch, "eta_dis": storage.eta_dis,
            "self_discharge_per_h": storage.self_discharge / SELF_DISCHARGE_DIVISOR,
            # per MWh discharged: what the throughput cost comes to on a cyclic day without self-discharge
            "degradation_eur_per_mwh": throughput * (1 + 1 / (storage.eta_ch * storage.eta_dis)),
            "ramp_mw_per_min": storage.sr_ramp_up_mw_per_min, "reserve_share": 1.0}


def _non_dispatchable(book: Workbook, unit) -> dict[str, Any]:
    return {"name": unit.name, "p_max_mw": unit.p_max_mw, "p_min_mw": unit.p_min_mw,
            "om_eur_per_mwh": unit.cost_eur_per_mwh, "ramp_up_mw_per_min": unit.sr_ramp_up_mw_per_min,
            "ramp_dn_mw_per_min": unit.sr_ramp_dn_mw_per_min,
            "reserve_share": book.settings.reserve_share_non_dispatchable}


def _solar_thermal(book: Workbook, plant) -> dict[str, Any]:
    tank = next((s for s in book.storages if s.name == plant.storage), None)
    if tank is None:
        raise WorkbookError("VPP_Units", "columns H:I", f'solar thermal plant "{plant.name}" has no tank (TES)')
    if tank.sr_ramp_up_mw_per_min != tank.sr_ramp_dn_mw_per_min:
        raise WorkbookError("ESS", f'unit "{tank.name}" columns "SR ramp up/down [MW/min]"',
                            "differ; rvpp has one band limit for the tank's four bands")
    if book.settings.reserve_call_fraction <= 0:
        raise WorkbookError("Global_params", "sFraction_Time_SR",
                            f"{book.settings.reserve_call_fraction:g} must be above 0 (the share of an hour a "
                            "band is called)")
    share = book.settings.reserve_share_solar_thermal
    curve = [list(point) for point in plant.breakpoints]
    first_output = next((p for p, eta in plant.breakpoints if p * eta > 0), None)
    if first_output is None:
        raise WorkbookError("STH", "columns P:S", f'plant "{plant.name}": no breakpoint gives electrical output')
    return {
        "name": plant.name,
        "om_eur_per_mwh": plant.cost_eur_per_mwh,
        "heat_efficiency": 1.0,
        # The tool limits the plant's band by its share of Pmax only: a ramp of share x Pmax per reserve
        # duration never binds before the share does.
        "ramp_mw_per_min": share * plant.p_el_max_mw / book.settings.reserve_duration_min,
        "reserve_share": share,
        "solar_field": {"p_max_mw_th": float(plant.forecast.available_mw.max())},
        "storage": {"e_min_mwh_th": tank.e_min_mwh, "e_max_mwh_th": tank.e_max_mwh,
                    "p_ch_max_mw_th": tank.p_ch_max_mw, "p_dis_max_mw_th": tank.p_dis_max_mw,
                    "eta_ch": tank.eta_ch, "eta_dis": tank.eta_dis,  # no e_init: the tool's day is cyclic
                    # the tool's conventions (docs/gams-tool.md D17, D19): each band within the reserve
                    # duration at the SR ramp; sFraction_Time_SR x the energy behind the bands <= 2 σ ΔE, σ <= 0.5
                    "reserve_band_max_mw_th": book.settings.reserve_duration_min * tank.sr_ramp_up_mw_per_min,
                    "reserve_energy_factor": 2.0 / book.settings.reserve_call_fraction,
                    "reserve_share_max": 0.5},
        "power_block": {"p_in_max_mw_th": plant.p_in_max_mw_th, "p_in_min_mw_th": first_output,
                        "output_capped": False,  # the tool's curve is not capped at p_el_max (D16)
                        "p_el_max_mw": plant.p_el_max_mw, "breakpoints": curve, "min_up_h": plant.min_up_h,
                        "min_down_h": plant.min_down_h, "startup_fraction": book.settings.startup_heat_fraction,
                        "initially_on": plant.initially_on,
                        "initial_status_h": plant.hours_on_before if plant.initially_on else plant.hours_off_before},
    }


def _demand(demand) -> dict[str, Any]:
    # rvpp's flex_up bounds the up band (a consumption decrease) and, with profile_window, the
    # window below the profile: the tool's negative fluctuation; flex_dn its positive one
    flex = {}
    for field, values, column in (("flex_up", demand.flex_dn, "Negative fluctuation [pu]"),
                                  ("flex_dn", demand.flex_up, "Positive fluctuation [pu]")):
        if values.nunique() != 1:
            raise WorkbookError("Demand", f'unit "{demand.name}" column "{column}"',
                                "varies between periods; rvpp's demand has one flexibility share for the day")
        flex[field] = float(values.iloc[0])
    if demand.sr_ramp_up_mw_per_min != demand.sr_ramp_dn_mw_per_min:
        raise WorkbookError("Demand", f'unit "{demand.name}" columns "SR Ramp Up/Down [MW/min]"',
                            "differ; the tool limits the up band by the down ramp and the reverse, which rvpp "
                            "does not reproduce, so only equal ramps are imported")
    return {"name": demand.name, "p_min_mw": demand.p_min_mw, "p_max_mw": demand.p_max_mw,
            "e_min_mwh": demand.e_min_mwh, "p_init_mw": demand.p_init_mw,
            "ramp_up_mw_per_min": demand.sr_ramp_up_mw_per_min, "ramp_dn_mw_per_min": demand.sr_ramp_dn_mw_per_min,
            **flex,
            # the tool's conventions (docs/gams-tool.md D23, D25, D26)
            "profile_window": True, "ramp_up_mw_per_h": demand.ramp_up_mw_per_h,
            "ramp_dn_mw_per_h": demand.ramp_dn_mw_per_h, "energy_net_of_up_band": False}


def _production_band(forecast: pd.DataFrame, where: str) -> Band:
    hi = forecast.available_mw.to_numpy(float)
    lo = hi - forecast.deviation_mw.to_numpy(float)
    return Band(lo, _middle(lo, hi), hi, "Energy_Forecast", where)


def _middle(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The midpoint of a one-sided band, to the digits the history keeps (rvpp does not use the
    median of these series: their nominal value is an end of the band)."""
    return np.array([float(f"{value:.{CSV_DIGITS}g}") for value in (lo + hi) / 2])


def _price_bands(book: Workbook) -> dict[str, Band]:
    p = book.prices
    da = p.price_da.to_numpy(float)
    up, dn = p.price_sr_up.to_numpy(float), p.price_sr_dn.to_numpy(float)
    up_lo, dn_lo = up - p.price_sr_up_dev_dn.to_numpy(float), dn - p.price_sr_dn_dev_dn.to_numpy(float)
    return {
        "price_da": Band(da - p.price_da_dev_dn.to_numpy(float), da, da + p.price_da_dev_up.to_numpy(float),
                         "Price_Forecast", 'column "DAM Price [Euro/MWh]"'),
        "price_sr_up": Band(up_lo, _middle(up_lo, up), up, "Price_Forecast", 'column "Up_SRM Price in DAM [Euro/MWh]"'),
        "price_sr_dn": Band(dn_lo, _middle(dn_lo, dn), dn, "Price_Forecast", 'column "D_SRM Price in DAM [Euro/MWh]"'),
    }


def _window(series: dict[str, Band], date: dt.date) -> History:
    """Six days before ``date`` (UTC), each hour ``lo, lo, mid, mid, hi, hi`` of every series."""
    columns: dict[str, np.ndarray] = {}
    for column, (lo, mid, hi, sheet, where) in series.items():
        if np.any(hi < lo):
            t = int(np.argmax(hi < lo)) + 1
            raise WorkbookError(sheet, f"{where} period T{t}",
                                f"the deviation makes the band's upper end {hi[t - 1]:g} lie below its lower end "
                                f"{lo[t - 1]:g}; deviations must be >= 0")
        for end, values in (("lower end", lo), ("middle", mid), ("upper end", hi)):
            for t, value in enumerate(values, start=1):
                kept = float(f"{value:.{CSV_DIGITS}g}")  # as the history CSV keeps it
                if not math.isclose(kept, value, rel_tol=1e-9, abs_tol=1e-9):
                    raise WorkbookError(sheet, f"{where} period T{t}",
                                        f"the band's {end} {value:.12g} needs more than {CSV_DIGITS} significant "
                                        f"digits; the case's history keeps {CSV_DIGITS}, so its band would not be "
                                        "the workbook's")
        days = np.stack([lo, lo, mid, mid, hi, hi]).ravel()  # [day, hour]
        columns[column] = np.array([float(f"{value:.{CSV_DIGITS}g}") for value in days])
    start = pd.Timestamp(date - dt.timedelta(days=WINDOW_DAYS), tz=TIMEZONE)
    stamps = pd.date_range(start, periods=WINDOW_DAYS * 24, freq="h")
    frame = pd.DataFrame({"timestamp": stamps, **columns})
    return History(frame, source=HISTORY_FILE)


def _check_out(out: Path, overwrite: bool) -> None:
    """Refuse a folder that already holds a case (unless ``overwrite``) and a path that is not a folder."""
    check_case_folder(out, WRITTEN, overwrite, DataImportError)


def _write(case: Case, out: Path, overwrite: bool) -> None:
    """Write the case into a temporary folder beside ``out``, then move its files into place."""
    write_case_folder(case, out, HISTORY_FILE, WRITTEN, overwrite, _check_out)
