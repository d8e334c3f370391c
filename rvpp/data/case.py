"""The case: typed, validated, immutable inputs of one RVPP.

A case is a folder holding ``case.yaml`` (units and settings) and the hourly history
CSV it names (read and written by :mod:`rvpp.data.case_yaml`). Every object here is
frozen and hashable, so a case can key a cache. Validation happens on creation and
every error names the unit, the field, the value and the rule (rendered by
:mod:`rvpp.data.case_messages`), e.g. ``csp "CSP1": storage.e_min_mwh_th=1200 must be <
storage.e_max_mwh_th=1100``. Parameters follow MODEL_SPEC §12 (paper Tables 3-7);
efficiencies and shares are fractions in [0, 1].
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Iterator, Mapping
from typing import Annotated, Any, ClassVar, Literal
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from pydantic import (AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, field_serializer, field_validator,
                      model_validator)
from pydantic_core import PydanticCustomError

from ..errors import CaseError
from .case_messages import as_number, kind_of, show_value, validate_into
from .files import CONTROL_CHARACTERS, excerpt, excerpt_names, refused_character
from .history import MAX_QUANTITY, PRICE_COLUMNS, History
from .kinds import DISPATCHABLE_KINDS, KINDS, PAPER_KINDS, SHARED_CLASS_KINDS, UNIT_KINDS, UnitKind
from .intraday import IntradaySettings
from .intraday import forecast_column as intraday_forecast_column, price_column as intraday_price_column
from .periods import ALLOWED_DT_H, delivery_periods


def _not_true_false(kind: str) -> BeforeValidator:
    """Refuse true/false where a number belongs (pydantic would read ``true`` as 1), reported as the
    pydantic error ``kind`` so that the message reads like any other wrong type."""

    def check(value: Any) -> Any:
        if isinstance(value, bool):
            raise PydanticCustomError(kind, "true/false is not a number")
        return value

    return BeforeValidator(check)


# Control characters (a YAML escape such as "\x01" or "\e", files.CONTROL_CHARACTERS) in text that
# is shown and exported. Ordinary Unicode letters, spaces and joiners are fine; prose keeps its tabs
# and line breaks. (pydantic refuses lone surrogates.)
_CONTROL_IN_PROSE = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]")


def _printable(pattern: re.Pattern) -> AfterValidator:
    """Refuse text holding a character that ``pattern`` matches, naming its code point."""

    def check(value: str) -> str:
        if refused := refused_character(value, ((pattern, "control characters"),)):
            raise ValueError(f"must not contain {refused}")
        return value

    return AfterValidator(check)


Number = Annotated[float, _not_true_false("float_type")]
WholeNumber = Annotated[int, _not_true_false("int_type")]
Fraction = Annotated[Number, Field(ge=0.0, le=1.0)]
NonNegative = Annotated[Number, Field(ge=0.0, le=MAX_QUANTITY)]
Positive = Annotated[Number, Field(gt=0.0, le=MAX_QUANTITY)]
ONE_LINE, PROSE = _printable(CONTROL_CHARACTERS), _printable(_CONTROL_IN_PROSE)  # after any length rule
Text = Annotated[str, ONE_LINE]  # a name, a column
Prose = Annotated[str, PROSE]  # a description: lines and tabs allowed
UnitName = Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,39}$")]

STRATEGIES = ("deterministic", "optimistic", "balanced", "pessimistic")
# Γ in hours per strategy and source kind (paper Table 7; MODEL_SPEC §6); "price" is each of
# the DAM, SR-up and SR-down prices. A solve scales them to periods (x 1/dt).
STRATEGY_BUDGETS_H = {
    "deterministic": {"price": 0, "wind": 0, "pv": 0, "csp": 0, "ed": 0, "td": 0},
    "optimistic": {"price": 3, "wind": 3, "pv": 2, "csp": 2, "ed": 3, "td": 3},
    "balanced": {"price": 6, "wind": 6, "pv": 4, "csp": 4, "ed": 6, "td": 6},
    "pessimistic": {"price": 9, "wind": 9, "pv": 6, "csp": 6, "ed": 9, "td": 9},
}
Strategy = Literal["deterministic", "optimistic", "balanced", "pessimistic"]
BudgetMode = Literal["paper", "planner_chosen"]  # MODEL_SPEC §5: the published method, or the teaching variant
Ties = Literal["choose", "earliest"]  # deviations tied at the Γ boundary: the model chooses, or the earliest
BudgetEncoding = Literal["top_gamma", "binary"]
# The VPP's reserve cap κ·base (MODEL_SPEC §7, §13): "net" (the paper) is supply nameplate less every unit's
# draw, "installed" (the authors' tool) the supply nameplate alone, storage discharge and dispatchable units included.
ReserveBase = Literal["net", "installed"]
PwlEncoding = Literal["incremental", "convex_combination"]
MARKET_NAMES = ("DAM", "SRM", "HPA")
RESERVED_NAMES = set(PRICE_COLUMNS) | {"timestamp"}
CASE_FILE = "case.yaml"
HOURS_PER_DAY = 24
FIRST_DATE, LAST_DATE = dt.date(1900, 1, 1), dt.date(2199, 12, 31)  # delivery dates rvpp plans
ISO_DATE = re.compile(r"\d{4}-\d{2}-\d{2}")
_ISO_TIME = re.compile(r"\d{4}-\d{2}-\d{2}[Tt ]\d")  # a date followed by a time of day
MAX_THREADS = 1024  # HiGHS threads or worker processes; more is a typo, not a machine
MAX_START_NAMES = 50_000  # integer variables a MIP start may name (4 CSPs at 15 minutes have about 3,700)


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


class _Unit(_Frozen):
    """What every unit class offers, whatever its kind (its kind's facts are in ``KINDS``)."""

    KIND: ClassVar[UnitKind]

    @property
    def unit_kind(self) -> UnitKind:
        return self.KIND

    @property
    def series_capacity(self) -> float | None:
        """The upper limit of its uncertain series (``None``: unbounded, as a demand's) [MW or MW_th]."""
        return None

    @property
    def series_range(self) -> tuple[float, float]:
        """The physical range of its realized series [MW or MW_th] (the settlement clips to it)."""
        return 0.0, self.series_capacity

    @property
    def supply_mw(self) -> float:
        """Electrical power it can supply [MW]: its part of ``ΣPmax_r + ΣPmax_θ`` (MODEL_SPEC §7)."""
        return 0.0

    @property
    def demand_mw(self) -> float:
        """Electrical power it can draw [MW]: its part of ``ΣPmax_d`` (MODEL_SPEC §7)."""
        return 0.0

    @classmethod
    def plain_data(cls, data: dict[str, Any]) -> dict[str, Any]:
        """``data`` (a dump of a unit) in the layout of ``case.yaml``."""
        return data


class _FollowsSeries(_Unit):
    """A unit whose forecast band follows one history column: ``series`` if set, else its name.

    ``forecast_series`` names the history column of its day-ahead point forecast, used
    when the unit's band is ``forecast`` (``uncertainty.bands``).
    """

    @property
    def column(self) -> str:
        return self.series or self.name

    @property
    def forecast_column(self) -> str | None:
        return self.forecast_series

    @property
    def scale(self) -> float:
        """The factor from the history column to this unit's series."""
        return self.series_scale


class NdresUnit(_FollowsSeries):
    """Wind farm or PV plant: non-dispatchable, curtailable (MODEL_SPEC §9, paper Table 6)."""

    name: UnitName
    kind: Literal["wind", "pv"]
    p_max_mw: Positive
    p_min_mw: NonNegative = 0.0
    om_eur_per_mwh: NonNegative = 0.0
    ramp_up_mw_per_min: NonNegative
    ramp_dn_mw_per_min: NonNegative
    reserve_share: Fraction = 0.1
    series: Text | None = None
    series_scale: Positive = 1.0
    forecast_series: Text | None = None

    @property
    def unit_kind(self) -> UnitKind:
        return UnitKind(self.kind)

    @property
    def series_capacity(self) -> float:
        return self.p_max_mw

    @property
    def supply_mw(self) -> float:
        return self.p_max_mw

    @model_validator(mode="after")
    def _limits(self) -> "NdresUnit":
        _require(self.p_min_mw <= self.p_max_mw, "p_min_mw", self.p_min_mw, "<=", "p_max_mw", self.p_max_mw)
        return self


class SolarField(_Frozen):
    """CSP solar field: thermal power collected, uncertain [MW_th]."""

    p_max_mw_th: Positive
    series: Text | None = None
    series_scale: Positive = 1.0
    forecast_series: Text | None = None


class ThermalStorage(_Frozen):
    """Two-tank molten-salt storage (paper TS1-TS11)."""

    e_min_mwh_th: NonNegative
    e_max_mwh_th: Positive
    p_ch_max_mw_th: NonNegative
    p_ch_min_mw_th: NonNegative = 0.0
    p_dis_max_mw_th: NonNegative
    p_dis_min_mw_th: NonNegative = 0.0
    eta_ch: Annotated[Number, Field(gt=0.0, le=1.0)]
    eta_dis: Annotated[Number, Field(gt=0.0, le=1.0)]
    e_init_mwh_th: NonNegative | None = None
    e_end_min_mwh_th: NonNegative | None = None
    # What a MWh_th left in the tank at the day's end, above the day's start, is worth to the
    # next day [EUR/MWh_th] (MODEL_SPEC §8 beyond the paper; 0: the paper's day, heat has no value
    # after midnight). Only a day from a fixed ``e_init`` has it; a cyclic day ends where it starts.
    end_value_eur_per_mwh_th: NonNegative = 0.0
    # The authors' tool's conventions (docs/gams-tool.md D17, D19), off by default (MODEL_SPEC §8):
    # each of the four bands (charge and discharge side, up and down) at most this [MW_th]; the
    # reserve energy Σ r·dt/η ≤ factor·σ·ΔE with σ ≤ reserve_share_max.
    reserve_band_max_mw_th: NonNegative | None = None
    reserve_energy_factor: Annotated[Number, Field(gt=0.0, le=100.0)] = 1.0
    reserve_share_max: Fraction = 1.0

    TOOL_DEFAULTS: ClassVar[dict[str, Any]] = {"reserve_band_max_mw_th": None, "reserve_energy_factor": 1.0,
                                               "reserve_share_max": 1.0}

    @property
    def cyclic(self) -> bool:
        """True when the day is cyclic (no fixed initial energy)."""
        return self.e_init_mwh_th is None

    @property
    def end_floor_mwh_th(self) -> float | None:
        """Least energy at the end of a day that starts from ``e_init`` [MWh_th].

        ``min(e_end_min, e_init)``: the day ends at or above the target level
        ``e_end_min``, or at or above its start if it started below the target (so the
        storage may always idle); without a target, at or above its start. ``None`` on
        a cyclic day.
        """
        return _end_floor(self.e_init_mwh_th, self.e_end_min_mwh_th)


class PowerBlock(_Frozen):
    """Steam power block and turbine (paper STU2-STU8, Appendix A).

    ``breakpoints`` are ``(thermal input [MW_th], efficiency [-])`` pairs; the
    electrical output at a breakpoint is ``efficiency * input``. The start-up heat
    ``startup_fraction * p_in_max_mw_th`` is drawn in the start-up period, or during
    ``startup_duration_h`` hours after a start when given.
    """

    def startup_periods(self, dt_h: float) -> int:
        """Periods during which a start draws its heat."""
        return 1 if self.startup_duration_h is None else int(round(self.startup_duration_h / dt_h))

    p_in_max_mw_th: Positive
    p_in_min_mw_th: Positive
    p_el_max_mw: Positive
    breakpoints: tuple[tuple[Annotated[Number, Field(le=MAX_QUANTITY)], Number], ...]
    min_up_h: Annotated[Number, Field(ge=0.0, le=HOURS_PER_DAY)] = 0.0
    min_down_h: Annotated[Number, Field(ge=0.0, le=HOURS_PER_DAY)] = 0.0
    startup_fraction: NonNegative = 0.0
    startup_duration_h: Positive | None = None
    initially_on: bool = False
    initial_status_h: NonNegative | None = None
    # false: the output follows the curve up to p_in_max_mw_th, even above p_el_max_mw (the authors'
    # tool, docs/gams-tool.md D16); p_el_max_mw still sizes the reserve share and the installed base
    output_capped: bool = True

    TOOL_DEFAULTS: ClassVar[dict[str, Any]] = {"output_capped": True}

    def initial_periods(self, dt_h: float) -> tuple[int, int]:
        """Periods ``(N_on, N_off)`` at the start of the day during which the turbine must stay
        online / offline to complete the minimum up / down time begun before the day
        (paper Appendix A, STU12 and STU15). Both are 0 when ``initial_status_h`` is unset."""
        if self.initial_status_h is None:
            return 0, 0
        needed = self.min_up_h if self.initially_on else self.min_down_h
        left = int(round(max(0.0, needed - self.initial_status_h) / dt_h))
        return (left, 0) if self.initially_on else (0, left)


class CSP(_Unit):
    """Concentrated solar power plant: solar field, thermal storage, power block."""

    KIND: ClassVar[UnitKind] = UnitKind.CSP

    name: UnitName
    om_eur_per_mwh: NonNegative = 0.0
    heat_efficiency: Annotated[Number, Field(gt=0.0, le=1.0)] = 1.0
    ramp_mw_per_min: NonNegative
    reserve_share: Fraction = 0.5
    solar_field: SolarField
    storage: ThermalStorage
    power_block: PowerBlock

    @property
    def column(self) -> str:
        return self.solar_field.series or self.name

    @property
    def forecast_column(self) -> str | None:
        return self.solar_field.forecast_series

    @property
    def scale(self) -> float:
        return self.solar_field.series_scale

    @property
    def series_capacity(self) -> float:
        return self.solar_field.p_max_mw_th

    @classmethod
    def plain_data(cls, data: dict[str, Any]) -> dict[str, Any]:
        data["power_block"]["breakpoints"] = [list(p) for p in data["power_block"]["breakpoints"]]
        # the tool's conventions are written only when set: cases and their digests stay as they were
        for part, model in (("storage", ThermalStorage), ("power_block", PowerBlock)):
            data[part] = _without_defaults(data[part], model.TOOL_DEFAULTS)
        return data

    @property
    def p_max_mw(self) -> float:
        """Electrical nameplate [MW]."""
        return self.power_block.p_el_max_mw

    @property
    def supply_mw(self) -> float:
        return self.p_max_mw

    @model_validator(mode="after")
    def _consistent(self) -> "CSP":
        ts, pb = self.storage, self.power_block
        _require(ts.e_min_mwh_th < ts.e_max_mwh_th, "storage.e_min_mwh_th", ts.e_min_mwh_th, "<",
                 "storage.e_max_mwh_th", ts.e_max_mwh_th)
        _require(ts.p_ch_min_mw_th <= ts.p_ch_max_mw_th, "storage.p_ch_min_mw_th", ts.p_ch_min_mw_th,
                 "<=", "storage.p_ch_max_mw_th", ts.p_ch_max_mw_th)
        _require(ts.p_dis_min_mw_th <= ts.p_dis_max_mw_th, "storage.p_dis_min_mw_th", ts.p_dis_min_mw_th,
                 "<=", "storage.p_dis_max_mw_th", ts.p_dis_max_mw_th)
        _require_within("storage.e_init_mwh_th", ts.e_init_mwh_th, "storage.e_min_mwh_th", ts.e_min_mwh_th,
                        "storage.e_max_mwh_th", ts.e_max_mwh_th)
        _require_within("storage.e_end_min_mwh_th", ts.e_end_min_mwh_th, "storage.e_min_mwh_th", ts.e_min_mwh_th,
                        "storage.e_max_mwh_th", ts.e_max_mwh_th)
        if ts.e_end_min_mwh_th is not None and ts.e_init_mwh_th is None:
            raise ValueError(f"storage.e_end_min_mwh_th={ts.e_end_min_mwh_th:g} needs storage.e_init_mwh_th: "
                             "a cyclic day (no initial energy) has no end target")
        _require(pb.p_in_min_mw_th < pb.p_in_max_mw_th, "power_block.p_in_min_mw_th", pb.p_in_min_mw_th,
                 "<", "power_block.p_in_max_mw_th", pb.p_in_max_mw_th)
        _check_breakpoints(pb)
        return self


def _check_breakpoints(pb: PowerBlock) -> None:
    points = pb.breakpoints
    if len(points) < 2:
        raise ValueError(f"power_block.breakpoints has {len(points)} point(s); at least 2 are needed")
    inputs = [p for p, _ in points]
    if inputs[0] != 0.0:
        raise ValueError(f"power_block.breakpoints must start at input 0 MW_th (got {inputs[0]:g})")
    for i, (prev, nxt) in enumerate(zip(inputs, inputs[1:]), start=2):
        if not nxt > prev:
            raise ValueError(f"power_block.breakpoints input {nxt:g} (point {i}) must be greater than "
                             f"the previous input {prev:g}: breakpoints must be strictly increasing")
    for i, (p, eta) in enumerate(points, start=1):
        if not 0.0 <= eta <= 1.0:
            raise ValueError(f"power_block.breakpoints efficiency {eta:g} at {p:g} MW_th (point {i}) "
                             "must be a fraction in [0, 1]")
    outputs = [p * eta for p, eta in points]
    for i, (prev, nxt) in enumerate(zip(outputs, outputs[1:]), start=2):
        if nxt < prev:
            raise ValueError(f"power_block.breakpoints output {nxt:g} MW at point {i} is below "
                             f"{prev:g} MW at the previous point: output must not decrease with input")
    if pb.p_in_max_mw_th > inputs[-1]:
        raise ValueError(f"power_block.p_in_max_mw_th={pb.p_in_max_mw_th:g} must be <= the last "
                         f"breakpoint input {inputs[-1]:g}")


class ElectricalDemand(_FollowsSeries):
    """Flexible electrical demand (MODEL_SPEC §9, paper Demand1-Demand8, Table 4)."""

    KIND: ClassVar[UnitKind] = UnitKind.ED

    name: UnitName
    p_min_mw: NonNegative
    p_max_mw: Positive
    e_min_mwh: NonNegative
    p_init_mw: NonNegative | None = None
    ramp_up_mw_per_min: NonNegative
    ramp_dn_mw_per_min: NonNegative
    flex_up: Fraction = 0.1
    flex_dn: Fraction = 0.1
    # The authors' tool's conventions (docs/gams-tool.md D23-D26), off by default (MODEL_SPEC §9):
    # a window around the profile, ramps between periods, an energy floor that counts the up band.
    profile_window: bool = False
    ramp_up_mw_per_h: NonNegative | None = None
    ramp_dn_mw_per_h: NonNegative | None = None
    energy_net_of_up_band: bool = True
    series: Text | None = None
    series_scale: Positive = 1.0
    forecast_series: Text | None = None

    TOOL_DEFAULTS: ClassVar[dict[str, Any]] = {"profile_window": False, "ramp_up_mw_per_h": None,
                                               "ramp_dn_mw_per_h": None, "energy_net_of_up_band": True}

    @property
    def series_range(self) -> tuple[float, float]:
        return self.p_min_mw, self.p_max_mw

    @property
    def demand_mw(self) -> float:
        return self.p_max_mw

    @classmethod
    def plain_data(cls, data: dict[str, Any]) -> dict[str, Any]:
        # the tool's conventions are written only when set: cases and their digests stay as they were
        return _without_defaults(data, cls.TOOL_DEFAULTS)

    @model_validator(mode="after")
    def _limits(self) -> "ElectricalDemand":
        _require(self.p_min_mw <= self.p_max_mw, "p_min_mw", self.p_min_mw, "<=", "p_max_mw", self.p_max_mw)
        _require_within("p_init_mw", self.p_init_mw, "p_min_mw", self.p_min_mw, "p_max_mw", self.p_max_mw)
        return self


class ThermalDemand(_FollowsSeries):
    """Thermal demand served by the CSPs and the HPA (MODEL_SPEC §9, paper Demand_Heat1-3)."""

    KIND: ClassVar[UnitKind] = UnitKind.TD

    name: UnitName
    h_min_mw_th: NonNegative
    h_max_mw_th: Positive
    q_min_mwh_th: NonNegative
    h_init_mw_th: NonNegative | None = None
    series: Text | None = None
    series_scale: Positive = 1.0
    forecast_series: Text | None = None

    @property
    def series_range(self) -> tuple[float, float]:
        return self.h_min_mw_th, self.h_max_mw_th

    @model_validator(mode="after")
    def _limits(self) -> "ThermalDemand":
        _require(self.h_min_mw_th <= self.h_max_mw_th, "h_min_mw_th", self.h_min_mw_th, "<=",
                 "h_max_mw_th", self.h_max_mw_th)
        _require_within("h_init_mw_th", self.h_init_mw_th, "h_min_mw_th", self.h_min_mw_th,
                        "h_max_mw_th", self.h_max_mw_th)
        return self


class Battery(_Unit):
    """Electrical storage (MODEL_SPEC §13): energy and power limits, charge and discharge
    efficiencies, self-discharge, a throughput (degradation) cost per MWh discharged, and
    reserve from both modes with the energy behind it held back.

    ``e_init_mwh`` is the energy at the start of the day (the day then ends at or above it, or
    at or above ``e_end_min_mwh`` when that is lower: :attr:`end_floor_mwh`); unset, the day is
    cyclic. A unit with ``enabled: false`` stays in the case but is left out of the model.
    """

    KIND: ClassVar[UnitKind] = UnitKind.BATTERY

    name: UnitName
    enabled: bool = True
    e_min_mwh: NonNegative = 0.0
    e_max_mwh: Positive
    p_ch_max_mw: Positive
    p_dis_max_mw: Positive
    eta_ch: Annotated[Number, Field(gt=0.0, le=1.0)] = 0.95
    eta_dis: Annotated[Number, Field(gt=0.0, le=1.0)] = 0.95
    self_discharge_per_h: Annotated[Number, Field(ge=0.0, lt=1.0)] = 0.0
    degradation_eur_per_mwh: NonNegative = 0.0
    e_init_mwh: NonNegative | None = None
    e_end_min_mwh: NonNegative | None = None
    ramp_mw_per_min: NonNegative
    reserve_share: Fraction = 1.0

    @property
    def cyclic(self) -> bool:
        """True when the day is cyclic (no initial energy)."""
        return self.e_init_mwh is None

    @property
    def end_floor_mwh(self) -> float | None:
        """Least energy at the end of a day that starts from ``e_init`` [MWh]: as the tank's
        (:attr:`ThermalStorage.end_floor_mwh_th`), ``min(e_end_min, e_init)``, or ``e_init``
        without an end target. ``None`` on a cyclic day."""
        return _end_floor(self.e_init_mwh, self.e_end_min_mwh)

    @classmethod
    def plain_data(cls, data: dict[str, Any]) -> dict[str, Any]:
        # the end target is written only when set: cases and their digests stay as they were
        return _without_defaults(data, {"e_end_min_mwh": None})

    @property
    def p_max_mw(self) -> float:
        """Discharge nameplate [MW]: the capacity of the flexibility table (MODEL_SPEC §11)."""
        return self.p_dis_max_mw

    @property
    def supply_mw(self) -> float:
        return self.p_dis_max_mw

    @property
    def demand_mw(self) -> float:
        return self.p_ch_max_mw

    @model_validator(mode="after")
    def _limits(self) -> "Battery":
        _require(self.e_min_mwh < self.e_max_mwh, "e_min_mwh", self.e_min_mwh, "<", "e_max_mwh", self.e_max_mwh)
        _require_within("e_init_mwh", self.e_init_mwh, "e_min_mwh", self.e_min_mwh, "e_max_mwh", self.e_max_mwh)
        _require_within("e_end_min_mwh", self.e_end_min_mwh, "e_min_mwh", self.e_min_mwh, "e_max_mwh", self.e_max_mwh)
        if self.e_end_min_mwh is not None and self.e_init_mwh is None:
            raise ValueError(f"e_end_min_mwh={self.e_end_min_mwh:g} needs e_init_mwh: a cyclic day (no initial "
                             "energy) has no end target")
        # The day keeps the energy at or above e_min (and, with an initial energy, ends at or above
        # its end floor): self-discharge there must not lose more than charging at full power puts
        # back. A level within a millionth of a MWh of that balance passes: a backtest carries the
        # settled day's end into the next, and a battery held at its balance ends there up to the
        # solver's round-off.
        if self.cyclic:
            held, level = "e_min_mwh", self.e_min_mwh
        elif self.end_floor_mwh < self.e_init_mwh:
            held, level = "e_end_min_mwh", self.e_end_min_mwh
        else:
            held, level = "e_init_mwh", self.e_init_mwh
        lost, restored = self.self_discharge_per_h * level, self.eta_ch * self.p_ch_max_mw
        if lost > restored * (1.0 + 1e-9) + self.self_discharge_per_h * 1e-6:
            goal = {"e_min_mwh": "the energy could not stay at or above its minimum",
                    "e_end_min_mwh": "the day could not end at or above its end target",
                    "e_init_mwh": "the day could not end at or above its initial energy"}[held]
            raise ValueError(f"self_discharge_per_h={self.self_discharge_per_h:g} loses {lost:g} MW at "
                             f"{held}={level:g}, more than charging at full power restores: eta_ch={self.eta_ch:g} x "
                             f"p_ch_max_mw={self.p_ch_max_mw:g} = {restored:g} MW; {goal}")
        return self


class DispatchableUnit(_Unit):
    """Hydro or biomass plant: a dispatchable renewable unit with commitment (MODEL_SPEC §13).

    Minimum up and down times carry over from the day before through ``initial_online`` and
    ``initial_hours_in_status`` (unset: nothing carries over); ``p_init_mw`` is the output in
    the last period before the day, from which the first period ramps (unset: the first
    period is free of ramp limits). Ramp limits left unset are no limit. ``energy_max_mwh``
    is the day's water or fuel [MWh], unset for none; it holds even if all up reserve is
    called. A unit with ``enabled: false`` stays in the case but is left out of the model.
    """

    name: UnitName
    kind: Literal["hydro", "biomass"]
    enabled: bool = True
    p_min_mw: NonNegative = 0.0
    p_max_mw: Positive
    marginal_cost_eur_per_mwh: NonNegative = 0.0
    startup_cost_eur: NonNegative = 0.0
    shutdown_cost_eur: NonNegative = 0.0
    ramp_up_mw_per_h: NonNegative | None = None
    ramp_dn_mw_per_h: NonNegative | None = None
    startup_ramp_mw_per_h: NonNegative | None = None
    shutdown_ramp_mw_per_h: NonNegative | None = None
    min_up_h: Annotated[Number, Field(ge=0.0, le=HOURS_PER_DAY)] = 0.0
    min_down_h: Annotated[Number, Field(ge=0.0, le=HOURS_PER_DAY)] = 0.0
    initial_online: bool = False
    initial_hours_in_status: NonNegative | None = None
    p_init_mw: NonNegative | None = None
    energy_max_mwh: NonNegative | None = None
    ramp_mw_per_min: NonNegative
    reserve_share: Fraction = 1.0

    @property
    def unit_kind(self) -> UnitKind:
        return UnitKind(self.kind)

    @property
    def supply_mw(self) -> float:
        return self.p_max_mw

    def initial_periods(self, dt_h: float) -> tuple[int, int]:
        """Periods ``(N_on, N_off)`` at the start of the day during which the unit must stay online /
        offline to complete the minimum up / down time begun before the day (0 when
        ``initial_hours_in_status`` is unset), as the CSP turbine's (:meth:`PowerBlock.initial_periods`)."""
        if self.initial_hours_in_status is None:
            return 0, 0
        needed = self.min_up_h if self.initial_online else self.min_down_h
        left = int(round(max(0.0, needed - self.initial_hours_in_status) / dt_h))
        return (left, 0) if self.initial_online else (0, left)

    def committed_run(self, dt_h: float, periods: int) -> tuple[float, int]:
        """The least energy [MWh] the day commits the unit to from its status before the day, and the
        periods it must stay online for it (0, 0 when it may stay off or stop at once).

        Online before the day, the unit stays on for the minimum up time begun before the day; from
        ``p_init_mw`` its output falls by at most ``ramp_dn`` per period, never below ``p_min``, and it
        may stop only once it is at or below the shutdown ramp (MODEL_SPEC §13): the cheapest run
        steps down as fast as it may and stops at the first period it may (at the day's end at most).
        """
        if not self.initial_online:
            return 0.0, 0
        held, _ = self.initial_periods(dt_h)
        if self.p_init_mw is None:  # the first period is free of ramp limits
            run = min(held, periods)
            return self.p_min_mw * run * dt_h, run
        step_down = (self.p_max_mw if self.ramp_dn_mw_per_h is None
                     else min(self.ramp_dn_mw_per_h * dt_h, self.p_max_mw))
        stop_from = (self.p_max_mw if self.shutdown_ramp_mw_per_h is None
                     else min(self.shutdown_ramp_mw_per_h * dt_h, self.p_max_mw))
        level, energy, run = self.p_init_mw, 0.0, 0
        while run < periods and (run < held or level > stop_from):
            level = max(self.p_min_mw, level - step_down)
            energy += level * dt_h
            run += 1
        return energy, run

    @model_validator(mode="after")
    def _limits(self) -> "DispatchableUnit":
        _require(self.p_min_mw <= self.p_max_mw, "p_min_mw", self.p_min_mw, "<=", "p_max_mw", self.p_max_mw)
        if self.p_init_mw is not None:
            if not self.initial_online and self.p_init_mw > 0.0:
                raise ValueError(f"p_init_mw={self.p_init_mw:g} must be 0 for a unit off before the day "
                                 "(initial_online=false): an offline unit produces nothing")
            if self.initial_online:
                _require_within("p_init_mw", self.p_init_mw, "p_min_mw", self.p_min_mw, "p_max_mw", self.p_max_mw)
        if self.enabled and self.energy_max_mwh is not None and self.energy_max_mwh < self.p_min_mw * self.min_up_h:
            raise ValueError(f"energy_max_mwh={self.energy_max_mwh:g} is below the {self.p_min_mw * self.min_up_h:g} "
                             f"MWh of a run at p_min_mw={self.p_min_mw:g} for min_up_h={self.min_up_h:g}: "
                             "once started, the unit could not run its minimum up time at its minimum output")
        return self


class ImbalancePrices(_Frozen):
    """History columns of real imbalance prices [EUR/MWh] that replace the settlement's
    ``π_def`` (``short``: paid for energy delivered short of the DAM bid) and ``π_sur``
    (``long``: received for energy delivered beyond it) (MODEL_SPEC §10)."""

    short: Annotated[str, Field(min_length=1), ONE_LINE]
    long: Annotated[str, Field(min_length=1), ONE_LINE]


class Markets(_Frozen):
    """Market switches and parameters (MODEL_SPEC §2, §7, §10)."""

    dam: Literal[True] = True
    srm: bool = True
    hpa: bool = True
    kappa: Fraction = 0.3
    reserve_base: ReserveBase = "net"
    reserve_duration_min: Positive = 15.0
    hpa_tariff_eur_per_mwh: Annotated[tuple[NonNegative, ...], Field(min_length=24, max_length=24)]
    imbalance_prices: ImbalancePrices | None = None

    @field_validator("hpa_tariff_eur_per_mwh", mode="before")
    @classmethod
    def _tariff_by_hour(cls, value: Any) -> Any:
        """Check the 24 tariffs one by one, naming each by its clock hour (``hour 07:00 = -5``)."""
        field = "hpa_tariff_eur_per_mwh"
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{field} must be a list of 24 tariffs [EUR/MWh_th], one per clock hour 00:00 to "
                             f"23:00; got {kind_of(value)}")
        if len(value) != HOURS_PER_DAY:
            raise ValueError(f"{field} has {len(value)} values; give 24, one per clock hour 00:00 to 23:00")
        numbers = [as_number(tariff) for tariff in value]
        problems = [f"{field} hour {hour:02d}:00 = {show_value(tariff)} "
                    + (number if isinstance(number, str) else
                       "must be >= 0" if number < 0 else f"must be <= {MAX_QUANTITY:g}")
                    for hour, (tariff, number) in enumerate(zip(value, numbers))
                    if isinstance(number, str) or not 0 <= number <= MAX_QUANTITY]
        if problems:
            raise ValueError("\n".join(problems))
        return tuple(numbers)

    @property
    def label(self) -> str:
        """e.g. ``DAM+SRM+HPA``."""
        return "+".join(name for name, on in zip(MARKET_NAMES, (True, self.srm, self.hpa)) if on)

    @property
    def reserve_duration_h(self) -> float:
        return self.reserve_duration_min / 60.0


