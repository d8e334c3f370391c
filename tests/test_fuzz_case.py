"""Property: loading any mutation of the default case either succeeds or raises rvpp's own error.

The mutations are those a careless edit or a hostile upload makes: keys dropped or
renamed, numbers replaced by extremes (0, -1, 1e308, nan, inf, huge integers), types
swapped (text for a list, a list for a mapping), units duplicated, sections reordered,
and bytes of the YAML text cut, doubled or replaced. Whatever comes in, the only
acceptable failure is an :class:`rvpp.errors.RvppError` whose message names the problem;
any other exception is a bug. A case that loads must hold only finite numbers within the
bounds docs/case-format.md gives, and a short solve of it must pass the audit.
"""

from __future__ import annotations

import copy
import datetime as dt
import math
from typing import Any

import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from rvpp import solve
from rvpp.data.case import parse_case
from rvpp.data.variants import with_options
from rvpp.data.history import History
from rvpp.errors import CaseError, RvppError
from rvpp.outputs.bundle import read_case_files
from rvpp.settle.audit import audit_result

from tests.factories import PAPER

RAW = yaml.safe_load((PAPER / "case.yaml").read_text(encoding="utf-8"))
# The paper case with a battery, a hydro and a biomass unit (MODEL_SPEC §13), every field written.
RAW_NEW_UNITS = {**RAW, "units": {**RAW["units"], "battery": [
    {"name": "BAT1", "enabled": True, "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 20.0, "p_dis_max_mw": 20.0,
     "eta_ch": 0.95, "eta_dis": 0.9, "self_discharge_per_h": 0.001, "degradation_eur_per_mwh": 5.0,
     "e_init_mwh": 10.0, "e_end_min_mwh": 8.0, "ramp_mw_per_min": 20.0, "reserve_share": 1.0}],
    "hydro": [{"name": "HY1", "enabled": True, "p_min_mw": 5.0, "p_max_mw": 30.0, "marginal_cost_eur_per_mwh": 5.0,
               "startup_cost_eur": 100.0, "shutdown_cost_eur": 10.0, "ramp_up_mw_per_h": 30.0, "ramp_dn_mw_per_h": 30.0,
               "startup_ramp_mw_per_h": 10.0, "shutdown_ramp_mw_per_h": 10.0, "min_up_h": 2.0, "min_down_h": 2.0,
               "initial_online": True, "initial_hours_in_status": 1.0, "p_init_mw": 10.0, "energy_max_mwh": 300.0,
               "ramp_mw_per_min": 10.0, "reserve_share": 0.5}],
    "biomass": [{"name": "BIO1", "enabled": False, "p_min_mw": 5.0, "p_max_mw": 15.0, "min_up_h": 4.0,
                 "min_down_h": 4.0, "ramp_mw_per_min": 1.0}]}}
# The paper case with the authors' tool's conventions set (docs/gams-tool.md).
RAW_TOOL = copy.deepcopy(RAW)
RAW_TOOL["units"]["ed"][0].update({"profile_window": True, "ramp_up_mw_per_h": 40.0, "ramp_dn_mw_per_h": 40.0,
                                   "energy_net_of_up_band": False})
RAW_TOOL["units"]["csp"][0]["storage"].update({"reserve_band_max_mw_th": 30.0, "reserve_energy_factor": 2.0,
                                               "reserve_share_max": 0.5})
RAW_TOOL["units"]["csp"][0]["power_block"]["output_capped"] = False
FAST = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])

EXTREMES = [0, -1, 1, 0.5, 1e308, -1e308, 5e-324, math.nan, math.inf, -math.inf, 10 ** 30, -10 ** 30, 2 ** 63,
            True, False, None, "", "x", "nan", "1e999", "2025-13-45", "../../etc/hostname", "\x00\x1b", "é" * 50,
            [], [1, 2, 3], [[0, 0], [1, 1]], {}, {"a": 1}, {"name": "X"}, list(range(30)), dt.date(2025, 5, 5)]


@pytest.fixture(scope="module")
def short_history(paper_case):
    """The paper history around its delivery date: enough for the bands, quick to parse."""
    frame = paper_case.history.frame
    start = pd.Timestamp(paper_case.delivery_date, tz="UTC") - pd.Timedelta(days=35)
    return History(frame[(frame.index >= start) & (frame.index < start + pd.Timedelta(days=40))])


