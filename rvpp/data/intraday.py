"""Intraday sessions of a case: when each closes, which periods it trades (MODEL_SPEC §14).

A session ``k`` has a gate closure (a clock time on the delivery day ``D`` or the day
before) and a delivery window: the periods of ``D`` from a clock time to the end of the
day. Two layouts are built in:

* ``iberian_2024``: the pan-European intraday auctions of the Iberian market since June
  2024: IDA1 (gate 15:00 on D-1, all of D), IDA2 (22:00 on D-1, all of D), IDA3 (10:00 on
  D, periods from 12:00);
* ``tool_seven``: the seven intraday sessions of the Iberian market the authors' tool models
  (IDM1 to IDM7), with the market's gate closures and horizons of 24, 24, 20, 17, 12, 8 and
  4 hours: IDM1 (18:45 D-1, all of D), IDM2 (21:45 D-1, all), IDM3 (01:45 D, from 04:00),
  IDM4 (04:45, from 07:00), IDM5 (08:45, from 12:00), IDM6 (12:45, from 16:00), IDM7
  (16:45, from 20:00). The tool's code starts its windows at periods 1, 1, 1, 5, 8, 13 and
  21: IDM3 over the whole day, which no gate on D allows, and IDM6 at 12:00; a case that
  wants those lists its sessions (docs/intraday.md).

A case may list its own sessions instead. The settings also hold the session budgets
(``gamma_shrink``, or a ``gamma_factor`` per session), the lead-time error model and the
intraday price model of :mod:`rvpp.uncertainty.intraday`. Everything is checked on
creation: a gate closing after its window starts, a window outside the day, sessions out
of time order and negative or non-finite model parameters are refused by name.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from dataclasses import dataclass
from typing import Annotated, Literal

import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..errors import CaseError
from .history import MAX_QUANTITY

_CLOCK = re.compile(r"^(\d{1,2}):(\d{2})$")
MINUTES_PER_DAY = 24 * 60
PRESETS = ("iberian_2024", "tool_seven")
DA_GATE_CLOSURE = "12:00"  # OMIE's day-ahead gate on D-1: the reference lead time of the error model


def clock_minutes(text: str) -> int:
    """``HH:MM`` as minutes after midnight (``24:00`` allowed: the end of the day)."""
    found = _CLOCK.match(str(text).strip())
    if not found or int(found[2]) >= 60 or int(found[1]) * 60 + int(found[2]) > MINUTES_PER_DAY:
        raise ValueError(f"{text!r} is not a clock time such as 15:00")
    return int(found[1]) * 60 + int(found[2])


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


class Session(_Frozen):
    """One intraday session: its name, gate closure (``gate_day`` 0 for D, -1 for the day before),
    the clock time its window starts on D (the window ends with the day) and optionally its own
    budget factor (Γ of the session = Γ of the day-ahead × factor × window share)."""

    name: Annotated[str, Field(pattern=r"^[A-Za-z][A-Za-z0-9]{0,15}$")]
    gate_closure: str
    gate_day: Literal[-1, 0]
    window_from: str = "00:00"
    gamma_factor: Annotated[float, Field(ge=0.0, le=1.0)] | None = None

    @field_validator("gate_closure", "window_from")
    @classmethod
    def _clock(cls, value: str) -> str:
        clock_minutes(value)
        return value

    @property
    def gate_minutes(self) -> int:
        """Gate closure in minutes from the start of D (negative on the day before)."""
        return self.gate_day * MINUTES_PER_DAY + clock_minutes(self.gate_closure)

    @property
    def window_minutes(self) -> int:
        return clock_minutes(self.window_from)

    @property
    def gate_label(self) -> str:
        return f"{self.gate_closure} on {'D-1' if self.gate_day else 'D'}"


def _session(name: str, gate: str, day: int, start: str = "00:00") -> Session:
    return Session(name=name, gate_closure=gate, gate_day=day, window_from=start)


PRESET_SESSIONS: dict[str, tuple[Session, ...]] = {
    "iberian_2024": (_session("IDA1", "15:00", -1), _session("IDA2", "22:00", -1),
                     _session("IDA3", "10:00", 0, "12:00")),
    "tool_seven": (_session("IDM1", "18:45", -1), _session("IDM2", "21:45", -1), _session("IDM3", "01:45", 0, "04:00"),
                   _session("IDM4", "04:45", 0, "07:00"), _session("IDM5", "08:45", 0, "12:00"),
                   _session("IDM6", "12:45", 0, "16:00"), _session("IDM7", "16:45", 0, "20:00")),
}


def price_column(name: str) -> str:
    """The history column of a session's real prices: ``price_ida2`` [EUR/MWh]."""
    return f"price_{name.lower()}"


def forecast_column(base: str, name: str) -> str:
    """The history column of a unit's forecast at a session's gate closure: ``wind_fc_ida2``."""
    return f"{base}_{name.lower()}"