BAND_METHODS = ("climatology", "forecast")
BandMethod = Literal["climatology", "forecast"]
PRICE_MODELS = ("same_hour_yesterday", "same_hour_last_week", "blend")
DEFAULT_BANDS = "default"


class UncertaintySettings(_Frozen):
    """How forecast bands are drawn from the history (MODEL_SPEC §6).

    ``bands`` chooses the method per source: ``climatology`` (the paper: percentiles of
    the window's observations per clock hour) or ``forecast`` (a point forecast plus
    percentiles of its past errors). Keys are ``default``, a unit kind (``wind``, ``pv``,
    ``csp``, ``ed``, ``td``) or a source name (a unit, ``price_da``, ``price_sr_up``,
    ``price_sr_dn``); the most specific key wins. ``price_forecast`` is the point
    forecast of prices with forecast bands.
    """

    window_days: Annotated[WholeNumber, Field(ge=1, le=366)] = 30
    q_lo: Annotated[Number, Field(gt=0.0, lt=0.5)] = 0.2
    q_hi: Annotated[Number, Field(gt=0.5, lt=1.0)] = 0.8
    bands: tuple[tuple[str, BandMethod], ...] = ()
    price_forecast: Literal["same_hour_yesterday", "same_hour_last_week", "blend"] = "same_hour_yesterday"

    @field_validator("bands", mode="before")
    @classmethod
    def _bands_from_mapping(cls, value: Any) -> Any:
        if isinstance(value, Mapping):
            for key, method in value.items():
                if method not in BAND_METHODS:
                    raise ValueError(f"{key}={method!r} must be one of {', '.join(BAND_METHODS)}")
            return tuple(sorted(value.items()))
        return value

    @field_serializer("bands")
    def _bands_as_mapping(self, value: tuple[tuple[str, str], ...]) -> dict[str, str]:
        return dict(value)

    @model_validator(mode="after")
    def _unique_bands(self) -> "UncertaintySettings":
        keys = [key for key, _ in self.bands]
        duplicated = sorted({k for k in keys if keys.count(k) > 1})
        if duplicated:
            raise ValueError(f"bands names {duplicated[0]!r} more than once")
        return self

    def band_method(self, source: str, kind: str | None = None) -> str:
        """``climatology`` or ``forecast`` for ``source`` (of unit ``kind``; ``None`` for prices)."""
        chosen = dict(self.bands)
        return chosen.get(source) or (chosen.get(kind) if kind else None) or chosen.get(DEFAULT_BANDS, "climatology")


