"""Shared fixtures: an isolated cache per test session, and a way to run the real CLI in-process."""

from __future__ import annotations

import faulthandler
import gc
import os
import sys
from collections.abc import Callable
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

GC_THRESHOLDS = (5000, 20, 100)
"""The cyclic garbage collector's thresholds in the test processes (``gc.set_threshold``; Python's are 700, 10, 10;
``RIK_TEST_GC=A,B,C`` sets others). A worker holds torch, LeRobot, MuJoCo, Mitsuba and its tests' fixtures (2.7-4 GB
at its peak), and every full collection walks all of it: with Python's thresholds each worker made 15-18 of them in a
run, 0.4-0.8 s each, and the collector took 8 % of the everyday tier's worker CPU. These look at the oldest generation
ten times less often (Python still skips a full collection until a quarter of the long-lived objects are new), so
cyclic garbage is still collected, later: 2 full collections a worker (benchmarks/suite_gc.py; docs/benchmarks.md,
"The test suite's CPU")."""


def _gc_thresholds() -> tuple[int, ...]:
    given = os.environ.get("RIK_TEST_GC")
    return tuple(int(n) for n in given.split(",")) if given else GC_THRESHOLDS


gc.set_threshold(*_gc_thresholds())


SESSION_LIMIT = 3600
"""Seconds after which a test session prints every thread's stack and exits with an error: a suite that hangs
somewhere pytest-timeout cannot see (a session fixture, a worker's teardown) ends with a diagnosis, well inside CI's
90-minute limit."""


def pytest_sessionstart(session: pytest.Session) -> None:
    faulthandler.dump_traceback_later(SESSION_LIMIT, exit=True)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    faulthandler.cancel_dump_traceback_later()
    if CPU_LOG:
        _write_gc_log()


CPU_LOG = os.environ.get("RIK_TEST_CPU_LOG")
"""A folder (optional) where each test process appends a line per test: its node id, the CPU-s of the test process
itself (every thread) and of the child processes it waited for, and the wall-clock s; one file per process. Where
the suite's CPU goes (docs/benchmarks.md, "The test suite's CPU"): ``RIK_TEST_CPU_LOG=/tmp/cpu bash scripts/test.sh``."""


_GC_CLOCK = [0.0, 0.0]
"""This process's CPU clock at the collection under way, and its CPU-s in the cyclic garbage collector so far (with
the CPU log on)."""
_GC_COLLECTIONS = [0, 0, 0]
"""This process's collections so far, per generation."""


def _time_gc(phase: str, info: dict[str, int]) -> None:
    import time

    if phase == "start":
        _GC_CLOCK[0] = time.process_time()
    else:
        _GC_CLOCK[1] += time.process_time() - _GC_CLOCK[0]
        _GC_COLLECTIONS[info["generation"]] += 1


def _write_gc_log() -> None:
    """``<pid>.gc`` in the CPU log: the collector's CPU-s, its collections per generation, this process's CPU-s and
    its peak resident memory (MB)."""
    import resource

    own = resource.getrusage(resource.RUSAGE_SELF)
    Path(CPU_LOG).mkdir(parents=True, exist_ok=True)
    (Path(CPU_LOG) / f"{os.getpid()}.gc").write_text(
        f"{_GC_CLOCK[1]:.2f}\t{','.join(map(str, _GC_COLLECTIONS))}\t{own.ru_utime + own.ru_stime:.2f}\t"
        f"{own.ru_maxrss / 1024:.0f}\n")


if CPU_LOG:
    gc.callbacks.append(_time_gc)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    if not CPU_LOG:
        yield
        return
    import resource
    import time

    def cpu() -> tuple[float, float]:
        own, waited = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime, waited.ru_utime + waited.ru_stime

    (own0, waited0), start = cpu(), time.monotonic()
    yield
    (own1, waited1), wall = cpu(), time.monotonic() - start
    Path(CPU_LOG).mkdir(parents=True, exist_ok=True)
    with open(Path(CPU_LOG) / f"{os.getpid()}.tsv", "a") as log:
        log.write(f"{item.nodeid}\t{own1 - own0:.2f}\t{waited1 - waited0:.2f}\t{wall:.2f}\n")


