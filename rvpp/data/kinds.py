"""Unit kinds: what rvpp knows of each kind of unit, in one registry.

A kind is a :class:`UnitKind`; :data:`KINDS` holds its facts (words, power unit, the role
of its uncertain series, its budget preset, the fields a form edits). The case model maps
each kind to its class (:data:`rvpp.data.case.UNIT_MODELS`) and the model to its builder
(:data:`rvpp.model.UNIT_BUILDERS`). Code dispatches on these, never on a kind's spelling;
docs/architecture.md lists the steps that add a kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class UnitKind(StrEnum):
    """A kind of unit, spelled as in ``case.yaml`` (``units: {wind: [...], csp: [...]}``)."""

    WIND = "wind"
    PV = "pv"
    CSP = "csp"
    ED = "ed"
    TD = "td"
    BATTERY = "battery"
    HYDRO = "hydro"
    BIOMASS = "biomass"


class Role(StrEnum):
    """What an uncertain series is, and so its bad direction (MODEL_SPEC §5): production
    deviates down (MILP-STU1, MILP-NDRES1), consumption up (MILP-Demand1)."""

    PRODUCTION = "production"
    CONSUMPTION = "consumption"


class Carrier(StrEnum):
    """What a unit's power is: electricity [MW] or heat [MW_th]."""

    ELECTRICITY = "MW"
    HEAT = "MW_th"


@dataclass(frozen=True)
class KindInfo:
    """The facts of one unit kind.

    ``words`` names one unit in a sentence, ``label`` the kind in a legend, ``group`` its units
    on a form, ``prefix`` the start of a new unit's name; ``role`` is that of the kind's
    uncertain series (``None``: the kind has none); ``budget`` the column of the strategy
    presets (MODEL_SPEC §6, paper Table 7); ``capacity_field`` the dotted field of the capacity
    its series scales with; ``series_prefix`` where its series fields sit (the CSP's in its
    solar field); ``electric_sign`` how its power enters the electrical balance (+1 output,
    −1 consumption, 0 none: heat only); ``flexible``: it offers reserve (a row of the
    flexibility table, MODEL_SPEC §11).
    """

    words: str
    label: str
    group: str
    prefix: str
    carrier: Carrier
    role: Role | None
    budget: str
    capacity_field: str
    electric_sign: int
    series_prefix: str = ""
    flexible: bool = True

    @property
    def power_unit(self) -> str:
        return self.carrier.value

    @property
    def scale_field(self) -> str:
        return f"{self.series_prefix}series_scale"

    @property
    def series_field(self) -> str:
        return f"{self.series_prefix}series"

    @property
    def forecast_field(self) -> str:
        return f"{self.series_prefix}forecast_series"


KINDS: dict[UnitKind, KindInfo] = {
    UnitKind.WIND: KindInfo("wind farm", "Wind", "Wind farms", "WF", Carrier.ELECTRICITY, Role.PRODUCTION, "wind",
                            "p_max_mw", electric_sign=+1),
    UnitKind.PV: KindInfo("PV plant", "PV", "PV plants", "PV", Carrier.ELECTRICITY, Role.PRODUCTION, "pv",
                          "p_max_mw", electric_sign=+1),
    UnitKind.CSP: KindInfo("CSP plant", "CSP", "CSP plants", "CSP", Carrier.HEAT, Role.PRODUCTION, "csp",
                           "solar_field.p_max_mw_th", electric_sign=+1, series_prefix="solar_field."),
    UnitKind.ED: KindInfo("electrical demand", "Electrical demand", "Electrical demands", "ED", Carrier.ELECTRICITY,
                          Role.CONSUMPTION, "ed", "p_max_mw", electric_sign=-1),
    UnitKind.TD: KindInfo("thermal demand", "Thermal demand", "Thermal demands", "TD", Carrier.HEAT,
                          Role.CONSUMPTION, "td", "h_max_mw_th", electric_sign=0, flexible=False),
    # Certain units (MODEL_SPEC §13): no uncertain series, so no role and no budget column.
    UnitKind.BATTERY: KindInfo("battery", "Battery", "Batteries", "BAT", Carrier.ELECTRICITY, None, "",
                               "p_dis_max_mw", electric_sign=+1),
    UnitKind.HYDRO: KindInfo("hydro plant", "Hydro", "Hydro plants", "HY", Carrier.ELECTRICITY, None, "",
                             "p_max_mw", electric_sign=+1),
    UnitKind.BIOMASS: KindInfo("biomass plant", "Biomass", "Biomass plants", "BIO", Carrier.ELECTRICITY, None, "",
                               "p_max_mw", electric_sign=+1),
}
UNIT_KINDS: tuple[UnitKind, ...] = tuple(KINDS)
PAPER_KINDS = (UnitKind.WIND, UnitKind.PV, UnitKind.CSP, UnitKind.ED, UnitKind.TD)  # the seed paper's kinds  # the order in which a case lists its units
FLEX_KINDS: tuple[UnitKind, ...] = tuple(kind for kind, info in KINDS.items() if info.flexible)
ELECTRIC_KINDS: tuple[UnitKind, ...] = tuple(kind for kind, info in KINDS.items() if info.electric_sign)
NDRES_KINDS = (UnitKind.WIND, UnitKind.PV)  # non-dispatchable renewables: one class, a kind field
DISPATCHABLE_KINDS = (UnitKind.HYDRO, UnitKind.BIOMASS)  # dispatchable renewables: one class, a kind field
SHARED_CLASS_KINDS = NDRES_KINDS + DISPATCHABLE_KINDS  # kinds whose class holds a ``kind`` field


def power_unit(kind: str) -> str:
    """The unit of a unit kind's power: thermal for the CSP's field and the thermal demands."""
    return KINDS[UnitKind(kind)].power_unit
