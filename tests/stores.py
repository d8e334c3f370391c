"""Databases for the store's tests: a SQLite file, and a real PostgreSQL server when Debian's
``postgresql`` package is installed (started in a temporary folder, stopped afterwards)."""

from __future__ import annotations

import glob
import os
import shutil
import socket
import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

POSTGRES_BINARIES = "/usr/lib/postgresql/*/bin"


def postgres_bin() -> Path | None:
    """The newest PostgreSQL server binaries folder, if installed."""
    folders = sorted(glob.glob(POSTGRES_BINARIES), key=lambda p: int(Path(p).parent.name))
    return Path(folders[-1]) if folders else None


def postgres_missing() -> str:
    """Why the PostgreSQL tests cannot run here ('' when they can)."""
    if postgres_bin() is None:
        return "PostgreSQL is not installed (Debian: apt-get install postgresql); the store's PostgreSQL tests need it"
    try:
        import psycopg  # noqa: F401
    except ImportError:
        return "the psycopg driver is not installed"
    return ""


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _as_postgres_user() -> list[str]:
    """PostgreSQL refuses to run as root: run its tools as the ``postgres`` user then."""
    if os.geteuid() != 0:
        return []
    return ["runuser", "-u", "postgres", "--"]


@contextmanager
def postgres_server() -> Iterator[str]:
    """A fresh PostgreSQL cluster on a free local port; yields its SQLAlchemy URL."""
    binaries = postgres_bin()
    folder = Path(tempfile.mkdtemp(prefix="rvpp-pg-"))
    data, port = folder / "data", _free_port()
    prefix = _as_postgres_user()
    if prefix:
        shutil.chown(folder, "postgres", "postgres")
    run = lambda *args: subprocess.run([*prefix, *map(str, args)], check=True, capture_output=True, text=True)  # noqa: E731
    try:
        run(binaries / "initdb", "-D", data, "-U", "rvpp", "--auth=trust", "-E", "UTF8")
        run(binaries / "pg_ctl", "-D", data, "-l", folder / "server.log", "-w", "-t", "60", "start",
            "-o", f"-p {port} -k {folder} -c listen_addresses=127.0.0.1 -c fsync=off")
        run(binaries / "createdb", "-h", "127.0.0.1", "-p", port, "-U", "rvpp", "rvpp")
        yield f"postgresql+psycopg://rvpp@127.0.0.1:{port}/rvpp"
    finally:
        subprocess.run([*prefix, str(binaries / "pg_ctl"), "-D", str(data), "-m", "immediate", "stop"],
                       capture_output=True)
        shutil.rmtree(folder, ignore_errors=True)