class Budgets(_Frozen):
    """Strategy preset, per-source overrides of Γ [periods] and the budget variant.

    ``fraction`` (a fraction of the day in [0, 1]), when set, replaces the preset: every
    source gets ``Γ = ⌊fraction·NT + ½⌋`` periods (e.g. 0.25 → 6 of 24 hours); overrides
    still apply on top.

    ``ties`` (paper mode): where equal deviations straddle the Γ boundary, ``choose`` lets
    the model pick which of them deviate, as the binary formulation of MODEL_SPEC §5 does
    (in the plan's favour); ``earliest`` makes the earliest of them deviate, one fixed
    pattern that the solver need not search.
    """

    strategy: Strategy = "balanced"
    overrides: tuple[tuple[str, Annotated[int, Field(ge=0)]], ...] = ()
    mode: BudgetMode = "paper"
    fraction: Fraction | None = None
    ties: Ties = "choose"

    @property
    def label(self) -> str:
        """The strategy's name, or e.g. ``Γ 25 % of the day`` for a fraction."""
        return self.strategy if self.fraction is None else f"Γ {self.fraction:.4g} of the day"

    @field_validator("overrides", mode="before")
    @classmethod
    def _from_mapping(cls, value: Any) -> Any:
        """A mapping ``{source: Γ}`` (or pairs), each Γ checked under the source's name."""
        if value is None:
            return ()
        if isinstance(value, Mapping):
            pairs = list(value.items())
        elif isinstance(value, (list, tuple)) and all(isinstance(p, (list, tuple)) and len(p) == 2 for p in value):
            pairs = [tuple(p) for p in value]
        else:
            raise ValueError(f"overrides must be a mapping of source: Γ [periods], e.g. {{price_da: 6, WF1: 3}}; "
                             f"got {kind_of(value)}")
        problems = []
        names = [source for source, _ in pairs]
        for source, gamma in pairs:
            if not isinstance(source, str):
                problems.append(f"overrides: source {show_value(source)} must be a name such as price_da or WF1")
                continue
            if names.count(source) > 1:
                problems.append(f"overrides name {source!r} more than once")
                continue
            number = as_number(gamma, whole=True)
            if isinstance(number, str):
                problems.append(f"overrides.{excerpt(source)}={show_value(gamma)} {number} [periods]")
            elif number < 0:
                problems.append(f"overrides.{excerpt(source)}={show_value(gamma)} must be >= 0 [periods]")
        if problems:
            raise ValueError("\n".join(dict.fromkeys(problems)))
        return tuple(sorted((source, as_number(gamma, whole=True)) for source, gamma in pairs))

    @property
    def override_map(self) -> dict[str, int]:
        return dict(self.overrides)


