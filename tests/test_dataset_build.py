"""``rik dataset plan|build|list|show|verify``: a small spec built once on local processes and shared by the tests
(load, rebuild, reuse of a work folder, kill -9 and resume, verify, list/show); bad specs and options."""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from shared import BOW

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

SPEC = """\
repo_id: local/rik-small
variants:
  ids: [drawer-chest-80__two_point-bow-128__normal, drawer-chest-80__knob-mushroom-30__normal]
operators:
  - strategy: contact_rich
episodes_per_variant: 2
max_seconds: 0.6
streams: [sim]
resolution: 64
shard_episodes: 2
"""
BUILD_META = "meta/rik_build.json"
RAY_WATCH = """import os, sys
mark = os.environ["RIK_TEST_RAY_MARK"]
with open(mark + ".started", "a") as log:
    log.write(f"{os.getpid()}\\n")


class RayWatch:
    def find_spec(self, name, path=None, target=None):
        if name == "ray" or name.startswith("ray."):
            with open(mark, "a") as log:
                log.write(f"{os.getpid()} {name}\\n")
        return None


sys.meta_path.insert(0, RayWatch())
"""
"""A ``sitecustomize`` for the build's processes (on ``PYTHONPATH``, so the spawned workers start it too): each notes
its pid in ``$RIK_TEST_RAY_MARK.started`` and, if it ever imports Ray, its pid and the module in
``$RIK_TEST_RAY_MARK`` (an import hook: a worker that ends without running exit handlers is still seen)."""


def rik_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "rik", *args]


def files_state(*roots: Path) -> dict[str, tuple[str, int]]:
    """sha256 and mtime (ns) of every file below ``roots``, by path."""
    out = {}
    for root in roots:
        for p in sorted(root.rglob("*")):
            if p.is_file():
                out[str(p)] = (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns)
    return out


def dataset_sums(root: Path) -> dict[str, str]:
    """sha256 of every file of a dataset but the build's statistics, by relative path."""
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file() and p.relative_to(root).as_posix() != BUILD_META}


@pytest.fixture(scope="module")
def spec_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("spec") / "spec.yaml"
    path.write_text(SPEC)
    return path


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The variants folder every build here shares (the first build fills it)."""
    return tmp_path_factory.mktemp("variants") / "V"


@pytest.fixture(scope="module")
def ray_watch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding :data:`RAY_WATCH` as ``sitecustomize.py``, where :func:`built`'s processes note themselves
    (``imported.started``) and any import of Ray (``imported``)."""
    watch = tmp_path_factory.mktemp("ray-watch")
    (watch / "sitecustomize.py").write_text(RAY_WATCH)
    return watch


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory, spec_file: Path, variants: Path, ray_watch: Path
          ) -> tuple[Path, str]:
    """The spec built once with two local worker processes: (dataset folder, the build's stdout). Its processes run
    :data:`RAY_WATCH` from :func:`ray_watch`."""
    out = tmp_path_factory.mktemp("build") / "ds"
    path = os.pathsep.join([str(ray_watch), *filter(None, [os.environ.get("PYTHONPATH")])])
    r = subprocess.run(rik_cmd("dataset", "build", str(spec_file), "--out", str(out), "-j", "2", "--variants",
                               str(variants)), capture_output=True, text=True, timeout=900,
                       env={**os.environ, "PYTHONPATH": path, "RIK_TEST_RAY_MARK": str(ray_watch / "imported")})
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    assert "Copy data and videos" not in r.stderr and "Map:" not in r.stderr  # lerobot's bars stay off rik's
    return out, r.stdout


def test_a_local_build_never_imports_ray(built, ray_watch: Path) -> None:
    """Ray is optional: a build on local processes never imports it, neither the command's process nor the workers
    that record, render and shard (this module's build, watched by :data:`RAY_WATCH`; the Ray engine's own test is
    tests/test_dataset_ray.py)."""
    started = (ray_watch / "imported.started").read_text().split()
    assert len(set(started)) >= 3, started  # the command and its two workers ran the watch
    assert not (ray_watch / "imported").exists(), (ray_watch / "imported").read_text()


