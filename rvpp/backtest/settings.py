"""What a backtest computes: its days, its variants (strategy or Γ fraction) and its rules.

A :class:`BacktestVariant` is one bidding rule followed every day: a strategy preset of the
paper (``deterministic`` ... ``pessimistic``), a Γ fraction of the day applied to every
source, or the perfect-information plan (the benchmark of the regret); it derives its case
through :class:`rvpp.data.variants.Variant`, the one way cases are varied. Each variant is a
chain of days: day ``D + 1`` starts from the state that day ``D``'s settlement left.
:class:`BacktestSettings` is frozen and checked on creation; its :meth:`stored` form is
what identifies the backtest in the store, so the same settings reopen the same records.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ..data.case import STRATEGIES, Case
from ..data.variants import Variant as CaseVariant
from ..errors import RvppError
from ..settle.penalties import Penalties

PRESET = "preset"            # the budget key of a strategy preset
FRACTION = "fraction"        # the strategy name of a Γ-fraction variant
PERFECT = "perfect"          # the strategy name of the perfect-information benchmark
CARRY = "carry"              # storage end rule: e[NT] ≥ e_init
ENGINE_VERSION = 1           # bump when a day's computation changes, so old records are not reused


class BacktestError(RvppError):
    """A backtest's settings or period break a rule (named with the option as the user wrote it)."""


@dataclass(frozen=True, order=True)
class BacktestVariant:
    """One bidding rule of a backtest: the ``(strategy, gamma)`` of its records.

    ``strategy`` is a preset name (``gamma`` = ``"preset"``), ``"fraction"`` (``gamma`` =
    the fraction as text, e.g. ``"0.25"``) or ``"perfect"``.
    """

    strategy: str
    gamma: str = PRESET

    @classmethod
    def preset(cls, name: str) -> "BacktestVariant":
        if name not in STRATEGIES:
            raise BacktestError(f"strategy {name!r} is not one of {', '.join(STRATEGIES)}")
        return cls(name)

    @classmethod
    def of_fraction(cls, fraction: float) -> "BacktestVariant":
        if not (isinstance(fraction, (int, float)) and math.isfinite(fraction) and 0.0 <= fraction <= 1.0):
            raise BacktestError(f"Γ fraction {fraction!r} must be a number in [0, 1] (a share of the day)")
        return cls(FRACTION, f"{float(fraction):g}")

    @classmethod
    def perfect(cls) -> "BacktestVariant":
        return cls(PERFECT)

    @property
    def fraction(self) -> float | None:
        return float(self.gamma) if self.strategy == FRACTION else None

    @property
    def is_perfect(self) -> bool:
        return self.strategy == PERFECT

    @property
    def label(self) -> str:
        if self.strategy == FRACTION:
            return f"Γ {self.gamma} of the day"
        if self.is_perfect:
            return "perfect information"
        return self.strategy

    @property
    def case_variant(self) -> CaseVariant:
        """The variant of the case this rule bids with (:mod:`rvpp.data.variants`): the preset as
        published or the Γ fraction, the case's own Γ edits set aside; the perfect-information plan
        has no deviations, so its budgets are the deterministic preset's (all 0)."""
        if self.strategy == FRACTION:
            return CaseVariant(gamma_fraction=self.fraction)
        return CaseVariant(strategy="deterministic" if self.is_perfect else self.strategy)

    def case(self, base: Case, **more: Any) -> Case:
        """``base`` with this rule's budgets (and ``more`` :meth:`Case.replace` changes in the same step)."""
        return self.case_variant.apply(base, **more)


def variants_of(strategies: Sequence[str] = (), fractions: Sequence[float] = (), perfect: bool = True
                ) -> tuple[BacktestVariant, ...]:
    """Presets, then fractions (sorted, duplicates dropped), then the perfect-information benchmark."""
    chosen = [BacktestVariant.preset(s) for s in dict.fromkeys(strategies)]
    chosen += sorted(dict.fromkeys(BacktestVariant.of_fraction(f) for f in fractions), key=lambda v: v.fraction)
    if perfect:
        chosen.append(BacktestVariant.perfect())
    return tuple(chosen)