class SolverSettings(_Frozen):
    """HiGHS settings and formulation choices."""

    time_limit_s: Positive = 120.0
    rel_gap: Annotated[Number, Field(ge=0.0, lt=1.0)] = 1e-4
    threads: Annotated[WholeNumber, Field(ge=0, le=MAX_THREADS)] = 0
    budget_encoding: BudgetEncoding = "top_gamma"
    pwl_encoding: PwlEncoding = "incremental"
    # A MIP start: the integer variables at one in an earlier plan (a backtest passes the day before's),
    # the others at zero. HiGHS checks it and ignores it when it does not fit the day, so it can shorten
    # the search but never changes what counts as optimal; names the model does not have are ignored.
    mip_start: Annotated[tuple[Annotated[str, Field(min_length=1, max_length=200), ONE_LINE], ...],
                         Field(max_length=MAX_START_NAMES)] = ()


class ColumnSource(_Frozen):
    """Where a history column comes from: ``real`` (a public record, named with its
    fingerprint), ``real-derived`` (made from a public record by a stated model, e.g. a
    solar field's heat from the solar fleet's clear-sky index), ``modelled`` or
    ``synthetic`` (generated; the two words mean the same), and how it was made from its source."""

    origin: Literal["real", "real-derived", "modelled", "synthetic"]
    source: Annotated[str, Field(min_length=1), ONE_LINE]
    note: Prose = ""