@pytest.fixture(scope="module")
def short_csv(short_history, tmp_path_factory):
    path = tmp_path_factory.mktemp("history") / "history.csv"
    short_history.to_csv(path, "Europe/Madrid")
    return path.read_bytes()


def paths(data: Any, prefix: tuple = ()) -> list[tuple]:
    """Every location in nested data: mapping keys and list positions."""
    found = [prefix] if prefix else []
    if isinstance(data, dict):
        for key, value in data.items():
            found += paths(value, prefix + (key,))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            found += paths(value, prefix + (i,))
    return found


def _parent(data: Any, path: tuple) -> Any:
    for part in path[:-1]:
        data = data[part]
    return data


@st.composite
def mutated_cases(draw) -> dict:
    data = copy.deepcopy(draw(st.sampled_from([RAW, RAW_NEW_UNITS, RAW_TOOL])))
    for _ in range(draw(st.integers(1, 4))):
        where = paths(data)
        if not where:
            break
        path = draw(st.sampled_from(where))
        parent, key = _parent(data, path), path[-1]
        action = draw(st.sampled_from(["drop", "extreme", "text-to-list", "rename", "duplicate", "shuffle",
                                       "wrap"]))
        if action == "drop":
            del parent[key]
        elif action == "extreme":
            parent[key] = copy.deepcopy(draw(st.sampled_from(EXTREMES)))
        elif action == "text-to-list":
            parent[key] = [parent[key]] if not isinstance(parent[key], list) else {"items": parent[key]}
        elif action == "rename" and isinstance(parent, dict):
            parent[draw(st.sampled_from(["", "Name", "units ", "p_max_MW", "1", "history"]))] = parent.pop(key)
        elif action == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
        elif action == "shuffle" and isinstance(parent, dict):
            items = list(parent.items())
            order = draw(st.permutations(range(len(items))))
            parent.clear()
            parent.update(items[i] for i in order)
        elif action == "wrap":
            parent[key] = {"value": parent[key]}
    return data


# docs/case-format.md: no quantity above 1,000,000 in its unit; efficiencies, shares, flexibilities in [0, 1].
LARGEST = 1e6
FRACTIONS = {"kappa", "reserve_share", "flex_up", "flex_dn", "heat_efficiency", "eta_ch", "eta_dis",
             "startup_fraction", "reserve_share_max"}


def numbers(data: Any, where: str = "") -> list[tuple[str, float]]:
    """Every number in nested data, with where it stands (booleans are not numbers)."""
    if isinstance(data, dict):
        return [n for key, value in data.items() for n in numbers(value, f"{where}.{key}")]
    if isinstance(data, (list, tuple)):
        return [n for i, value in enumerate(data) for n in numbers(value, f"{where}[{i}]")]
    if isinstance(data, (int, float)) and not isinstance(data, bool):
        return [(where, data)]
    return []


