"""State carried between days: turbine minimum times begun the day before, the end-of-day storage
rule, the end-of-day state the settlement reports, Γ as a fraction of the day, and their validation."""

from __future__ import annotations

import copy

import numpy as np
import pyomo.environ as pyo
import pytest
import yaml

from rvpp import CaseError, prepare, solve_problem, with_options
from rvpp.data.case import parse_case
from rvpp.settle.audit import audit_result
from rvpp.settle.recourse import (Penalties, build_recourse_model, end_state, first_stage, nominal_realization,
                                  realized_problem)
from rvpp.solving.highs import run_highs
from tests.factories import PAPER, tiny_case, tiny_problem

NT = 24
HOURS = np.arange(1, NT + 1, dtype=float)


def csp_unit(min_up=6.0, min_down=6.0, on=False, status_h=None, e_init=None, e_end_min=None, om=0.0):
    """A CSP with no start-up heat, a 10 MW_th minimum input and a 100 MW_th turbine input limit."""
    return {"name": "C", "om_eur_per_mwh": om, "heat_efficiency": 1.0, "ramp_mw_per_min": 10, "reserve_share": 0.5,
            "solar_field": {"p_max_mw_th": 200},
            "storage": {"e_min_mwh_th": 100, "e_max_mwh_th": 1000, "p_ch_max_mw_th": 100, "p_dis_max_mw_th": 100,
                        "eta_ch": 1.0, "eta_dis": 1.0, "e_init_mwh_th": e_init, "e_end_min_mwh_th": e_end_min},
            "power_block": {"p_in_max_mw_th": 100, "p_in_min_mw_th": 10, "p_el_max_mw": 40,
                            "breakpoints": [[0, 0], [10, 0.4], [100, 0.4]], "min_up_h": min_up,
                            "min_down_h": min_down, "startup_fraction": 0.0, "initially_on": on,
                            "initial_status_h": status_h}}


def online(result) -> list[int]:
    return result.csp["online"].astype(int).tolist()


def solved(problem):
    result = solve_problem(problem)
    assert result.status == "optimal", result.message
    assert audit_result(result, bands=problem.bands) == []
    return result


def test_a_minimum_up_time_begun_the_day_before_keeps_the_turbine_on():
    # Every MWh costs 5 EUR to sell at price 0... the turbine would stop at once; it has run 2 h of its
    # 6 h minimum, so it must stay on for periods 1-4 and only then stop.
    price = np.full(NT, -5.0)
    for status_h, expected in ((2.0, [1] * 4 + [0] * 20), (None, [0] * 24), (6.0, [0] * 24), (5.0, [1] + [0] * 23)):
        case = tiny_case(csp_units=[csp_unit(on=True, status_h=status_h, e_init=600, e_end_min=100)])
        result = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
        assert online(result) == expected, status_h


def test_a_minimum_down_time_begun_the_day_before_keeps_the_turbine_off():
    # A high price, falling over the day, makes the turbine start as early as it may: at once unless
    # 1 h of its 6 h minimum down time was spent (then in period 6).
    price = 300.0 - HOURS
    for status_h, first_on in ((1.0, 6), (None, 1), (4.0, 3)):
        case = tiny_case(csp_units=[csp_unit(on=False, status_h=status_h, e_init=900, e_end_min=100)])
        result = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
        assert online(result).index(1) + 1 == first_on, status_h