def test_the_web_apps_episodes_page_lists_the_built_dataset_with_its_numbers(built, tmp_path: Path) -> None:
    """The dataset this module built, in the datasets folder of ``rik serve``: the episodes page's row has its name,
    repo id, robot, episodes, frames and outcomes as the build recorded them (here, where a real build exists)."""
    import json

    from web_fixtures import app_client

    from rik.registry.load import load_catalog
    from rik.web.app import AppConfig

    out, _ = built
    recorded = json.loads((out / "meta" / "rik_dataset.json").read_text())
    config = AppConfig(load_catalog(), variants=tmp_path / "variants", episodes=tmp_path / "ep", datasets=out.parent)
    with app_client(config) as client:
        row, = client.get("/api/episodes").json()["datasets"]
    assert row == {"name": out.name, "repo_id": "local/rik-small", "robot": "hand-e",
                   "episodes": recorded["counts"]["episodes"], "frames": recorded["counts"]["frames"],
                   "variants": 2, "outcomes": recorded["outcomes"], "streams": ["sim"]}
    assert row["episodes"] == 4 and row["frames"] > 4


def test_build_loads_and_rebuild_does_nothing(rik, built, spec_file, variants) -> None:
    out, stdout = built
    assert "engine: local processes, 2 workers" in stdout
    assert "ran record 4, render 4, shard 2 units (0 reused)" in stdout
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("local/rik-small", root=out, video_backend="pyav")
    assert ds.meta.total_episodes == 4
    names = set(ds.meta.features)
    assert {"observation.state", "observation.environment_state", "action"} <= names
    episodes = ds.meta.episodes
    for col in ("rik/episode_id", "rik/variant", "rik/operator", "rik/outcome", "rik/seed"):
        assert col in episodes.column_names, episodes.column_names
    assert sorted(set(episodes["rik/variant"])) == ["drawer-chest-80__knob-mushroom-30__normal",
                                                    BOW]
    assert sorted(episodes["rik/seed"]) == [0, 0, 1, 1]
    images = [n for n in names if n.startswith("observation.images.")]
    assert images, sorted(names)
    frame = ds[0]
    img = frame[images[0]]
    assert tuple(img.shape) == (3, 64, 64) and float(img.max()) > 0

    work = out.with_name("ds.work")
    before = files_state(out, work)
    r = rik("dataset", "build", str(spec_file), "--out", str(out), "-j", "2", "--variants", str(variants))
    assert r.code == 0, r
    assert "already built from this spec; nothing to do (4 episodes)" in r.out
    assert files_state(out, work) == before


def test_new_out_with_same_work_reuses_every_unit(rik, built, spec_file, variants, tmp_path) -> None:
    out, _ = built
    again = tmp_path / "again"
    r = rik("dataset", "build", str(spec_file), "--out", str(again), "-j", "1", "--variants", str(variants),
            "--work", str(out.with_name("ds.work")))
    assert r.code == 0, r
    assert "ran record 0, render 0, shard 0 units (10 reused)" in r.out
    assert not again.with_name("again.work").exists()
    first, second = dataset_sums(out), dataset_sums(again)
    assert first.keys() == second.keys()
    assert [k for k in first if first[k] != second[k]] == []


