"""What one day hands to the next: storage energy, turbine status and time in that status
(CSPs), a battery's state of charge, a hydro or biomass unit's status, time in it and output.

As in operation, the state at the end of day ``D``'s *settled* dispatch (not its plan)
is day ``D + 1``'s initial condition, for the plan and for the settlement. A state is
plain data (``{csp: {"e_mwh_th", "online", "status_h"}}``), the layout of
:func:`rvpp.settle.recourse.end_state`, so it travels in records and through the store
unchanged: a resumed backtest restarts from the last recorded day's ``end_state``.
"""

from __future__ import annotations

from typing import Any

from ..data.case import Case
from .settings import CARRY

State = dict[str, dict[str, Any]]


def initial_state(case: Case) -> State:
    """The first day's state: the case's initial conditions.

    Storage at ``storage.e_init_mwh_th``, or empty (``e_min``) on a cyclic case; the turbine
    ``initially_on`` with ``initial_status_h`` hours in that status (unset: free to switch).
    """
    state = {}
    for csp in case.csp:
        ts, pb = csp.storage, csp.power_block
        energy = ts.e_init_mwh_th if ts.e_init_mwh_th is not None else ts.e_min_mwh_th
        state[csp.name] = {"e_mwh_th": float(energy), "online": pb.initially_on, "status_h": pb.initial_status_h}
    # Units switched off (enabled: false) are out of the model: no state, as the settlement reports none for them
    for bat in (b for b in case.battery if b.enabled):  # MODEL_SPEC §13: at e_init, or at E min on a cyclic case
        state[bat.name] = {"e_mwh": float(bat.e_min_mwh if bat.e_init_mwh is None else bat.e_init_mwh)}
    for unit in (u for u in (*case.hydro, *case.biomass) if u.enabled):
        state[unit.name] = {"online": unit.initial_online, "status_h": unit.initial_hours_in_status,
                            "p_mw": unit.p_init_mw}
    return state


def with_state(case: Case, state: State, storage_end: str | float = CARRY) -> Case:
    """``case`` starting from ``state``, with the end-of-day storage rule ``storage_end``
    (the settlement lets a turbine trip, see :func:`rvpp.settle.recourse.allow_trip`)."""
    units = []
    for csp in case.csp:
        data = csp.model_dump(mode="python")
        start = state[csp.name]
        ts = data["storage"]
        ts["e_init_mwh_th"] = start["e_mwh_th"]
        ts["e_end_min_mwh_th"] = _end_target(ts["e_min_mwh_th"], ts["e_max_mwh_th"], storage_end)
        pb = data["power_block"]
        pb["initially_on"] = bool(start["online"])
        pb["initial_status_h"] = start["status_h"]
        units.append(data)
    changes = {"csp": units} if units else {}
    changes.update(_carried(case, state, storage_end))
    return case.replace(**changes) if changes else case


def _end_target(e_min: float, e_max: float, storage_end: str | float) -> float | None:
    """The end target of a storage between ``e_min`` and ``e_max`` under the rule ``storage_end``:
    none for ``carry`` (the day ends at or above its start), else ``e_min + F·(e_max − e_min)``."""
    return None if storage_end == CARRY else e_min + float(storage_end) * (e_max - e_min)


def _carried(case: Case, state: State, storage_end: str | float) -> dict[str, list]:
    """Batteries, hydro and biomass units starting from ``state``, a battery with the end-of-day
    rule ``storage_end`` as the tank (a unit ``state`` does not name, as in a backtest recorded
    before these kinds, keeps the case's initial conditions)."""
    changes = {}
    if any(bat.name in state for bat in case.battery):
        changes["battery"] = [bat.model_copy(update={"e_init_mwh": state[bat.name]["e_mwh"],
                                                     "e_end_min_mwh": _end_target(bat.e_min_mwh, bat.e_max_mwh,
                                                                                  storage_end)})
                              if bat.name in state else bat for bat in case.battery]
    for kind in ("hydro", "biomass"):
        units = getattr(case, kind)
        if any(unit.name in state for unit in units):
            changes[kind] = [unit.model_copy(update={
                "initial_online": bool(state[unit.name]["online"]),
                "initial_hours_in_status": state[unit.name]["status_h"],
                "p_init_mw": state[unit.name]["p_mw"]}) if unit.name in state else unit for unit in units]
    return changes


def min_up_lifted(case: Case) -> Case:
    """``case`` with the minimum up time a turbine online at midnight carries into the day counted as
    done, so the turbine may stop from the first period, as the settlement lets it trip
    (:func:`rvpp.settle.recourse.allow_trip`); ``case`` itself when no turbine carries one."""
    units, lifted = [], False
    for csp in case.csp:
        data = csp.model_dump(mode="python")
        pb = data["power_block"]
        if pb["initially_on"] and pb["initial_status_h"] is not None and pb["initial_status_h"] < pb["min_up_h"]:
            pb["initial_status_h"], lifted = pb["min_up_h"], True
        units.append(data)
    return case.replace(csp=units) if lifted else case