@pytest.mark.parametrize("dt_h", [1.0, 0.5, 0.25])
def test_minimum_times_begun_the_day_before_are_hours_whatever_the_period_length(dt_h):
    # As in the two tests above, at periods of 1 h, 30 min and 15 min: on for the 6 − 2 = 4 h left of
    # the minimum up time, off for the 6 − 1 = 5 h left of the minimum down time, and a start within
    # the day keeps the turbine on for 6 h.
    nt = round(24 / dt_h)
    falling = 300.0 - np.arange(nt) * dt_h
    negative = np.full(nt, -5.0)
    up = tiny_case(csp_units=[csp_unit(on=True, status_h=2.0, e_init=600, e_end_min=100)], dt_h=dt_h)
    kept_on = online(solved(tiny_problem(up, C=(0, 0, 0), price_da=(negative, negative, negative))))
    assert kept_on == [1] * round(4 / dt_h) + [0] * (nt - round(4 / dt_h))
    down = tiny_case(csp_units=[csp_unit(on=False, status_h=1.0, e_init=900, e_end_min=100)], dt_h=dt_h)
    kept_off = online(solved(tiny_problem(down, C=(0, 0, 0), price_da=(falling, falling, falling))))
    assert kept_off.index(1) * dt_h == 5.0
    # Started within the day for one good hour (300 EUR/MWh, then −5), it runs its whole 6 h minimum.
    spike = np.where(np.arange(nt) * dt_h < 1.0, 300.0, -5.0)
    fresh = tiny_case(csp_units=[csp_unit(on=False, e_init=900, e_end_min=100)], dt_h=dt_h)
    ran = online(solved(tiny_problem(fresh, C=(0, 0, 0), price_da=(spike, spike, spike))))
    assert ran == [1] * round(6 / dt_h) + [0] * (nt - round(6 / dt_h))


def test_the_storage_may_run_down_to_its_end_target_and_no_further():
    # No sun, price 100: the turbine sells all it can. Starting at 600 with a 300 MWh_th target, it
    # spends exactly 300 MWh_th; starting at 250 (below the target), it may not end below 250.
    price = np.full(NT, 100.0)
    for e_init, e_end_min, end in ((600, 300, 300.0), (250, 300, 250.0), (600, None, 600.0)):
        case = tiny_case(csp_units=[csp_unit(e_init=e_init, e_end_min=e_end_min, min_up=0, min_down=0)])
        result = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
        energy = result.csp["ts_energy_mwh"].to_numpy()
        assert energy[-1] == pytest.approx(end, abs=1e-6)
        output = result.csp["e_none_mw"].sum()
        assert output == pytest.approx(0.4 * (e_init - end), rel=1e-6)  # 40 % of the heat spent


@pytest.mark.parametrize("storage_end, tank, battery", [("carry", None, None), (0.5, 550.0, 22.0),
                                                         (0.0, 100.0, 4.0), (1.0, 1000.0, 40.0)])
def test_the_end_of_day_rule_gives_the_battery_its_target_as_the_tank(storage_end, tank, battery):
    # Tank 100-1000 MWh_th, battery 4-40 MWh: e_min + F x (e_max - e_min), e.g. 4 + 0.5 x 36 = 22 MWh
    from rvpp.backtest.state import with_state
    unit = {"name": "B", "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 10.0, "p_dis_max_mw": 10.0,
            "e_init_mwh": 12.0, "ramp_mw_per_min": 5.0}
    case = tiny_case(csp_units=[csp_unit(e_init=600)], battery_units=[unit])
    state = {"C": {"e_mwh_th": 700.0, "online": False, "status_h": None}, "B": {"e_mwh": 30.0}}
    day = with_state(case, state, storage_end)
    assert (day.csp[0].storage.e_init_mwh_th, day.csp[0].storage.e_end_min_mwh_th) == (700.0, tank)
    assert (day.battery[0].e_init_mwh, day.battery[0].e_end_min_mwh) == (30.0, battery)
    assert day.battery[0].end_floor_mwh == (30.0 if battery is None else min(battery, 30.0))


def test_a_unit_switched_off_has_no_state_to_carry():
    # records.csv had start_D_e_mwh for a battery switched off, filled on the first day only (no end_D_e_mwh):
    # the first day's state named it, the settlement of an idle unit does not
    from rvpp.backtest.state import initial_state, with_state
    unit = {"name": "B", "e_min_mwh": 4.0, "e_max_mwh": 40.0, "p_ch_max_mw": 10.0, "p_dis_max_mw": 10.0,
            "e_init_mwh": 12.0, "ramp_mw_per_min": 5.0}
    case = tiny_case(csp_units=[csp_unit(e_init=600)], battery_units=[unit, {**unit, "name": "D", "enabled": False}])
    assert initial_state(case) == {"C": {"e_mwh_th": 600.0, "online": False, "status_h": None}, "B": {"e_mwh": 12.0}}
    day = with_state(case, {"C": {"e_mwh_th": 700.0, "online": False, "status_h": None}, "B": {"e_mwh": 30.0}})
    assert [(b.name, b.e_init_mwh, b.enabled) for b in day.battery] == [("B", 30.0, True), ("D", 12.0, False)]


