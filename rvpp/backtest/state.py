"""What one day hands to the next: storage energy, turbine status and time in that status.

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
        span = ts["e_max_mwh_th"] - ts["e_min_mwh_th"]
        ts["e_end_min_mwh_th"] = None if storage_end == CARRY else ts["e_min_mwh_th"] + float(storage_end) * span
        pb = data["power_block"]
        pb["initially_on"] = bool(start["online"])
        pb["initial_status_h"] = start["status_h"]
        units.append(data)
    return case.replace(csp=units) if units else case
