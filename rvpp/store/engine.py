"""Where saved runs and backtest records live: one database, one schema.

The store is written against SQLAlchemy Core, so the same code serves a local SQLite
file (the default) and a team's PostgreSQL server:

* ``RVPP_STORE_URL``: a SQLAlchemy URL, e.g. ``postgresql+psycopg://user:pw@host/rvpp``;
* otherwise ``sqlite:///<RVPP_DATA_DIR>/rvpp.sqlite3``, with ``RVPP_DATA_DIR`` defaulting to
  the folder ``rvpp-data`` in the working directory (git-ignored).

SQLite runs in WAL mode with ``synchronous=NORMAL``: readers never block the writer,
and every committed transaction survives the process being killed. Each record (a saved
run, one backtest day) is written in one transaction, so a crash loses at most the
record being written, never half of one.

Large values (history tables, result tables) are stored once in ``blobs`` under their
SHA-256 digest, so fifty runs of one case keep one copy of its history.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import os
import re
import urllib.parse
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import sqlalchemy as sa

from ..data.edits import LABEL_LENGTH
from ..data.files import excerpt
from ..errors import RvppError

URL_VARIABLE = "RVPP_STORE_URL"
DIR_VARIABLE = "RVPP_DATA_DIR"
BACKENDS = ("sqlite", "postgresql")  # the store's SQL is tested on these two
DEFAULT_DIR = "rvpp-data"
SQLITE_FILE = "rvpp.sqlite3"
BUSY_TIMEOUT_MS = 30_000  # a writer waits this long for another writer's transaction [ms]

metadata = sa.MetaData()

blobs = sa.Table(
    "blobs", metadata,
    sa.Column("digest", sa.String(64), primary_key=True),   # sha256 hex of data
    sa.Column("kind", sa.String(32), nullable=False),       # e.g. history.parquet, tables.zip
    sa.Column("size", sa.BigInteger, nullable=False),       # [bytes]
    sa.Column("data", sa.LargeBinary, nullable=False),
)

runs = sa.Table(
    "runs", metadata,
    sa.Column("id", sa.String(32), primary_key=True),
    sa.Column("label", sa.String(LABEL_LENGTH), nullable=False, unique=True),
    sa.Column("created_at", sa.String(32), nullable=False),  # ISO 8601, UTC
    sa.Column("updated_at", sa.String(32), nullable=False),
    sa.Column("case_name", sa.String(200), nullable=False),
    sa.Column("delivery_date", sa.String(10), nullable=False),
    sa.Column("strategy", sa.String(32), nullable=False),
    sa.Column("markets", sa.String(32), nullable=False),
    sa.Column("status", sa.String(32), nullable=False),
    sa.Column("objective_eur", sa.Float, nullable=True),
    sa.Column("case", sa.JSON, nullable=False),              # case.yaml layout, without the history
    sa.Column("history_digest", sa.String(64), sa.ForeignKey("blobs.digest"), nullable=False),
    sa.Column("settings", sa.JSON, nullable=False),          # run switches the case does not hold
    sa.Column("result", sa.JSON, nullable=False),            # status, timings, objective parts
    sa.Column("tables_digest", sa.String(64), sa.ForeignKey("blobs.digest"), nullable=True),
)

backtests = sa.Table(
    "backtests", metadata,
    sa.Column("id", sa.String(64), primary_key=True),        # digest of the inputs: same inputs, same id
    sa.Column("label", sa.String(LABEL_LENGTH), nullable=False),
    sa.Column("created_at", sa.String(32), nullable=False),
    sa.Column("case", sa.JSON, nullable=False),
    sa.Column("history_digest", sa.String(64), sa.ForeignKey("blobs.digest"), nullable=False),
    sa.Column("settings", sa.JSON, nullable=False),          # days, strategies, budgets, penalties, ...
    sa.Column("keys_total", sa.Integer, nullable=False),     # records the backtest will hold when done
)

backtest_records = sa.Table(
    "backtest_records", metadata,
    sa.Column("backtest_id", sa.String(64), sa.ForeignKey("backtests.id", ondelete="CASCADE"),
              primary_key=True),
    sa.Column("day", sa.String(10), primary_key=True),        # delivery day, ISO date
    sa.Column("strategy", sa.String(64), primary_key=True),   # preset name or a named variant
    sa.Column("gamma", sa.String(64), primary_key=True),      # budget key as text ("preset", "0.25", ...)
    sa.Column("status", sa.String(32), nullable=False),
    sa.Column("net_cost_eur", sa.Float, nullable=True),
    sa.Column("recorded_at", sa.String(32), nullable=False),
    sa.Column("record", sa.JSON, nullable=False),             # every number of the day, plain data
)

backtest_progress = sa.Table(
    "backtest_progress", metadata,
    sa.Column("backtest_id", sa.String(64), sa.ForeignKey("backtests.id", ondelete="CASCADE"), primary_key=True),
    sa.Column("state", sa.String(16), nullable=False),        # running, finished, failed, interrupted
    sa.Column("host", sa.String(255), nullable=False),        # machine of the process running it
    sa.Column("pid", sa.Integer, nullable=False),             # its process id there
    sa.Column("started_at", sa.String(32), nullable=False),
    sa.Column("updated_at", sa.String(32), nullable=False),
    sa.Column("done", sa.Integer, nullable=False),            # records held (including earlier runs')
    sa.Column("total", sa.Integer, nullable=False),
    sa.Column("eta_s", sa.Float, nullable=True),              # expected seconds left [s]
    sa.Column("message", sa.Text, nullable=False),
)


recommendations = sa.Table(
    "recommendations", metadata,
    sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
    sa.Column("backtest_id", sa.String(64), sa.ForeignKey("backtests.id", ondelete="CASCADE"), nullable=False),
    sa.Column("created_at", sa.String(32), nullable=False),
    sa.Column("case_name", sa.String(200), nullable=False),
    sa.Column("fraction", sa.Float, nullable=False),         # Γ as a fraction of the day, every source [-]
    sa.Column("criterion", sa.String(16), nullable=False),   # mean, cvar95
    sa.Column("train_first", sa.String(10), nullable=False),  # ISO dates of the training and test periods
    sa.Column("train_last", sa.String(10), nullable=False),
    sa.Column("test_first", sa.String(10), nullable=False),
    sa.Column("test_last", sa.String(10), nullable=False),
    sa.Column("verdict", sa.Text, nullable=False),
)


class StoreError(RvppError):
    """The store cannot be opened or refuses an operation (unknown run, label taken, ...)."""


# What reading a store may raise: a StoreError naming the store, or a database error the driver
# leaves unnamed (a connection lost mid-read, which the pool retries next time).
STORE_ERRORS = (StoreError, sa.exc.SQLAlchemyError)


# What decoding a damaged stored value raises: bad JSON or Parquet (ValueError, pyarrow's errors
# among them), a missing or mistyped field, a cut zip. (A case that breaks a rule raises CaseError.)
DAMAGED = (ValueError, TypeError, KeyError, AttributeError, IndexError, EOFError, OSError, zipfile.BadZipFile)


@contextmanager
def decoding(what: str, advice: str = "") -> Iterator[None]:
    """Name ``what`` (a saved run, a backtest) as damaged when decoding its stored values fails,
    instead of the decoder's own traceback."""
    try:
        yield
    except DAMAGED as exc:
        raise StoreError(f"{what} is damaged and cannot be opened ({type(exc).__name__}: {excerpt(exc, 120)})"
                         f"{advice}") from None


