"""``rik export-lerobot``: the dataset loads offline with LeRobotDataset with both streams, rik's metadata and
matching frame counts; a behaviour-cloning policy trains on it; a killed export resumes to the same dataset; bad
input gets one line and leaves nothing behind."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rik.episodes.episode import write_meta
from rik.episodes.record import record
from rik.errors import RikError
from rik.exporters.lerobot_export import export_lerobot
from rik.exporters.lerobot_frames import resample_indices
from rik.exporters.spec import ExportSpec
from rik.registry import load_catalog
from rik.sim.observation import ENV_STATE_NAMES, ROBOT_STATE_NAMES

slow = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow"); all but the keys test

CAT = load_catalog()
BOW = "drawer-chest-80__two_point-bow-128__normal"
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"
REPO = "local/rik-test"
SPEC = dict(width=32, height=24, spp=2, denoise=False, variant="scalar_rgb", codec="h264")
KEYS = ("observation.images.front", "observation.images.wrist", "observation.images.front_rerendered",
        "observation.images.wrist_rerendered")


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("export")
    for variant, strategy, seed in ((BOW, "contact_rich", 0), (KNOB, "grasp_vertical", 1), (BOW, "grasp_vertical", 2)):
        record(CAT, variant, strategy, seed=seed, out=root / "episodes", variants=root / "variants",
               max_seconds=0.6)
    return root


def _export_script(work: Path, out: Path, shard_episodes: int) -> str:
    """``python -c`` code exporting :func:`work`'s episodes to ``out`` with :data:`SPEC` in ``shard_episodes``-episode
    shards, as :func:`dataset` does in this process."""
    return (f"from pathlib import Path; from rik.registry import load_catalog; "
            f"from rik.exporters.lerobot_export import export_lerobot; from rik.exporters.spec import ExportSpec; "
            f"export_lerobot(load_catalog(), [Path({str(work / 'episodes')!r})], Path({str(out)!r}), "
            f"ExportSpec({REPO!r}, shard_episodes={shard_episodes}, **{SPEC!r}), "
            f"renders=Path({str(work / 'renders')!r}), variants=Path({str(work / 'variants')!r}))")


@pytest.fixture(scope="module")
def dataset(work: Path) -> Path:
    out = work / "ds"
    export_lerobot(CAT, [work / "episodes"], out, ExportSpec(REPO, shard_episodes=2, **SPEC),
                   renders=work / "renders", variants=work / "variants")
    return out


@slow
def test_export_loads_with_both_streams_metadata_and_matching_counts(dataset: Path, work: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.episodes.episode import find_episodes, read_meta
    from rik.exporters.lerobot_check import check_frame_counts

    ds = LeRobotDataset(REPO, root=dataset, video_backend="pyav")
    metas = {read_meta(d).id: read_meta(d) for d in find_episodes([work / "episodes"])}
    assert ds.meta.total_episodes == 3 and ds.meta.fps == 20
    for key in KEYS:
        assert ds.meta.features[key]["dtype"] == "video" and tuple(ds.meta.features[key]["shape"]) == (24, 32, 3)
    assert ds.meta.features["observation.state"]["names"] == list(ROBOT_STATE_NAMES)
    assert ds.meta.features["observation.environment_state"]["names"] == list(ENV_STATE_NAMES)
    assert ds.meta.features["action"]["names"][-1] == "gripper"
    for ep in ds.meta.episodes:
        meta = metas[ep["rik/episode_id"]]
        assert ep["length"] == meta.steps + 1
        assert (ep["rik/variant"], ep["rik/outcome"], ep["rik/seed"]) == (meta.variant, meta.outcome, meta.seed)
        assert ep["rik/handle_type"] == meta.handle_type and ep["rik/operator"] == meta.operator
    decoded = check_frame_counts(dataset)
    assert set(decoded) == set(KEYS) and all(n == ds.meta.total_frames for n in decoded.values())
    item = ds[ds.meta.total_frames - 1]
    for key in KEYS:
        assert tuple(item[key].shape) == (3, 24, 32) and float(item[key].max()) > 0.05
    assert item["task"] in {"open the drawer by its bow handle", "open the drawer by its mushroom knob"}
    knob = LeRobotDataset(REPO, root=dataset, video_backend="pyav",
                          episode_filter=lambda e: e["rik/handle_type"] == "knob")
    assert knob.meta.total_episodes == 3 and len(knob) == metas[next(m for m in metas if "knob" in m)].steps + 1
    card = (dataset / "README.md").read_text()
    assert "observation.images.front_rerendered" in card and "Real-IKEA" in card and "| normal |" in card
    # how the sim stream was drawn: its render settings and its stream's key (a rebuild with others is another one)
    assert ("MuJoCo rendered the sim stream with 512 px shadow maps and 4x multisampling (stream "
            "`sim-32x24-shadow512-msaa4`" in " ".join(card.split()))


@slow
def test_behaviour_cloning_loss_goes_down(dataset: Path) -> None:
    import torch
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    torch.manual_seed(0)
    chunk = 4
    ds = LeRobotDataset(REPO, root=dataset, video_backend="pyav",
                        delta_timestamps={"action": [k / 20 for k in range(chunk)]})
    loader = torch.utils.data.DataLoader(ds, batch_size=16, shuffle=True, num_workers=0,
                                         generator=torch.Generator().manual_seed(0))

    def stat(key: str, name: str) -> torch.Tensor:
        return torch.tensor(ds.meta.stats[key][name], dtype=torch.float32)

    states = ("observation.state", "observation.environment_state")
    act_mean = torch.tensor(ds.meta.stats["action"]["mean"], dtype=torch.float32)
    act_std = torch.tensor(ds.meta.stats["action"]["std"], dtype=torch.float32) + 1e-3
    vision = torch.nn.Sequential(torch.nn.Conv2d(3, 8, 5, stride=2), torch.nn.ReLU(), torch.nn.AdaptiveAvgPool2d(1),
                                 torch.nn.Flatten())
    head = torch.nn.Sequential(torch.nn.Linear(8 + len(ROBOT_STATE_NAMES) + len(ENV_STATE_NAMES), 64), torch.nn.ReLU(), torch.nn.Linear(64, 7 * chunk))
    params = list(vision.parameters()) + list(head.parameters())
    opt = torch.optim.Adam(params, lr=3e-3)
    losses = []
    for _epoch in range(6):
        for batch in loader:
            feats = torch.cat([vision(batch["observation.images.front_rerendered"])]
                              + [(batch[k] - stat(k, "mean")) / (stat(k, "std") + 1e-3) for k in states], dim=1)
            target = (batch["action"] - act_mean) / act_std
            assert target.shape[1:] == (chunk, 7)
            loss = torch.nn.functional.mse_loss(head(feats).view(-1, chunk, 7), target)
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(float(loss))
    assert np.mean(losses[-3:]) < 0.5 * np.mean(losses[:3])


def _tables(root: Path) -> dict[str, list]:
    import pyarrow.parquet as pq

    out = {}
    for sub in ("data", "meta/episodes"):
        rows = []
        for f in sorted((root / sub).rglob("*.parquet")):
            rows += pq.read_table(f).to_pylist()
        out[sub] = rows
    out["info"] = json.loads((root / "meta" / "info.json").read_text())
    return out


def _frames(root: Path) -> dict[str, np.ndarray]:
    import av

    out = {}
    for f in sorted((root / "videos").rglob("*.mp4")):
        with av.open(str(f)) as c:
            out[str(f.relative_to(root))] = np.stack([fr.to_ndarray(format="rgb24") for fr in c.decode(video=0)])
    return out


@slow
def test_killed_export_resumes_to_the_same_dataset(dataset: Path, work: Path, tmp_path: Path) -> None:
    killed = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-c", _export_script(work, killed, 1)], env=os.environ.copy())
    first = tmp_path / "killed.partial" / "shards" / "shard-0000" / "DONE"
    deadline = time.time() + 300
    while not first.exists() and proc.poll() is None and time.time() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert first.exists() and not killed.exists(), "the export was not killed midway"
    with pytest.raises(RikError, match=r"an interrupted export is there; run again with --resume"):
        export_lerobot(CAT, [work / "episodes"], killed, ExportSpec(REPO, shard_episodes=1, **SPEC),
                       renders=work / "renders", variants=work / "variants")
    result = export_lerobot(CAT, [work / "episodes"], killed, ExportSpec(REPO, shard_episodes=1, **SPEC),
                            renders=work / "renders", variants=work / "variants", resume=True)
    assert result.shards_skipped >= 1 and result.shards_written >= 1
    whole = tmp_path / "whole"
    export_lerobot(CAT, [work / "episodes"], whole, ExportSpec(REPO, shard_episodes=1, **SPEC),
                   renders=work / "renders", variants=work / "variants")
    assert _tables(killed) == _tables(whole)
    a, b = _frames(killed), _frames(whole)
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert not (tmp_path / "killed.partial").exists()


@slow
def test_export_of_one_stream_and_camera_resampled(dataset: Path, work: Path, tmp_path: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.episodes.episode import find_episodes, read_meta

    spec = ExportSpec(REPO, streams=("sim",), cameras=("front",), fps=10, **SPEC)
    result = export_lerobot(CAT, [work / "episodes"], tmp_path / "ds10", spec, renders=work / "renders",
                            variants=work / "variants")
    ds = LeRobotDataset(REPO, root=tmp_path / "ds10", video_backend="pyav")
    assert ds.meta.fps == 10 and sorted(k for k in ds.meta.features if k.startswith("observation.images")) == [
        "observation.images.front"]
    rows = {read_meta(d).id: len(resample_indices(read_meta(d).steps + 1, 20, 10))
            for d in find_episodes([work / "episodes"])}
    assert {e["rik/episode_id"]: e["length"] for e in ds.meta.episodes} == rows
    assert result.frames == sum(rows.values()) and all(e["rik/source_fps"] == 20 for e in ds.meta.episodes)


@slow
def test_an_export_reads_each_episode_once_and_renders_from_that_read(work: Path, tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """states.parquet is read (sha256, parse) and the scene built once per episode, also where the export renders
    the episode's missing stream; the progress counts episodes."""
    import rik.episodes.recorded as recorded_module  # where RecordedEpisode, every export's reader, looks them up

    reads: list[Path] = []
    scenes: list[Path] = []
    read, build = recorded_module.read_episode, recorded_module.episode_scene
    monkeypatch.setattr(recorded_module, "read_episode", lambda d, *a, **k: reads.append(Path(d)) or read(d, *a, **k))
    monkeypatch.setattr(recorded_module, "episode_scene",
                        lambda c, d, *a, **k: scenes.append(Path(d)) or build(c, d, *a, **k))
    stages: list[tuple[str, int, int]] = []
    spec = ExportSpec(REPO, streams=("sim",), cameras=("front",), **SPEC)
    export_lerobot(CAT, [work / "episodes"], tmp_path / "once", spec, renders=tmp_path / "renders",
                   variants=work / "variants", progress=lambda *s: stages.append(s))
    episodes = sorted((work / "episodes").iterdir())
    assert sorted(reads) == episodes and sorted(scenes) == episodes  # each once, the renders included
    assert len(list((tmp_path / "renders").iterdir())) == 3
    assert ("episodes", 3, 3) in stages and stages[-1] == ("shards", 1, 1)
    # a shard reads all its episodes before it renders or writes any: a bad last episode costs no render
    bad = tmp_path / "bad"
    for d in episodes[:2]:
        shutil.copytree(d, bad / d.name)
    states = bad / episodes[1].name / "states.parquet"
    states.write_bytes(states.read_bytes()[:200])
    with pytest.raises(RikError, match="truncated or corrupt"):
        export_lerobot(CAT, [bad], tmp_path / "never", spec, renders=tmp_path / "renders-bad",
                       variants=work / "variants")
    assert not (tmp_path / "renders-bad").exists() and not (tmp_path / "never.partial").exists()