class Case(_Frozen):
    """One RVPP: its units, market settings, uncertainty settings and history."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False,
                              arbitrary_types_allowed=True)

    name: Annotated[str, Field(min_length=1), ONE_LINE]
    description: Prose = ""
    delivery_date: dt.date
    timezone: str = "Europe/Madrid"
    dt_h: Number = 1.0
    markets: Markets
    uncertainty: UncertaintySettings = UncertaintySettings()
    budgets: Budgets = Budgets()
    solver: SolverSettings = SolverSettings()
    intraday: IntradaySettings = IntradaySettings()
    wind: tuple[NdresUnit, ...] = ()
    pv: tuple[NdresUnit, ...] = ()
    csp: tuple[CSP, ...] = ()
    ed: tuple[ElectricalDemand, ...] = ()
    td: tuple[ThermalDemand, ...] = ()
    battery: tuple[Battery, ...] = ()
    hydro: tuple[DispatchableUnit, ...] = ()
    biomass: tuple[DispatchableUnit, ...] = ()
    provenance: tuple[tuple[Text, ColumnSource], ...] = ()
    history: History

    @field_validator("provenance", mode="before")
    @classmethod
    def _provenance_from_mapping(cls, value: Any) -> Any:
        if isinstance(value, Mapping):
            return tuple(value.items())
        return value

    @property
    def provenance_map(self) -> dict[str, ColumnSource]:
        """Origin of each history column the case labels (empty: unlabelled, e.g. the paper case)."""
        return dict(self.provenance)

    def provenance_summary(self) -> str | None:
        """One line naming the history columns of each origin (``None`` if unlabelled)."""
        if not self.provenance:
            return self.intraday_summary() if self.intraday.enabled else None
        word = {"synthetic": "modelled"}  # the older cases' word for the same origin
        by_origin = {origin: [c for c, p in self.provenance if word.get(p.origin, p.origin) == origin]
                     for origin in ("real", "real-derived", "modelled")}
        parts = [f"{origin}: {', '.join(columns)}" for origin, columns in by_origin.items() if columns]
        line = "History columns — " + "; ".join(parts) + " (sources and fingerprints in the case's provenance)."
        return f"{line} {self.intraday_summary()}" if self.intraday.enabled else line

    def intraday_summary(self) -> str:
        """Where the intraday sessions' prices and forecasts come from: the history's per-session
        columns (real) or the seeded models of docs/intraday.md (modelled)."""
        sessions = [s.name for s in self.intraday.resolved]
        columns = set(self.history.columns)
        prices = [name for name in sessions if intraday_price_column(name) in columns]
        bases = [unit.forecast_column for _, unit in self.uncertain_units() if unit.forecast_column]
        forecasts = sorted({intraday_forecast_column(base, name) for base in bases for name in sessions} & columns)
        said = f"Intraday sessions {', '.join(sessions)}: prices "
        said += (f"real for {', '.join(prices)}, " if prices else "") + (
            "modelled (the day-ahead price and a seeded spread)" if len(prices) < len(sessions) else "")
        said += "; forecasts " + (f"real in {', '.join(forecasts)}, otherwise " if forecasts else "")
        return said.replace(", ;", ";") + "modelled (the day-ahead error shrunk with the lead time)."

    @property
    def ndres(self) -> tuple[NdresUnit, ...]:
        return self.wind + self.pv

    def units(self) -> Iterator[tuple[UnitKind, Any]]:
        """``(kind, unit)`` for every unit the model holds, in the order of
        :data:`~rvpp.data.kinds.UNIT_KINDS`: a unit with ``enabled: false`` is left out."""
        return ((kind, unit) for kind, unit in self.all_units() if getattr(unit, "enabled", True))

    def all_units(self) -> Iterator[tuple[UnitKind, Any]]:
        """``(kind, unit)`` for every unit of the case, disabled ones included."""
        for kind in UNIT_KINDS:
            for unit in getattr(self, kind):
                yield kind, unit

    def unit_names(self) -> list[str]:
        return [unit.name for _, unit in self.all_units()]

    def uncertain_units(self) -> Iterator[tuple[UnitKind, Any]]:
        """``(kind, unit)`` for every unit whose kind has an uncertain series."""
        return ((kind, unit) for kind, unit in self.units() if KINDS[kind].role is not None)

    def sources(self) -> list[str]:
        """Names of every uncertain source that has a budget Γ."""
        return list(PRICE_COLUMNS) + [unit.name for _, unit in self.uncertain_units()]

    def replace(self, **changes: Any) -> "Case":
        """A validated copy with fields changed.

        Sections (``markets``, ``budgets``, ...) may be given as objects or as dicts of
        the fields to change; unit kinds (``wind``, ``csp``, ...) as lists of units or
        dicts; ``history`` as a :class:`History`.
        """
        data = self.to_data()
        history = changes.pop("history", self.history)
        for key, value in changes.items():
            if isinstance(value, BaseModel):
                value = value.model_dump(mode="python")
            if key in UNIT_KINDS:
                data["units"][key] = [_plain(kind=key, unit=u) for u in value]
            elif key in _SECTIONS and isinstance(value, Mapping):
                data[key] = {**data.get(key, {}), **value}
            else:
                data[key] = value
        return parse_case(data, history)

    def to_data(self) -> dict[str, Any]:
        """Plain data in the layout of ``case.yaml`` (without the history)."""
        dump = self.model_dump(mode="python", exclude={"history"})
        units = {kind.value: [_unit_data(kind, u) for u in dump.pop(kind)] for kind in UNIT_KINDS}
        # a kind beyond the paper's is written only when it has units: cases and their digests stay as they were
        units = {kind: entries for kind, entries in units.items() if entries or kind in PAPER_KINDS}
        if dump["markets"]["reserve_base"] == "net":
            del dump["markets"]["reserve_base"]
        dump["budgets"]["overrides"] = dict(dump["budgets"]["overrides"])
        if dump["budgets"]["ties"] == "choose":
            del dump["budgets"]["ties"]  # written only when set: cases and their digests stay as they were
        dump["provenance"] = dict(dump["provenance"])
        if self.intraday == IntradaySettings():
            del dump["intraday"]  # written only when set: cases and their digests stay as they were
        else:
            dump["intraday"]["sessions"] = [{k: v for k, v in s.items() if v is not None}
                                            for s in dump["intraday"]["sessions"]]
        return {**dump, "units": units}

    @field_validator("delivery_date", mode="before")
    @classmethod
    def _date_as_written(cls, value: Any) -> Any:
        """A date is written as one (``2025-03-18``): never as a number of seconds since 1970,
        nor with a time of day, even midnight (a plan covers a whole delivery day)."""
        if isinstance(value, dt.datetime) or (isinstance(value, str) and _ISO_TIME.match(value)):
            raise ValueError(f"delivery_date={show_value(value)} must be a date such as 2025-03-18, "
                             "without a time of day")
        if isinstance(value, (int, float)) or (isinstance(value, str) and not ISO_DATE.fullmatch(value)):
            raise ValueError(f"delivery_date={show_value(value)} must be a date such as 2025-03-18")
        return value

    @field_validator("delivery_date")
    @classmethod
    def _date_in_range(cls, value: dt.date) -> dt.date:
        """Dates far outside any market history cannot be placed in local time by pandas; refuse them by name."""
        if not FIRST_DATE <= value <= LAST_DATE:
            raise ValueError(f"delivery_date={value.isoformat()} must lie between {FIRST_DATE.isoformat()} and "
                             f"{LAST_DATE.isoformat()}")
        return value

    @field_validator("dt_h")
    @classmethod
    def _dt(cls, value: float) -> float:
        if value not in ALLOWED_DT_H:
            raise ValueError(f"dt_h={value:g} must be one of {', '.join(f'{v:g}' for v in ALLOWED_DT_H)} [h]")
        return float(value)

    @field_validator("timezone")
    @classmethod
    def _timezone(cls, value: str) -> str:
        try:
            ZoneInfo(value)
        except (ZoneInfoNotFoundError, ValueError):
            raise ValueError(f"timezone={value!r} is not an IANA time zone such as Europe/Madrid") from None
        return value

    @model_validator(mode="after")
    def _cross_checks(self) -> "Case":
        problems = []
        for kind in SHARED_CLASS_KINDS:
            for unit in getattr(self, kind):
                if unit.kind != kind:
                    problems.append(f'{kind} "{unit.name}": kind={unit.kind!r} must be {kind.value!r} in the '
                                    f"{kind} list")
        seen: set[str] = set()
        for kind, unit in self.all_units():
            if unit.name in seen:
                problems.append(f'{kind} "{unit.name}": name is used by more than one unit; names must be unique')
            if unit.name in RESERVED_NAMES:
                problems.append(f'{kind} "{unit.name}": name is reserved for a price series; choose another')
            seen.add(unit.name)
        switched_off = [unit.name for _, unit in self.all_units()]
        if switched_off and not any(True for _ in self.units()):
            problems.append(f"units: every unit is switched off (enabled: false: {excerpt_names(switched_off, 12)}); "
                            "the plan would hold no unit and trade nothing; switch one on")
        known = set(self.sources())
        uncertain = [unit.name for _, unit in self.uncertain_units()]
        for source, _ in self.budgets.overrides:
            if source not in known:
                problems.append(f"budgets.overrides: unknown source {excerpt(source)!r}; sources are "
                                f"{', '.join(PRICE_COLUMNS)} and the unit names ({', '.join(uncertain)})")
        columns = set(self.history.columns)
        for kind, unit in self.uncertain_units():
            if unit.column in PRICE_COLUMNS or unit.forecast_column in PRICE_COLUMNS:
                problems.append(f'{kind} "{unit.name}": follows the price column '
                                f"{unit.column if unit.column in PRICE_COLUMNS else unit.forecast_column!r}; a unit "
                                "follows a column of output, demand or heat, not a price [EUR/MWh]")
            elif unit.column not in columns:
                problems.append(f'{kind} "{unit.name}": history column {excerpt(unit.column)!r} is missing from '
                                f"{self.history.source} (columns: {excerpt_names(sorted(columns), 20)})")
        for price in PRICE_COLUMNS:
            if price not in columns:
                problems.append(f"{self.history.source}: price column {price!r} is missing")
        problems += self._band_problems(known, columns)
        if self.budgets.ties == "earliest" and (self.budgets.mode != "paper"
                                                or self.solver.budget_encoding != "top_gamma"):
            problems.append(f"budgets.ties=earliest needs budgets.mode=paper and solver.budget_encoding=top_gamma "
                            f"(here {self.budgets.mode} and {self.solver.budget_encoding}): the other variants "
                            "choose the deviating periods in the model")
        for csp in self.csp:
            for field in ("min_up_h", "min_down_h", "startup_duration_h", "initial_status_h"):
                hours = getattr(csp.power_block, field)
                if hours is not None and not _is_multiple(hours, self.dt_h):
                    problems.append(f'csp "{csp.name}": power_block.{field}={hours:g} must be a multiple of '
                                    f"dt_h={self.dt_h:g}")
            duration = csp.power_block.startup_duration_h
            if duration is not None and duration < self.dt_h and _is_multiple(duration, self.dt_h):
                # rounds to no period at all: a start would draw no heat
                problems.append(f'csp "{csp.name}": power_block.startup_duration_h={duration:g} must be at least '
                                f"one period, dt_h={self.dt_h:g}")
        problems += self._dispatchable_problems()
        if problems:
            raise ValueError("\n".join(problems))
        return self

    def _dispatchable_problems(self) -> list[str]:
        """Hours of hydro and biomass units in whole periods, and a day's energy that allows one period and
        the run a unit online before the day is committed to (for a unit switched on)."""
        problems = []
        periods = len(delivery_periods(self.delivery_date, self.timezone, self.dt_h))
        for kind in DISPATCHABLE_KINDS:
            for unit in getattr(self, kind):
                for field in ("min_up_h", "min_down_h", "initial_hours_in_status"):
                    hours = getattr(unit, field)
                    if hours is not None and not _is_multiple(hours, self.dt_h):
                        problems.append(f'{kind} "{unit.name}": {field}={hours:g} must be a multiple of '
                                        f"dt_h={self.dt_h:g}")
                problems += _ramp_problems(kind, unit, self.dt_h)
                least = unit.p_min_mw * self.dt_h
                if not unit.enabled or unit.energy_max_mwh is None:  # a unit switched off may have no water or fuel
                    continue
                if unit.energy_max_mwh < least:
                    problems.append(f'{kind} "{unit.name}": energy_max_mwh={unit.energy_max_mwh:g} is below the '
                                    f"{least:g} MWh of one period (dt_h={self.dt_h:g}) at p_min_mw={unit.p_min_mw:g}: "
                                    "the unit could never run")
                else:
                    committed, run = unit.committed_run(self.dt_h, periods)
                    if unit.energy_max_mwh < committed - 1e-9:
                        problems.append(_committed_problem(kind, unit, committed, run, self.dt_h))
        return problems

    def _band_problems(self, sources: set[str], columns: set[str]) -> list[str]:
        """Band methods, forecast columns, imbalance prices and provenance name what exists."""
        problems = []
        keys = sources | set(UNIT_KINDS) | {DEFAULT_BANDS}
        for key, _ in self.uncertainty.bands:
            if key not in keys:
                problems.append(f"uncertainty.bands: unknown key {excerpt(key)!r}; keys are {DEFAULT_BANDS}, a unit "
                                f"kind ({', '.join(UNIT_KINDS)}) or a source ({excerpt_names(sorted(sources), 12)})")
        for kind, unit in self.uncertain_units():
            column = unit.forecast_column
            if column is not None and column not in columns:
                problems.append(f'{kind} "{unit.name}": forecast history column {excerpt(column)!r} is missing from '
                                f"{self.history.source}")
            if self.uncertainty.band_method(unit.name, kind) == "forecast" and column is None:
                field = KINDS[kind].forecast_field
                problems.append(f'{kind} "{unit.name}": uncertainty.bands asks for forecast bands but the unit '
                                f"has no {field} (the history column of its day-ahead forecast)")
        imbalance = self.markets.imbalance_prices
        if imbalance is not None:
            for side in ("short", "long"):
                column = getattr(imbalance, side)
                if column not in columns:
                    problems.append(f"markets.imbalance_prices.{side}: history column {excerpt(column)!r} is missing "
                                    f"from {self.history.source}")
        for column, _ in self.provenance:
            if column not in columns:
                problems.append(f"provenance: {excerpt(column)!r} is not a column of {self.history.source}")
        return problems


# The class of each unit kind (rvpp.data.kinds.KINDS holds the kind's other facts).
UNIT_MODELS: dict[UnitKind, type[_Frozen]] = {UnitKind.WIND: NdresUnit, UnitKind.PV: NdresUnit, UnitKind.CSP: CSP,
                                               UnitKind.ED: ElectricalDemand, UnitKind.TD: ThermalDemand,
                                               UnitKind.BATTERY: Battery, UnitKind.HYDRO: DispatchableUnit,
                                               UnitKind.BIOMASS: DispatchableUnit}
_SECTIONS = {"markets": Markets, "uncertainty": UncertaintySettings, "budgets": Budgets, "solver": SolverSettings,
             "intraday": IntradaySettings}
_TOP_FIELDS = {"name", "description", "delivery_date", "timezone", "dt_h", "history", "units", "provenance",
               *_SECTIONS}


def _plain(kind: str, unit: Any) -> dict[str, Any]:
    if isinstance(unit, BaseModel):
        return _unit_data(kind, unit.model_dump(mode="python"))
    return dict(unit)


def _unit_data(kind: str, unit: dict[str, Any]) -> dict[str, Any]:
    if kind in SHARED_CLASS_KINDS:
        unit = {k: v for k, v in unit.items() if k != "kind"}
    return UNIT_MODELS[kind].plain_data(unit)


def _end_floor(e_init: float | None, e_end_min: float | None) -> float | None:
    """Least energy at the end of a storage's day: ``min(e_end_min, e_init)``, ``e_init`` without an
    end target, ``None`` on a cyclic day (no ``e_init``)."""
    if e_init is None:
        return None
    return e_init if e_end_min is None else min(e_end_min, e_init)


def _without_defaults(data: dict[str, Any], defaults: Mapping[str, Any]) -> dict[str, Any]:
    """``data`` without the options ``defaults`` names where they hold their default."""
    return {k: v for k, v in data.items() if k not in defaults or v != defaults[k]}


def _ramp_problems(kind: str, unit: DispatchableUnit, dt_h: float) -> list[str]:
    """A start-up or shut-down ramp whose step in one period stays below ``p_min``: the unit could never
    start (the start's period must reach ``p_min``) or never stop (the period before a stop must be at or
    below the step), as the model has it (MODEL_SPEC §13: ``SU·dt``, ``SD·dt``)."""
    problems = []
    for field, action, where in (("startup_ramp_mw_per_h", "start", "in the period of a start"),
                                 ("shutdown_ramp_mw_per_h", "stop", "in the period before a stop")):
        ramp = getattr(unit, field)
        if ramp is not None and ramp * dt_h < unit.p_min_mw - 1e-9:
            problems.append(f'{kind} "{unit.name}": {field}={ramp:g} allows at most {ramp * dt_h:g} MW {where} '
                            f"(dt_h={dt_h:g}), below p_min_mw={unit.p_min_mw:g}: the unit could never {action}; "
                            f"give a ramp of at least {unit.p_min_mw / dt_h:g} MW/h")
    return problems


def _committed_problem(kind: str, unit: DispatchableUnit, committed: float, run: int, dt_h: float) -> str:
    """The day's water or fuel falls short of the run the status before the day commits the unit to."""
    reasons = [f"p_init_mw={unit.p_init_mw:g}"] if unit.p_init_mw is not None else []
    reasons += [f"{field}={getattr(unit, field):g}" for field in ("ramp_dn_mw_per_h", "shutdown_ramp_mw_per_h")
                if unit.p_init_mw is not None and getattr(unit, field) is not None]
    if unit.initial_periods(dt_h)[0]:
        reasons += [f"min_up_h={unit.min_up_h:g}", f"initial_hours_in_status={unit.initial_hours_in_status:g}"]
    return (f'{kind} "{unit.name}": energy_max_mwh={unit.energy_max_mwh:g} is below the {committed:g} MWh the day '
            f"commits the unit to: online before the day ({', '.join(reasons)}), it must run {run * dt_h:g} h "
            "at least before it may stop")


