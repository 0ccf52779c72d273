"""Run a function over catalog ids in worker processes, each of which loads the catalog once."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rik.errors import RikError

if TYPE_CHECKING:
    from concurrent.futures import ProcessPoolExecutor

    from rik.registry.catalog import Catalog

_CATALOG: Catalog | None = None
"""The catalog of this worker process."""


PARENT_POLL_S = 0.5
"""How often, in seconds, a worker's watch thread checks that its parent still lives."""

WORKERS_PER_CORE = 4
"""Most worker processes per core of the machine (:func:`check_workers`): each loads the catalog and its
libraries (hundreds of MB), so ``--workers 10000`` would exhaust memory long before it helped."""


def check_workers(workers: int) -> int:
    """``workers`` when it lies in 1 .. :data:`WORKERS_PER_CORE` x this machine's cores, else a one-line
    :class:`rik.errors.RikError`: checked before any process starts or any work is done."""

    most = WORKERS_PER_CORE * (os.cpu_count() or 1)
    if not 1 <= workers <= most:
        raise RikError(f"--workers {workers}: give 1 to {most} ({WORKERS_PER_CORE} per core of this machine's "
                       f"{os.cpu_count() or 1}); each worker process holds the catalog and its libraries in memory")
    return workers


def exit_with_parent(parent: int) -> None:
    """Make this (worker) process exit when process ``parent`` dies, even by ``kill -9`` or the OOM killer, so
    that no orphan keeps writing into the output or the cache, then hangs on a queue nobody reads.

    On Linux the kernel sends SIGKILL on the parent's death (``prctl(PR_SET_PDEATHSIG)``), which stops the
    worker even inside C code that holds the GIL (CoACD). Where that is unavailable, a daemon thread checks
    ``os.getppid()`` every :data:`PARENT_POLL_S` seconds. A parent already dead before either was set up is
    caught by comparing ``os.getppid()`` with ``parent``.

    PR_SET_PDEATHSIG fires when the *thread* that spawned the worker ends, not the process. That is safe for
    :func:`map_ids`: ProcessPoolExecutor (spawn context, Python 3.12) starts workers only in ``submit``, and
    map_ids submits every call at once from the thread that iterates it, which stays inside map_ids (waiting
    on the results) until the pool is shut down; the pool's manager thread spawns replacements only with
    ``max_tasks_per_child``, which map_ids does not set."""
    import sys
    import threading

    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        pr_set_pdeathsig = 1
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(pr_set_pdeathsig, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):
            pass  # the watch thread below still covers it
    if os.getppid() != parent:  # the parent died before the signal was asked for
        os._exit(1)

    def watch() -> None:
        import time

        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="rik-parent-watch", daemon=True).start()


def _load(overlays: list[Path], parent: int | None = None) -> None:
    global _CATALOG
    from rik.registry.load import load_catalog

    if parent is not None:
        exit_with_parent(parent)
    _CATALOG = load_catalog(overlays)


def _call[T](fn: Callable[[Catalog, str], T], item: str) -> tuple[str, T]:
    assert _CATALOG is not None
    return item, fn(_CATALOG, item)


def worker_pool(workers: int, overlays: Sequence[Path] = ()) -> ProcessPoolExecutor:
    """``workers`` spawned processes that each load the catalog from ``overlays`` once and exit with this process
    (:func:`exit_with_parent`); calls run there with the catalog in :data:`_CATALOG`."""
    from concurrent.futures import ProcessPoolExecutor

    check_workers(workers)
    from multiprocessing import get_context

    return ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn"), initializer=_load,
                               initargs=(list(overlays), os.getpid()))


def map_ids[T](fn: Callable[[Catalog, str], T], catalog: Catalog, ids: Sequence[str], *, workers: int = 1,
               overlays: Sequence[Path] = ()) -> Iterator[tuple[str, T]]:
    """``(id, fn(catalog, id))`` for every id, as each finishes. With ``workers`` > 1 and more than one id the
    calls run in that many spawned processes (``fn`` must be picklable: a module-level function, or a
    ``functools.partial`` of one), which load the catalog from ``overlays`` themselves; otherwise here, in order."""
    if workers > 1 and len(ids) > 1:
        from concurrent.futures import as_completed

        with worker_pool(workers, overlays) as pool:
            for future in as_completed([pool.submit(_call, fn, i) for i in ids]):
                yield future.result()
    else:
        for i in ids:
            yield i, fn(catalog, i)
