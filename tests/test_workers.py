"""Worker processes of ``rik ... --workers N`` exit when the rik process that started them dies (kill -9, OOM)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads processes from /proc")


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent pid) of a process from /proc, or None when it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return fields[0], int(fields[1])


def _alive(pid: int) -> bool:
    stat = _stat(pid)
    return stat is not None and stat[0] not in ("Z", "X")  # a zombie has exited: only its exit status is left


def _workers_of(parent: int) -> list[int]:
    """Live children of ``parent`` that are multiprocessing workers (not its resource tracker)."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (stat := _stat(int(entry.name))) and stat[1] == parent and _alive(int(entry.name)):
            try:
                if b"spawn_main" in (entry / "cmdline").read_bytes():
                    pids.append(int(entry.name))
            except OSError:
                pass
    return pids


def _wait_for(condition: Callable[[], bool], limit_s: float) -> bool:
    """Poll ``condition`` every 0.2 s until it holds or ``limit_s`` seconds have passed."""
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.2)
    return condition()


def _listing(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


@pytest.mark.slow
def test_workers_exit_when_the_parent_is_killed(tmp_path: Path) -> None:
    cache, out = tmp_path / "cache", tmp_path / "variants"
    env = {**os.environ, "RIK_CACHE": str(cache)}
    # a fresh cache: every knob needs CoACD first (seconds each), so the workers are busy when the parent dies
    cmd = [sys.executable, "-m", "rik", "variants", "build", "--all", "--base", "drawer/chest-80", "-t", "knob",
           "-p", "normal", "--workers", "2", "--out", str(out)]
    proc = subprocess.Popen(cmd, env=env, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        assert _wait_for(lambda: len(_workers_of(proc.pid)) == 2 or proc.poll() is not None, 120)
        workers = _workers_of(proc.pid)
        assert len(workers) == 2, f"rik exited with {proc.returncode} before starting its workers"
        # the workers are past start-up and inside a build once the first asset is in the cache
        assert _wait_for(lambda: any((cache / "assets").rglob("meta.json")) or proc.poll() is not None, 300)
        assert proc.poll() is None
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        assert _wait_for(lambda: not any(_alive(w) for w in workers), 20), \
            f"workers {[w for w in workers if _alive(w)]} outlived their parent"
        before = _listing(out), _listing(cache)
        time.sleep(1.0)
        assert (_listing(out), _listing(cache)) == before  # nothing is written after the parent died
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for w in workers:
            if _alive(w):
                os.kill(w, signal.SIGKILL)


def _where(catalog: object, item: str) -> tuple[str, str | None, str]:
    """What a worker sees: its working folder, the variable RIK_TEST_WORKER_MARK and ``item``."""
    return os.getcwd(), os.environ.get("RIK_TEST_WORKER_MARK"), item


def test_workers_take_the_owners_folder_and_environment_at_each_pools_start(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each pool's workers run in the folder and with the environment their owner has when the pool starts: a
    relative output path lands in the command's folder, and a cache setting is the current one, also for a second
    pool in the same process (a forkserver, tried on 2026-11-29, holds the folder and environment of its own start:
    workers forked from it needed both passed in; docs/benchmarks.md)."""
    from rik.registry import load_catalog
    from rik.workers import map_ids

    catalog = load_catalog()
    for mark in ("one", "two"):
        folder = tmp_path / mark
        folder.mkdir()
        monkeypatch.chdir(folder)
        monkeypatch.setenv("RIK_TEST_WORKER_MARK", mark)
        seen = sorted(r for _, r in map_ids(_where, catalog, ["a", "b", "c"], workers=2))
        assert seen == [(str(folder), mark, i) for i in "abc"]
    monkeypatch.delenv("RIK_TEST_WORKER_MARK")
    assert [r[1] for _, r in map_ids(_where, catalog, ["a", "b"], workers=2)] == [None, None]  # unset is unset