def _is_multiple(hours: float, dt_h: float) -> bool:
    ratio = hours / dt_h
    return math.isclose(ratio, round(ratio), abs_tol=1e-9)


def _require(ok: bool, left: str, lval: float, op: str, right: str, rval: float) -> None:
    if not ok:
        raise ValueError(f"{left}={lval:g} must be {op} {right}={rval:g}")


def _require_within(name: str, value: float | None, low: str, lval: float, high: str, hval: float) -> None:
    """An optional initial value must lie in its unit's range."""
    if value is not None and not lval <= value <= hval:
        raise ValueError(f"{name}={value:g} must lie in [{low}={lval:g}, {high}={hval:g}]")


def parse_case(data: Mapping[str, Any], history: History) -> Case:
    """Build a :class:`Case` from plain data (the ``case.yaml`` layout).

    Raises :class:`CaseError` listing every problem found, each naming unit, field,
    value and rule in the words of ``case.yaml``.
    """
    if not isinstance(data, Mapping):
        raise CaseError(f"{CASE_FILE}: the top level must be a mapping of settings, got {kind_of(data)}")
    problems: list[str] = []
    sections, units = settings_of(data, problems)
    if problems:
        raise CaseError(in_file_order(problems, data))
    top = {k: data[k] for k in ("name", "description", "delivery_date", "timezone", "dt_h", "provenance")
           if k in data and not (k == "provenance" and data[k] is None)}
    case = validate_into(Case, {**top, **sections, **units, "history": history}, "", problems)
    if problems:
        raise CaseError(problems)
    return case


