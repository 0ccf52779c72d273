"""``rik dataset build`` on a Ray cluster: two worker nodes on loopback (``ray.cluster_utils.Cluster``, one cluster
for the session), one killed mid-build; the dataset must equal the one built on local processes, and the teardown
must leave no Ray process behind."""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from shared import builtin_catalog

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = builtin_catalog()
SPEC = """repo_id: local/rik-ray
variants:
  ids: [drawer-chest-80__two_point-bow-128__normal, drawer-chest-80__knob-mushroom-30__normal]
operators:
  - strategy: contact_rich
episodes_per_variant: 2
max_seconds: 0.6
streams: [sim]
cameras: [front]
resolution: 64
shard_episodes: 2
"""
HEALTH_CHECKS = {"RAY_health_check_initial_delay_ms": "500", "RAY_health_check_period_ms": "500",
                 "RAY_health_check_timeout_ms": "1000", "RAY_health_check_failure_threshold": "3"}
"""Ray's config of its node health checks, as environment variables."""
RAY_PROGRAMS = ("raylet", "gcs_server", "ray::", "dashboard", "runtime_env_agent", "default_worker.py")


def _ray_processes() -> set[int]:
    """Pids of this machine's processes that belong to Ray (by their command line)."""
    found = set()
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if any(p in cmd for p in RAY_PROGRAMS):
            found.add(int(entry.name))
    return found


@pytest.fixture(scope="module")
def ray_sessions() -> Iterator[Path]:
    """Where Ray keeps its session folders (``RAY_TMPDIR``: its sockets, whose paths may be 107 bytes at most, and its
    logs, which Ray never removes): a short folder of this module's own, not ``/tmp/ray`` nor the run's longer
    ``TMPDIR``, removed at the end (after the cluster's teardown, also when the cluster failed to start)."""
    folder = tempfile.mkdtemp(prefix="rik-ray-", dir="/tmp")
    try:
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("RAY_TMPDIR", folder)
            yield Path(folder)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="module")
def cluster(ray_sessions: Path):
    """A head without CPUs and two worker nodes of one CPU each; shut down, and checked gone, at the end. The
    cluster's health checks run every 0.5 s and give a node up after 3 missed (Ray's defaults: 3 s and 5, after a
    5 s delay), so that a killed node is found in about 2 s rather than 15-20 (the lost-node test's call took 30 s
    against 38-41 s, 2026-11-29)."""
    os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    for name, value in HEALTH_CHECKS.items():  # read by the cluster's processes, which inherit them
        os.environ.setdefault(name, value)
    from ray.cluster_utils import Cluster

    before = _ray_processes()
    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 0, "include_dashboard": False})
    nodes = [c.add_node(num_cpus=1) for _ in range(2)]
    c.wait_for_nodes()
    assert list(ray_sessions.glob("ray/session_*")), f"Ray kept its session elsewhere than {ray_sessions}"
    yield c, nodes
    import ray

    if ray.is_initialized():
        ray.shutdown()
    c.shutdown()
    deadline = time.monotonic() + 30
    while (left := _ray_processes() - before) and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not left, f"Ray processes left behind after the cluster's shutdown: {sorted(left)}"


def _dataset_sums(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file() and p.name != "rik_build.json"}


def _plan(tmp: Path, variants: Path):
    from rik.dataset.plan import make_plan
    from rik.dataset.spec import load_spec

    spec_file = tmp / "spec.yaml"
    spec_file.write_text(SPEC)
    return make_plan(CAT, load_spec(spec_file), source="spec.yaml", variants_dir=variants)


def test_ray_build_survives_a_lost_node_and_equals_the_local_build(cluster, tmp_path: Path) -> None:
    from rik.dataset.build import build_dataset
    from rik.dataset.engines import InlineEngine, RayEngine

    c, nodes = cluster
    variants = tmp_path / "variants"
    plan = _plan(tmp_path, variants)
    local = build_dataset(CAT, plan, tmp_path / "local", InlineEngine(CAT), variants=variants, register=False)
    assert not local.failures and local.episodes == 4

    killed: list[str] = []
    engine = RayEngine(c.address, render_actors=2)  # the render actors of a GPU cluster, here on CPU
    assert engine.workers == 2 and len(engine.actors) == 2
    import ray

    homes = set(ray.get([a.node.remote() for a in engine.actors]))
    victim = next((n for n in nodes if n.node_id in homes), nodes[0])  # a worker node that hosts a render actor

    def progress(stage: str, done: int, total: int) -> None:
        if stage == "record" and done == 1 and not killed:  # a node dies while the other units are in flight
            c.remove_node(victim, allow_graceful=False)
            killed.append(victim.node_id)
    on_ray = build_dataset(CAT, plan, tmp_path / "ray", engine, variants=variants, progress=progress,
                           register=False)
    assert killed, "the build finished before a node could be killed"
    assert not on_ray.failures, on_ray.failures
    assert on_ray.ran == {"record": 4, "render": 4, "shard": 2}
    assert _dataset_sums(tmp_path / "ray") == _dataset_sums(tmp_path / "local")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("local/rik-ray", root=tmp_path / "ray", video_backend="pyav")
    assert ds.meta.total_episodes == 4 and "observation.images.front" in ds.meta.features