def default_url() -> str:
    """The store URL from the environment (see the module docstring)."""
    url = os.environ.get(URL_VARIABLE, "").strip()
    if url:
        return url
    folder = Path(os.environ.get(DIR_VARIABLE, "").strip() or DEFAULT_DIR)
    # Quoted: a "?", "#" or "%" in the folder's name is part of the path, not of the URL.
    return f"sqlite:///{urllib.parse.quote(str((folder / SQLITE_FILE).resolve()), safe='/')}"


def masked(url: str) -> str:
    """``url`` for a message, whatever its shape: the password between ``user:`` and the host's
    ``@`` hidden (to the last ``@`` before the path, so a password holding ``@`` stays hidden)."""
    return re.sub(r"(:/*[^:/@\s]*:)[^/]*@", r"\1***@", url)


def connect(url: str | None = None, existing: bool = False) -> sa.Engine:
    """An engine on ``url`` (default: :func:`default_url`) with the schema created.

    ``existing``: the store must already be there (an SQLite file that exists): a command that
    only reads refuses a mistyped path instead of making an empty store there."""
    given = "store URL " if url else f"{URL_VARIABLE}="  # named as the user gave it
    url = url or default_url()
    try:
        parsed = sa.make_url(url)
        parsed.port  # a port that is not a number fails here
    except (sa.exc.ArgumentError, ValueError):
        raise StoreError(f"{given}{masked(url)!r} is not a database URL such as sqlite:///runs.sqlite3 or "
                         "postgresql+psycopg://user@host/rvpp (special characters in a user name or password "
                         "are written percent-encoded, e.g. @ as %40)") from None
    shown, backend = parsed.render_as_string(hide_password=True), parsed.get_backend_name()
    if "@" in (parsed.host or ""):
        raise StoreError(f"{given}{masked(url)!r}: the host holds '@'; write an '@' of the password "
                         "percent-encoded, as %40")
    if backend not in BACKENDS:
        raise StoreError(f"{given}{shown!r}: the store is kept in SQLite or PostgreSQL, not {backend!r}; give a URL "
                         "such as sqlite:///runs.sqlite3 or postgresql+psycopg://user@host/rvpp")
    if backend == "sqlite" and parsed.database in (None, "", ":memory:"):
        raise StoreError(f"{given}{masked(url)!r} names no file: a store in memory keeps nothing; give a file, "
                         "e.g. sqlite:///runs.sqlite3")
    if existing and backend == "sqlite" and not Path(parsed.database).is_file():
        raise StoreError(f"{given}{shown!r}: no store there ({excerpt(parsed.database, 200)} does not exist); "
                         "check the path (a store is made by the first saved run or backtest)")
    try:
        if backend == "sqlite":
            engine = _sqlite_engine(parsed)
        else:
            engine = sa.create_engine(parsed, pool_pre_ping=True)
    except (ImportError, sa.exc.NoSuchModuleError) as exc:
        raise StoreError(f"cannot open the store at {shown}: its database driver is not available ({exc})") from None
    except OSError as exc:  # the store's folder cannot be made: a file of that name, a read-only disk
        where = f" (from {DIR_VARIABLE})" if given == f"{URL_VARIABLE}=" and os.environ.get(DIR_VARIABLE) else ""
        raise StoreError(f"cannot open the store at {shown}{where}: its folder cannot be made "
                         f"({exc.strerror or exc})") from None
    for attempt in (1, 2):
        try:
            _check_tables(engine, shown)
            metadata.create_all(engine)
            break
        except sa.exc.SQLAlchemyError as exc:
            # Two processes opening a new store at once: one creates a table the other then finds. The
            # second attempt sees the tables and creates nothing.
            if attempt == 2:
                raise StoreError(f"cannot open the store at {shown}: "
                                 f"{exc.__class__.__name__}: {excerpt(getattr(exc, 'orig', exc), 200)}") from None
    _name_database_errors(engine, shown)
    return engine