BROWSER_TEST_S = 600
"""Bound of a test that drives a browser or a window, s (they take 3-30 s on an idle 2-core machine): past it the
test fails with every thread's stack (pytest-timeout), also where a call of Playwright's has no timeout of its
own (``keyboard.up`` waits for the page, which a starved machine may never schedule)."""


FILE_SECONDS: dict[str, tuple[int, int]] = {
    "test_web_teleop.py": (139, 0), "test_sysid_discover.py": (107, 0), "test_policy_loop.py": (101, 0),
    "test_dataset_ray.py": (94, 0), "test_dataset_build.py": (86, 0), "test_cli_catalog.py": (83, 4),
    "test_env_robots.py": (81, 0), "test_export.py": (77, 3), "test_finger.py": (75, 0), "test_render.py": (65, 0), "test_image_eval.py": (17, 0), "test_images_only.py": (20, 0),
    "test_policy_experiment.py": (52, 0), "test_teleop_viewer.py": (44, 0), "test_assets_import.py": (39, 0),
    "test_export_robots.py": (39, 0), "test_web_viewer3d.py": (34, 1), "test_sysid_foreign_discover.py": (33, 0),
    "test_combinator.py": (9, 21), "test_web_catalog.py": (24, 0), "test_sysid_cli.py": (4, 18),
    "test_dataset_draw.py": (19, 0), "test_sim.py": (0, 19), "test_hostile_input.py": (0, 18),
    "test_record_split.py": (18, 0), "test_swing_grasp.py": (10, 7), "test_collision_mode.py": (16, 0),
    "test_assets_core.py": (7, 9), "test_robots_sim.py": (5, 11), "test_output_contract.py": (3, 12),
    "test_web_security.py": (10, 5), "test_nothing_lost.py": (7, 7), "test_dataset_scale.py": (5, 9),
    "test_visual_gap.py": (8, 5), "test_layering.py": (0, 13), "test_workers.py": (12, 0),
    "test_assets_import_base.py": (11, 0), "test_bounded_reader.py": (3, 8), "test_gen_knobs.py": (4, 7),
    "test_gen_two_point.py": (5, 5), "test_untrusted_folders.py": (0, 10), "test_sysid_generate.py": (3, 6),
    "test_export_outcomes.py": (0, 8), "test_teleop_view_model.py": (7, 1), "test_sysid_roundtrip.py": (0, 8),
    "test_handle_shape.py": (3, 4), "test_eval_labels.py": (0, 6), "test_leader_teleop.py": (0, 4),
}
"""Seconds a worker spent in each of the longest test files (its ``slow`` tests, its others) in a run of the whole
suite and one of the everyday tier with three workers on an idle 2-core machine (2026-11-28): the order in which
:func:`pytest_collection_modifyitems` hands the files out. Only the order depends on them; a file not listed
(a few seconds) runs after these, slow files first."""


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A test that drives a browser or opens a window is also ``slow`` (out of the everyday tier) and bounded by
    :data:`BROWSER_TEST_S`. The longest files run first (:data:`FILE_SECONDS`, counting only the part of a file that
    this run selects), then the other files with slow tests, then the rest: pytest-xdist hands out files in this
    order (``--no-loadscope-reorder`` in scripts/test.sh; by default it orders them by their number of tests), so
    the long ones start at once and the many short ones fill the workers' last minutes (longest first packs best;
    the files that wait on a browser or a window at a person's pace run beside ones that keep the cores busy)."""
    for item in items:
        if item.get_closest_marker("browser") or item.get_closest_marker("display"):
            item.add_marker(pytest.mark.slow)
            if item.get_closest_marker("timeout") is None:
                item.add_marker(pytest.mark.timeout(BROWSER_TEST_S))
    slow_files = {item.path for item in items if item.get_closest_marker("slow")}
    fast_files = {item.path for item in items if not item.get_closest_marker("slow")}
    seconds = {path: (FILE_SECONDS.get(path.name, (0, 0))[0] if path in slow_files else 0)
               + (FILE_SECONDS.get(path.name, (0, 0))[1] if path in fast_files else 0)
               for path in slow_files | fast_files}
    # stable: each file's own order is kept, and files of equal weight stay in collection order
    items.sort(key=lambda item: (-seconds[item.path], item.path not in slow_files))


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
    """Keep rik's cache out of the user's home and free of other runs' state; and the Arrow copies that Hugging Face
    ``datasets`` makes of every LeRobot dataset a test or a command it starts loads (``lerobot-train``, a test's own
    ``LeRobotDataset``; rik's own loads use :func:`rik.lerobot.arrow_cache.scratch_arrow_cache`): in the run's
    temporary folder, not ``~/.cache/huggingface``. The machine's temporary folder too (``TMPDIR``, and ``tempfile``'s
    own in this process): what the libraries under test leave there (LeRobot's ``lerobot-eval`` and
    ``lerobot-train`` a copy of each policy config they load, multiprocessing a ``pymp-*`` folder where a test kills
    its owner) stays inside the run's folder, not ``/tmp``."""
    import tempfile

    mp = pytest.MonkeyPatch()
    if os.environ.get("PYTEST_XDIST_WORKER"):  # one cache for all of a run's workers: assets are built once
        shared = tmp_path_factory.getbasetemp().parent / "rik-cache"  # (content-addressed, written by rename)
        shared.mkdir(exist_ok=True)
        mp.setenv("RIK_CACHE", str(shared))
        scratch = tmp_path_factory.getbasetemp().parent / "tmp"
    else:
        mp.setenv("RIK_CACHE", str(tmp_path_factory.mktemp("rik-cache")))
        scratch = tmp_path_factory.getbasetemp() / "tmp"
    scratch.mkdir(exist_ok=True)
    mp.setenv("TMPDIR", str(scratch))
    mp.setattr(tempfile, "tempdir", str(scratch))
    mp.delenv("RIK_CATALOG", raising=False)
    arrow = tmp_path_factory.getbasetemp() / "hf-datasets"
    mp.setenv("HF_DATASETS_CACHE", str(arrow))  # read when datasets is first imported, here and in child processes
    if "datasets.config" in sys.modules:  # imported already (while collecting a test module)
        mp.setattr(sys.modules["datasets.config"], "HF_DATASETS_CACHE", arrow)
    yield
    mp.undo()