class IntradaySettings(_Frozen):
    """The ``intraday:`` section of a case (MODEL_SPEC §14; docs/intraday.md).

    ``enabled``: the backtest trades the sessions after the day-ahead market. ``preset`` or
    ``sessions`` (a list given replaces the preset). ``gamma_shrink``: session ``k`` (1, 2, ...)
    keeps ``gamma_shrink^k`` of the day-ahead budgets, scaled to its window, unless the session
    sets ``gamma_factor``. ``lead_time_exponent`` and ``reference_gate_closure`` (the day-ahead
    gate on D-1) shape the modelled forecast error; ``price_spread_eur_per_mwh`` and
    ``price_seed`` the modelled intraday price.
    """

    enabled: bool = False
    preset: Literal["iberian_2024", "tool_seven"] = "iberian_2024"
    sessions: tuple[Session, ...] = ()
    gamma_shrink: Annotated[float, Field(ge=0.0, le=1.0)] = 1.0
    lead_time_exponent: Annotated[float, Field(ge=0.0, le=10.0)] = 0.5
    reference_gate_closure: str = DA_GATE_CLOSURE
    price_spread_eur_per_mwh: Annotated[float, Field(ge=0.0, le=MAX_QUANTITY)] = 5.0
    price_seed: Annotated[int, Field(ge=0, le=2**32 - 1)] = 0

    @field_validator("reference_gate_closure")
    @classmethod
    def _reference(cls, value: str) -> str:
        clock_minutes(value)
        return value

    @model_validator(mode="after")
    def _in_time_order(self) -> "IntradaySettings":
        problems = []
        reference = clock_minutes(self.reference_gate_closure) - MINUTES_PER_DAY
        names = [s.name for s in self.resolved]
        for twice in sorted({n for n in names if names.count(n) > 1}):
            problems.append(f"session {twice!r} is listed twice")
        previous: Session | None = None
        for s in self.resolved:
            if s.window_minutes >= MINUTES_PER_DAY:
                problems.append(f"session {s.name}: window_from={s.window_from} lies outside the delivery day "
                                "(00:00 to 24:00); its window would hold no period")
            if s.gate_minutes > s.window_minutes:
                problems.append(f"session {s.name}: the gate closes at {s.gate_label}, after its window starts at "
                                f"{s.window_from} on D; a session trades only periods after its gate")
            if s.gate_minutes <= reference:
                problems.append(f"session {s.name}: the gate closes at {s.gate_label}, not after the day-ahead gate "
                                f"(reference_gate_closure={self.reference_gate_closure} on D-1)")
            if previous is not None and s.gate_minutes <= previous.gate_minutes:
                problems.append(f"sessions out of time order: {s.name} closes at {s.gate_label}, not after "
                                f"{previous.name} at {previous.gate_label}; list them by gate closure")
            previous = s
        if problems:
            raise ValueError("; ".join(problems))
        return self

    @property
    def resolved(self) -> tuple[Session, ...]:
        """The sessions in force: the list given, or the preset's."""
        return self.sessions or PRESET_SESSIONS[self.preset]

    def gamma_factor(self, k: int) -> float:
        """Share of the day-ahead budgets session ``k`` (1-based) keeps before scaling to its window."""
        own = self.resolved[k - 1].gamma_factor
        return own if own is not None else self.gamma_shrink ** k


@dataclass(frozen=True)
class SessionTime:
    """A session placed on one delivery day: its gate [local time] and first period (0-based)."""

    index: int  # 1-based order of the session
    session: Session
    gate: pd.Timestamp
    first: int

    @property
    def name(self) -> str:
        return self.session.name


def local_time(day: dt.date, minutes: int, timezone: str) -> pd.Timestamp:
    """``minutes`` after the start of ``day`` on the wall clock (a time skipped when clocks go forward
    moves forward; one repeated when they go back is its first occurrence)."""
    wall = pd.Timestamp(day) + pd.Timedelta(minutes=minutes)
    return wall.tz_localize(timezone, nonexistent="shift_forward", ambiguous=True)


def session_times(settings: IntradaySettings, day: dt.date, periods: pd.DatetimeIndex, timezone: str,
                  dt_h: float) -> list[SessionTime]:
    """Every session of ``settings`` placed on ``day`` with ``periods`` (local starts).

    The window of a session starts at the first period beginning at or after its
    ``window_from``; a start that is not a period boundary at ``dt_h`` is refused.
    """
    step = round(dt_h * 60)
    out = []
    for k, s in enumerate(settings.resolved, start=1):
        if s.window_minutes % step:
            raise CaseError(f"intraday: session {s.name}: window_from={s.window_from} is not the start of a "
                            f"{step}-minute period")
        start = local_time(day, s.window_minutes, timezone)
        first = int((periods < start).sum())
        gate = local_time(day, s.gate_minutes, timezone) if s.gate_day == 0 else \
            local_time(day - dt.timedelta(days=1), clock_minutes(s.gate_closure), timezone)
        out.append(SessionTime(k, s, gate, first))
    return out


def reference_gate(settings: IntradaySettings, day: dt.date, timezone: str) -> pd.Timestamp:
    """The day-ahead gate closure of ``day`` (on D-1), from which the day-ahead lead time is measured."""
    return local_time(day - dt.timedelta(days=1), clock_minutes(settings.reference_gate_closure), timezone)


def session_gamma(gamma_da: int, factor: float, window: int, nt: int) -> int:
    """Γ of a session [periods]: ``⌊Γ_da·factor·|W|/NT + ½⌋``, at most ``|W|``."""
    if nt <= 0 or not math.isfinite(factor):
        return 0
    return min(window, int(math.floor(gamma_da * factor * window / nt + 0.5)))