def assert_within_documented_bounds(case) -> None:
    """The rules of docs/case-format.md, checked on a loaded case by code of this test's own."""
    data = case.model_dump(mode="python", exclude={"history"})
    for where, value in numbers(data):
        assert math.isfinite(value) and abs(value) <= LARGEST, f"{where} = {value!r}"
        if where.rsplit(".", 1)[-1] in FRACTIONS:
            assert 0.0 <= value <= 1.0, f"{where} = {value!r}"
    assert case.dt_h in (1.0, 0.5, 0.25)
    markets, uncertainty = data["markets"], data["uncertainty"]
    for unit in data["csp"]:
        assert 0 < unit["storage"]["reserve_energy_factor"] <= 100, unit["name"]
    assert len(markets["hpa_tariff_eur_per_mwh"]) == 24 and min(markets["hpa_tariff_eur_per_mwh"]) >= 0
    assert markets["reserve_duration_min"] > 0
    assert 1 <= uncertainty["window_days"] <= 366 and 0 < uncertainty["q_lo"] < 0.5 < uncertainty["q_hi"] < 1
    for unit in data["wind"] + data["pv"]:
        assert unit["p_max_mw"] > 0 and unit["series_scale"] > 0, unit
    for unit in data["ed"]:
        assert unit["p_min_mw"] <= unit["p_max_mw"], unit
    for unit in data["td"]:
        assert unit["h_min_mw_th"] <= unit["h_max_mw_th"], unit
    for unit in data["csp"]:
        ts, pb = unit["storage"], unit["power_block"]
        assert ts["e_min_mwh_th"] < ts["e_max_mwh_th"] and ts["eta_ch"] > 0 and ts["eta_dis"] > 0, ts
        if ts["e_init_mwh_th"] is not None:
            assert ts["e_min_mwh_th"] <= ts["e_init_mwh_th"] <= ts["e_max_mwh_th"], ts
        inputs = [point[0] for point in pb["breakpoints"]]
        outputs = [point[0] * point[1] for point in pb["breakpoints"]]
        assert inputs[0] == 0 and all(b > a for a, b in zip(inputs, inputs[1:])), pb
        assert all(0 <= point[1] <= 1 for point in pb["breakpoints"]), pb
        assert all(b >= a for a, b in zip(outputs, outputs[1:])) and inputs[-1] >= pb["p_in_max_mw_th"], pb
        for field in ("min_up_h", "min_down_h"):
            periods = pb[field] / case.dt_h
            assert pb[field] >= 0 and abs(periods - round(periods)) <= 1e-9, (field, pb[field])
        for field in ("min_up_h", "min_down_h"):
            assert pb[field] <= 24, (field, pb[field])  # no minimum time longer than the day
    for unit in data["battery"]:  # MODEL_SPEC §13
        assert unit["e_min_mwh"] < unit["e_max_mwh"], unit
        if unit["e_init_mwh"] is not None:
            assert unit["e_min_mwh"] <= unit["e_init_mwh"] <= unit["e_max_mwh"], unit
        target = unit.get("e_end_min_mwh")  # written only when set
        if target is not None:  # an end target only beside a start, within the battery
            assert unit["e_init_mwh"] is not None and unit["e_min_mwh"] <= target <= unit["e_max_mwh"], unit
        assert 0 < unit["eta_ch"] <= 1 and 0 < unit["eta_dis"] <= 1, unit
        assert 0 <= unit["self_discharge_per_h"] < 1 and unit["p_ch_max_mw"] > 0 and unit["p_dis_max_mw"] > 0, unit
        # charging at full power makes up for the self-discharge at the lowest level the day must hold:
        # E min on a cyclic day, else where it must end, min(target, start)
        end = unit["e_init_mwh"] if target is None else min(unit["e_init_mwh"], target)
        held = unit["e_min_mwh"] if unit["e_init_mwh"] is None else end
        assert unit["self_discharge_per_h"] * (held - 1e-6) <= unit["eta_ch"] * unit["p_ch_max_mw"] * (1 + 1e-9), unit
    for unit in data["hydro"] + data["biomass"]:
        assert unit["p_min_mw"] <= unit["p_max_mw"], unit
        for field in ("min_up_h", "min_down_h"):
            periods = unit[field] / case.dt_h
            assert 0 <= unit[field] <= 24 and abs(periods - round(periods)) <= 1e-9, (field, unit)
        if unit["energy_max_mwh"] is not None:  # enough water or fuel for the least a start commits it to
            assert unit["energy_max_mwh"] >= unit["p_min_mw"] * max(unit["min_up_h"], case.dt_h), unit
            assert unit["energy_max_mwh"] >= least_run_mwh(unit, case.dt_h) - 1e-9, unit
        if unit["p_init_mw"] is not None:
            low, high = (unit["p_min_mw"], unit["p_max_mw"]) if unit["initial_online"] else (0.0, 0.0)
            assert low <= unit["p_init_mw"] <= high, unit
    names = [unit["name"] for kind in ("wind", "pv", "csp", "ed", "td", "battery", "hydro", "biomass")
             for unit in data[kind]]
    assert len(names) == len(set(names)), names
    assert not [name for name, gamma in data["budgets"]["overrides"] if gamma < 0]
    frame = case.history.frame.select_dtypes("number")
    assert frame.notna().all().all() and (frame.abs() <= LARGEST).all().all()