def _children(pid: int) -> set[int]:
    """Pids of the living children of ``pid`` (every thread's)."""
    kids: set[int] = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            kids |= {int(c) for c in (task / "children").read_text().split()}
        except OSError:
            pass
    return kids


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, exited but not yet reaped, does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def test_kill_and_resume(rik, built, spec_file, variants, tmp_path) -> None:
    out = tmp_path / "ds"
    work = tmp_path / "ds.work"
    env = {**os.environ, "MUJOCO_GL": "egl"}
    proc = subprocess.Popen(rik_cmd("dataset", "build", str(spec_file), "--out", str(out), "-j", "2",
                                    "--variants", str(variants)),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 600
        while not any((work / "units" / "record").glob("*.json")):
            assert proc.poll() is None, "the build ended before it recorded an episode"
            assert time.monotonic() < deadline, "no episode recorded in 600 s"
            time.sleep(0.05)
        children = _children(proc.pid)
        assert len(children) >= 2, children  # two workers (and multiprocessing's resource tracker)
        assert not out.exists()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        deadline = time.monotonic() + 15
        while (left := {c for c in children if _alive(c)}) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not left, f"workers outlived the killed build: {left}"
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # whatever is left of its session, should the test fail
        except ProcessLookupError:
            pass
    assert not out.exists()
    r = rik("dataset", "build", str(spec_file), "--out", str(out), "-j", "1", "--variants", str(variants))
    assert r.code == 0, r
    line = next(x for x in r.out.splitlines() if x.startswith("ran record"))
    reused = int(line.split("(")[1].split()[0])
    assert reused > 0, line
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    assert LeRobotDataset("local/rik-small", root=out, video_backend="pyav").meta.total_episodes == 4
    first, resumed = dataset_sums(built[0]), dataset_sums(out)
    assert first.keys() == resumed.keys()
    assert [k for k in first if first[k] != resumed[k]] == []


def test_verify_passes_and_finds_corruption(rik, built, tmp_path) -> None:
    out, _ = built
    r = rik("dataset", "verify", str(out))
    assert r.code == 0, r
    assert "ok:" in r.out and "4 episodes" in r.out
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    victim = sorted((copy / "data").rglob("*.parquet"))[0]
    raw = bytearray(victim.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    victim.write_bytes(bytes(raw))
    rel = victim.relative_to(copy).as_posix()
    r = rik("dataset", "verify", str(copy))
    assert r.code == 2, r
    assert "Traceback" not in r.err
    assert f"{rel}: sha256 differs" in r.out
    assert r.err.strip().splitlines() == [f"rik: error: {copy}: 1 problem, listed above"]
    assert dataset_sums(out) != dataset_sums(copy)  # the shared dataset is untouched: verify it again
    assert rik("dataset", "verify", str(out)).code == 0


def test_list_and_show(rik, built) -> None:
    import json

    out, _ = built
    meta = json.loads((out / "meta" / "rik_dataset.json").read_text())
    prefix = meta["spec_hash"][:12]
    r = rik("dataset", "list", "--json")
    assert r.code == 0, r
    rows = [row for row in json.loads(r.out) if row["path"] == str(out)]
    assert len(rows) == 1 and rows[0]["repo_id"] == "local/rik-small" and rows[0]["episodes"] == 4
    assert rows[0]["spec_hash"] == meta["spec_hash"]
    r = rik("dataset", "list")
    assert r.code == 0 and "local/rik-small" in r.out and prefix in r.out, r
    r = rik("dataset", "show", str(out))
    assert r.code == 0, r
    assert f"local/rik-small, spec hash {prefix}" in r.out and "4 episodes" in r.out
    r = rik("dataset", "show", str(out), "--json")
    assert r.code == 0, r
    info = json.loads(r.out)
    assert info["episodes"] == 4 and info["spec_hash"] == meta["spec_hash"] and info["repo_id"] == "local/rik-small"


def test_plan_prints_counts_and_estimate(rik, built, spec_file, variants) -> None:
    r = rik("dataset", "plan", str(spec_file), "--sample", "1", "--variants", str(variants))
    assert r.code == 0, r
    assert "2 variants x 1 operators (contact_rich) x 2 episodes = 4 episodes" in r.out
    for stage in ("record", "render:sim", "export"):
        assert any(line.strip("│┃ ").startswith(stage) for line in r.out.splitlines()), (stage, r.out)


# ---- bad input: one line, exit 2, nothing written ---------------------------------------------------------------
BASE = "repo_id: local/rik-small\noperators:\n  - strategy: contact_rich\n"
BAD_SPECS = {
    "malformed": ("repo_id: local/x\noperators: [strategy: contact_rich\n",
                  ["bad.yaml:3: malformed YAML"]),
    "unknown_field": (BASE + "episodes: 3\n",
                      ["bad.yaml:4, field 'episodes': unknown field; valid fields: ", "episodes_per_variant"]),
    "unknown_variant": (BASE + "variants:\n  ids: [drawer-chest-80__two_point-nope-128__normal]\n",
                        ["bad.yaml, field 'variants.ids.0': no handle 'two_point-nope-128'"]),
    "unknown_split": (BASE + "variants: {split: holdout}\n",
                      ["bad.yaml, field 'variants.split': unknown split 'holdout'", "train, val, test, or all for every handle"]),
    "unknown_strategy": ("repo_id: local/x\noperators:\n  - strategy: teleport\n",
                         ["bad.yaml, field 'operators.0.strategy': unknown strategy 'teleport'", "contact_rich"]),
    "selects_nothing": (BASE + "variants: {handles: [knob/mushroom-30], handle_types: [two_point]}\n",
                        ["bad.yaml, field 'variants': the selection keeps no variant"]),
    "environment_state_not_a_flag": (BASE + 'environment_state: "no"\n',
                                     ["bad.yaml:4, field 'environment_state': input should be a valid boolean "
                                      "(got 'no')"]),
    "no_front_state_and_no_images": (BASE + "environment_state: false\nstreams: []\n",
                                     ["bad.yaml, field 'environment_state': environment_state False: a policy "
                                      "without the front's state reads the robot's state and images: give it "
                                      "streams (sim)"]),
    "unknown_robot": (BASE + "robot: so10\n",
                      ["bad.yaml, field 'robot': no robot 'so10' in the catalog; did you mean 'so101' or 'so100'? (the catalog's robots: hand-e, panda-2f85, so100, so101)"]),
}


def _one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("rik: error: "), lines
    return lines[0]


@pytest.mark.parametrize("case", sorted(BAD_SPECS))
def test_bad_spec(rik, tmp_path, case: str) -> None:
    text, parts = BAD_SPECS[case]
    written = ["bad.yaml"]
    spec = tmp_path / "bad.yaml"
    spec.write_text(text)
    out = tmp_path / "out"
    r = rik("dataset", "build", str(spec), "--out", str(out), "--variants", str(tmp_path / "variants"))
    assert r.code == 2, r
    assert "Traceback" not in r.err and r.out == ""
    line = _one_line(r.err)
    for part in parts:
        assert part in line, (part, line)
    assert sorted(p.name for p in tmp_path.iterdir()) == written  # no out, out.work or variants


@pytest.mark.parametrize("robot", ["so100", "so101"])
def test_spec_robot_records_and_exports_that_robot(rik, tmp_path, variants, robot: str) -> None:
    """``robot: so100`` (or ``so101``): the episodes are that arm's (their ids say so), the dataset is in its layout; a spec that
    names the Hand-E, rik's default, hashes as one that names no robot (specs from before robots keep their hash)."""
    import json

    from rik.dataset.spec import load_spec, spec_hash

    spec = tmp_path / f"{robot}.yaml"
    spec.write_text(f"repo_id: local/rik-{robot}\nrobot: {robot}\nvariants:\n  ids: [drawer-chest-80__two_point-bow-128__normal]\n"
                    "operators:\n  - strategy: contact_rich\nmax_seconds: 0.5\nstreams: []\n")
    hand_e = tmp_path / "hand-e.yaml"
    hand_e.write_text(spec.read_text().replace(f"robot: {robot}", "robot: hand-e"))
    default = tmp_path / "default.yaml"
    default.write_text(spec.read_text().replace(f"robot: {robot}\n", ""))
    assert spec_hash(load_spec(hand_e)) == spec_hash(load_spec(default)) != spec_hash(load_spec(spec))
    out = tmp_path / "ds"
    r = rik("dataset", "build", str(spec), "--out", str(out), "-j", "1", "--variants", str(variants))
    assert r.code == 0, r
    assert f"robot: {robot}" in r.out
    warning = next(line for line in r.out.splitlines() if line.startswith("warning: "))  # one variant
    assert " never change in this dataset (" in warning and "observation.environment_state: " in warning
    assert "grasp_x" in warning
    episodes = sorted(p.name for p in (tmp_path / "ds.work" / "episodes").iterdir() if not p.name.startswith("."))
    assert episodes == [f"drawer-chest-80__two_point-bow-128__normal__drawer-1__contact_rich.{robot}__s0000"]
    info = json.loads((out / "meta" / "info.json").read_text())
    assert info["robot_type"] == "so_follower" and info["features"]["action"]["names"][0] == "shoulder_pan.pos"
    assert f"rik catalog robot `{robot}`" in (out / "README.md").read_text()
    assert rik("dataset", "verify", str(out)).code == 0


def test_render_actors_without_ray(rik, tmp_path, spec_file) -> None:
    written: list[str] = []
    out = tmp_path / "out"
    r = rik("dataset", "build", str(spec_file), "--out", str(out), "--variants", str(tmp_path / "variants"),
            "--render-actors", "2")
    assert r.code == 2, r
    assert _one_line(r.err) == "rik: error: --render-actors: render actors are Ray's; give --ray too"
    assert sorted(p.name for p in tmp_path.iterdir()) == written  # no out, out.work or variants


def test_ray_without_the_extra(tmp_path, spec_file) -> None:
    written: list[str] = []
    out = tmp_path / "out"
    argv = ["rik", "dataset", "build", str(spec_file), "--out", str(out), "--variants", str(tmp_path / "variants"),
            "--ray", "auto"]
    code = f"import sys; sys.modules['ray'] = None; from rik.cli.app import main; sys.argv = {argv!r}; main()"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r
    assert "Traceback" not in r.stderr
    line = _one_line(r.stderr)
    assert line.startswith("rik: error: --ray: Ray is not installed; install the extra with `uv sync --extra ray`")
    assert sorted(p.name for p in tmp_path.iterdir()) == written  # no out, out.work or variants


@pytest.mark.parametrize("timeout", ["3", "soon"])
def test_ray_address_that_does_not_answer(tmp_path, spec_file, timeout: str) -> None:
    written: list[str] = []
    out = tmp_path / "out"
    env = {**os.environ, "RIK_RAY_CONNECT_TIMEOUT": timeout}
    cmd = rik_cmd("dataset", "build", str(spec_file), "--out", str(out), "--variants", str(tmp_path / "variants"),
                  "--ray", "127.0.0.1:1")
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 2, r
    assert "Traceback" not in r.stderr
    rik_lines = [x for x in r.stderr.splitlines() if x.startswith("rik:")]
    if timeout == "3":  # (Ray logs lines of its own once it has waited 5 s)
        assert rik_lines == [
            "rik: error: --ray 127.0.0.1:1: no Ray cluster answered within 3 s; start one (`ray start --head`) or "
            "give the head's address as HOST:PORT"], r.stderr
    else:
        assert _one_line(r.stderr) == "rik: error: RIK_RAY_CONNECT_TIMEOUT: a number of seconds above 0 (got 'soon')"
    assert sorted(p.name for p in tmp_path.iterdir()) == written  # no out, out.work or variants


@pytest.mark.parametrize("command", ["show", "verify"])
def test_show_and_verify_of_a_folder_that_is_no_dataset(rik, tmp_path, command: str) -> None:
    (tmp_path / "meta").mkdir()
    r = rik("dataset", command, str(tmp_path))
    assert r.code == 2, r
    assert _one_line(r.err) == (f"rik: error: {tmp_path}: not a dataset built by rik dataset build (no readable "
                                "meta/rik_dataset.json)")


def test_out_taken_by_something_else(rik, built, spec_file, variants, tmp_path) -> None:
    taken = tmp_path / "taken"
    taken.mkdir()
    (taken / "notes.txt").write_text("mine")
    r = rik("dataset", "build", str(spec_file), "--out", str(taken), "-j", "1", "--variants", str(variants))
    assert r.code == 2, r
    assert _one_line(r.err) == (f"rik: error: {taken}: exists and is not a dataset built by rik dataset build (no "
                                "meta/rik_dataset.json); choose another --out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]  # no taken.work

    other = tmp_path / "other.yaml"
    other.write_text(SPEC + "seed: 5\n")
    out, _ = built
    before = files_state(out)
    r = rik("dataset", "build", str(other), "--out", str(out), "-j", "1", "--variants", str(variants))
    assert r.code == 2, r
    line = _one_line(r.err)
    assert line.startswith(f"rik: error: {out}: holds the dataset of another spec (spec hash ") and \
        line.endswith("); choose another --out"), line
    assert files_state(out) == before