def settings_of(data: Mapping[str, Any], problems: list[str]) -> tuple[dict[str, Any], dict[str, tuple]]:
    """The sections and unit lists of ``data``, validated without the history; ``problems`` gets
    what breaks a rule."""
    for key in data:
        if key not in _TOP_FIELDS:
            problems.append(f'{CASE_FILE}: unknown setting "{excerpt(key)}" (known: {", ".join(sorted(_TOP_FIELDS))})')
    sections: dict[str, Any] = {}
    for key, model in _SECTIONS.items():
        raw = data.get(key)
        if raw is None and key == "markets":
            problems.append(f"{key}: section is {'empty' if key in data else 'required'}; it needs at least "
                            "hpa_tariff_eur_per_mwh")
            continue
        sections[key] = validate_into(model, {} if raw is None else raw, key, problems)  # blank: the defaults
    return sections, _parse_units(data.get("units"), problems)


# The setting a problem names: an unknown one, a quoted one ("history") or its leading key (units: ...).
_SETTING_OF = re.compile(rf'(?:{re.escape(CASE_FILE)}: )?'
                         r'(?:unknown setting "(?P<unknown>[^"]*)"|"(?P<quoted>\w+)"|(?P<key>\w+))')


def in_file_order(problems: list[str], data: Mapping[str, Any]) -> list[str]:
    """``problems`` ordered by where the setting each names stands in the file (a setting the file
    lacks after those it has); problems of one setting keep their order."""
    order = {str(key): position for position, key in enumerate(data)}

    def position(problem: str) -> int:
        found = _SETTING_OF.match(problem)
        named = found and (found["unknown"] or found["quoted"] or found["key"])
        return order.get(named, len(order))

    return sorted(problems, key=position)