def least_run_mwh(unit: dict, dt_h: float) -> float:
    """What a hydro or biomass unit online before the day must produce before it may stop: the rest of
    a minimum up time begun before the day, and from ``p_init_mw`` down at its ramp to where it may
    stop (docs/case-format.md); whole 24-hour days here, where the case may have 23 hours."""
    if not unit["initial_online"]:
        return 0.0
    done = unit["initial_hours_in_status"]
    left = 0 if done is None else max(0, round((unit["min_up_h"] - done) / dt_h))
    level, hours_on, energy = unit["p_init_mw"], 0, 0.0
    down = math.inf if unit["ramp_dn_mw_per_h"] is None else unit["ramp_dn_mw_per_h"] * dt_h
    stop = math.inf if unit["shutdown_ramp_mw_per_h"] is None else unit["shutdown_ramp_mw_per_h"] * dt_h
    while hours_on < round(23 / dt_h) and (hours_on < left
                                           or (level is not None and level > min(stop, unit["p_max_mw"]))):
        level = unit["p_min_mw"] if level is None else max(unit["p_min_mw"], level - down)
        energy += level * dt_h
        hours_on += 1
    return energy


def load_or_refuse(load):
    """Call ``load``; a loaded case must keep the documented bounds; a refusal (RvppError) must name
    something. Returns the case, or ``None`` when it was refused."""
    try:
        case = load()
    except RvppError as err:
        message = str(err)
        assert message.strip() and "Traceback" not in message
        assert "UnitKind" not in message, message  # kinds as written in case.yaml, not as the code spells them
        if isinstance(err, CaseError):
            assert err.problems and all(isinstance(p, str) and p for p in err.problems)
        return None
    assert_within_documented_bounds(case)
    return case


def _check_mutation(data: dict, history: History):
    return load_or_refuse(lambda: parse_case(data, history))


def _check_text(text: bytes, csv: bytes):
    return load_or_refuse(lambda: read_case_files({"case.yaml": text, "history.csv": csv}))


def changed(path: tuple, value: Any, base: dict = RAW) -> dict:
    """The default case (or ``base``) with the value at ``path`` replaced."""
    data = copy.deepcopy(base)
    _parent(data, path)[path[-1]] = value
    return data


def changed_unit(listed_under: str, **values: Any) -> dict:
    """The case with the new units, its first unit listed under ``listed_under`` (battery, hydro, biomass)
    given ``values``."""
    data = copy.deepcopy(RAW_NEW_UNITS)
    data["units"][listed_under][0].update(values)
    return data


@settings(max_examples=100, **FAST)
@given(data=mutated_cases())
# Values past a documented bound, tried on every run: a percentage where a fraction belongs, a
# quantity past 1,000,000, a tank level outside the tank.
@example(data=changed(("units", "wind", 0, "p_max_mw"), 1e308))
@example(data=changed(("units", "csp", 0, "storage", "eta_ch"), 95))
@example(data=changed(("units", "ed", 1, "flex_up"), 10))
@example(data=changed(("markets", "hpa_tariff_eur_per_mwh", 7), 2e6))
@example(data=changed(("units", "csp", 0, "storage", "e_init_mwh_th"), 5000))
@example(data=changed(("units", "csp", 0, "power_block", "min_up_h"), 2.5))
@example(data=changed(("units", "csp", 0, "storage", "reserve_share_max"), 1.5))
@example(data=changed(("units", "csp", 0, "storage", "reserve_energy_factor"), 0))
@example(data=changed(("units", "ed", 0, "profile_window"), "sometimes"))
@example(data=changed(("units", "ed", 0, "ramp_dn_mw_per_h"), -5))
# The bad batteries, hydro and biomass units of MODEL_SPEC §13, and minimum times longer than the day.
@example(data=changed_unit("battery", e_min_mwh=50.0))
@example(data=changed_unit("battery", e_init_mwh=45.0))
@example(data=changed_unit("battery", e_init_mwh=2.0))
@example(data=changed_unit("battery", e_end_min_mwh=45.0))
@example(data=changed_unit("battery", e_end_min_mwh=2.0))
@example(data=changed_unit("battery", e_init_mwh=None))
@example(data=changed_unit("battery", eta_ch=0.0))
@example(data=changed_unit("battery", eta_dis=95))
@example(data=changed_unit("battery", self_discharge_per_h=0.9, p_ch_max_mw=1.0))
@example(data=changed_unit("hydro", energy_max_mwh=8.0))
@example(data=changed_unit("hydro", p_init_mw=40.0))
@example(data=changed_unit("hydro", min_up_h=25.0))
@example(data=changed_unit("hydro", p_init_mw=30.0, ramp_dn_mw_per_h=5.0, energy_max_mwh=60.0, min_up_h=0.0,
                           initial_hours_in_status=None))
