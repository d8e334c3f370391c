"""Backtest records: one row per (day, strategy, budget), written as each finishes.

A backtest's identity is a digest of its inputs (case, history, settings), so running
the same backtest again opens the same record set: the keys already recorded are
skipped and resuming is the same code path as starting. Each record is its own
transaction; an interrupted run loses at most the records in flight.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import pandas as pd
import sqlalchemy as sa

from ..data.case import Case
from .codec import case_data, history_bytes, jsonable
from .engine import StoreError, backtest_records, backtests, connect, now, put_blob


@dataclass(frozen=True, order=True)
class RecordKey:
    """What one record settles: a delivery day (ISO date), a strategy and a budget key."""

    day: str
    strategy: str
    gamma: str


@dataclass(frozen=True)
class BacktestInfo:
    id: str
    label: str
    created_at: str
    keys_total: int
    keys_done: int
    settings: dict[str, Any]


def backtest_id(case: Case, settings: Mapping[str, Any]) -> str:
    """Digest of everything a backtest depends on: the case, its history and the settings."""
    text = json.dumps({"case": case_data(case), "history": case.history.fingerprint,
                       "settings": jsonable(dict(settings))}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


class BacktestStore:
    """Backtests and their records in the store at ``url`` (default: the environment's)."""

    def __init__(self, url: str | None = None, engine: sa.Engine | None = None):
        self.engine = engine or connect(url)

    def open(self, case: Case, settings: Mapping[str, Any], keys_total: int, label: str = "") -> str:
        """Create the backtest if it is new; return its id either way."""
        ident = backtest_id(case, settings)
        with self.engine.begin() as connection:
            exists = connection.execute(sa.select(backtests.c.id).where(backtests.c.id == ident)).first()
            if exists is None:
                digest = put_blob(connection, "history.parquet", history_bytes(case.history))
                connection.execute(backtests.insert().values(
                    id=ident, label=label or f"{case.name} backtest", created_at=now(), case=case_data(case),
                    history_digest=digest, settings=jsonable(dict(settings)), keys_total=keys_total))
        return ident

    def done(self, ident: str) -> set[RecordKey]:
        """The keys already recorded."""
        query = sa.select(backtest_records.c.day, backtest_records.c.strategy, backtest_records.c.gamma).where(
            backtest_records.c.backtest_id == ident)
        with self.engine.connect() as connection:
            return {RecordKey(*row) for row in connection.execute(query)}

    def record(self, ident: str, key: RecordKey, record: Mapping[str, Any]) -> None:
        """Write one finished record in its own transaction (a rerun of the same key replaces it)."""
        values = {"status": str(record.get("status", "")), "net_cost_eur": record.get("net_cost_eur"),
                  "recorded_at": now(), "record": jsonable(dict(record))}
        where = sa.and_(backtest_records.c.backtest_id == ident, backtest_records.c.day == key.day,
                        backtest_records.c.strategy == key.strategy, backtest_records.c.gamma == key.gamma)
        with self.engine.begin() as connection:
            connection.execute(backtest_records.delete().where(where))
            connection.execute(backtest_records.insert().values(
                backtest_id=ident, day=key.day, strategy=key.strategy, gamma=key.gamma, **values))

    def records(self, ident: str) -> pd.DataFrame:
        """Every record of a backtest, one row each, ordered by day, strategy and budget."""
        query = sa.select(backtest_records.c.record).where(backtest_records.c.backtest_id == ident).order_by(
            backtest_records.c.day, backtest_records.c.strategy, backtest_records.c.gamma)
        with self.engine.connect() as connection:
            rows = [dict(row) for row in connection.execute(query).scalars()]
        return pd.DataFrame(rows)

    def list(self) -> list[BacktestInfo]:
        """Every backtest with its progress, newest first."""
        done = sa.select(backtest_records.c.backtest_id, sa.func.count().label("n")).group_by(
            backtest_records.c.backtest_id).subquery()
        query = sa.select(backtests.c.id, backtests.c.label, backtests.c.created_at, backtests.c.keys_total,
                          sa.func.coalesce(done.c.n, 0), backtests.c.settings).outerjoin(
            done, done.c.backtest_id == backtests.c.id).order_by(backtests.c.created_at.desc())
        with self.engine.connect() as connection:
            return [BacktestInfo(*row) for row in connection.execute(query)]

    def delete(self, ident: str) -> None:
        with self.engine.begin() as connection:
            connection.execute(backtest_records.delete().where(backtest_records.c.backtest_id == ident))
            if not connection.execute(backtests.delete().where(backtests.c.id == ident)).rowcount:
                raise StoreError(f"no backtest has the id {ident!r}")


def pending(keys: Iterable[RecordKey], done: set[RecordKey]) -> list[RecordKey]:
    """The keys still to compute, in their given order."""
    return [key for key in keys if key not in done]