SHORT_KNOB = "drawer-bedside-45__knob-mushroom-30__normal"


def shared_folder(tmp_path_factory: pytest.TempPathFactory, name: str, build: Callable[[Path], None]) -> Path:
    """The folder ``name`` that ``build(folder)`` fills, made once per run: under pytest-xdist the first worker that
    asks builds it in a temporary folder beside the shared cache (:func:`_isolated_cache`) and renames it into place,
    holding a file lock, while the others wait for it and then use the same folder; without workers, in this
    session's own temporary directory. Users treat it as read-only (a test that changes it works on a copy)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        folder = tmp_path_factory.mktemp(name)
        build(folder)
        return folder
    import fcntl
    import shutil
    import tempfile

    root = tmp_path_factory.getbasetemp().parent / "shared"
    root.mkdir(exist_ok=True)
    folder = root / name
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes (also when this process dies)
        if not folder.is_dir():
            staging = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=root))
            try:
                build(staging)
                staging.rename(folder)  # complete, or not there at all
            finally:
                shutil.rmtree(staging, ignore_errors=True)
    return folder


@pytest.fixture(scope="session")
def bow_variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A variants folder holding the demo's variant :data:`shared.BOW`, built once per run and shared by the test
    processes (:func:`shared_folder`: use it read-only; a test that changes variants builds its own)."""
    from shared import BOW, builtin_catalog

    from rik.combinator.build import ensure_variant

    return shared_folder(tmp_path_factory, "bow-variants", lambda out: ensure_variant(builtin_catalog(), BOW, out))


@pytest.fixture(scope="session")
def knob_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with ``episodes/`` holding one short episode of :data:`SHORT_KNOB` (grasp_vertical, seed 3, 0.3 s) and
    the ``variants/`` it was recorded in, made once per run and shared by the test processes (:func:`shared_folder`):
    the input that tests of damaged or hostile input copy, or hand to a command that must refuse something else.
    Tests never write into it."""
    from rik.episodes.record import record
    from rik.registry import load_catalog

    def build(root: Path) -> None:
        record(load_catalog(), SHORT_KNOB, "grasp_vertical", seed=3, out=root / "episodes",
               variants=root / "variants", max_seconds=0.3)

    return shared_folder(tmp_path_factory, "knob-recording", build)


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
