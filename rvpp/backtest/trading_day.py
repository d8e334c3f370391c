"""One backtest day with intraday sessions (MODEL_SPEC §14), read from its record.

A day record of a backtest run with intraday sessions carries ``intraday``: one entry per
session, in time order, with ``session``, ``gate_closure`` (local ISO time),
``window_first_period`` (0-based), ``status``, ``traded_mw`` (per period, + sell / − buy,
0 outside the window), ``price_eur_per_mwh``, ``position_mw`` (day-ahead energy plus the
trades so far), ``trading_revenue_eur``, ``expected_imbalance_before_mwh`` and
``expected_imbalance_after_mwh``, ``forecast_change_mw`` (per uncertain source, per period)
and ``solve_s``; and at the top ``intraday_revenue_eur`` and ``final_position_mw``.

This module checks such a record (every per-period list as long as the day's bids) and
turns it into the plain tables the trading-day view draws (:func:`sessions`,
:func:`session_table`, :func:`day_summary`); the figure is
:func:`rvpp.backtest.figures.trading_day_figure`. A record without ``intraday`` has no
trading day.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..data.files import excerpt
from ..errors import RvppError
from ..outputs.money import IN_EUR, MoneyUnit

HOURS_PER_DAY = 24
SESSION_COLUMNS = ("Session", "Gate closure", "Status", "Sold [MWh]", "Bought [MWh]", "Trading cost [{money}]",
                   "Expected imbalance before [MWh]", "Expected imbalance after [MWh]")


def has_intraday(record: Mapping[str, Any]) -> bool:
    """True for a record of a day traded in intraday sessions."""
    value = record.get("intraday")
    return isinstance(value, list) and len(value) > 0


def intraday_days(records: pd.DataFrame) -> pd.DataFrame:
    """The records with intraday sessions: ``day``, ``strategy``, ``gamma``, ``label`` (by day)."""
    if records.empty or "intraday" not in records.columns:
        return pd.DataFrame(columns=["day", "strategy", "gamma", "label"])
    traded = records[[has_intraday({"intraday": v}) for v in records["intraday"]]]
    return traded[["day", "strategy", "gamma", "label"]].sort_values(["day", "strategy", "gamma"]).reset_index(
        drop=True)


def period_hours(periods: int) -> float:
    """Length of a period [h] of a day of ``periods`` periods: 1 for 23 to 25, 0.5 for 46 to 50,
    0.25 for 92 to 100 (the clock-change days have one hour less or more)."""
    per_hour = round(periods / HOURS_PER_DAY)
    if per_hour not in (1, 2, 4) or abs(periods - per_hour * HOURS_PER_DAY) > per_hour:
        raise RvppError(f"a day of {periods} periods is not a day of hours, half-hours or quarter-hours")
    return 1.0 / per_hour


@dataclass(frozen=True)
class SessionTrades:
    """One session of a record, checked: its trades, prices and position per period."""

    session: str
    gate_closure: str
    window_first_period: int
    status: str
    traded_mw: np.ndarray
    price_eur_per_mwh: np.ndarray
    position_mw: np.ndarray
    trading_revenue_eur: float
    expected_imbalance_before_mwh: float
    expected_imbalance_after_mwh: float
    forecast_change_mw: dict[str, np.ndarray]


@dataclass(frozen=True)
class TradingDay:
    """A day with intraday sessions: the day-ahead energy, each session, the final position."""

    day: str
    label: str
    dt_h: float
    p_da_mw: np.ndarray
    sessions: tuple[SessionTrades, ...]
    final_position_mw: np.ndarray
    intraday_revenue_eur: float

    @property
    def periods(self) -> int:
        return len(self.p_da_mw)


def sessions(record: Mapping[str, Any]) -> TradingDay:
    """The record's day with its sessions checked; a record without sessions, or with a list of
    the wrong length, raises :class:`~rvpp.errors.RvppError` naming the day, session and field."""
    day = str(record.get("day", "?"))
    if not has_intraday(record):
        raise RvppError(f"the record of {excerpt(day)} has no intraday sessions")
    p_da = _series(record.get("bids", {}).get("p_da_mw") if isinstance(record.get("bids"), Mapping) else None,
                   None, f"the record of {excerpt(day)}: bids.p_da_mw")
    nt = len(p_da)
    dt_h = period_hours(nt)
    out = []
    for index, entry in enumerate(record["intraday"]):
        if not isinstance(entry, Mapping):
            raise RvppError(f"the record of {excerpt(day)}: intraday session {index + 1} is not a table of values")
        name = excerpt(str(entry.get("session", f"session {index + 1}")))
        where = f"the record of {excerpt(day)}, {name}"
        changes = entry.get("forecast_change_mw") or {}
        if not isinstance(changes, Mapping):
            raise RvppError(f"{where}: forecast_change_mw is not a table of sources")
        first = entry.get("window_first_period", 0)
        if not isinstance(first, int) or not 0 <= first < nt:
            raise RvppError(f"{where}: window_first_period={excerpt(first)} is not a period of the day (0 to "
                            f"{nt - 1})")
        out.append(SessionTrades(
            session=name, gate_closure=excerpt(str(entry.get("gate_closure", ""))), window_first_period=first,
            status=excerpt(str(entry.get("status", ""))),
            traded_mw=_series(entry.get("traded_mw"), nt, f"{where}: traded_mw"),
            price_eur_per_mwh=_series(entry.get("price_eur_per_mwh"), nt, f"{where}: price_eur_per_mwh"),
            position_mw=_series(entry.get("position_mw"), nt, f"{where}: position_mw"),
            trading_revenue_eur=_number(entry.get("trading_revenue_eur"), f"{where}: trading_revenue_eur"),
            expected_imbalance_before_mwh=_number(entry.get("expected_imbalance_before_mwh"),
                                                  f"{where}: expected_imbalance_before_mwh"),
            expected_imbalance_after_mwh=_number(entry.get("expected_imbalance_after_mwh"),
                                                 f"{where}: expected_imbalance_after_mwh"),
            forecast_change_mw={excerpt(str(source)): _series(values, nt, f"{where}: forecast_change_mw.{source}")
                                for source, values in changes.items()}))
    final = _series(record.get("final_position_mw"), nt, f"the record of {excerpt(day)}: final_position_mw")
    return TradingDay(day=day, label=excerpt(str(record.get("label", ""))), dt_h=dt_h, p_da_mw=p_da,
                      sessions=tuple(out), final_position_mw=final,
                      intraday_revenue_eur=_number(record.get("intraday_revenue_eur"),
                                                   f"the record of {excerpt(day)}: intraday_revenue_eur"))


def session_table(record: Mapping[str, Any], money: MoneyUnit = IN_EUR) -> pd.DataFrame:
    """One row per session: energy sold and bought [MWh], the trading cost in ``money`` (minus the
    trading revenue: positive when the plant pays, the dashboard's money convention) and the
    expected imbalance before and after the session [MWh]."""
    day = sessions(record)
    rows = []
    for s in day.sessions:
        rows.append((s.session, s.gate_closure, s.status, float(np.clip(s.traded_mw, 0.0, None).sum() * day.dt_h),
                     float(np.clip(-s.traded_mw, 0.0, None).sum() * day.dt_h), money.of(-s.trading_revenue_eur),
                     s.expected_imbalance_before_mwh, s.expected_imbalance_after_mwh))
    return pd.DataFrame(rows, columns=[c.format(money=money.symbol) for c in SESSION_COLUMNS])


def day_summary(record: Mapping[str, Any]) -> dict[str, float | None]:
    """The day's money [EUR, cost positive when the plant pays] and the imbalance the settlement
    left [MWh]: net cost, market cost, intraday trading cost, penalty, energy short and in surplus."""
    day = sessions(record)

    def value(key: str) -> float | None:
        number = record.get(key)
        return float(number) if isinstance(number, (int, float)) and math.isfinite(number) else None

    return {"net_cost_eur": value("net_cost_eur"), "market_cost_eur": value("market_cost_eur"),
            "intraday_cost_eur": -day.intraday_revenue_eur, "penalty_eur": value("penalty_eur"),
            "deficit_mwh": value("deficit_mwh"), "surplus_mwh": value("surplus_mwh")}


def _series(values: Any, length: int | None, where: str) -> np.ndarray:
    if not isinstance(values, (list, tuple)) or not values:
        raise RvppError(f"{where} is missing or not a list of numbers")
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise RvppError(f"{where} holds a value that is not a number") from None
    if array.ndim != 1 or not np.isfinite(array).all():
        raise RvppError(f"{where} holds a value that is not a finite number")
    if length is not None and len(array) != length:
        raise RvppError(f"{where} has {len(array)} values for the day's {length} periods")
    return array


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RvppError(f"{where}={excerpt(value)} is not a finite number")
    return float(value)