@slow
def test_resampling_holds_the_latest_row() -> None:
    assert resample_indices(5, 20, 20).tolist() == [0, 1, 2, 3, 4]
    assert resample_indices(5, 20, 10).tolist() == [0, 2, 4]
    assert resample_indices(3, 10, 20).tolist() == [0, 0, 1, 1, 2]


@slow
def test_export_messages(rik, dataset: Path, work: Path, tmp_path: Path) -> None:
    base = ["export-lerobot", str(work / "episodes"), "--repo-id", REPO, "--res", "32x24", "--renders",
            str(work / "renders"), "--variants", str(work / "variants"), "--variant", "scalar_rgb", "--spp", "2",
            "--no-denoise", "--codec", "h264"]

    def run(*extra: str, out: Path | None = None):
        target = out or tmp_path / "new"
        result = rik(*base, "--out", str(target), *extra)
        assert result.code == 2 and "Traceback" not in result.err, result.err
        assert not target.exists() or target == dataset
        return result.err.strip()

    assert run(out=dataset) == f"rik: error: {dataset}: already exists; choose another --out (or delete it)"
    assert run("--streams", "sim,photo") == ("rik: error: --streams: unknown stream 'photo' (streams: sim, rerendered, "
                                          "or none)")
    assert run("--codec", "auto") == "rik: error: --codec: 'auto' is not offered (codecs: libsvtav1, h264, hevc)"
    err = run("--cameras", "top")
    assert err.startswith("rik: error: ") and err.endswith(": no camera 'top' in the scene (cameras: front, wrist)")
    bad_repo = rik(*base[:3], "rikdata", *base[4:], "--out", str(tmp_path / "r"))
    assert bad_repo.err.strip() == "rik: error: --repo-id 'rikdata': give it as OWNER/NAME, e.g. local/rik-drawers"
    # Episodes at different rates, or with different recorded features.
    mixed = tmp_path / "mixed"
    for i, d in enumerate(sorted((work / "episodes").iterdir())[:2]):
        shutil.copytree(d, mixed / d.name)
        if i == 1:
            meta = json.loads((mixed / d.name / "meta.json").read_text())
            meta["fps"] = 10
            write_meta(mixed / d.name, meta)  # as if recorded at 10 Hz: sealed anew
    err = rik("export-lerobot", str(mixed), "--repo-id", REPO, "--out", str(tmp_path / "m")).err.strip()
    assert err.startswith("rik: error: the episodes were recorded at different rates (") and "pass --fps" in err
    import hashlib

    import pyarrow as pa
    import pyarrow.parquet as pq

    path = mixed / d.name / "states.parquet"
    table = pq.read_table(path)
    shorter = pa.array([row[:6] for row in table.column("action").to_pylist()], pa.list_(pa.float64()))
    pq.write_table(table.set_column(table.schema.get_field_index("action"), "action", shorter), path)
    meta["fps"], meta["states_sha256"] = 20, hashlib.sha256(path.read_bytes()).hexdigest()
    write_meta(mixed / d.name, meta)
    err = rik("export-lerobot", str(mixed), "--repo-id", REPO, "--out", str(tmp_path / "m")).err.strip()
    assert err == (f"rik: error: {path}: column 'action' has 6 numbers per row where the other episodes have 7 "
                   "(target_x, target_y, target_z, target_pitch, target_yaw, target_roll, gripper); export it to a "
                   "separate dataset")
    # A corrupt episode: named, and nothing written.
    corrupt = tmp_path / "corrupt"
    shutil.copytree(sorted((work / "episodes").iterdir())[0], corrupt / "ep")
    states = corrupt / "ep" / "states.parquet"
    states.write_bytes(states.read_bytes()[:200])
    err = rik("export-lerobot", str(corrupt), "--repo-id", REPO, "--out", str(tmp_path / "c")).err.strip()
    assert err.startswith(f"rik: error: {states}") and "truncated or corrupt" in err
    assert not (tmp_path / "c").exists() and not (tmp_path / "c.partial").exists()
    missing = rik("export-lerobot", str(tmp_path / "none"), "--repo-id", REPO, "--out", str(tmp_path / "n"))
    assert missing.code == 2 and "none: no such episode or directory" in missing.err


