"""Where many solves run: serially, on a local process pool or on a Dask cluster.

:func:`open_executor` turns the ``--scheduler`` setting of the command line into a
``concurrent.futures.Executor`` (or ``None`` for serial runs) and shuts it down
afterwards:

* ``processes`` (default): a local pool of worker processes;
* ``serial``: no executor, every solve in the calling process;
* ``local``: a Dask ``LocalCluster`` of worker processes started for the run;
* any other value: the address of a running Dask scheduler, e.g.
  ``tcp://10.0.0.5:8786``; the work then runs on that cluster's workers.

Workers build and solve in their own process and return plain data.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

from ..errors import RvppError

SCHEDULERS = ("processes", "serial", "local")
PARENT_CHECK_S = 2.0  # how often a pool worker looks whether the process that started it is still there


def default_workers() -> int:
    """Worker processes of a local pool: the cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@contextmanager
def open_executor(scheduler: str = "processes", workers: int | None = None) -> Iterator[Executor | None]:
    """The executor for ``scheduler`` (see the module docstring), closed on exit.

    A local pool (``processes``, ``local``) has at most one worker per core: more would
    only share the cores, each holding a model in memory.
    """
    cores = default_workers()
    workers = workers or cores
    if workers < 1:
        raise RvppError(f"--workers={workers} must be at least 1")
    workers = min(workers, cores)
    if scheduler == "serial":
        yield None
    elif scheduler == "processes":
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=end_with_parent, initargs=(os.getpid(),)) as pool:
            yield pool
    elif scheduler == "local":
        with _dask_local(workers) as executor:
            yield executor
    else:
        with _dask_remote(scheduler) as executor:
            yield executor


def end_with_parent(parent: int) -> None:
    """In a pool worker: end the worker once ``parent`` (the process that started the pool) is
    gone, e.g. killed with ``kill -9``, which gives its workers no word; they would otherwise
    wait for work forever, each holding its imports in memory."""
    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_S)
        os._exit(1)

    threading.Thread(target=watch, name="rvpp-parent-watch", daemon=True).start()


@contextmanager
def _dask_local(workers: int) -> Iterator[Executor]:
    from dask.distributed import Client, LocalCluster  # heavy: Dask loads only when a cluster is asked for

    with LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client.get_executor()


@contextmanager
def _dask_remote(address: str) -> Iterator[Executor]:
    from dask.distributed import Client  # heavy: Dask loads only when a cluster is asked for

    try:
        client = Client(address, timeout="20s")
    except (OSError, TimeoutError) as exc:
        raise RvppError(f"--scheduler {address!r}: cannot reach a Dask scheduler there ({exc}); "
                        f"use one of {', '.join(SCHEDULERS)} or a scheduler address") from None
    with client:
        yield client.get_executor()
