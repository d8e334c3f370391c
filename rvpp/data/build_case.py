"""A case built from downloaded data: real prices, wind and PV; synthetic where nothing is public.

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
CSP, ED, TD units         synthetic series of :mod:`rvpp.data.synth` on the same hours
========================  =====================================================================

The case's ``provenance`` section records, per column, whether it is real or synthetic,
from which files (with their fingerprints) and how it was made. The data files themselves
are the user's: nothing here downloads or ships them.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import CaseError, DataImportError, RvppError
from . import synth
from .case import Case, CASE_FILE, parse_case
from .case_yaml import load_case, save_case
from .history import History
from .importers import ImportReport, fill_gaps, hourly_table, import_files

FLEETS = {"wind": ("actual_wind_onshore", "forecast_wind_onshore"), "pv": ("actual_solar", "forecast_solar")}
FORECAST_SUFFIX = "_fc"
SYNTHETIC_CSP_FIELD_MW_TH = 300.0  # the solar field synth.py models (MODEL_SPEC §12)
PRICE_LAG_DAYS = 7  # naive price forecasts look back up to a week before the window
HISTORY_FILE = "history.csv"
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

    def __post_init__(self) -> None:
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


@dataclass(frozen=True, eq=False)
class BuiltCase:
    """A case written by :func:`build_case`, with what went into it."""

    folder: Path
    case: Case
    reports: tuple[ImportReport, ...]
    capacities_mw: dict[str, float]
    notes: tuple[str, ...]

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
    needed = ["price_da"] + [c for pair in fleets.values() for c in pair if c]
    frame, first, last = _span(table.frame[needed], base.timezone, options)
    notes = list(table.notes)
    filled: list[str] = []
    if frame.isna().any().any():
        if options.fill_gaps_h == 0:
            raise DataImportError(_gap_message(frame, base.timezone))
        frame, filled = fill_gaps(frame, options.fill_gaps_h)
        notes += filled

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
                f"{actual_col} / {capacity:,.0f} MW × {unit.p_max_mw:g} MW{night}", actual_col))
            if forecast_col is None:
                continue
            columns[unit.name + FORECAST_SUFFIX] = np.clip(
                actual - options.errors_scale * (actual - forecast_cf * unit.p_max_mw), 0.0, unit.p_max_mw)
            provenance[unit.name + FORECAST_SUFFIX] = _real(
                forecast_col, table.origins[actual_col] + table.origins[forecast_col], made(
                    f"{unit.name} − {options.errors_scale:g}·({unit.name} − {forecast_col} / {capacity:,.0f} MW "
                    f"× {unit.p_max_mw:g} MW), clipped to [0, {unit.p_max_mw:g}] MW{night}", actual_col, forecast_col))
    for kind in ("wind", "pv"):
        if getattr(base, kind) and kind not in fleets:
            notes.append(f"{kind}: the files give no {FLEETS[kind][0]}; {kind} units are synthetic")
    say("generating the synthetic series")
    synthetic, sources_text = _synthetic(base, frame.index, first, last, columns, fleets, capacities, frame, seed)
    columns.update(synthetic)
    provenance.update(sources_text)
    history = History(pd.DataFrame({"timestamp": frame.index, **columns}), source=HISTORY_FILE)
    case = _case(base, out.name or "real", history, delivery, provenance, options, fleets, first, last)
    _write(case, out, overwrite)
    say(f"wrote {out}")
    return BuiltCase(folder=out, case=case, reports=tuple(i.report for i in imports), capacities_mw=capacities,
                     notes=tuple(notes))


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


def _real(column: str, reports: tuple[ImportReport, ...], how: str) -> dict[str, str]:
    names = sorted({f.name for r in reports for f in r.files})
    digest = hashlib.sha256("".join(sorted(f.sha256 for r in reports for f in r.files)).encode()).hexdigest()[:16]
    files = names[0] if len(names) == 1 else f"{len(names)} files, {names[0]} to {names[-1]}"
    zone = next((r.zone for r in reports if r.zone), None)
    source = f"{reports[0].source}: {column}{f', zone {zone}' if zone else ''}; {files}, sha256 {digest}"
    return {"origin": "real", "source": source, "note": how}


def _synthetic(case: Case, index: pd.DatetimeIndex, first: dt.date, last: dt.date, real: dict[str, np.ndarray],
               fleets: dict, capacities: dict[str, float], frame: pd.DataFrame, seed: int):
    """Reserve prices, CSP solar-field heat, demands (and wind or PV the data does not give) from
    :mod:`rvpp.data.synth` on the same hours."""
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
    provenance["price_sr_up"] = {"origin": "synthetic", "source": label,
                                 "note": "aFRR up band price model driven by the real day-ahead price"}
    provenance["price_sr_dn"] = {"origin": "synthetic", "source": label,
                                 "note": f"aFRR down band price model driven by the real day-ahead price and "
                                         f"{solar_text}"}
    for unit in case.csp:
        scale = unit.solar_field.p_max_mw_th / SYNTHETIC_CSP_FIELD_MW_TH
        columns[unit.name] = made["CSP1"].to_numpy(float) * scale
        provenance[unit.name] = {"origin": "synthetic", "source": label,
                                 "note": "solar-field heat from modelled DNI, scaled to "
                                         f"{unit.solar_field.p_max_mw_th:g} MW_th"}
    profiles = {"wind": synth.WIND_COLUMNS, "pv": synth.PV_COLUMNS, "ed": synth.ED_COLUMNS, "td": synth.TD_COLUMNS}
    notes = {"wind": "modelled wind farm output", "pv": "modelled PV output", "ed": "modelled consumption",
             "td": "modelled heat consumption"}
    for kind in ("wind", "pv", "ed", "td"):
        if kind in fleets:
            continue
        for unit in getattr(case, kind):
            if unit.column not in profiles[kind]:
                raise RvppError(f'{kind} "{unit.name}": no synthetic profile {unit.column!r}; name the unit (or '
                                f"its series) after one of {', '.join(profiles[kind])}")
            columns[unit.column] = made[unit.column].to_numpy(float)
            provenance[unit.column] = {"origin": "synthetic", "source": label, "note": notes[kind]}
    return columns, provenance


def _case(base: Case, name: str, history: History, delivery: dt.date, provenance: dict, options: BuildOptions,
          fleets: dict, first: dt.date, last: dt.date) -> Case:
    data = base.to_data()
    data["name"] = name
    real = " and ".join({"wind": "wind", "pv": "PV"}[k] for k in fleets)
    data["description"] = (
        f"Built from downloaded data ({first} to {last}): real day-ahead prices"
        + (f", {real} from the fleet's capacity factor (forecast errors scaled by {options.errors_scale:g})"
           if fleets else "")
        + "; everything else synthetic. See provenance.")
    data["delivery_date"] = delivery.isoformat()
    for kind, (_, forecast) in fleets.items():
        for unit in data["units"][kind]:
            unit.update(series=None, series_scale=1.0,
                        forecast_series=unit["name"] + FORECAST_SUFFIX if forecast else None)
    for unit in data["units"]["csp"]:
        unit["solar_field"].update(series=None, series_scale=1.0)
    for kind in ("wind", "pv", "ed", "td"):
        if kind not in fleets:
            for unit in data["units"][kind]:
                unit.update(series_scale=1.0, forecast_series=None)
    bands = {"default": "climatology"}
    if options.bands == "forecast":
        bands.update({kind: "forecast" for kind, (_, forecast) in fleets.items() if forecast})
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
    if out.exists() and not out.is_dir():
        raise RvppError(f"{out} exists and is not a folder")
    for name in WRITTEN:
        target = out / name
        if target.is_dir():
            raise RvppError(f"{target} is a folder, where the case's {name} belongs; choose another folder")
        if os.path.lexists(target) and not overwrite:
            raise RvppError(f"{out} already holds {name}; choose another folder or overwrite it (--force)")


def _write(case: Case, out: Path, overwrite: bool) -> None:
    """Write the case into a temporary folder beside ``out``, then move its two files into place
    (checking again that nothing has appeared there meanwhile that ``overwrite`` does not allow)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    temp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp"))
    try:
        save_case(case, temp, HISTORY_FILE)
        out.mkdir(exist_ok=True)
        _check_out(out, overwrite)
        for name in WRITTEN:
            os.replace(temp / name, out / name)
    finally:
        shutil.rmtree(temp, ignore_errors=True)
