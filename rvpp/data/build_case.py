"""A case built from downloaded data: real prices, units and demands derived from the fleets and load, modelled the rest.

:func:`build_case` reads the files with the importers, puts them on one hour grid and writes
a case folder (``case.yaml`` and ``history.csv``) whose units and settings come from a
template case (the paper's by default):

========================  =====================================================================
history column            made from
========================  =====================================================================
``price_da``              the day-ahead price as published (real)
wind unit ``W``           fleet capacity factor × the unit's nameplate: ``actual / capacity``,
                          capacity = the fleet's highest output in the data or a given value
``W_fc``                  ``actual - K·(actual - fleet forecast)`` on the same scale, clipped to
                          ``[0, nameplate]``: the fleet's day-ahead forecast error scaled by ``K``
                          (``errors_scale``), since one farm errs several times more than a
                          spatially smoothed national fleet
PV unit ``P``, ``P_fc``   the same from the solar fleet, set to 0 while the sun is below the
                          horizon at the site (the Spanish solar fleet includes solar-thermal
                          plants, which produce after sunset)
``price_sr_up``/``_dn``   synthetic aFRR band prices (:mod:`rvpp.data.synth`) driven by the real
                          day-ahead price (and the real solar capacity factor for the down band)
CSP unit ``C``, ``C_fc``  real-derived when the files give the solar fleet: the fleet's clear-sky
                          index (:func:`clear_sky_index`) turned into beam irradiance and the
                          field's heat by the modelled optics
                          (:func:`rvpp.data.synth.field_heat_from_clear_sky_index`), scaled to the
                          field; ``C_fc`` the same from the fleet's day-ahead forecast, its error
                          scaled by ``K`` as for wind
ED unit ``E``, ``E_fc``    real-derived when the files give the system load: the load (and its
                          day-ahead forecast, its error scaled by ``K``) mapped onto the unit's
                          energy and range by :func:`scaled_to_demand`
TD unit ``H``             with a weather file (``--weather``), real-derived: the heating
                          degree-hours of its temperature above a base share mapped onto the
                          unit's energy and range by :func:`heat_from_temperature`; without
                          one, the synthetic heat demand
``H_fc``                  real-derived from the weather file's forecast temperature on the same
                          map (its error scaled by ``K``) when it has one; else a modelled
                          day-ahead forecast with a stated error (:data:`HEAT_FORECAST_ERROR`,
                          scaled by ``K``)
ED (without a system      synthetic series of :mod:`rvpp.data.synth` on the same hours
load), CSP (without a
solar fleet)
========================  =====================================================================

``sky="modelled"`` and ``demands="modelled"`` (``--sky modelled``, ``--demands modelled``)
set the real sky and the system load aside: the CSP's field heat then comes from the
modelled DNI (no forecast column, climatology bands) and the electrical demands from the
synthetic series, labelled modelled, as when the files do not give them. They build the
counterpart of a real case that differs from it in those columns only, for comparison.

The case's ``provenance`` section records, per column, whether it is real (as published),
real-derived (made from a public record by a stated model) or modelled (generated),
from which files (with their fingerprints) and how it was made. The data files themselves
are the user's: nothing here downloads or ships them.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import CaseError, DataImportError, RvppError
from . import synth
from .case import Case, CASE_FILE, parse_case
from .case_yaml import check_case_folder, load_case, write_case_folder
from .history import History
from .importers import ImportReport, fill_gaps, hourly_table, import_files, weather
from .importers.report import hourly

FLEETS = {"wind": ("actual_wind_onshore", "forecast_wind_onshore"), "pv": ("actual_solar", "forecast_solar")}
FORECAST_SUFFIX = "_fc"
SYNTHETIC_CSP_FIELD_MW_TH = 300.0  # the solar field synth.py models (MODEL_SPEC §12)
# The fleet's clear-sky envelope: per UTC hour of the day, this quantile of the ratio of its
# capacity factor to the site's clear-sky GHI over the days before (MODEL_SPEC §12's site).
ENVELOPE_DAYS, ENVELOPE_MIN_DAYS, ENVELOPE_QUANTILE = 30, 7, 0.9
INDEX_MIN_ELEVATION = 5.0  # [deg] below it the ratio is noise (and the field gives no heat)
LOAD = ("load_actual", "load_forecast")  # the system load and its day-ahead forecast [MW]
# The modelled heat demand's day-ahead forecast: a relative error of this standard deviation,
# persistent over HEAT_FORECAST_PERSISTENCE_H hours (a district-heating load forecast from a
# temperature forecast errs by a few per cent).
HEAT_FORECAST_ERROR, HEAT_FORECAST_PERSISTENCE_H = 0.05, 6.0
# Thermal demands from a temperature series: heating degree-hours below HEATING_BASE_C, on top
# of a base that does not depend on the weather, HEAT_BASE_SHARE of an hour of average heating
# (network losses and hot water in a district network; process heat has a larger base).
HEATING_BASE_C = 15.5  # [°C] the base temperature of the UK's degree-day statistics
HEAT_BASE_SHARE = 0.5  # [-]
TEMPERATURE = ("temperature", "temperature_forecast")  # the weather series [°C]
PRICE_LAG_DAYS = 7  # naive price forecasts look back up to a week before the window
HISTORY_FILE = "history.csv"
ORIGINS = ("real", "modelled")  # where --sky and --demands take the field heat and the demands from
WRITTEN = (HISTORY_FILE, CASE_FILE)  # the files a build writes into its folder, in this order


@dataclass(frozen=True)
class BuildOptions:
    """Choices of :func:`build_case` (all optional)."""

    errors_scale: float = 1.0
    start: dt.date | str | None = None
    end: dt.date | str | None = None
    date: dt.date | str | None = None
    zone: str | None = None
    wind_capacity_mw: float | None = None
    solar_capacity_mw: float | None = None
    seed: int | None = None
    fill_gaps_h: int = 0
    bands: str = "forecast"
    weather: str | Path | None = None
    weather_columns: tuple[str, ...] = ()
    weather_timezone: str | None = None
    heating_base_c: float = HEATING_BASE_C
    heat_base_share: float = HEAT_BASE_SHARE
    sky: str = "real"
    demands: str = "real"

    def __post_init__(self) -> None:
        for name in ("sky", "demands"):
            if getattr(self, name) not in ORIGINS:
                raise RvppError(f"--{name} {getattr(self, name)!r} must be real (from the files) or modelled "
                                "(the synthetic series)")
        if not (math.isfinite(self.errors_scale) and self.errors_scale >= 0):
            raise RvppError(f"--errors-scale K={self.errors_scale:g} must be a finite number >= 0")
        for name in ("wind_capacity_mw", "solar_capacity_mw"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise RvppError(f"--{name.replace('_mw', '').replace('_', '-')}={value:g} MW must be > 0")
        if self.fill_gaps_h < 0:
            raise RvppError(f"--fill-gaps={self.fill_gaps_h} must be >= 0 hours")
        if self.bands not in ("forecast", "climatology"):
            raise RvppError(f"--bands {self.bands!r} must be forecast or climatology")
        low, high = weather.TEMPERATURE_RANGE_C
        if not (math.isfinite(self.heating_base_c) and low <= self.heating_base_c <= high):
            raise RvppError(f"--heating-base {self.heating_base_c:g} °C must lie in {low:g} to {high:g} °C")
        if not (math.isfinite(self.heat_base_share) and 0.0 < self.heat_base_share <= 1.0):
            raise RvppError(f"--heat-base-share {self.heat_base_share:g} must be > 0 and <= 1 (a share of the "
                            "demand in an hour of average heating)")
        weather.WeatherColumns.parse(self.weather_columns)
        weather.zone_of(self.weather_timezone)


@dataclass(frozen=True, eq=False)
class BuiltCase:
    """A case written by :func:`build_case`, with what went into it."""

    folder: Path
    case: Case
    reports: tuple[ImportReport, ...]
    capacities_mw: dict[str, float]
    notes: tuple[str, ...]
    weather: ImportReport | None = None  # the weather file's report, also among ``reports``

    def lines(self) -> list[str]:
        case = self.case
        days = case.history.local_days(case.timezone)
        out = [f"wrote case {case.name!r} to {self.folder}",
               f"  history: {days[0]} to {days[-1]} ({len(days)} days, {len(case.history.frame)} hours); "
               f"delivery date {case.delivery_date}"]
        out += [f"  {fleet} fleet capacity: {mw:,.0f} MW" for fleet, mw in self.capacities_mw.items()]
        for column, origin in case.provenance:
            out.append(f"  {column}: {origin.origin}, {origin.source}" + (f" ({origin.note})" if origin.note else ""))
        out += [f"  note: {n}" for n in self.notes]
        if self.weather is not None:
            out += ["  " + line for line in self.weather.lines()]
        return out


def build_case(sources: list[str | Path], out: str | Path, *, template: str | Path | Case,
               options: BuildOptions = BuildOptions(), overwrite: bool = False,
               progress: Callable[[str], None] | None = None) -> BuiltCase:
    """Build a case folder from downloaded files; see the module notes for what each column is."""
    say = progress or (lambda _m: None)
    out = Path(out)
    _check_out(out, overwrite)
    base = template if isinstance(template, Case) else load_case(template)
    say(f"reading {len(sources)} file(s)")
    imports = import_files(list(sources), options.zone)
    table = hourly_table(imports)
    if "price_da" not in table.frame.columns:
        raise DataImportError(f"the files give no day-ahead price (price_da); they give "
                              f"{', '.join(table.frame.columns) or 'nothing'}")
    fleets = _fleets(base, table.frame.columns)
    taken = [u.name + FORECAST_SUFFIX for kind in fleets for u in getattr(base, kind)
             if u.name + FORECAST_SUFFIX in base.unit_names()]
    if taken:
        raise RvppError(f"the template has a unit named {taken[0]!r}, the name of a forecast column; rename it")
    load = tuple(c for c in LOAD if c in table.frame.columns) \
        if base.ed and LOAD[0] in table.frame.columns and options.demands == "real" else ()
    needed = ["price_da"] + [c for pair in fleets.values() for c in pair if c]
    frame, first, last = _span(table.frame[needed], base.timezone, options)
    notes = list(table.notes)
    filled: list[str] = []
    if frame.isna().any().any():
        if options.fill_gaps_h == 0:
            raise DataImportError(_gap_message(frame, base.timezone))
        frame, filled = fill_gaps(frame, options.fill_gaps_h)
        notes += filled

    if load:
        frame, load = _with_load(frame, table.frame[list(load)], load, options, base.timezone, notes, filled)
    weather_report, temperature = None, ()
    if options.weather is not None and not base.td:
        notes.append("the template has no thermal demand: the weather file is not read")
    elif options.weather is not None:
        say("reading the weather file")
        weather_report, series, runs = _weather(options, frame.index, base.timezone, first, last, notes)
        frame = pd.concat([frame, series], axis=1)
        temperature = tuple(series.columns)
        notes += runs
        filled += runs

    def made(how: str, *used: str) -> str:
        gaps = [f.split(": ", 1)[1] for f in filled if f.split(":", 1)[0] in used]
        return how + (f"; {'; '.join(gaps)}" if gaps else "")

    say(f"span {first} to {last}: {len(frame)} hours")
    delivery = _delivery_date(options.date, first, last, base)
    seed = synth.DEFAULT_SEED if options.seed is None else options.seed
    columns, capacities, provenance = {}, {}, {}
    columns["price_da"] = frame["price_da"].to_numpy(float)
    provenance["price_da"] = _real("price_da", table.origins["price_da"], made("as published", "price_da"))
    for kind, (actual_col, forecast_col) in fleets.items():
        given = options.wind_capacity_mw if kind == "wind" else options.solar_capacity_mw
        capacity = float(given) if given is not None else float(frame[actual_col].max())
        capacities[kind] = capacity
        actual_cf = frame[actual_col].to_numpy(float) / capacity
        forecast_cf = frame[forecast_col].to_numpy(float) / capacity if forecast_col else None
        above = int((actual_cf > 1.0).sum() + (0 if forecast_cf is None else (forecast_cf > 1.0).sum()))
        if above:
            notes.append(f"{kind}: {above} values above the given fleet capacity {capacity:,.0f} MW were capped at it")
        dark = _sun_down(frame.index) if kind == "pv" else np.zeros(len(frame), dtype=bool)
        night = "; 0 while the sun is below the horizon at the site (the fleet includes solar-thermal plants)" \
            if kind == "pv" else ""
        actual_cf = np.where(dark, 0.0, np.clip(actual_cf, 0.0, 1.0))
        if forecast_col is None:
            notes.append(f"{kind}: the files give no {FLEETS[kind][1]}; {kind} units keep climatology bands")
        else:
            forecast_cf = np.where(dark, 0.0, np.clip(forecast_cf, 0.0, 1.0))
        for unit in getattr(base, kind):
            actual = actual_cf * unit.p_max_mw
            columns[unit.name] = actual
            provenance[unit.name] = _real(actual_col, table.origins[actual_col], made(
                f"{actual_col} / {capacity:,.0f} MW × {unit.p_max_mw:g} MW{night}", actual_col), "real-derived")
            if forecast_col is None:
                continue
            columns[unit.name + FORECAST_SUFFIX] = np.clip(
                actual - options.errors_scale * (actual - forecast_cf * unit.p_max_mw), 0.0, unit.p_max_mw)
            provenance[unit.name + FORECAST_SUFFIX] = _real(
                forecast_col, table.origins[actual_col] + table.origins[forecast_col], made(
                    f"{unit.name} − {options.errors_scale:g}·({unit.name} − {forecast_col} / {capacity:,.0f} MW "
                    f"× {unit.p_max_mw:g} MW), clipped to [0, {unit.p_max_mw:g}] MW{night}", actual_col, forecast_col),
                "real-derived")
    for kind in ("wind", "pv"):
        if getattr(base, kind) and kind not in fleets:
            notes.append(f"{kind}: the files give no {FLEETS[kind][0]}; {kind} units are synthetic")
    say("generating the synthetic series")
    field_from_sky = "pv" in fleets and options.sky == "real"
    synthetic, sources_text = _synthetic(base, frame.index, first, last, columns, fleets, capacities, frame, seed,
                                         heat_from_weather=bool(temperature), field_from_sky=field_from_sky)
    columns.update(synthetic)
    provenance.update(sources_text)
    if field_from_sky:
        field, field_text = _field_heat(base, frame, fleets["pv"], capacities["pv"], options, table, made)
        columns.update(field)
        provenance.update(field_text)
    if load:
        demands, demand_text = _demands_from_load(base, frame, load, options, table, made)
        columns.update(demands)
        provenance.update(demand_text)
    heated = ()
    if temperature:
        heat, heat_text, heated = _demands_from_weather(base, frame, temperature, options, weather_report, made,
                                                        notes)
        columns.update(heat)
        provenance.update(heat_text)
    heat_fc, heat_text = _heat_forecasts(base, columns, options, seed, skip=heated,
                                         heat_from_weather=bool(temperature))
    columns.update(heat_fc)
    provenance.update(heat_text)
    history = History(pd.DataFrame({"timestamp": frame.index, **columns}), source=HISTORY_FILE)
    case = _case(base, out.name or "real", history, delivery, provenance, options, fleets, first, last, bool(load),
                 bool(temperature), field_from_sky)
    _write(case, out, overwrite)
    say(f"wrote {out}")
    reports = tuple(i.report for i in imports) + ((weather_report,) if weather_report else ())
    return BuiltCase(folder=out, case=case, reports=reports, capacities_mw=capacities, notes=tuple(notes),
                     weather=weather_report)


def clear_sky_index(capacity_factor: np.ndarray, index: pd.DatetimeIndex,
                    envelope_from: np.ndarray | None = None) -> np.ndarray:
    """The solar fleet's clear-sky index per hour [-, 0..1] at the case's site.

    ``capacity_factor`` over the site's clear-sky GHI (pvlib, :func:`rvpp.data.synth.clear_sky_ghi`)
    [per kW/m2] is divided by its clear-sky envelope: per UTC hour of the day, the
    :data:`ENVELOPE_QUANTILE` quantile of the same ratio over the :data:`ENVELOPE_DAYS` days
    before (at least :data:`ENVELOPE_MIN_DAYS`; the first days of the data take the first
    envelope found). So the fleet's growth, its trackers' flatter day and the solar-thermal
    plants' evening output do not read as clouds. ``envelope_from``: another capacity factor
    whose envelope to use (a forecast is measured against the actual fleet's clear days).
    Hours with the sun below :data:`INDEX_MIN_ELEVATION` take the mean index of their day's
    other hours (1 if it has none).
    """
    times = index.tz_convert(synth.SITE.timezone)
    ghi, elevation = synth.clear_sky_ghi(times)
    up = elevation > INDEX_MIN_ELEVATION
    utc = index.tz_convert("UTC")

    def ratio(cf: np.ndarray) -> pd.Series:
        values = np.where(up, np.asarray(cf, dtype=float) / np.maximum(ghi / 1000.0, 1e-6), np.nan)
        return pd.Series(values, index=pd.MultiIndex.from_arrays([utc.normalize(), utc.hour]))

    reference = ratio(capacity_factor if envelope_from is None else envelope_from)
    table = reference.groupby(level=[0, 1]).first().unstack()
    envelope = (table.rolling(ENVELOPE_DAYS, min_periods=ENVELOPE_MIN_DAYS).quantile(ENVELOPE_QUANTILE)
                .shift(1).bfill())
    at = envelope.stack().reindex(reference.index).to_numpy()
    measured = ratio(capacity_factor).to_numpy()
    known = ~np.isnan(measured) & (at > 0.0)  # nan where the sun is low or no envelope exists
    k = pd.Series(np.clip(np.divide(measured, at, out=np.full(len(at), np.nan), where=known), 0.0, 1.0),
                  index=index)
    day_mean = k.groupby(times.date).transform("mean").fillna(1.0)
    return np.where(np.isnan(k.to_numpy()), day_mean.to_numpy(), k.to_numpy())


def _field_heat(case: Case, frame: pd.DataFrame, fleet: tuple[str, str | None], capacity: float,
                options: BuildOptions, table, made: Callable[..., str]):
    """Solar-field heat of each CSP unit (and its day-ahead forecast) from the solar fleet."""
    actual_col, forecast_col = fleet
    times = frame.index.tz_convert(synth.SITE.timezone)
    actual_cf = frame[actual_col].to_numpy(float) / capacity
    heat = synth.field_heat_from_clear_sky_index(times, clear_sky_index(actual_cf, frame.index))
    guess = None
    if forecast_col is not None:
        forecast_cf = frame[forecast_col].to_numpy(float) / capacity
        guess = synth.field_heat_from_clear_sky_index(
            times, clear_sky_index(forecast_cf, frame.index, envelope_from=actual_cf))
    columns, provenance = {}, {}
    how = (f"{actual_col}'s clear-sky index at the site (pvlib clear sky, {ENVELOPE_QUANTILE:g} quantile of the "
           f"{ENVELOPE_DAYS} days before per hour as the clear-day envelope) → beam irradiance and heat of the "
           f"modelled trough field")
    origins = table.origins[actual_col] + (table.origins[forecast_col] if forecast_col else ())
    for unit in case.csp:
        p_max = unit.solar_field.p_max_mw_th
        actual = heat * p_max / SYNTHETIC_CSP_FIELD_MW_TH
        columns[unit.name] = actual
        provenance[unit.name] = _real(actual_col, table.origins[actual_col],
                                      made(f"{how}, scaled to {p_max:g} MW_th", actual_col), "real-derived")
        if guess is None:
            continue
        forecast = guess * p_max / SYNTHETIC_CSP_FIELD_MW_TH
        columns[unit.name + FORECAST_SUFFIX] = np.clip(actual - options.errors_scale * (actual - forecast), 0.0, p_max)
        provenance[unit.name + FORECAST_SUFFIX] = _real(forecast_col, origins, made(
            f"{unit.name} − {options.errors_scale:g}·({unit.name} − the same from {forecast_col}), clipped to "
            f"[0, {p_max:g}] MW_th", actual_col, forecast_col), "real-derived")
    return columns, provenance


def scaled_to_demand(load: np.ndarray, dates: np.ndarray, e_min_mwh: float, p_min_mw: float, p_max_mw: float,
                     reference: np.ndarray | None = None) -> np.ndarray:
    """The system load's shape on one flexible demand [MW]: ``level + spread·(L/L̃ − 1)``.

    ``L̃`` is the median over the days of the daily mean load, ``level`` the mean power of a
    median day of the synthetic demands (:data:`rvpp.data.synth.MEDIAN_DAY_ENERGY_RATIO`
    times ``e_min`` over 24 h), and ``spread = level`` (the load's own relative swings) unless
    that would leave ``[1.2·p_min, 0.9·p_max]`` (the synthetic demands' range), when it is
    narrowed to fit. ``reference``: the series whose ``L̃`` and extremes set the map (a
    forecast takes the actual load's map).
    """
    base = np.asarray(load if reference is None else reference, dtype=float)
    typical = float(np.median(pd.Series(base).groupby(dates).mean()))
    x_low, x_high = base.min() / typical, base.max() / typical
    level = synth.MEDIAN_DAY_ENERGY_RATIO * e_min_mwh / synth.HOURS_PER_DAY
    floor, ceiling = synth.DEMAND_FLOOR_FACTOR * p_min_mw, synth.DEMAND_CEILING_FACTOR * p_max_mw
    spread = level
    if x_low < 1.0:
        spread = min(spread, (level - floor) / (1.0 - x_low))
    if x_high > 1.0:
        spread = min(spread, (ceiling - level) / (x_high - 1.0))
    return level + max(spread, 0.0) * (np.asarray(load, dtype=float) / typical - 1.0)


def _with_load(frame: pd.DataFrame, load_table: pd.DataFrame, load: tuple[str, ...], options: BuildOptions,
               timezone: str, notes: list[str], filled: list[str]) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """``frame`` with the system load's columns on its hours, or unchanged when the load has gaps
    there that ``--fill-gaps`` does not cover (the electrical demands then stay modelled, and a
    note says why): the load is optional, so its gaps never stop a build."""
    series = load_table.reindex(frame.index)
    if series.isna().any().any():
        if options.fill_gaps_h == 0:
            notes.append(f"electrical demands stay modelled: {_gap_message(series, timezone)}")
            return frame, ()
        try:
            series, runs = fill_gaps(series, options.fill_gaps_h)
        except DataImportError as err:
            notes.append(f"electrical demands stay modelled: {err}")
            return frame, ()
        notes += runs
        filled += runs
    return pd.concat([frame, series], axis=1), load


def _demands_from_load(case: Case, frame: pd.DataFrame, load: tuple[str, ...], options: BuildOptions, table,
                       made: Callable[..., str]):
    """Each electrical demand (and its day-ahead forecast) from the system load."""
    dates = np.asarray(frame.index.tz_convert(case.timezone).date)
    actual_load = frame[load[0]].to_numpy(float)
    columns, provenance = {}, {}
    for unit in case.ed:
        shape = (unit.e_min_mwh, unit.p_min_mw, unit.p_max_mw)
        actual = scaled_to_demand(actual_load, dates, *shape)
        columns[unit.column] = actual
        how = (f"{load[0]} mapped onto {unit.name}'s median-day energy "
               f"{synth.MEDIAN_DAY_ENERGY_RATIO:g} × {unit.e_min_mwh:g} MWh and range")
        provenance[unit.column] = _real(load[0], table.origins[load[0]], made(how, load[0]), "real-derived")
        if len(load) < 2:
            continue
        guess = scaled_to_demand(frame[load[1]].to_numpy(float), dates, *shape, reference=actual_load)
        columns[unit.name + FORECAST_SUFFIX] = np.maximum(actual - options.errors_scale * (actual - guess), 0.0)
        provenance[unit.name + FORECAST_SUFFIX] = _real(load[1], table.origins[load[0]] + table.origins[load[1]], made(
            f"{unit.column} − {options.errors_scale:g}·({unit.column} − {load[1]} on the same map), at least 0",
            load[0], load[1]), "real-derived")
    return columns, provenance


def heating_degree_hours(temperature: np.ndarray, base_c: float = HEATING_BASE_C) -> np.ndarray:
    """Heating degree-hours of each hour [K, degree-hours of one hour]: ``HDH = max(0, T_base − T)``."""
    return np.maximum(base_c - np.asarray(temperature, dtype=float), 0.0)


def heat_from_temperature(temperature: np.ndarray, dates: np.ndarray, q_min_mwh: float, h_min_mw: float,
                          h_max_mw: float, base_c: float = HEATING_BASE_C, base_share: float = HEAT_BASE_SHARE,
                          reference: np.ndarray | None = None) -> np.ndarray | None:
    """A thermal demand following the temperature [MW_th]; ``None`` when no hour needs heat.

    The heating signal ``S = β + (1 − β)·HDH/HDH̄`` (``HDH`` of :func:`heating_degree_hours`,
    ``HDH̄`` their mean over the hours with ``HDH > 0``, ``β`` the base share: the demand
    that does not depend on the weather, as a share of an hour of average heating) is mapped
    onto the demand as the system load is onto an electrical one (:func:`scaled_to_demand`):
    a median day of ``S`` gets the median-day energy ``1.05·q_min``, and its swings are
    narrowed where they would leave ``[1.2·h_min, 0.9·h_max]``. ``reference``: the
    temperature whose ``HDH̄`` and map are used (a forecast takes the actual's).
    """
    actual = heating_degree_hours(temperature if reference is None else reference, base_c)
    heating = actual[actual > 0.0]
    if heating.size == 0:
        return None
    mean = float(heating.mean())

    def signal(series: np.ndarray) -> np.ndarray:
        return base_share + (1.0 - base_share) * heating_degree_hours(series, base_c) / mean

    shape = (q_min_mwh, h_min_mw, h_max_mw)
    if reference is None:
        return scaled_to_demand(signal(temperature), dates, *shape)
    return scaled_to_demand(signal(temperature), dates, *shape, reference=signal(reference))


def _weather(options: BuildOptions, index: pd.DatetimeIndex, timezone: str, first: dt.date, last: dt.date,
             notes: list[str]) -> tuple[ImportReport, pd.DataFrame, list[str]]:
    """The weather file's temperature (and its forecast, when it has one and covers the period)
    on the case's hours [°C], with the runs ``--fill-gaps`` interpolated."""
    read = weather.read(options.weather, weather.WeatherColumns.parse(options.weather_columns),
                        options.weather_timezone)
    table, partial = hourly(read)
    notes += [f"weather: {n}" for n in partial]
    series = table.reindex(index)
    runs: list[str] = []
    actual = series[[TEMPERATURE[0]]]
    if actual.isna().any().any() and options.fill_gaps_h:
        try:
            actual, runs = fill_gaps(actual, options.fill_gaps_h)
        except DataImportError:
            pass  # the days left empty are named below
    if actual.isna().any().any():
        raise DataImportError(_uncovered(actual[TEMPERATURE[0]], timezone, first, last, read.report, options))
    if TEMPERATURE[1] not in series.columns:
        return read.report, actual, runs
    forecast = series[[TEMPERATURE[1]]]
    if forecast.isna().any().any() and options.fill_gaps_h:
        try:
            forecast, more = fill_gaps(forecast, options.fill_gaps_h)
            runs += more
        except DataImportError:
            pass
    if forecast.isna().any().any():
        days = _days(forecast[TEMPERATURE[1]], timezone)
        notes.append(f"thermal demand forecasts stay modelled: the weather's {TEMPERATURE[1]} has no value on "
                     f"{len(days)} day(s) of the case ({_ranges(days)})")
        return read.report, actual, runs
    return read.report, pd.concat([actual, forecast], axis=1), runs


def _days(values: pd.Series, timezone: str) -> list[dt.date]:
    """The local days with an hour where ``values`` is empty."""
    empty = values.index[values.isna().to_numpy()]
    return sorted(set(empty.tz_convert(timezone).date))


def _ranges(days: list[dt.date]) -> str:
    """``2018-01-01 to 2018-01-03, 2018-02-10`` (the first twelve runs, then how many more)."""
    runs: list[list[dt.date]] = []
    for day in days:
        if runs and day - runs[-1][-1] == dt.timedelta(days=1):
            runs[-1].append(day)
        else:
            runs.append([day])
    text = [f"{r[0]} to {r[-1]}" if len(r) > 1 else f"{r[0]}" for r in runs[:12]]
    return ", ".join(text) + (f" and {len(runs) - 12} more stretches" if len(runs) > 12 else "")


def _uncovered(values: pd.Series, timezone: str, first: dt.date, last: dt.date, report: ImportReport,
               options: BuildOptions) -> str:
    days = _days(values, timezone)
    hours = int(values.isna().sum())
    span = (f"{report.start.tz_convert(timezone):%Y-%m-%d %H:%M} to {report.end.tz_convert(timezone):%Y-%m-%d %H:%M}")
    filled = f" (--fill-gaps interpolates runs of at most {options.fill_gaps_h} hours inside the file's span; " \
        "these are longer or at its edge)" if options.fill_gaps_h else ""
    return (f"{report.files[0].name}: the weather does not cover the case's period {first} to {last}: no "
            f"temperature in {hours} hour(s) of {len(days)} day(s): {_ranges(days)}{filled}; the file spans "
            f"{span}. Give a weather file for the whole period, or choose --start/--end inside it"
            + ("" if options.fill_gaps_h else " (or interpolate short gaps with --fill-gaps HOURS)"))


def _demands_from_weather(case: Case, frame: pd.DataFrame, temperature: tuple[str, ...], options: BuildOptions,
                          report: ImportReport, made: Callable[..., str], notes: list[str]):
    """Each thermal demand (and its day-ahead forecast) from the weather's temperature; returns
    the columns, their provenance and the units whose forecast came from the forecast temperature."""
    dates = np.asarray(frame.index.tz_convert(case.timezone).date)
    actual_t = frame[temperature[0]].to_numpy(float)
    forecast_t = frame[temperature[1]].to_numpy(float) if len(temperature) > 1 else None
    base_c, share = options.heating_base_c, options.heat_base_share
    columns, provenance, heated = {}, {}, []
    how = (f"heating degree-hours max(0, {base_c:g} °C − {temperature[0]}) over their mean in the hours that need "
           f"heat, on a base share {share:g} (S = {share:g} + {1.0 - share:g}·HDH/HDH̄), mapped onto the unit's "
           f"median-day energy {synth.MEDIAN_DAY_ENERGY_RATIO:g} × q_min and range")
    for unit in case.td:
        shape = (unit.q_min_mwh_th, unit.h_min_mw_th, unit.h_max_mw_th)
        actual = heat_from_temperature(actual_t, dates, *shape, base_c=base_c, base_share=share)
        if actual is None:
            level = synth.MEDIAN_DAY_ENERGY_RATIO * unit.q_min_mwh_th / synth.HOURS_PER_DAY
            actual = np.full(len(actual_t), level)
            columns[unit.column] = actual
            provenance[unit.column] = _real(temperature[0], (report,), made(
                f"no hour below {base_c:g} °C in the period: flat at the median-day level {level:g} MW_th",
                temperature[0]), "real-derived")
            notes.append(f'td "{unit.name}": no hour of the period is below {base_c:g} °C; the demand is flat at '
                         "its median-day level and its forecast error is modelled")
            continue
        columns[unit.column] = actual
        provenance[unit.column] = _real(temperature[0], (report,), made(f"{how} of {unit.name}", temperature[0]),
                                        "real-derived")
        if forecast_t is None:
            continue
        guess = heat_from_temperature(forecast_t, dates, *shape, base_c=base_c, base_share=share, reference=actual_t)
        columns[unit.name + FORECAST_SUFFIX] = np.maximum(actual - options.errors_scale * (actual - guess), 0.0)
        provenance[unit.name + FORECAST_SUFFIX] = _real(temperature[1], (report,), made(
            f"{unit.column} − {options.errors_scale:g}·({unit.column} − {temperature[1]} on the same map), at least 0",
            temperature[0], temperature[1]), "real-derived")
        heated.append(unit.name)
    return columns, provenance, tuple(heated)


def _heat_forecasts(case: Case, columns: dict[str, np.ndarray], options: BuildOptions, seed: int,
                    skip: tuple[str, ...] = (), heat_from_weather: bool = False):
    """A modelled day-ahead forecast of each thermal demand (but those in ``skip``): its series
    times ``1 − K·ε``, ``ε`` a persistent error of :data:`HEAT_FORECAST_ERROR` standard deviation."""
    out, provenance = {}, {}
    made_from = " (the demand from the actual temperature; the weather file gives no forecast of it)" \
        if heat_from_weather else ""
    for unit in case.td:
        if unit.name in skip:
            continue
        actual = columns[unit.column]
        error = HEAT_FORECAST_ERROR * synth.ar1(synth.component_rng(seed, f"forecast/{unit.name}"), len(actual),
                                                HEAT_FORECAST_PERSISTENCE_H)
        out[unit.name + FORECAST_SUFFIX] = np.maximum(actual * (1.0 - options.errors_scale * error), 0.0)
        provenance[unit.name + FORECAST_SUFFIX] = {
            "origin": "modelled", "source": f"rvpp.data.synth (seed {seed})",
            "note": f"{unit.column}{made_from} × (1 − {options.errors_scale:g}·ε), ε a relative error of standard "
                    f"deviation {HEAT_FORECAST_ERROR:g} persisting {HEAT_FORECAST_PERSISTENCE_H:g} h"}
    return out, provenance


def _fleets(case: Case, available) -> dict[str, tuple[str, str | None]]:
    """Fleet series the units of ``case`` take from the data: ``{kind: (actual, forecast or None)}``.

    A kind whose actual output the files do not give stays synthetic (not listed).
    """
    fleets = {}
    for kind, (actual, forecast) in FLEETS.items():
        if getattr(case, kind) and actual in available:
            fleets[kind] = (actual, forecast if forecast in available else None)
    return fleets


def _day(value: dt.date | str | None, label: str) -> dt.date | None:
    if value is None or isinstance(value, dt.date):
        return value
    try:
        return dt.date.fromisoformat(str(value))
    except ValueError:
        raise RvppError(f"{label}={value!r} must be a date such as 2018-03-15") from None


def _span(frame: pd.DataFrame, timezone: str, options: BuildOptions) -> tuple[pd.DataFrame, dt.date, dt.date]:
    """The whole local days every needed series covers (or the chosen ones)."""
    present = frame.dropna(how="any")
    if present.empty:
        raise DataImportError("the files share no hour where every needed series has a value")
    local_first = present.index[0].tz_convert(timezone)
    local_last = (present.index[-1] + pd.Timedelta(hours=1)).tz_convert(timezone)
    first = local_first.date() if local_first.hour == 0 else local_first.date() + dt.timedelta(days=1)
    last = (local_last - pd.Timedelta(hours=1)).date() if local_last.hour == 0 else \
        local_last.date() - dt.timedelta(days=1)
    start, end = _day(options.start, "--start"), _day(options.end, "--end")
    if start is not None:
        if start < first:
            raise DataImportError(f"--start {start} is before the first whole day with every series ({first})")
        first = start
    if end is not None:
        if end > last:
            raise DataImportError(f"--end {end} is after the last whole day with every series ({last})")
        last = end
    if last < first:
        raise DataImportError(f"no whole day from {first} to {last}")
    begin = pd.Timestamp(first).tz_localize(timezone).tz_convert("UTC")
    stop = pd.Timestamp(last + dt.timedelta(days=1)).tz_localize(timezone).tz_convert("UTC")
    grid = pd.date_range(begin, stop, freq="h", inclusive="left", name="timestamp")
    return frame.reindex(grid), first, last


def _gap_message(frame: pd.DataFrame, timezone: str) -> str:
    lines = []
    for column in frame.columns:
        empty = frame.index[frame[column].isna().to_numpy()]
        if len(empty):
            lines.append(f"{column} has no value in {len(empty)} hour(s), first at "
                         f"{empty[0].tz_convert(timezone):%Y-%m-%d %H:%M%z}")
    best = _longest_complete_run(frame, timezone)
    hint = f"; the longest span of whole days with every value is {best[0]} to {best[1]}" if best else ""
    return ("the data has gaps: " + "; ".join(lines) + hint
            + ". Choose --start/--end inside a complete span, or interpolate short gaps with --fill-gaps HOURS")


def _longest_complete_run(frame: pd.DataFrame, timezone: str) -> tuple[dt.date, dt.date] | None:
    complete = frame.notna().all(axis=1).groupby(frame.index.tz_convert(timezone).date).all()
    best, run = None, []
    for day, ok in complete.items():
        run = run + [day] if ok else []
        if run and (best is None or len(run) > (best[1] - best[0]).days + 1):
            best = (run[0], run[-1])
    return best


def _delivery_date(value, first: dt.date, last: dt.date, case: Case) -> dt.date:
    day = _day(value, "--date") or last
    needed = case.uncertainty.window_days + PRICE_LAG_DAYS
    earliest = first + dt.timedelta(days=needed)
    if earliest > last:
        raise RvppError(f"the data cover {(last - first).days + 1} whole day(s), {first} to {last}; a case needs "
                        f"{needed + 1} (its {case.uncertainty.window_days}-day window and a week more for price "
                        "forecasts before the delivery date): import a longer span")
    if not earliest <= day <= last:
        raise RvppError(f"--date {day} must lie in {earliest} to {last}: the history needs the "
                        f"{case.uncertainty.window_days}-day window (and a week more for price forecasts) "
                        "before it")
    return day


def _sun_down(index: pd.DatetimeIndex) -> np.ndarray:
    """True in the hours whose middle has the sun below the horizon at the synthetic site."""
    position = synth.solar_position(index.tz_convert(synth.SITE.timezone))
    return position["apparent_elevation"].to_numpy() <= 0.0


def _real(column: str, reports: tuple[ImportReport, ...], how: str, origin: str = "real") -> dict[str, str]:
    names = sorted({f.name for r in reports for f in r.files})
    digest = hashlib.sha256("".join(sorted(f.sha256 for r in reports for f in r.files)).encode()).hexdigest()[:16]
    files = names[0] if len(names) == 1 else f"{len(names)} files, {names[0]} to {names[-1]}"
    zone = next((r.zone for r in reports if r.zone), None)
    source = f"{reports[0].source}: {column}{f', zone {zone}' if zone else ''}; {files}, sha256 {digest}"
    return {"origin": origin, "source": source, "note": how}


def _synthetic(case: Case, index: pd.DatetimeIndex, first: dt.date, last: dt.date, real: dict[str, np.ndarray],
               fleets: dict, capacities: dict[str, float], frame: pd.DataFrame, seed: int,
               heat_from_weather: bool = False, field_from_sky: bool = False):
    """Reserve prices, demands (and wind, PV or, unless ``field_from_sky``, CSP solar-field heat
    the data does not give) from :mod:`rvpp.data.synth` on the same hours."""
    made = synth.build_history(seed, start=first.isoformat(), end=(last + dt.timedelta(days=1)).isoformat())
    stamps = pd.DatetimeIndex(made["timestamp"]).tz_convert("UTC")
    if not stamps.equals(index):
        raise RvppError("the synthetic series do not fall on the data's hours")  # a bug, not an input error
    label = f"rvpp.data.synth (seed {seed})"
    columns, provenance = {}, {}
    times = pd.DatetimeIndex(made["timestamp"])
    calendar = synth.make_calendar(times)
    if "pv" in fleets:
        solar_index = np.clip(frame[FLEETS["pv"][0]].to_numpy(float) / capacities["pv"], 0.0, 1.0)
        solar_text = "the real solar capacity factor"
    else:
        solar_index = synth.clear_sky(times, synth.solar_position(times),
                                      synth.linke_turbidity(calendar, synth.component_rng(seed, "weather/turbidity")))[
            "ghi"].to_numpy() / synth.REFERENCE_IRRADIANCE
        solar_text = "the clear-sky irradiance of the site"
    columns["price_sr_up"] = synth.reserve_up_price(calendar, real["price_da"],
                                                    synth.component_rng(seed, "price/sr_up"))
    columns["price_sr_dn"] = synth.reserve_down_price(calendar, real["price_da"], solar_index,
                                                      synth.component_rng(seed, "price/sr_dn"))
    provenance["price_sr_up"] = {"origin": "modelled", "source": label,
                                 "note": "aFRR up band price model driven by the real day-ahead price"}
    provenance["price_sr_dn"] = {"origin": "modelled", "source": label,
                                 "note": f"aFRR down band price model driven by the real day-ahead price and "
                                         f"{solar_text}"}
    for unit in case.csp if not field_from_sky else ():
        scale = unit.solar_field.p_max_mw_th / SYNTHETIC_CSP_FIELD_MW_TH
        columns[unit.name] = made["CSP1"].to_numpy(float) * scale
        provenance[unit.name] = {"origin": "modelled", "source": label,
                                 "note": "solar-field heat from modelled DNI, scaled to "
                                         f"{unit.solar_field.p_max_mw_th:g} MW_th"}
    profiles = {"wind": synth.WIND_COLUMNS, "pv": synth.PV_COLUMNS, "ed": synth.ED_COLUMNS, "td": synth.TD_COLUMNS}
    notes = {"wind": "modelled wind farm output", "pv": "modelled PV output", "ed": "modelled consumption",
             "td": "modelled heat consumption"}
    for kind in ("wind", "pv", "ed", "td"):
        if kind in fleets or (kind == "ed" and "load_actual" in frame.columns) or (kind == "td" and heat_from_weather):
            continue
        for unit in getattr(case, kind):
            if unit.column not in profiles[kind]:
                raise RvppError(f'{kind} "{unit.name}": no synthetic profile {unit.column!r}; name the unit (or '
                                f"its series) after one of {', '.join(profiles[kind])}")
            columns[unit.column] = made[unit.column].to_numpy(float)
            provenance[unit.column] = {"origin": "modelled", "source": label, "note": notes[kind]}
    return columns, provenance


def _case(base: Case, name: str, history: History, delivery: dt.date, provenance: dict, options: BuildOptions,
          fleets: dict, first: dt.date, last: dt.date, load: bool = False, heat: bool = False,
          field_from_sky: bool = False) -> Case:
    data = base.to_data()
    data["name"] = name
    real = " and ".join({"wind": "wind", "pv": "PV"}[k] for k in fleets)
    data["description"] = (
        f"Built from downloaded data ({first} to {last}): real day-ahead prices"
        + (f", {real} from the fleet's capacity factor (forecast errors scaled by {options.errors_scale:g})"
           if fleets else "")
        + (", solar-field heat from the solar fleet's clear-sky index" if field_from_sky and data["units"]["csp"]
           else "")
        + (", electrical demands from the system load" if load and data["units"]["ed"] else "")
        + (", thermal demands from the temperature (heating degree-hours)" if heat and data["units"]["td"] else "")
        + "; everything else synthetic. See provenance.")
    data["delivery_date"] = delivery.isoformat()
    for kind, (_, forecast) in fleets.items():
        for unit in data["units"][kind]:
            unit.update(series=None, series_scale=1.0,
                        forecast_series=unit["name"] + FORECAST_SUFFIX if forecast else None)
    field_forecast = field_from_sky and fleets["pv"][1] is not None
    for unit in data["units"]["csp"]:
        unit["solar_field"].update(series=None, series_scale=1.0,
                                   forecast_series=unit["name"] + FORECAST_SUFFIX if field_forecast else None)
    for kind in ("wind", "pv", "ed", "td"):
        if kind not in fleets:
            for unit in data["units"][kind]:
                unit.update(series_scale=1.0, forecast_series=None)
    for unit in data["units"]["td"]:
        unit.update(forecast_series=unit["name"] + FORECAST_SUFFIX)
    demand_forecast = load and all(u.name + FORECAST_SUFFIX in history.columns for u in base.ed)
    for unit in data["units"]["ed"] if demand_forecast else ():
        unit.update(forecast_series=unit["name"] + FORECAST_SUFFIX)
    bands = {"default": "climatology"}
    if options.bands == "forecast":
        bands.update({kind: "forecast" for kind, (_, forecast) in fleets.items() if forecast})
        if field_forecast and data["units"]["csp"]:
            bands["csp"] = "forecast"
        if data["units"]["td"]:
            bands["td"] = "forecast"
        if demand_forecast and data["units"]["ed"]:
            bands["ed"] = "forecast"
        bands["price_da"] = "forecast"
    data["uncertainty"]["bands"] = bands
    data["provenance"] = provenance
    try:
        return parse_case(data, history)
    except CaseError as err:
        raise CaseError([f"the built case breaks a rule: {p}" for p in err.problems]) from None


def _check_out(out: Path, overwrite: bool) -> None:
    """Refuse to replace a file ``out`` already holds (a case, or a user's own history.csv)
    unless ``overwrite`` (--force), and a folder where one of the two files belongs even then."""
    if os.path.lexists(out / CASE_FILE) and not overwrite:
        raise RvppError(f"{out} already holds a case; choose another folder or overwrite it (--force)")
    check_case_folder(out, WRITTEN, overwrite)


def _write(case: Case, out: Path, overwrite: bool) -> None:
    """Write the case into a temporary folder beside ``out``, then move its two files into place
    (checking again that nothing has appeared there meanwhile that ``overwrite`` does not allow)."""
    write_case_folder(case, out, HISTORY_FILE, WRITTEN, overwrite, _check_out)
