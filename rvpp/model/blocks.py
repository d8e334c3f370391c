"""Where each unit kind's blocks sit on a model: one indexed Block per group of kinds, indexed
by unit name (wind and PV share ``ndres``, hydro and biomass ``dispatchable``). Builders live in :data:`rvpp.model.UNIT_BUILDERS`."""

from __future__ import annotations

import pyomo.environ as pyo

from ..data.kinds import UnitKind

UNIT_BLOCKS: dict[UnitKind, str] = {
    UnitKind.WIND: "ndres",
    UnitKind.PV: "ndres",
    UnitKind.CSP: "csp",
    UnitKind.ED: "ed",
    UnitKind.TD: "td",
    UnitKind.BATTERY: "battery",
    UnitKind.HYDRO: "dispatchable",
    UnitKind.BIOMASS: "dispatchable",
}


def unit_block(m: pyo.Block, kind: UnitKind, name: str) -> pyo.Block:
    """The block of unit ``name`` of ``kind`` on ``m`` (the model or a scenario block)."""
    return getattr(m, UNIT_BLOCKS[kind])[name]