@slow
def test_push_to_hub_reaches_the_upload_and_says_why_it_failed(dataset: Path) -> None:
    from rik.exporters.lerobot_export import push

    with pytest.raises(RikError) as err:
        push(dataset, REPO)
    msg = str(err.value)
    assert msg.startswith(f"{dataset}: cannot push {REPO} to the Hugging Face Hub: ")
    assert "offline" in msg.lower()


@pytest.fixture(scope="module")
def fresh_export(dataset: Path, work: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The episodes of :func:`dataset` exported again with its settings by a fresh interpreter, as a user's are: its
    dataset folder and the last line it printed, which says whether the export imported ``rik.envs.open_front`` and
    whether ``rik/OpenFront-v0`` was registered with gymnasium. Against :func:`dataset` (this test process's export)
    it differs in what could leak into the bytes: the hash seed (this process's is random; set orders differ) and
    the leftovers in freshly allocated memory (``MALLOC_PERTURB_``; x264's macroblock tree once read them)."""
    out = tmp_path_factory.mktemp("fresh-export") / "ds"
    script = (_export_script(work, out, 2) + "; import sys, gymnasium; "
              "print('rik.envs.open_front' in sys.modules, 'rik/OpenFront-v0' in gymnasium.registry)")
    env = {**os.environ, "PYTHONHASHSEED": "1", "MALLOC_PERTURB_": "85"}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return out, done.stdout.strip().splitlines()[-1]


@slow
def test_identical_exports_are_byte_identical(dataset: Path, fresh_export: tuple[Path, str]) -> None:
    """The same episodes and settings exported by two processes (:func:`dataset` here, :func:`fresh_export` in a
    fresh interpreter) give the same bytes in every file."""
    roots = [dataset, fresh_export[0]]
    files = [sorted(p.relative_to(r) for p in r.rglob("*") if p.is_file()) for r in roots]
    assert files[0] == files[1]
    differ = [str(f) for f in files[0] if (roots[0] / f).read_bytes() != (roots[1] / f).read_bytes()]
    assert differ == []


@slow
def test_state_only_export_has_the_two_state_vectors_and_action(rik, work: Path, tmp_path: Path) -> None:
    """``--streams none``: no video features and nothing rendered; loads with LeRobotDataset, and lerobot's policies
    see the front's state as ENV; the card names both vectors and the normalisation to pass for ENV."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.utils.feature_utils import dataset_to_policy_features

    from rik.exporters.lerobot_card import NORMALIZATION

    out, renders = tmp_path / "states", tmp_path / "renders"
    res = rik("export-lerobot", str(work / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(out),
              "--renders", str(renders), "--variants", str(work / "variants"), "--shard-episodes", "2")
    assert res.code == 0, res.err
    assert "state layout 2" in res.out and "no video features to check (a state-only export)" in res.out
    assert not renders.exists()
    ds = LeRobotDataset(REPO, root=out, video_backend="pyav")
    defaults = {"timestamp", "frame_index", "episode_index", "index", "task_index"}
    assert set(ds.meta.features) - defaults == {"observation.state", "observation.environment_state", "action"}
    assert ds.meta.video_keys == [] and not (out / "videos").exists() and ds.meta.total_episodes == 3
    shapes = {k: (tuple(f["shape"]), f["names"]) for k, f in ds.meta.features.items() if k not in defaults}
    assert shapes == {"observation.state": ((11,), list(ROBOT_STATE_NAMES)),
                      "observation.environment_state": ((13,), list(ENV_STATE_NAMES)),
                      "action": ((7,), ["target_x", "target_y", "target_z", "target_pitch", "target_yaw",
                                        "target_roll", "gripper"])}
    item = ds[len(ds) - 1]
    assert tuple(item["observation.environment_state"].shape) == (13,) and float(item["observation.state"][2]) > 0.3
    types = {k: f.type.value for k, f in dataset_to_policy_features(ds.meta.features).items()}
    assert types == {"observation.state": "STATE", "observation.environment_state": "ENV", "action": "ACTION"}
    card = (out / "README.md").read_text()
    assert "`grasp_x`, `grasp_y`, `grasp_z`" in card and "`contact_normal_force`" in card
    assert f"--policy.normalization_mapping='{NORMALIZATION['act']}'" in card and "state-only export" in card
    base = ["export-lerobot", str(work / "episodes"), "--repo-id", REPO, "--out", str(tmp_path / "bad")]
    err = rik(*base, "--streams", "none,sim").err.strip()
    assert err == ("rik: error: --streams none,sim: 'none' (a state-only export) cannot be combined with image "
                   "streams; give either none or some of sim, rerendered")
    err = rik(*base, "--streams", "none", "--cameras", "front").err.strip()
    assert err == ("rik: error: --cameras front: a state-only export (--streams none) has no cameras; drop --cameras "
                   "or give --streams")
    assert rik(*base, "--streams", ",").err.strip() == ("rik: error: --streams: give at least one of sim, rerendered, "
                                                         "or none for a state-only export")
    assert not (tmp_path / "bad").exists()


@slow
def test_resume_of_an_older_layout_says_to_export_again(rik, work: Path, tmp_path: Path) -> None:
    """A partial export written before the state split (plan.json without a layout) is not continued."""
    from rik.episodes.episode import find_episodes, read_meta
    from rik.exporters.lerobot_export import _plan

    out = tmp_path / "old"
    partial = tmp_path / "old.partial"
    metas = {d: read_meta(d) for d in find_episodes([work / "episodes"])}
    plan = _plan(metas, ExportSpec(REPO, streams=(), shard_episodes=16), 20)
    del plan["spec"]["layout"]  # what rik wrote before the layout was recorded
    (partial / "shards" / "shard-0000").mkdir(parents=True)
    (partial / "plan.json").write_text(json.dumps(plan, indent=1) + "\n")
    res = rik("export-lerobot", str(work / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(out),
              "--variants", str(work / "variants"), "--resume")
    assert res.code == 2 and res.err.strip() == (
        f"rik: error: {partial}: the interrupted export there has rik's state layout 1 (one 14-number "
        "observation.state) and this rik writes layout 2 (observation.state and observation.environment_state); "
        "delete it and export again without --resume (the episodes are unchanged)")
    assert not out.exists() and (partial / "plan.json").is_file()


@slow
def test_check_names_the_state_layout(dataset: Path) -> None:
    from rik.exporters.lerobot_check import check_dataset, describe_layout, state_layout
    from rik.exporters.lerobot_frames import LAYOUT_1_STATE_NAMES

    assert check_dataset(dataset, REPO, 3)["layout"] == 2
    old = {"observation.state": {"dtype": "float32", "shape": [14], "names": list(LAYOUT_1_STATE_NAMES)},
           "action": {"dtype": "float32", "shape": [7], "names": None}}
    assert state_layout(old) == 1 and describe_layout(1).startswith("1 (one 14-number observation.state")
    assert state_layout({"observation.state": {"names": ["a"]}}) is None


@slow
def test_export_does_not_import_or_register_the_env(fresh_export: tuple[Path, str]) -> None:
    """Exporting reads observations through rik.sim.observation: it does not import rik.envs.open_front, which would
    register rik/OpenFront-v0 with gymnasium as a side effect. (gymnasium itself is loaded all the same: lerobot's
    dataset module imports it.) A fresh interpreter, as a user has (:func:`fresh_export`)."""
    root, last_line = fresh_export
    assert last_line == "False False"
    assert (root / "meta" / "info.json").is_file()


def test_feature_keys_are_lerobots_constants() -> None:
    """rik's names of LeRobot's feature keys (rik.lerobot.features, which imports no lerobot) are lerobot's own."""
    from lerobot.utils import constants

    from rik.lerobot import features as keys

    for name in ("OBS_STATE", "OBS_ENV_STATE", "OBS_IMAGES", "ACTION"):
        assert getattr(keys, name) == getattr(constants, name), name
    assert keys.EE_POSE == f"{constants.OBS_STR}.ee_pose"  # what lerobot makes of the env's ee_pose
