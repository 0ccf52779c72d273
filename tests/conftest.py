"""Shared fixtures: an isolated cache per test session, and a way to run the real CLI in-process."""

from __future__ import annotations

import faulthandler
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
os.environ.setdefault("MUJOCO_GL", "egl")  # headless rendering; must be set before mujoco is first imported
os.environ["HF_HUB_OFFLINE"] = "1"  # nothing may download at run time: tests make their own data
os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1's banner
# The CLI silences lerobot's tqdm bars (rik.cli.common.quiet_writers) before tqdm is first imported, which tqdm
# requires; in a test process another test may import tqdm first, so the in-process CLI needs it set here too.
os.environ.setdefault("TQDM_DISABLE", "1")
# One BLAS thread per test process: each pytest-xdist worker has a core of its own. OpenBLAS otherwise starts a
# thread per core in every worker and dispatches even a 430 x 5 least-squares to them; its waits spin, so with two
# workers in BLAS at once (the sysid tests) on 2 cores each call waited on a thread that could not run, and the
# suite crawled for many minutes. Set before numpy is first imported (OpenBLAS reads it then).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# For the same reason one thread for Mesa's llvmpipe (MuJoCo's EGL renders: 0.12 CPU-s per 128 px frame against 0.14
# with its default thread per core, measured on the demo's scene) and for torch's OpenMP pool, in this process and in
# the commands the tests start (they inherit it). The images are the same: llvmpipe splits a frame into tiles.
os.environ.setdefault("LP_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


SESSION_LIMIT = 3600
"""Seconds after which a test session prints every thread's stack and exits with an error: a suite that hangs
somewhere pytest-timeout cannot see (a session fixture, a worker's teardown) ends with a diagnosis, well inside CI's
90-minute limit."""


def pytest_sessionstart(session: pytest.Session) -> None:
    faulthandler.dump_traceback_later(SESSION_LIMIT, exit=True)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    faulthandler.cancel_dump_traceback_later()


BROWSER_TEST_S = 600
"""Bound of a test that drives a browser or a window, s (they take 3-30 s on an idle 2-core machine): past it the
test fails with every thread's stack (pytest-timeout), also where a call of Playwright's has no timeout of its
own (``keyboard.up`` waits for the page, which a starved machine may never schedule)."""


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A test that drives a browser or opens a window is also ``slow`` (out of the everyday tier) and bounded by
    :data:`BROWSER_TEST_S`. Files with slow tests run first: pytest-xdist hands out files in this order
    (``--no-loadscope-reorder`` in scripts/test.sh; by default it orders them by their number of tests), so the long
    ones start at once and the many short ones fill the workers' last minutes (longest first packs best)."""
    for item in items:
        if item.get_closest_marker("browser") or item.get_closest_marker("display"):
            item.add_marker(pytest.mark.slow)
            if item.get_closest_marker("timeout") is None:
                item.add_marker(pytest.mark.timeout(BROWSER_TEST_S))
    slow_files = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow_files)  # stable: each file's own order is kept


@pytest.fixture(autouse=True)
def _normal_scheduling() -> None:
    """Fail a test that leaves its process at real-time scheduling, and put it back: SVT-AV1 raises the thread that
    encodes video to SCHED_FIFO 99 when run as root (rik.scheduling), and a browser a later test starts from that
    thread inherits it: its spinning helpers then starved the machine."""
    yield
    if hasattr(os, "sched_getscheduler") and os.sched_getscheduler(0) != os.SCHED_OTHER:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        pytest.fail("the test left its process at real-time scheduling (an unguarded video encode? rik.scheduling)")


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Keep the catalog index cache out of the user's home and free of other runs' state."""
    mp = pytest.MonkeyPatch()
    if os.environ.get("PYTEST_XDIST_WORKER"):  # one cache for all of a run's workers: assets are built once
        shared = tmp_path_factory.getbasetemp().parent / "rik-cache"  # (content-addressed, written by rename)
        shared.mkdir(exist_ok=True)
        mp.setenv("RIK_CACHE", str(shared))
    else:
        mp.setenv("RIK_CACHE", str(tmp_path_factory.mktemp("rik-cache")))
    mp.delenv("RIK_CATALOG", raising=False)
    yield
    mp.undo()


SHORT_KNOB = "drawer-bedside-45__knob-mushroom-30__normal"


@pytest.fixture(scope="session")
def bow_variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A variants folder holding the demo's variant :data:`shared.BOW`, built once per test process (shared: use it
    read-only; a test that changes variants builds its own)."""
    from shared import BOW, builtin_catalog

    from rik.combinator.build import ensure_variant

    out = tmp_path_factory.mktemp("bow-variants")
    ensure_variant(builtin_catalog(), BOW, out)
    return out


@pytest.fixture(scope="session")
def knob_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with ``episodes/`` holding one short episode of :data:`SHORT_KNOB` (grasp_vertical, seed 3, 0.3 s) and
    the ``variants/`` it was recorded in, made once per session (per worker): the input that tests of damaged or
    hostile input copy, or hand to a command that must refuse something else. Tests never write into it."""
    from rik.episodes.record import record
    from rik.registry import load_catalog

    root = tmp_path_factory.mktemp("knob-recording")
    record(load_catalog(), SHORT_KNOB, "grasp_vertical", seed=3, out=root / "episodes", variants=root / "variants",
           max_seconds=0.3)
    return root


def read_line(stream, timeout: float = 120.0) -> str:
    """The next line of a child process's text ``stream``, waiting at most ``timeout`` s (an assertion error past
    it: a test never blocks on a child that stops talking). Reads on a daemon thread, which ends with the stream."""
    import queue
    import threading

    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: lines.put(stream.readline()), daemon=True).start()
    try:
        return lines.get(timeout=timeout)
    except queue.Empty:
        raise AssertionError(f"no line from the child process in {timeout:.0f} s") from None


@dataclass
class Result:
    code: int
    out: str
    err: str


@pytest.fixture
def rik(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch):
    """Run ``rik ARGS...`` through its real entry point; returns exit code, stdout and stderr."""
    from rik.cli.app import main

    def run(*args: str) -> Result:
        monkeypatch.setattr(sys, "argv", ["rik", *args])
        code = 0
        try:
            main()
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        captured = capsys.readouterr()
        return Result(code, captured.out, captured.err)

    return run