@dataclass(frozen=True)
class BacktestSettings:
    """A backtest: the days ``first_day..last_day`` (both included) for every variant.

    ``storage_end``: the end-of-day storage rule of the plan and the settlement,
    ``"carry"`` (``e[NT] ≥ e_init``: never end below the start) or a fraction ``f`` of
    the storage range (end target ``e_min + f·(e_max − e_min)``: may run down to the
    target, never below it nor below the start if that was lower; see docs/backtest.md).
    ``fix_commitment``: settle with the plan's turbine schedule (no start where the plan
    is off). ``audit``: audit every plan (:func:`rvpp.settle.audit.audit_result`).
    ``intraday``: trade the intraday sessions of the case after the day-ahead market (also on
    when the case's ``intraday.enabled`` is; MODEL_SPEC §14, docs/intraday.md).
    """

    first_day: dt.date
    last_day: dt.date
    variants: tuple[BacktestVariant, ...]
    penalties: Penalties = field(default_factory=Penalties)
    storage_end: str | float = CARRY
    fix_commitment: bool = False
    audit: bool = True
    intraday: bool = False

    def __post_init__(self) -> None:
        problems = []
        if self.last_day < self.first_day:
            problems.append(f"--to {self.last_day} is before --from {self.first_day}")
        if not self.variants:
            problems.append("no strategy and no Γ fraction chosen; give --strategies or --fractions")
        if len(set(self.variants)) != len(self.variants):
            problems.append("a variant is listed twice")
        if self.storage_end != CARRY and not (isinstance(self.storage_end, (int, float))
                                              and not isinstance(self.storage_end, bool)
                                              and 0.0 <= self.storage_end <= 1.0):
            problems.append(f"--storage-end {self.storage_end!r} must be {CARRY!r} or a fraction in [0, 1] "
                            "of the storage range")
        if problems:
            raise BacktestError("backtest settings: " + "; ".join(problems))

    @property
    def days(self) -> list[dt.date]:
        n = (self.last_day - self.first_day).days + 1
        return [self.first_day + dt.timedelta(days=k) for k in range(n)]

    @property
    def perfect(self) -> bool:
        return any(v.is_perfect for v in self.variants)

    def stored(self) -> dict[str, Any]:
        """Plain data identifying the backtest (part of its id in the store)."""
        return {"engine_version": ENGINE_VERSION, "from": self.first_day.isoformat(),
                "to": self.last_day.isoformat(), "variants": [[v.strategy, v.gamma] for v in self.variants],
                "penalties": dataclasses.asdict(self.penalties), "storage_end": self.storage_end,
                "fix_commitment": self.fix_commitment, "audit": self.audit,
                **({"intraday": True} if self.intraday else {})}  # written only when on: older ids stay

    @classmethod
    def from_stored(cls, data: dict[str, Any]) -> "BacktestSettings":
        """The settings of :meth:`stored` data."""
        if data.get("engine_version") != ENGINE_VERSION:
            raise BacktestError(f"the backtest was recorded by engine version {data.get('engine_version')}; "
                                f"this rvpp computes version {ENGINE_VERSION}")
        return cls(first_day=dt.date.fromisoformat(data["from"]), last_day=dt.date.fromisoformat(data["to"]),
                   variants=tuple(BacktestVariant(*v) for v in data["variants"]), penalties=Penalties(**data["penalties"]),
                   storage_end=data["storage_end"], fix_commitment=data["fix_commitment"], audit=data["audit"],
                   intraday=bool(data.get("intraday", False)))

    def trades_intraday(self, case: Case) -> bool:
        """True when the days of ``case`` trade the intraday sessions (this setting or the case's)."""
        return self.intraday or case.intraday.enabled

    def with_changes(self, **changes: Any) -> "BacktestSettings":
        return dataclasses.replace(self, **changes)

    def check_case(self, case: Case, first_option: str = "--from", last_option: str = "--to") -> None:
        """Refuse days the case's history cannot plan (window before) or settle (the day itself).

        The messages name the first and last day by the options the user gave them with
        (``backtest recommend``: ``--train`` and ``--test``)."""
        covered = case.history.local_days(case.timezone)
        first, last = covered[0], covered[-1]
        earliest = first + dt.timedelta(days=case.uncertainty.window_days)
        if self.first_day < earliest:
            raise BacktestError(f"{first_option} {self.first_day}: the first day needs the "
                                f"{case.uncertainty.window_days} days of history before it; {case.history.source} "
                                f"starts on {first}, so the earliest day is {earliest}")
        if self.last_day > last:
            raise BacktestError(f"{last_option} {self.last_day}: the day is settled against its own observations, "
                                f"and {case.history.source} ends on {last}; choose a day up to {last}")


def parse_day(text: str, option: str) -> dt.date:
    """``YYYY-MM-DD`` as a date; a named error otherwise."""
    try:
        return dt.date.fromisoformat(str(text).strip())
    except ValueError:
        raise BacktestError(f"{option} {text!r} is not a date such as 2025-03-18") from None


def parse_period(text: str, option: str) -> tuple[dt.date, dt.date]:
    """``D1:D2`` as two dates, the first not after the second."""
    first, sep, last = str(text).partition(":")
    if not sep:
        raise BacktestError(f"{option} {text!r} must look like FIRST:LAST, e.g. 2025-01-01:2025-03-31")
    start, end = parse_day(first, option), parse_day(last, option)
    if end < start:
        raise BacktestError(f"{option} {text!r}: {end} is before {start}")
    return start, end
