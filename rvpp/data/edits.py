"""Edits of a case in the user's words.

A person edits a case through forms whose fields read ``P max [MW]`` or ``κ: reserve
band cap [-]``, not ``p_max_mw`` or ``markets.kappa``. This module keeps those words in
one place and speaks them:

* :data:`FIELDS` — label, unit and help of every unit field (paper Tables 3-6);
* :func:`describe_edits` — what changed between the case as loaded and as edited, e.g.
  ``["WF1 80 MW", "κ 0.2", "PV3 removed"]``, the words of a saved run's label;
* :func:`follow_capacity` — a unit whose capacity changed gets its forecast band
  scaled by the same ratio (its ``series_scale``), so an 80 MW wind farm is forecast
  as 80 MW, not as the 50 MW farm whose history it follows;
* :func:`plain_message` — a case-model message with the field names as the forms show
  them: ``CSP1: TS E min [MWh_th] = 1200 must be < TS E max [MWh_th] = 1100``;
  :func:`table_message` says the same of a unit table's cells (``WF1: P max [MW] is
  empty; enter a number``);
* :func:`with_period_length` — a new period length whose Γ overrides keep their duration
  in hours (``WF1 80 quarter-hours → 20 hours``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection, Mapping
from typing import Any

from .case import Case
from .kinds import KINDS, UNIT_KINDS, power_unit
from .periods import delivery_periods

# field -> (name, unit, help); the form shows "name [unit]".
FIELDS: dict[str, tuple[str, str, str]] = {
    "name": ("Name", "", "Unique name of the unit"),
    "p_max_mw": ("P max", "MW", "Installed (nameplate) power"),
    "p_min_mw": ("P min", "MW", "Minimum power"),
    "om_eur_per_mwh": ("O&M", "EUR/MWh", "Operating cost per MWh produced"),
    "ramp_up_mw_per_min": ("Ramp up", "MW/min", "Reserve ramp; × the reserve delivery time caps the up reserve"),
    "ramp_dn_mw_per_min": ("Ramp down", "MW/min", "Reserve ramp; × the reserve delivery time caps the down reserve"),
    "ramp_mw_per_min": ("Ramp", "MW/min", "Reserve ramp; × the reserve delivery time caps each reserve band"),
    "reserve_share": ("Reserve share", "-", "Largest reserve band as a fraction of P max (0-1)"),
    "series": ("History series", "", "History column that gives the unit's forecast band"),
    "series_scale": ("Series scale", "-", "Factor applied to the history series; follows the capacity while "
                                          "'Scale band with capacity' is ticked"),
    "forecast_series": ("Forecast series", "", "History column of the unit's day-ahead forecast, for forecast-error "
                                               "bands (see Uncertainty); empty: none"),
    "heat_efficiency": ("Heat efficiency", "-", "Fraction of solar-field heat delivered to thermal demands"),
    "p_max_mw_th": ("SF max", "MW_th", "Solar-field thermal capacity"),
    "e_min_mwh_th": ("TS E min", "MWh_th", "Minimum stored energy"),
    "e_max_mwh_th": ("TS E max", "MWh_th", "Maximum stored energy"),
    "p_ch_max_mw_th": ("TS charge max", "MW_th", "Largest charging power"),
    "p_ch_min_mw_th": ("TS charge min", "MW_th", "Smallest charging power while charging"),
    "p_dis_max_mw_th": ("TS discharge max", "MW_th", "Largest discharging power"),
    "p_dis_min_mw_th": ("TS discharge min", "MW_th", "Smallest discharging power while discharging"),
    "storage.eta_ch": ("TS η charge", "-", "Charging efficiency (0-1]"),
    "storage.eta_dis": ("TS η discharge", "-", "Discharging efficiency (0-1]"),
    "eta_ch": ("η charge", "-", "Charging efficiency (0-1]"),
    "eta_dis": ("η discharge", "-", "Discharging efficiency (0-1]"),
    "e_init_mwh_th": ("TS E start", "MWh_th", "Energy at the start of the day; empty: cyclic day"),
    "e_end_min_mwh_th": ("TS E end min", "MWh_th", "Least energy at the end of the day (up to TS E start); "
                         "empty: TS E start"),
    "end_value_eur_per_mwh_th": ("TS heat value", "EUR/MWh_th", "Value of the heat left in the tank at the end "
                                 "of the day over its start"),
    "initial_status_h": ("Hours in status", "h", "Hours the turbine has been on (or off) at midnight; empty: "
                         "no minimum time carried in"),
    "p_in_max_mw_th": ("PB input max", "MW_th", "Largest power-block thermal input"),
    "p_in_min_mw_th": ("PB input min", "MW_th", "Smallest thermal input while the turbine runs"),
    "p_el_max_mw": ("Turbine max", "MW", "Turbine nameplate, caps the output in every scenario"),
    "min_up_h": ("Min up", "h", "Minimum up time once started"),
    "min_down_h": ("Min down", "h", "Minimum down time once stopped"),
    "startup_fraction": ("Start-up heat", "-", "Thermal use at start-up as a fraction of PB input max"),
    "startup_duration_h": ("Start-up time", "h", "Duration of the start-up heat use"),
    "initially_on": ("On at midnight", "", "Turbine online at the start of the day"),
    "breakpoints": ("Power-block curve", "", "Thermal input and efficiency at each breakpoint"),
    "e_min_mwh": ("E min", "MWh", "A demand's least energy over the day; a battery's least stored energy"),
    "p_init_mw": ("P start", "MW", "Power before the day starts: a hydro or biomass unit's output, or a demand's "
                                   "consumption, from which its first period ramps (empty: no ramp limit)"),
    "flex_up": ("Flex up", "-", "Up reserve (consumption decrease) as a fraction of consumption"),
    "flex_dn": ("Flex down", "-", "Down reserve (consumption increase) as a fraction of consumption"),
    "h_min_mw_th": ("H min", "MW_th", "Minimum heat"),
    "h_max_mw_th": ("H max", "MW_th", "Maximum heat"),
    "q_min_mwh_th": ("Q min", "MWh_th", "Minimum heat over the day"),
    "h_init_mw_th": ("H start", "MW_th", "Heat before the day starts (informative)"),
    "enabled": ("In the plan", "", "Unticked: the unit is kept in the case but left out of the plan"),
    "e_max_mwh": ("E max", "MWh", "Largest stored energy"),
    "p_ch_max_mw": ("Charge max", "MW", "Largest charging power"),
    "p_dis_max_mw": ("Discharge max", "MW", "Largest discharging power"),
    "self_discharge_per_h": ("Self-discharge", "1/h", "Fraction of the stored energy lost per hour [0-1)"),
    "degradation_eur_per_mwh": ("Degradation", "EUR/MWh", "Wear cost per MWh discharged"),
    "e_init_mwh": ("E start", "MWh", "Stored energy at the start of the day; empty: cyclic day"),
    "e_end_min_mwh": ("E end min", "MWh", "Least stored energy at the end of the day (up to E start); "
                      "empty: E start"),
    "marginal_cost_eur_per_mwh": ("Marginal cost", "EUR/MWh", "Cost per MWh produced (fuel, water value, O&M)"),
    "startup_cost_eur": ("Start-up cost", "EUR", "Cost of one start"),
    "shutdown_cost_eur": ("Shut-down cost", "EUR", "Cost of one stop"),
    "ramp_up_mw_per_h": ("Ramp up", "MW/h", "Largest rise of output (a demand's consumption, bands included) from "
                                            "one hour to the next; empty: no limit"),
    "ramp_dn_mw_per_h": ("Ramp down", "MW/h", "Largest fall of output (a demand's consumption, bands included) from "
                                              "one hour to the next; empty: no limit"),
    "profile_window": ("Window around profile", "", "The authors' tool's demand: consumption within flex of its "
                                                    "profile, bands by the profile"),
    "energy_net_of_up_band": ("E min net of up band", "", "Unticked: the authors' tool's floor, Σ consumption ≥ E min"),
    "reserve_band_max_mw_th": ("TS band max", "MW_th", "Largest of each tank band (the authors' tool); empty: none"),
    "reserve_energy_factor": ("TS reserve factor", "-", "k in Σ band energy ≤ k·σ·ΔE (1; the authors' tool 2)"),
    "reserve_share_max": ("TS σ max", "-", "Largest share of the tank held for reserve (1; the authors' tool 0.5)"),
    "output_capped": ("Turbine caps output", "", "Unticked: the curve alone limits the output (the authors' tool)"),
    "startup_ramp_mw_per_h": ("Start-up ramp", "MW/h", "Largest output in the period of a start; empty: P max"),
    "shutdown_ramp_mw_per_h": ("Shut-down ramp", "MW/h", "Largest output in the period before a stop; empty: "
                                                         "P max"),
    "initial_online": ("On at midnight", "", "Online at the start of the day"),
    "initial_hours_in_status": ("Hours in status", "h", "Hours the unit has been on (or off) at the start of "
                                                        "the day; empty: no minimum time carries over"),
    "energy_max_mwh": ("Energy max", "MWh", "Water or fuel for the day, up reserve included; empty: no limit"),
}

# Settings as the Markets, Uncertainty and Home pages name them: dotted path -> (name, unit).
SETTINGS: dict[str, tuple[str, str]] = {
    "delivery_date": ("Delivery day", ""),
    "dt_h": ("Market time unit", "h"),
    "markets.srm": ("Secondary reserve (SRM)", ""),
    "markets.hpa": ("Heat purchase (HPA)", ""),
    "markets.kappa": ("κ: reserve band cap", "-"),
    "markets.reserve_duration_min": ("Reserve delivery time", "min"),
    "markets.hpa_tariff_eur_per_mwh": ("HPA tariff", "EUR/MWh_th"),
    "uncertainty.window_days": ("History window", "days"),
    "uncertainty.q_lo": ("Lower percentile", ""),
    "uncertainty.q_hi": ("Upper percentile", ""),
    "budgets.strategy": ("Strategy preset", ""),
    "budgets.mode": ("Budget variant", ""),
    "budgets.ties": ("Tied deviations", ""),
    "budgets.overrides": ("Γ", "periods"),
    "solver.time_limit_s": ("Solver time limit", "s"),
    "solver.rel_gap": ("Solver relative gap", "-"),
    "solver.threads": ("Solver threads", ""),
}
# What a label says for a changed setting: dotted path -> format of the new value.
SETTING_WORDS = {
    "markets.kappa": "κ {:g}",
    "markets.reserve_duration_min": "reserve time {:g} min",
    "uncertainty.window_days": "{:d}-day window",
    "uncertainty.q_lo": "lower percentile {:g}",
    "uncertainty.q_hi": "upper percentile {:g}",
    "solver.time_limit_s": "time limit {:g} s",
    "solver.rel_gap": "gap {:g}",
    "solver.threads": "{:d} threads",
}
# Study settings as the study pages name them.
STUDY_FIELDS: dict[str, str] = {
    "strategies": "Strategies",
    "gammas": "Γ grid [periods]",
    "market_sets": "Market sets",
    "market_sets_without_csp": "Market sets without the CSP",
    "hpa_flat_prices": "Flat HPA tariffs [EUR/MWh_th]",
    "test_days": "Test days",
    "scenario_counts": "Scenario counts N",
    "sp_time_limit_s": "Time limit per stochastic program [s]",
    "threads": "Threads",
}
LABEL_LIMIT = 120  # characters of a default run label
LABEL_LENGTH = 200  # characters a saved run's label may hold (the run store keeps none longer)
# Period lengths [h] as the pages name them: plural, singular.
PERIOD_NAMES = {1.0: "hours", 0.5: "half-hours", 0.25: "quarter-hours"}
PERIOD_NAME = {1.0: "hour", 0.5: "half-hour", 0.25: "quarter-hour"}
# A required unit field the case model found missing, i.e. an empty cell of a unit table:
# ``wind "WF1": p_max_mw is required`` or, for a row without a name, ``units.wind item 2: name is required``.
_KIND_WORDS = "|".join(UNIT_KINDS)
REQUIRED_CELL = re.compile(rf'^(?:(?:{_KIND_WORDS}) "(?P<unit>[^"]+)"|units\.(?P<kind>{_KIND_WORDS}) '
                           r"item (?P<row>\d+)): (?P<field>[a-z_]+(?:\.[a-z_]+)*) is required$")
CELL_ENTRIES = {"name": "a name", "series": "a history column"}  # what an empty cell asks for; others a number


def field_words(field: str) -> tuple[str, str, str] | None:
    """``(name, unit, help)`` of a unit field, dotted (``storage.eta_ch``) or not; ``None`` if unknown.
    A dotted entry of :data:`FIELDS` wins over its last part (the CSP storage's η is labelled TS η)."""
    return FIELDS.get(field) or FIELDS.get(field.split(".")[-1])


def label(field: str) -> str:
    """``"p_max_mw"`` or ``"storage.e_max_mwh_th"`` → ``"P max [MW]"`` / ``"TS E max [MWh_th]"``."""
    words = field_words(field)
    if field in SETTINGS:
        name, unit = SETTINGS[field]
    elif words is not None:
        name, unit, _ = words
    else:
        return field
    return f"{name} [{unit}]" if unit else name


def capacity(kind: str, unit: Any) -> float:
    """The capacity a unit's forecast band scales with [MW or MW_th]."""
    return float(_get(unit, KINDS[kind].capacity_field))


def follow_capacity(before: Case, after: Case, fixed: Collection[str] = ()) -> Case:
    """``after`` with the forecast band of every unit whose capacity changed scaled to match.

    A unit of ``after`` that existed in ``before`` (same kind and name) with another
    capacity gets ``series_scale × new capacity / old capacity``, unless its name is in
    ``fixed`` or its series scale was edited too (the user's value stands).
    """
    old = {(kind, u.name): u for kind, u in before.units()}
    changes: dict[str, list] = {}
    for kind in UNIT_KINDS:
        units, changed = [], False
        for unit in getattr(after, kind):
            prior = old.get((kind, unit.name))
            scale_field = KINDS[kind].scale_field
            if (prior is not None and unit.name not in fixed and capacity(kind, prior) > 0
                    and not math.isclose(capacity(kind, unit), capacity(kind, prior))
                    and _get(unit, scale_field) == _get(prior, scale_field)):
                ratio = capacity(kind, unit) / capacity(kind, prior)
                unit = _set(unit, scale_field, _get(prior, scale_field) * ratio)
                changed = True
            units.append(unit)
        if changed:
            changes[kind] = units
    return after.replace(**changes) if changes else after


def periods_in_words(count: int, dt_h: float) -> str:
    """``80, 0.25`` → ``"80 quarter-hours"``; ``1, 1.0`` → ``"1 hour"``."""
    return f"{count} {(PERIOD_NAME if count == 1 else PERIOD_NAMES)[dt_h]}"


def convert_overrides(overrides: Mapping[str, int], old_dt_h: float, new_dt_h: float,
                      periods: int) -> dict[str, int]:
    """Γ overrides [periods of ``old_dt_h`` hours] in periods of ``new_dt_h`` hours, each keeping
    its duration: ``⌊Γ · old_dt_h / new_dt_h + ½⌋``, at most the day's ``periods``.

    ``{"WF1": 80}`` in quarter-hours is ``{"WF1": 20}`` in hours; 5 quarter-hours (1.25 h)
    become 1 hour, 6 (1.5 h) become 2.
    """
    return {source: min(math.floor(gamma * old_dt_h / new_dt_h + 0.5), periods)
            for source, gamma in overrides.items()}


def with_period_length(case: Case, dt_h: float) -> tuple[Case, list[str]]:
    """``case`` with periods of ``dt_h`` hours and its Γ overrides converted to keep their hours
    (:func:`convert_overrides`), with what was converted in words:
    ``["WF1 80 quarter-hours → 20 hours"]``, ``"PV1 5 quarter-hours → 1 hour (1.25 h rounded)"``.

    A Γ override counts periods, so the same number would mean another duration (20 hours
    becoming 20 quarter-hours) or no longer fit the day (80 quarter-hours in 24 hours).
    Raises :class:`~rvpp.errors.CaseError` for a period length the case model refuses.
    """
    moved = case.replace(dt_h=dt_h)
    old = case.budgets.override_map
    if moved.dt_h == case.dt_h or not old:
        return moved, []
    periods = len(delivery_periods(moved.delivery_date, moved.timezone, moved.dt_h))
    new = convert_overrides(old, case.dt_h, moved.dt_h, periods)
    notes = []
    for source, gamma in old.items():
        hours = gamma * case.dt_h
        note = f"{source} {periods_in_words(gamma, case.dt_h)} → {periods_in_words(new[source], moved.dt_h)}"
        if new[source] == periods and hours > periods * moved.dt_h:
            note += f" (at most the day's {periods})"
        elif not math.isclose(new[source] * moved.dt_h, hours):
            note += f" ({hours:g} h rounded)"
        notes.append(note)
    return moved.replace(budgets={"overrides": new}), notes


def describe_edits(origin: Case, edited: Case) -> list[str]:
    """What was edited from ``origin`` to ``edited``, in the words of the forms.

    The strategy and the market switches are left out (every run label names them).
    A capacity reads ``"WF1 80 MW"``; another unit field ``"WF1 O&M 20 EUR/MWh"``; a
    series scale that only followed its capacity is not repeated.
    """
    words = _settings_edits(origin, edited)
    words += _budget_edits(origin, edited)
    words += _unit_edits(origin, edited)
    return words


def run_label(origin: Case, edited: Case, csp: bool = True, limit: int = LABEL_LIMIT) -> str:
    """A run's default label: strategy, market set and what was edited, e.g.
    ``"balanced · DAM+SRM+HPA · WF1 80 MW"``; ``csp=False`` adds ``"no CSP"``.

    Past ``limit`` characters the last edits are summed up (``"… and 3 more edits"``).
    """
    edits = describe_edits(origin, edited) + (["no CSP"] if not csp and edited.csp else [])
    head = [edited.budgets.label, edited.markets.label]
    shown, hidden = list(edits), 0

    def joined() -> str:
        more = [f"… and {hidden} more edit{'s' if hidden > 1 else ''}"] if hidden else []
        return " · ".join(head + shown + more)

    while len(joined()) > limit and shown:
        shown.pop()
        hidden += 1
    return joined()


def plain_message(message: str) -> str:
    """A case-model message with field names as the forms show them.

    ``csp "CSP1": storage.e_min_mwh_th=1200 must be < storage.e_max_mwh_th=1100`` becomes
    ``CSP1: TS E min [MWh_th] = 1200 must be < TS E max [MWh_th] = 1100``;
    ``markets: hpa_tariff_eur_per_mwh hour 03:00 = -5 must be >= 0`` becomes
    ``HPA tariff at 03:00 [EUR/MWh_th] = −5 must be ≥ 0``.
    """
    text = re.sub(rf'^(?:{_KIND_WORDS}) "([^"]+)": ', r"\1: ", message)
    if text.startswith("study settings: "):
        text = re.sub(r"(?:(?<=^study settings: )|(?<=; ))([a-z_]+)(?=[=: ])",
                      lambda m: STUDY_FIELDS.get(m.group(1), m.group(1)), text)
        text = re.sub(r"(?<=\w)=(?=[-\d])", " = ", text)
    section = re.match(r"^(markets|uncertainty|budgets|solver): ", text)
    prefix = ""
    if section:
        prefix, text = section.group(1) + ".", text[section.end():]
    named = []  # the fields named in the forms' words: they say where without the section

    def field(match: re.Match) -> str:
        path, index = match.group(1), match.group(2)
        full = prefix + path if prefix + path in SETTINGS else path
        name = label(full)
        if name == full and path not in SETTINGS:
            return match.group(0)
        if index is not None:
            name = f"{name} (value {int(index) + 1})"
        named.append(name)
        return f"{name} = "

    text, tariffs = re.subn(r"\bhpa_tariff_eur_per_mwh hour (\d\d:\d\d) = ", r"HPA tariff at \1 [EUR/MWh_th] = ",
                            text)
    text = re.sub(r"\b([a-z][a-z_]*(?:\.[a-z][a-z_]*)*)(?:\.(\d+))?=", field, text)
    if section and not (named or tariffs):  # "markets: section is required" keeps its section
        text = section.group(0) + text
    text = re.sub(r"(?<=[ =])-(?=\d)", "−", text)
    return text.replace(">=", "≥").replace("<=", "≤")


def table_message(message: str) -> str:
    """A case-model message about a unit table, in the words of its columns.

    An empty cell of a required field reads ``WF1: P max [MW] is empty; enter a number``
    (a row without a name: ``wind farm in row 2: Name is empty; enter a name``); any other
    message as :func:`plain_message` says it. Messages about case files keep ``is required``:
    there the field is named as the file writes it.
    """
    cell = REQUIRED_CELL.match(message)
    if cell is None:
        return plain_message(message)
    where = cell["unit"] if cell["unit"] is not None else f"{KINDS[cell['kind']].words} in row {cell['row']}"
    entry = CELL_ENTRIES.get(cell["field"].split(".")[-1], "a number")
    return f"{where}: {label(cell['field'])} is empty; enter {entry}"


# ----------------------------------------------------------------------------- helpers


def _settings_edits(origin: Case, edited: Case) -> list[str]:
    words = []
    if edited.delivery_date != origin.delivery_date:
        words.append(f"{edited.delivery_date:%d %b %Y}")
    if edited.dt_h != origin.dt_h:
        words.append(f"{edited.dt_h * 60:g}-min periods")
    tariff, before = edited.markets.hpa_tariff_eur_per_mwh, origin.markets.hpa_tariff_eur_per_mwh
    if tariff != before:
        words.append(f"HPA flat {tariff[0]:g}" if len(set(tariff)) == 1 else "HPA tariff edited")
    for path, words_format in SETTING_WORDS.items():
        section, name = path.split(".")
        new, old = getattr(getattr(edited, section), name), getattr(getattr(origin, section), name)
        if new != old:
            words.append(words_format.format(new))
    return words


def _budget_edits(origin: Case, edited: Case) -> list[str]:
    words = []
    if edited.budgets.mode != origin.budgets.mode:
        words.append("planner-chosen Γ" if edited.budgets.mode == "planner_chosen" else "paper-mode Γ")
    if edited.budgets.ties != origin.budgets.ties:
        words.append("earliest tied periods" if edited.budgets.ties == "earliest" else "tied periods chosen")
    new, old = edited.budgets.override_map, origin.budgets.override_map
    for source in sorted(set(new) | set(old)):
        if new.get(source) != old.get(source):
            words.append(f"Γ {source} {new[source]}" if source in new else f"Γ {source} preset")
    return words


def _unit_edits(origin: Case, edited: Case) -> list[str]:
    words = []
    for kind in UNIT_KINDS:
        before = {u.name: u for u in getattr(origin, kind)}
        after = {u.name: u for u in getattr(edited, kind)}
        for name in after:
            if name not in before:
                words.append(f"{name} added ({capacity(kind, after[name]):g} {power_unit(kind)})")
                continue
            words += _field_edits(kind, before[name], after[name])
        words += [f"{name} removed" for name in before if name not in after]
    return words


def _field_edits(kind: str, old: Any, new: Any) -> list[str]:
    flat_old, flat_new = flatten(old.model_dump(mode="python")), flatten(new.model_dump(mode="python"))
    cap_field = KINDS[kind].capacity_field
    ratio = capacity(kind, new) / capacity(kind, old) if capacity(kind, old) else 1.0
    words = []
    if flat_new[cap_field] != flat_old[cap_field]:
        words.append(f"{new.name} {flat_new[cap_field]:g} {power_unit(kind)}")
    for path, value in flat_new.items():
        before = flat_old.get(path)
        if path in (cap_field, "kind") or value == before:
            continue
        leaf = path.split(".")[-1]
        if leaf == "series_scale" and before is not None and math.isclose(value, before * ratio):
            continue  # followed the capacity: already said
        if leaf == "breakpoints":
            words.append(f"{new.name} power-block curve edited")
            continue
        name, unit, _ = FIELDS.get(leaf, (leaf, "", ""))
        if leaf == "series" and value is None:
            value = new.name  # no series of its own: the unit reads the history column of its name
        shown = "empty" if value is None else (f"{value:g}" if isinstance(value, float) else str(value))
        words.append(f"{new.name} {name} {shown}{f' {unit}' if unit and unit != '-' and value is not None else ''}")
    return words


def flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested settings as dotted field paths: ``{"storage": {"e_min_mwh_th": 110}}`` gives
    ``{"storage.e_min_mwh_th": 110}``."""
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            flat.update(flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _get(unit: Any, path: str) -> Any:
    for part in path.split("."):
        unit = getattr(unit, part)
    return unit


def _set(unit: Any, path: str, value: Any) -> Any:
    head, _, rest = path.partition(".")
    if not rest:
        return unit.model_copy(update={head: value})
    return unit.model_copy(update={head: _set(getattr(unit, head), rest, value)})