def _check_tables(engine: sa.Engine, shown: str) -> None:
    """Refuse a database whose tables of rvpp's names lack rvpp's columns (a file of another
    program), before anything is created in it. A store of an older version, which lacks only
    tables added since, is fine: they are created."""
    inspector = sa.inspect(engine)
    present = set(inspector.get_table_names())
    for table in metadata.sorted_tables:
        if table.name in present:
            missing = {c.name for c in table.columns} - {c["name"] for c in inspector.get_columns(table.name)}
            if missing:
                raise StoreError(f"the database at {shown} is not an rvpp store: its table {table.name!r} has no "
                                 f"column {sorted(missing)[0]!r}; give another with {URL_VARIABLE} or "
                                 f"{DIR_VARIABLE}")


def _name_database_errors(engine: sa.Engine, shown: str) -> None:
    """Have the database's refusals (a full disk, a read-only file, a file of another program's
    tables, a value the column cannot hold) reach the user as :class:`StoreError` naming the
    store, not as a driver's traceback. A taken key (``IntegrityError``) is left to the caller,
    which picks another label; a lost connection is left to the pool, which reconnects."""

    @sa.event.listens_for(engine, "handle_error")
    def _named(context) -> StoreError | None:
        error = context.sqlalchemy_exception
        if context.is_disconnect or error is None or isinstance(error, sa.exc.IntegrityError):
            return None
        if isinstance(error, sa.exc.DBAPIError):
            return StoreError(f"the store at {shown} refused the operation "
                              f"({excerpt(context.original_exception, 200)}); if it is not rvpp's store, "
                              f"give another with {URL_VARIABLE} or {DIR_VARIABLE}")
        return None


def _sqlite_engine(url: sa.URL) -> sa.Engine:
    Path(url.database).parent.mkdir(parents=True, exist_ok=True)  # connect refuses a store in memory
    engine = sa.create_engine(url, connect_args={"timeout": BUSY_TIMEOUT_MS / 1000})

    @sa.event.listens_for(engine, "connect")
    def _pragmas(connection, _record) -> None:
        cursor = connection.cursor()
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA synchronous=NORMAL")
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
        cursor.close()

    return engine


def now() -> str:
    """The current instant as ISO 8601 in UTC, to the microsecond (sorts as text)."""
    return dt.datetime.now(dt.timezone.utc).isoformat(timespec="microseconds")


def put_blob(connection: sa.Connection, kind: str, data: bytes) -> str:
    """Store ``data`` once under its digest (inside the caller's transaction); return the digest."""
    digest = hashlib.sha256(data).hexdigest()
    exists = connection.execute(sa.select(blobs.c.digest).where(blobs.c.digest == digest)).first()
    if exists is None:
        connection.execute(blobs.insert().values(digest=digest, kind=kind, size=len(data), data=data))
    return digest


def get_blob(connection: sa.Connection, digest: str) -> bytes:
    """A stored value, checked against its digest."""
    data = connection.execute(sa.select(blobs.c.data).where(blobs.c.digest == digest)).scalar_one_or_none()
    if data is None:
        raise StoreError(f"the store has lost a stored table ({digest[:12]}); the run cannot be opened")
    if hashlib.sha256(data).hexdigest() != digest:
        raise StoreError(f"a stored table ({digest[:12]}) is damaged: its content no longer matches its digest")
    return bytes(data)


def drop_unused_blobs(connection: sa.Connection) -> int:
    """Delete blobs no run or backtest refers to; return how many went."""
    used = sa.union(sa.select(runs.c.history_digest), sa.select(runs.c.tables_digest),
                    sa.select(backtests.c.history_digest)).subquery()
    stale = sa.select(blobs.c.digest).where(blobs.c.digest.not_in(
        sa.select(used.c[0]).where(used.c[0].is_not(None))))
    return connection.execute(blobs.delete().where(blobs.c.digest.in_(stale))).rowcount