@example(data=changed_unit("biomass", min_down_h=30.0, enabled=True))
@example(data=changed(("units", "csp", 0, "power_block", "min_up_h"), 30))
@example(data=changed_unit("battery", name="HY1"))
@example(data=changed_unit("biomass", name="WF1"))
@example(data=changed_unit("hydro", kind="biomass"))
def test_a_mutated_case_loads_or_is_refused_by_rule(short_history, data):
    _check_mutation(data, short_history)


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(data=mutated_cases())
def test_a_mutated_case_that_loads_solves_to_a_plan_that_passes_the_audit(short_history, data):
    case = _check_mutation(data, short_history)
    assume(case is not None)  # about one mutation in eight loads; the others are refused by rule
    result = solve(case.replace(solver={"time_limit_s": 20.0, "threads": 1}))
    assert result.status in ("optimal", "time_limit", "infeasible"), (result.status, result.message)
    if result.has_plan:
        assert audit_result(result) == []
    else:
        assert result.message, "a case without a plan says why"


@settings(max_examples=60, **FAST)
@given(data=mutated_cases())
def test_a_mutated_case_yaml_uploads_or_is_refused_by_rule(short_csv, data):
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True).encode()
    _check_text(text, short_csv)


@st.composite
def damaged_texts(draw) -> bytes:
    """The default case.yaml with bytes cut, doubled or replaced."""
    text = bytearray((PAPER / "case.yaml").read_bytes())
    for _ in range(draw(st.integers(1, 6))):
        at = draw(st.integers(0, len(text) - 1))
        span = draw(st.integers(1, 40))
        action = draw(st.sampled_from(["cut", "double", "replace", "insert"]))
        if action == "cut":
            del text[at:at + span]
        elif action == "double":
            text[at:at] = text[at:at + span]
        else:
            new = draw(st.binary(min_size=1, max_size=8) | st.sampled_from(
                [b":", b"- ", b"&a ", b"*a", b"{", b"[", b"\t", b"'", b"!!python/object ", b"\xff", b"<<: "]))
            text[at:at + (span if action == "replace" else 0)] = new
        if not text:
            break
    return bytes(text)


@settings(max_examples=60, **FAST)
@given(text=damaged_texts())
def test_a_damaged_case_yaml_uploads_or_is_refused_by_rule(short_csv, text):
    _check_text(text, short_csv)


@settings(max_examples=60, **FAST)
@given(hpa_flat=st.sampled_from([None, *EXTREMES[:14]]), time_limit=st.sampled_from([None, *EXTREMES[:14]]),
       gap=st.sampled_from([None, *EXTREMES[:14]]), threads=st.sampled_from([None, *EXTREMES[:14]]),
       markets=st.sampled_from([None, "", ",", "DAM", "SRM", "dam+hpa", "DAM,IDM", "DAM,,SRM"]),
       dt_h=st.sampled_from([None, 1, 0.25, 0.3, 0, -1, math.nan]),
       date=st.sampled_from([None, "2025-05-05", "", "2025-02-30", "1900-01-01", 20250505]))
def test_run_options_apply_or_are_refused_by_rule(paper_case, hpa_flat, time_limit, gap, threads, markets, dt_h,
                                                  date):
    load_or_refuse(lambda: with_options(paper_case, hpa_flat=hpa_flat, time_limit_s=time_limit, rel_gap=gap,
                                        threads=threads, markets=markets, dt_h=dt_h, date=date))


@pytest.mark.slow
@settings(max_examples=800, **FAST)
@given(data=mutated_cases(), text=damaged_texts())
def test_many_more_mutations_load_or_are_refused_by_rule(short_history, short_csv, data, text):
    _check_mutation(data, short_history)
    _check_text(text, short_csv)
