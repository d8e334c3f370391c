"""Backtest records: one row per (day, strategy, budget), written as each finishes.

A backtest's identity is a digest of its inputs (case, history, settings), so running
the same backtest again opens the same record set: the keys already recorded are
skipped and resuming is the same code path as starting. Each record is its own
transaction; an interrupted run loses at most the records in flight.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
import socket
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import pandas as pd
import sqlalchemy as sa

from ..data.case import Case, parse_case
from ..data.files import excerpt
from .codec import case_data, history_bytes, history_from, jsonable
from .engine import (StoreError, backtest_progress, backtest_records, backtests, connect, decoding,
                     drop_unused_blobs, get_blob, now, put_blob, recommendations)

STALE_AFTER_S = 600.0  # a run on another machine silent this long is taken as stopped [s]


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
    case_name: str = ""


@dataclass(frozen=True)
class BacktestProgress:
    """Where a backtest's process stands: its state, records held and expected time left.

    ``state`` is ``running``, ``finished``, ``failed``, ``interrupted`` or ``stopped`` (the
    row still says running but the process is gone: killed, or the machine restarted);
    ``eta_s`` [s] is ``None`` until the first record of the run.
    """

    backtest_id: str
    state: str
    host: str
    pid: int
    started_at: str
    updated_at: str
    done: int
    total: int
    eta_s: float | None
    message: str

    @property
    def running(self) -> bool:
        return self.state == "running"


@dataclass(frozen=True)
class StoredRecommendation:
    """A recommended Γ fraction remembered for later solves, with where it was computed.

    ``fraction``: Γ of every source as a fraction of the day [-]; ``criterion``: ``mean`` or
    ``cvar95``; ``train`` and ``test``: the periods (ISO dates, both ends included).
    """

    id: int
    backtest_id: str
    created_at: str
    case_name: str
    fraction: float
    criterion: str
    train: tuple[str, str]
    test: tuple[str, str]
    verdict: str


def backtest_id(case: Case, settings: Mapping[str, Any]) -> str:
    """Digest of everything a backtest depends on: the case, its history and the settings."""
    text = json.dumps({"case": case_data(case), "history": case.history.fingerprint,
                       "settings": jsonable(dict(settings))}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


class BacktestStore:
    """Backtests and their records in the store at ``url`` (default: the environment's)."""

    def __init__(self, url: str | None = None, engine: sa.Engine | None = None, existing: bool = False):
        """``existing``: the store at ``url`` must already be there (see :func:`~.engine.connect`)."""
        self.engine = engine or connect(url, existing=existing)

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

    def record_map(self, ident: str) -> dict[RecordKey, dict[str, Any]]:
        """Every record of a backtest by its key."""
        query = sa.select(backtest_records.c.day, backtest_records.c.strategy, backtest_records.c.gamma,
                          backtest_records.c.record).where(backtest_records.c.backtest_id == ident)
        with self.engine.connect() as connection:
            return {RecordKey(day, strategy, gamma): dict(record)
                    for day, strategy, gamma, record in connection.execute(query)}

    def load(self, ident: str) -> tuple[Case, dict[str, Any]]:
        """The case (with its history) and the settings a backtest was opened with."""
        with self.engine.connect() as connection:
            row = connection.execute(sa.select(backtests).where(backtests.c.id == ident)).first()
            if row is None:
                raise StoreError(f"no backtest has the id {ident!r}; it may have been deleted")
            history = get_blob(connection, row.history_digest)
        with decoding(f"the backtest {excerpt(ident)!r} in the store"):
            return parse_case(row.case, history_from(history, "history")), dict(row.settings)

    def set_progress(self, ident: str, state: str, done: int, total: int, eta_s: float | None = None,
                     message: str = "", started_at: str | None = None) -> None:
        """Write the progress row of the process running ``ident`` (this process, this machine)."""
        values = {"state": state, "host": socket.gethostname(), "pid": os.getpid(), "updated_at": now(),
                  "done": done, "total": total, "eta_s": eta_s, "message": message}
        with self.engine.begin() as connection:
            where = backtest_progress.c.backtest_id == ident
            if started_at is None:
                if connection.execute(backtest_progress.update().where(where).values(**values)).rowcount:
                    return
                started_at = values["updated_at"]
            connection.execute(backtest_progress.delete().where(where))
            connection.execute(backtest_progress.insert().values(backtest_id=ident, started_at=started_at,
                                                                 **values))

    def progress(self, ident: str) -> BacktestProgress | None:
        """The progress of ``ident``'s latest run (``None`` if it never ran); a ``running`` row whose
        process is gone reads ``stopped``."""
        with self.engine.connect() as connection:
            row = connection.execute(sa.select(backtest_progress).where(
                backtest_progress.c.backtest_id == ident)).first()
        if row is None:
            return None
        info = BacktestProgress(**row._asdict())
        if info.running and not _alive(info):
            info = BacktestProgress(**{**row._asdict(), "state": "stopped", "eta_s": None,
                                       "message": "the process stopped before the end; run it again to resume"})
        return info

    def list(self) -> list[BacktestInfo]:
        """Every backtest with its progress, newest first."""
        done = sa.select(backtest_records.c.backtest_id, sa.func.count().label("n")).group_by(
            backtest_records.c.backtest_id).subquery()
        query = sa.select(backtests.c.id, backtests.c.label, backtests.c.created_at, backtests.c.keys_total,
                          sa.func.coalesce(done.c.n, 0), backtests.c.settings, backtests.c.case).outerjoin(
            done, done.c.backtest_id == backtests.c.id).order_by(backtests.c.created_at.desc())
        with self.engine.connect() as connection:
            return [BacktestInfo(*row[:-1], case_name=str((row[-1] or {}).get("name", "")))
                    for row in connection.execute(query)]

    def remember_recommendation(self, ident: str, fraction: float, criterion: str, train: tuple[dt.date, dt.date],
                                test: tuple[dt.date, dt.date], verdict: str) -> StoredRecommendation:
        """Keep the recommended Γ ``fraction`` computed from backtest ``ident`` (it becomes the latest)."""
        with self.engine.begin() as connection:
            case = connection.execute(sa.select(backtests.c.case).where(backtests.c.id == ident)).scalar_one_or_none()
            if case is None:
                raise StoreError(f"no backtest has the id {ident!r}; it may have been deleted")
            inserted = connection.execute(recommendations.insert().values(
                backtest_id=ident, created_at=now(), case_name=str(case.get("name", ""))[:200],
                fraction=float(fraction), criterion=criterion, train_first=train[0].isoformat(),
                train_last=train[1].isoformat(), test_first=test[0].isoformat(), test_last=test[1].isoformat(),
                verdict=verdict))
            key = inserted.inserted_primary_key[0]
        return self._recommendation(recommendations.c.id == key)

    def recommendation(self) -> StoredRecommendation | None:
        """The latest remembered recommendation (``None`` before the first)."""
        return self._recommendation(sa.true())

    def _recommendation(self, where) -> StoredRecommendation | None:
        query = sa.select(recommendations).where(where).order_by(recommendations.c.created_at.desc(),
                                                                 recommendations.c.id.desc()).limit(1)
        with self.engine.connect() as connection:
            row = connection.execute(query).first()
        if row is None:
            return None
        return StoredRecommendation(row.id, row.backtest_id, row.created_at, row.case_name, row.fraction,
                                    row.criterion, (row.train_first, row.train_last),
                                    (row.test_first, row.test_last), row.verdict)

    def delete(self, ident: str) -> None:
        """Delete a backtest, its records and its stored history once nothing else shares it."""
        with self.engine.begin() as connection:
            connection.execute(recommendations.delete().where(recommendations.c.backtest_id == ident))
            connection.execute(backtest_records.delete().where(backtest_records.c.backtest_id == ident))
            connection.execute(backtest_progress.delete().where(backtest_progress.c.backtest_id == ident))
            if not connection.execute(backtests.delete().where(backtests.c.id == ident)).rowcount:
                raise StoreError(f"no backtest has the id {excerpt(ident)!r}")
            drop_unused_blobs(connection)


def pending(keys: Iterable[RecordKey], done: set[RecordKey]) -> list[RecordKey]:
    """The keys still to compute, in their given order."""
    return [key for key in keys if key not in done]


def _alive(info: BacktestProgress) -> bool:
    """Whether the process of a ``running`` row still runs: asked directly on this machine, judged by
    the age of its last update elsewhere."""
    if info.host == socket.gethostname():
        try:
            os.kill(info.pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        # A process started after the run it would be: its number was given again (after a restart).
        return not _zombie(info.pid) and not _started_after(info.pid, info.started_at)
    updated = dt.datetime.fromisoformat(info.updated_at)
    return (dt.datetime.now(dt.timezone.utc) - updated).total_seconds() < STALE_AFTER_S


def _started_after(pid: int, instant: str) -> bool:
    """Whether process ``pid`` started more than a second after ``instant`` (ISO 8601), from
    ``/proc`` (Linux; False where its start time cannot be read)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as stat:
            ticks = int(stat.read().rsplit(")", 1)[1].split()[19])  # field 22: start time after boot
        with open("/proc/stat", encoding="utf-8") as system:
            boot = next(int(line.split()[1]) for line in system if line.startswith("btime "))
        started = boot + ticks / os.sysconf("SC_CLK_TCK")
        return started > dt.datetime.fromisoformat(instant).timestamp() + 1.0
    except (OSError, ValueError, IndexError, StopIteration):
        return False


def _zombie(pid: int) -> bool:
    """A process that ended but was not yet reaped by its parent (Linux; False elsewhere)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] == "Z"
    except (OSError, IndexError):
        return False