def test_the_settlement_reports_the_end_of_day_state_counting_into_the_day_before():
    # A settled day whose turbine never switches hands on its hours plus those carried in
    # (selling at 10 EUR/MWh does not pay the 50 EUR/MWh operating cost: it stays off).
    price = np.full(NT, 10.0)
    case = tiny_case(csp_units=[csp_unit(on=False, status_h=7.0, e_init=600, e_end_min=100, om=50.0)])
    plan = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
    problem = realized_problem(case, nominal_realization(plan.problem))
    m = build_recourse_model([problem], Penalties(), first_stage(plan))
    assert run_highs(m, case.solver).status == "optimal"
    b = m.scenario[0].csp["C"]
    schedule = [round(pyo.value(b.online[t])) for t in m.T]
    assert schedule == [0] * NT
    state = end_state(m.scenario[0], case, 1.0)["C"]
    assert state == {"e_mwh_th": pytest.approx(pyo.value(b.e_ts[NT])), "online": False, "status_h": 31.0}


def test_the_settlement_counts_only_the_last_run_when_the_turbine_switched():
    # 800 MWh_th to spend at up to 100 MW_th: all of it in the 8 periods priced 100, none after.
    price = np.where(HOURS <= 8, 100.0, 10.0)
    case = tiny_case(csp_units=[csp_unit(on=True, status_h=3.0, e_init=900, e_end_min=100, min_up=0, min_down=0,
                                         om=20.0)])
    plan = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
    assert online(plan) == [1] * 8 + [0] * 16
    problem = realized_problem(case, nominal_realization(plan.problem))
    m = build_recourse_model([problem], Penalties(), first_stage(plan))
    assert run_highs(m, case.solver).status == "optimal"
    state = end_state(m.scenario[0], case, 1.0)["C"]
    assert state["online"] is False and state["status_h"] == 16.0


def test_the_settlement_lets_a_turbine_trip_before_its_carried_minimum_up_time():
    # The plan must keep the turbine on for 4 periods; the settlement may stop it at once.
    price = np.full(NT, 10.0)
    case = tiny_case(csp_units=[csp_unit(on=True, status_h=2.0, e_init=600, e_end_min=100, om=50.0)])
    plan = solved(tiny_problem(case, C=(0, 0, 0), price_da=(price, price, price)))
    assert online(plan)[:5] == [1, 1, 1, 1, 0]
    zero = np.zeros(NT)
    from rvpp.settle.recourse import FirstStage

    problem = realized_problem(case, nominal_realization(plan.problem))
    m = build_recourse_model([problem], Penalties(), FirstStage(zero, zero, zero, zero))
    assert run_highs(m, case.solver).status == "optimal"
    assert [round(pyo.value(m.scenario[0].csp["C"].online[t])) for t in (1, 2)] == [0, 0]


@pytest.mark.parametrize("fraction, nt, gamma", [(0.125, 24, 3), (0.25, 24, 6), (0.0625, 24, 2), (0.3125, 24, 8),
                                                 (0.125, 23, 3), (0.25, 25, 6), (0.0, 24, 0), (1.0, 23, 23)])
def test_a_fraction_of_the_day_rounds_half_up_for_every_source(paper_case, fraction, nt, gamma):
    day = {24: "2025-05-05", 23: "2025-03-30", 25: "2025-10-26"}[nt]
    problem = prepare(with_options(paper_case, date=day, gamma_fraction=fraction))
    assert problem.nt == nt
    assert set(problem.budgets.values()) == {gamma}
    assert set(problem.budgets) == set(paper_case.sources())


def test_a_strategy_option_clears_a_fraction_and_overrides_still_apply(paper_case):
    fraction = with_options(paper_case, gamma_fraction=0.25, gammas={"WF1": 2})
    assert prepare(fraction).budgets["WF1"] == 2 and prepare(fraction).budgets["PV1"] == 6
    assert fraction.budgets.label == "Γ 0.25 of the day"
    back = with_options(fraction, strategy="optimistic")
    assert back.budgets.fraction is None and prepare(back).budgets["PV1"] == 2