def _parse_units(raw_units: Any, problems: list[str]) -> dict[str, tuple]:
    """The unit lists of ``units:``, each unit validated and named in messages as ``csp "CSP1"``."""
    kinds = ", ".join(UNIT_KINDS)
    if raw_units is None:
        problems.append(f"units: section is required; list the units of the case under {kinds}")
        return {}
    if not isinstance(raw_units, Mapping):
        problems.append(f"units: must be a mapping of unit lists ({kinds}); got {kind_of(raw_units)}")
        return {}
    for kind in raw_units:
        if kind not in UNIT_KINDS:
            problems.append(f'units: unknown unit kind "{excerpt(kind)}" (known: {kinds})')
    units: dict[str, tuple] = {}
    for kind in UNIT_KINDS:
        entries = raw_units.get(kind) or []
        if not isinstance(entries, (list, tuple)):
            problems.append(f"units.{kind}: must be a list of units; got {kind_of(entries)}")
            continue
        built = []
        for i, entry in enumerate(entries, start=1):
            if not isinstance(entry, Mapping):
                problems.append(f"units.{kind} item {i}: must be a mapping of fields (name: ..., ...); got "
                                f"{kind_of(entry)}")
                continue
            name = entry.get("name")
            label = f'{kind} "{excerpt(name)}"' if isinstance(name, str) and name else f"units.{kind} item {i}"
            payload = dict(entry)
            if kind in SHARED_CLASS_KINDS:
                payload.setdefault("kind", kind.value)
            unit = validate_into(UNIT_MODELS[kind], payload, label, problems)
            if unit is not None:
                built.append(unit)
        units[kind] = tuple(built)
    if not any(isinstance(raw_units.get(kind), (list, tuple)) and raw_units.get(kind) for kind in UNIT_KINDS) \
            and not any(kind not in UNIT_KINDS for kind in raw_units):
        problems.append(f"units: no unit is listed; a case needs at least one unit under {kinds}")
    return units