def raw_case():
    return yaml.safe_load((PAPER / "case.yaml").read_text())


BAD = {
    "end target without a start": (lambda c: c["storage"].update(e_init_mwh_th=None, e_end_min_mwh_th=300),
                                    "storage.e_end_min_mwh_th=300 needs storage.e_init_mwh_th"),
    "end target above the storage": (lambda c: c["storage"].update(e_init_mwh_th=500, e_end_min_mwh_th=2000),
                                     "storage.e_end_min_mwh_th=2000 must lie in [storage.e_min_mwh_th=110, "
                                     "storage.e_max_mwh_th=1100]"),
    "status time not whole periods": (lambda c: c["power_block"].update(initial_status_h=2.5),
                                      'csp "CSP1": power_block.initial_status_h=2.5 must be a multiple of dt_h=1'),
    "negative status time": (lambda c: c["power_block"].update(initial_status_h=-1),
                             "power_block.initial_status_h=-1 must be >= 0"),
}


@pytest.mark.parametrize("label", list(BAD))
def test_initial_conditions_are_validated(paper_case, label):
    edit, message = BAD[label]
    data = copy.deepcopy(raw_case())
    edit(data["units"]["csp"][0])
    with pytest.raises(CaseError) as info:
        parse_case(data, paper_case.history)
    assert any(message in p for p in info.value.problems), info.value.problems


def test_a_fraction_outside_the_day_is_refused(paper_case):
    data = copy.deepcopy(raw_case())
    data["budgets"]["fraction"] = 1.5
    with pytest.raises(CaseError, match=r"budgets: fraction=1.5 must be <= 1"):
        parse_case(data, paper_case.history)


def test_the_case_variant_of_a_fraction_sets_the_case_edits_aside_and_names_the_fraction(paper_case):
    from rvpp.data.variants import Variant, describe

    edited = paper_case.replace(budgets={"overrides": {"WF1": 1}})
    case = Variant(gamma_fraction=0.25, gammas={"PV1": 2}).apply(edited)
    assert case.budgets.fraction == 0.25 and case.budgets.override_map == {"PV1": 2}
    assert prepare(case).budgets["WF1"] == 6 and prepare(case).budgets["PV1"] == 2
    assert describe(case).startswith("Γ 0.25 of the day · DAM+SRM+HPA")
    preset = Variant(strategy="pessimistic").apply(case)
    assert preset.budgets.fraction is None and describe(preset).startswith("pessimistic · ")


def test_a_day_a_carried_minimum_up_time_leaves_without_plan_is_planned_with_a_trip():
    # The turbine has run 2 h of its 6 h minimum, the storage is empty (at E min) and the day has no
    # sun: it cannot run the 4 periods it owes, so the plan is infeasible. Planned again with that
    # minimum counted as done (as the settlement lets it trip), the turbine stops at once.
    from rvpp.backtest.engine import day_plan
    from rvpp.backtest.state import min_up_lifted

    price = np.full(NT, 10.0)
    case = tiny_case(csp_units=[csp_unit(on=True, status_h=2.0, e_init=100)])
    make = lambda day: solve_problem(tiny_problem(day, C=(0, 0, 0), price_da=(price, price, price)))  # noqa: E731
    assert make(case).status == "infeasible"
    planned_for, result, lifted = day_plan(case, make)
    assert lifted and result.status == "optimal"
    assert planned_for.csp[0].power_block.initial_status_h == 6.0 and case.csp[0].power_block.initial_status_h == 2.0
    assert online(result) == [0] * NT
    assert audit_result(result, bands=result.problem.bands) == []
    # With heat in store the owed periods can be run: planned as it is, the minimum up time kept.
    stored = tiny_case(csp_units=[csp_unit(on=True, status_h=2.0, e_init=600, e_end_min=100, om=50.0)])
    planned_for, result, lifted = day_plan(stored, make)
    assert not lifted and planned_for is stored and online(result)[:5] == [1, 1, 1, 1, 0]
    for unlifted in (csp_unit(on=True, status_h=None), csp_unit(on=True, status_h=6.0), csp_unit(on=False, status_h=2.0)):
        one = tiny_case(csp_units=[unlifted])
        assert min_up_lifted(one) is one
