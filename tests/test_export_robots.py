"""``rik export-lerobot`` in each robot's own layout: episodes recorded with ``rik record --robot so100``,
``so101`` and ``panda-2f85`` export, load with ``LeRobotDataset`` and hold the recorded joints and servo targets in
LeRobot's names and units; the SO arms' features equal those lerobot 0.6.1's own SO follower gives a dataset; the
Panda's ``observation.ee_pose`` is its gripper frame in its base frame; a dataset holds one robot."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from shared import cli
from so_follower import so_follower_motors

from rik.registry import load_catalog

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = load_catalog()
BOW = "drawer-chest-80__two_point-bow-128__normal"
REPO = "local/rik-robots"


def recorded(root: Path, variants: Path, robot: str, strategy: str) -> Path:
    """Two episodes of ``robot`` on the bow-handle drawer, recorded by ``rik record --robot`` into
    ``root/episodes`` and exported state-only to ``root/ds``; returns ``root``."""
    cli("record", BOW, "-s", strategy, "--robot", robot, "--episodes", "2", "--variants", str(variants),
        "--out", str(root / "episodes"))
    cli("export-lerobot", str(root / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(root / "ds"),
        "--variants", str(variants))
    return root


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The variants folder of every test here (the first recording builds the variant)."""
    return tmp_path_factory.mktemp("variants")


@pytest.fixture(scope="module")
def so100(tmp_path_factory: pytest.TempPathFactory, variants: Path) -> Path:
    return recorded(tmp_path_factory.mktemp("so100"), variants, "so100", "contact_rich")


@pytest.fixture(scope="module")
def so101(tmp_path_factory: pytest.TempPathFactory, variants: Path) -> Path:
    return recorded(tmp_path_factory.mktemp("so101"), variants, "so101", "grasp_vertical")


@pytest.fixture(scope="module")
def panda(tmp_path_factory: pytest.TempPathFactory, variants: Path) -> Path:
    return recorded(tmp_path_factory.mktemp("panda"), variants, "panda-2f85", "grasp_vertical")


def recordings(root: Path) -> dict[str, tuple]:
    """Episode id -> (meta, states table as numpy columns) of the recorded episodes."""
    import pyarrow as pa

    from rik.episodes.episode import find_episodes, read_episode

    out = {}
    for d in find_episodes([root / "episodes"]):
        meta, table = read_episode(d)

        def column(name: str, table: pa.Table = table) -> np.ndarray:
            return np.array(table.column(name).to_pylist(), np.float64)

        out[meta.id] = (meta, {c: column(c) for c in ("robot_joints", "robot_targets", "action", "tcp",
                                                      "tcp_quat")})
    return out


def frames_by_episode(ds_root: Path) -> dict[str, dict[str, np.ndarray]]:
    """Episode id -> feature -> (frames, width) array, read from the dataset's parquet files."""
    import pyarrow.parquet as pq

    from rik.exporters.lerobot_check import _episodes_table

    ids = {e["episode_index"]: e["rik/episode_id"] for e in _episodes_table(ds_root)}
    rows = []
    for f in sorted((ds_root / "data").rglob("*.parquet")):
        rows += pq.read_table(f).to_pylist()
    out: dict[str, dict[str, list]] = {}
    for r in sorted(rows, key=lambda r: r["index"]):
        ep = out.setdefault(ids[r["episode_index"]], {})
        for key, value in r.items():
            if key.startswith(("observation.", "action")):
                ep.setdefault(key, []).append(value)
    return {e: {k: np.array(v, np.float64) for k, v in feats.items()} for e, feats in out.items()}


MID_RANGE = np.array([(j.range[0] + j.range[1]) / 2 for j in CAT.robot("so100").joints.joints])
"""The SO-100's joint positions (rad) its export reads as 0: the middle of each catalog range."""


def closure(robot_id: str, jaw: np.ndarray) -> np.ndarray:
    """The gripper's closure (0 open, 1 touching) from its recorded opening joint, rad."""
    act = CAT.robot(robot_id).gripper.actuation
    assert act is not None
    return np.clip((jaw - act.joint_open) / (act.joint_closed - act.joint_open), 0.0, 1.0)


# ---- the SO arms -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("arm", ["so100", "so101"])
def test_so_export_has_lerobots_so_follower_features_and_units(arm: str, request: pytest.FixtureRequest) -> None:
    """observation.state and action: the names, order, shape and dtype lerobot's SO follower gives a dataset
    (``_motors_ft`` through ``hw_to_dataset_features``), the units of its motors' norm modes, its robot name:
    the same for the SO-100 and the SO-101 (lerobot's one SOFollower drives both)."""
    root = request.getfixturevalue(arm)
    from types import SimpleNamespace

    from lerobot.motors import MotorNormMode
    from lerobot.robots.so_follower import SOFollower
    from lerobot.utils.constants import ACTION, OBS_STR
    from lerobot.utils.feature_utils import hw_to_dataset_features

    motors = so_follower_motors()
    motor_features = SOFollower._motors_ft.fget(SimpleNamespace(bus=SimpleNamespace(motors=motors)))
    assert all(t is float for t in motor_features.values())
    expected = {**hw_to_dataset_features(motor_features, OBS_STR), **hw_to_dataset_features(motor_features, ACTION)}
    assert set(expected) == {"observation.state", "action"}
    info = json.loads((root / "ds" / "meta" / "info.json").read_text())
    for key, feature in expected.items():
        ours = info["features"][key]
        assert ours["names"] == feature["names"], key
        assert tuple(ours["shape"]) == tuple(feature["shape"]) and ours["dtype"] == feature["dtype"], key
    assert info["robot_type"] == SOFollower.name == "so_follower"
    units = {MotorNormMode.DEGREES: "deg", MotorNormMode.RANGE_0_100: "percent"}
    assert {f"{name}.pos": units[m.norm_mode] for name, m in motors.items()} == {
        e.name: e.unit for e in CAT.robot(arm).lerobot.joints}


def test_so100_dataset_holds_joints_in_degrees_and_servo_targets(so100: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset(REPO, root=so100 / "ds", video_backend="pyav")
    recs = recordings(so100)
    assert ds.meta.total_episodes == 2 and ds.meta.robot_type == "so_follower" and ds.meta.video_keys == []
    defaults = {"timestamp", "frame_index", "episode_index", "index", "task_index"}
    assert set(ds.meta.features) - defaults == {"observation.state", "observation.environment_state", "action"}
    assert {e["rik/episode_id"]: e["length"] for e in ds.meta.episodes} == {
        i: meta.steps + 1 for i, (meta, _) in recs.items()}
    data = frames_by_episode(so100 / "ds")
    for episode, (_, cols) in recs.items():
        state, action = data[episode]["observation.state"], data[episode]["action"]
        joints, targets = cols["robot_joints"], cols["robot_targets"]
        # degrees from the middle of each joint's range (LeRobot's calibration; tests/test_so_calibration.py)
        np.testing.assert_allclose(state[:, :5], np.degrees(joints[:, :5] - MID_RANGE), atol=1e-3)
        np.testing.assert_allclose(state[:, 5], 100.0 * (1.0 - closure("so100", joints[:, 5])), atol=1e-3)
        np.testing.assert_allclose(action[:, :5], np.degrees(targets[:, :5] - MID_RANGE), atol=1e-3)
        np.testing.assert_allclose(action[:, 5], 100.0 * (1.0 - np.clip(cols["action"][:, 6], 0, 1)), atol=1e-4)
        assert np.ptp(state[:, :5], axis=0).max() > 5.0, "the arm did not move"
        assert np.abs(action[:, :5] - state[:, :5]).max() > 0.1, "actions are the targets, not the positions"
    item = ds[3]
    first = data[ds.meta.episodes[0]["rik/episode_id"]]
    np.testing.assert_allclose(item["observation.state"].numpy(), first["observation.state"][3], atol=1e-6)
    card = (so100 / "ds" / "README.md").read_text()
    assert "**Robot: SO-100 arm (SO-ARM100)** (rik catalog robot `so100`, `robot_type` `so_follower`)" in card
    assert "**Calibration (LeRobot's SO follower).**" in card and "licence Apache-2.0" in card
    assert "| `shoulder_lift.pos` | so_arm100_left/Pitch | -180.0 .. 11.5 | -84.3 |" in card
    assert "100 sets the jaw's goal at 1.5 rad, 0 at -0.6 rad, past the closed end" in card
    grip = CAT.robot("so100").gripper.grip_force.value
    assert f"grip force {grip:g} N (measured in rik's scene" in card and "pad friction 0.35 (assumed" in card
    assert "| so_arm100_left/Rotation | `shoulder_pan.pos` | -2.2 .. 2.2 | 1.91 | 5.45 | 14 | 0.3 |" in card
    assert "`gripper.pos` (percent of the opening: 100 open, 0 closed)" in card


def test_so100_export_with_a_camera_stream(tmp_path: Path, variants: Path) -> None:
    """One tiny camera stream of a short SO-100 episode: the arm's wrist camera is ``wrist`` like the Hand-E's."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.episodes.record import record

    record(CAT, BOW, "contact_rich", robot=CAT.robot("so100"), max_seconds=0.4, out=tmp_path / "episodes",
           variants=variants)
    out = tmp_path / "ds"
    cli("export-lerobot", str(tmp_path / "episodes"), "--streams", "sim", "--cameras", "wrist", "--res", "32x24",
        "--codec", "h264", "--repo-id", REPO, "--out", str(out), "--variants", str(variants),
        "--renders", str(tmp_path / "renders"))
    ds = LeRobotDataset(REPO, root=out, video_backend="pyav")
    assert ds.meta.video_keys == ["observation.images.wrist"] and ds.meta.robot_type == "so_follower"
    assert tuple(ds.meta.features["observation.images.wrist"]["shape"]) == (24, 32, 3)
    item = ds[len(ds) - 1]
    assert tuple(item["observation.images.wrist"].shape) == (3, 24, 32) and float(item["observation.images.wrist"].max()) > 0.05
    assert tuple(item["observation.state"].shape) == (6,)


def test_so101_dataset_holds_joints_from_mid_range_and_the_jaw_over_its_range(so101: Path) -> None:
    """``rik record --robot so101`` -> ``rik export-lerobot``: a LeRobotDataset of robot_type so_follower whose
    joints are the model's own degrees (its 0 is mid-range already) and whose gripper runs 0 .. 100 over the jaw's
    whole range, its action the jaw servo's goal on that scale; the card says how a real follower's calibration
    maps onto them."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset(REPO, root=so101 / "ds", video_backend="pyav")
    recs = recordings(so101)
    assert ds.meta.total_episodes == 2 and ds.meta.robot_type == "so_follower"
    assert ds.meta.features["observation.state"]["names"] == [f"{m}.pos" for m in so_follower_motors()]
    act = CAT.robot("so101").gripper.actuation
    assert act is not None and (act.joint_closed, act.joint_open) == (act.ctrl_closed, act.ctrl_open)
    data = frames_by_episode(so101 / "ds")
    for episode, (_, cols) in recs.items():
        state, action = data[episode]["observation.state"], data[episode]["action"]
        joints, targets = cols["robot_joints"], cols["robot_targets"]
        np.testing.assert_allclose(state[:, :5], np.degrees(joints[:, :5]), atol=1e-3)
        jaw = 100.0 * (joints[:, 5] - act.joint_closed) / (act.joint_open - act.joint_closed)
        np.testing.assert_allclose(state[:, 5], np.clip(jaw, 0.0, 100.0), atol=1e-3)
        goal = 100.0 * (targets[:, 5] - act.joint_closed) / (act.joint_open - act.joint_closed)
        np.testing.assert_allclose(action[:, 5], goal, atol=1e-3)
        np.testing.assert_allclose(action[:, :5], np.degrees(targets[:, :5]), atol=1e-3)
        assert np.ptp(state[:, :5], axis=0).max() > 5.0 and state[:, 5].min() < 20.0, "the arm moved and closed"
    card = (so101 / "ds" / "README.md").read_text()
    assert "**Robot: SO-101 arm** (rik catalog robot `so101`, `robot_type` `so_follower`)" in card
    assert "**Calibration (LeRobot's SO follower).**" in card and "range_min" in card
    assert "| `elbow_flex.pos` | elbow_flex | -96.8 .. 96.8 | 0.0 |" in card
    assert "Its action is the jaw servo's goal on the same scale" in card


# ---- the Panda ---------------------------------------------------------------------------------------------------
def test_panda_dataset_holds_joints_targets_and_its_ee_pose(panda: Path, variants: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from scipy.spatial.transform import Rotation

    from rik.sim.robots.layout import EE_NAMES

    ds = LeRobotDataset(REPO, root=panda / "ds", video_backend="pyav")
    names = [f"joint{i}.pos" for i in range(1, 8)] + ["gripper.pos"]
    feats = ds.meta.features
    assert ds.meta.robot_type == "franka_panda" and ds.meta.total_episodes == 2
    assert feats["observation.state"]["names"] == names == feats["action"]["names"]
    assert feats["observation.ee_pose"]["names"] == list(EE_NAMES) and feats["observation.ee_pose"]["dtype"] == "float32"
    assert tuple(feats["observation.ee_pose"]["shape"]) == (6,)
    from rik.episodes.episode import find_episodes, read_episode, states
    from rik.episodes.replay import episode_scene

    recs = recordings(panda)
    data = frames_by_episode(panda / "ds")
    first = find_episodes([panda / "episodes"])[0]
    scene = episode_scene(CAT, first, variants, read_episode(first)[0])
    recorded = {d.name: states(read_episode(d)[1]) for d in find_episodes([panda / "episodes"])}
    for episode, (meta, cols) in recs.items():
        got = data[episode]
        assert len(got["action"]) == meta.steps + 1
        joints, targets = cols["robot_joints"], cols["robot_targets"]
        np.testing.assert_allclose(got["observation.state"][:, :7], joints[:, :7], atol=1e-6)
        np.testing.assert_allclose(got["observation.state"][:, 7], closure("panda-2f85", joints[:, 7]), atol=1e-6)
        np.testing.assert_allclose(got["action"][:, :7], targets[:, :7], atol=1e-6)
        np.testing.assert_allclose(got["action"][:, 7], np.clip(cols["action"][:, 6], 0, 1), atol=1e-6)
        # one frame's end effector: the scene's gripper frame (world) at that row, seen from the recorded arm base
        k = meta.steps // 2
        assert meta.robot_base is not None
        scene.restore(recorded[episode][k])
        base = Rotation.from_euler("z", meta.robot_base.yaw)
        position = base.inv().apply(scene.tcp() - np.array(meta.robot_base.pos))
        rotation = (base.inv() * Rotation.from_matrix(scene.gripper_rotation())).as_matrix()
        ee = got["observation.ee_pose"][k]
        np.testing.assert_allclose(ee[:3], position, atol=1e-5)
        np.testing.assert_allclose(Rotation.from_rotvec(ee[3:]).as_matrix(), rotation, atol=1e-5)
        # (states.parquet's tcp column is read before the row's last integration step: close, not equal)
        np.testing.assert_allclose(scene.tcp(), cols["tcp"][k], atol=2e-3)
        assert 0.2 < float(np.linalg.norm(position)) < 1.2, "the gripper within the Panda's reach of its base"
    card = (panda / "ds" / "README.md").read_text()
    assert "rik catalog robot `panda-2f85`" in card and "`observation.ee_pose`" in card
    assert "**Calibration" not in card and "gravity compensated by the controller" in card


# ---- one robot per dataset ---------------------------------------------------------------------------------------
def test_a_dataset_holds_one_robot(rik, so100: Path, panda: Path, variants: Path, tmp_path: Path) -> None:
    from rik.episodes.episode import find_episodes

    out = tmp_path / "mixed"
    r = rik("export-lerobot", str(so100 / "episodes"), str(panda / "episodes"), "--streams", "none", "--repo-id",
            REPO, "--out", str(out), "--variants", str(variants))
    so, pa = find_episodes([so100 / "episodes"])[0], find_episodes([panda / "episodes"])[0]
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {pa / 'meta.json'}: robot 'panda-2f85' differs from robot 'so100' of {so / 'meta.json'}; a "
        "dataset holds one robot's state and action layout, so export each robot's episodes to a dataset of its own")
    assert not out.exists() and not (tmp_path / "mixed.partial").exists()


def test_an_arms_episodes_have_no_handle_frame(rik, so100: Path, variants: Path, tmp_path: Path) -> None:
    from rik.episodes.episode import find_episodes

    out = tmp_path / "handle"
    r = rik("export-lerobot", str(so100 / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(out),
            "--variants", str(variants), "--action-frame", "handle")
    so = find_episodes([so100 / "episodes"])[0]
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {so / 'meta.json'}: action frame 'handle': robot so100 acts with joint targets, which have no "
        "handle frame (it is the Hand-E's pose action's); export it with --action-frame world")
    assert not out.exists() and not (tmp_path / "handle.partial").exists()


def test_resume_takes_the_robot_as_part_of_the_plan(rik, panda: Path, variants: Path, tmp_path: Path) -> None:
    """An interrupted export's plan names the robot; one of another robot (or a plan from before robots, which was
    the Hand-E's) is not continued with these episodes; the right one is."""
    from rik.episodes.episode import find_episodes, read_meta
    from rik.exporters.lerobot_export import _plan
    from rik.exporters.spec import ExportSpec

    out, partial = tmp_path / "ds", tmp_path / "ds.partial"
    metas = {d: read_meta(d) for d in find_episodes([panda / "episodes"])}
    plan = _plan(metas, ExportSpec(REPO, streams=(), shard_episodes=16), 20, "panda-2f85")
    assert plan["spec"]["robot"] == "panda-2f85"
    args = ("export-lerobot", str(panda / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(out),
            "--variants", str(variants), "--resume")
    partial.mkdir()
    for robot in ("so100", None):
        old = json.loads(json.dumps(plan))
        if robot is None:
            del old["spec"]["robot"]
        else:
            old["spec"]["robot"] = robot
        (partial / "plan.json").write_text(json.dumps(old, indent=1) + "\n")
        r = rik(*args)
        assert r.code == 2 and r.err.strip() == (
            f"rik: error: {partial}: the interrupted export there was of other episodes or settings; delete it, or "
            "run it again with the same ones"), r.err
    (partial / "plan.json").write_text(json.dumps(plan, indent=1) + "\n")
    r = rik(*args)
    assert r.code == 0, r.err
    assert "robot: panda-2f85 (robot_type franka_panda)" in r.out
    assert json.loads((out / "meta" / "info.json").read_text())["robot_type"] == "franka_panda"
    assert not partial.exists()


def test_an_episode_whose_robot_the_catalog_lacks_is_named(rik, panda: Path, variants: Path, tmp_path: Path) -> None:
    """Before anything is written: an episode of a robot that is not in the catalog, or whose recorded joints are
    not its catalog entry's."""
    import shutil

    from rik.episodes.episode import find_episodes, write_meta

    src = find_episodes([panda / "episodes"])[0]
    for field, value, expected in (
            ("robot", "panda-2f58", "field 'robot': no robot 'panda-2f58' in the catalog; did you mean 'panda-2f85'? (the catalog's robots: "
                                    "hand-e, panda-2f85, so100, so101) "
                                    "(give the catalog it was recorded with, --catalog)"),
            ("robot_joints", ["joint1", "gripper"], "field 'robot_joints': the episode recorded joints joint1, "
                                                    "gripper, but robot 'panda-2f85' of the catalog has joint1, "
                                                    "joint2, joint3, joint4, joint5, joint6, joint7, gripper; export "
                                                    "it with the catalog it was recorded with (--catalog)")):
        eps = tmp_path / field
        shutil.copytree(src, eps / src.name)
        meta = json.loads((eps / src.name / "meta.json").read_text())
        meta[field] = value
        write_meta(eps / src.name, meta)
        out = tmp_path / f"{field}-ds"
        r = rik("export-lerobot", str(eps), "--streams", "none", "--repo-id", REPO, "--out", str(out),
                "--variants", str(variants))
        assert r.code == 2 and r.err.strip() == f"rik: error: {eps / src.name / 'meta.json'}: {expected}"
        assert not out.exists() and not out.with_name(f"{out.name}.partial").exists()



# ---- the Hand-E, before and after robots ---------------------------------------------------------------------------
def test_a_format_2_hand_e_episode_exports_as_before(variants: Path, tmp_path: Path) -> None:
    """An episode recorded before robots (format 2: no robot, no robot columns) is the Hand-E's: it exports to the
    same table as the same episode in format 3, in the Hand-E's pose layout."""
    import hashlib
    import shutil

    import pyarrow.parquet as pq

    from rik.episodes.episode import COLUMNS_2, meta_digest
    from rik.episodes.record import record
    from rik.exporters.lerobot_export import export_lerobot
    from rik.exporters.spec import ExportSpec
    from rik.sim.observation import ROBOT_STATE_NAMES

    (meta,) = record(CAT, BOW, "contact_rich", max_seconds=0.3, out=tmp_path / "new", variants=variants)
    old = tmp_path / "old" / meta.id
    shutil.copytree(tmp_path / "new" / meta.id, old)
    pq.write_table(pq.read_table(old / "states.parquet").select(list(COLUMNS_2)), old / "states.parquet",
                   compression="zstd")
    data = json.loads((old / "meta.json").read_text())
    for key in ("robot", "robot_base", "robot_joints", "meta_sha256"):
        data.pop(key)
    data["format"], data["states_sha256"] = 2, hashlib.sha256((old / "states.parquet").read_bytes()).hexdigest()
    data["meta_sha256"] = meta_digest(data)
    (old / "meta.json").write_text(json.dumps(data, indent=2) + "\n")
    tables = []
    for name in ("new", "old"):
        result = export_lerobot(CAT, [tmp_path / name], tmp_path / f"{name}-ds", ExportSpec(REPO, streams=()),
                                variants=variants)
        assert (result.robot, result.robot_type) == ("hand-e", "rik_hand_e")
        info = json.loads((tmp_path / f"{name}-ds" / "meta" / "info.json").read_text())
        assert info["robot_type"] == "rik_hand_e"
        assert info["features"]["observation.state"]["names"] == list(ROBOT_STATE_NAMES)
        assert info["features"]["action"]["names"] == ["target_x", "target_y", "target_z", "target_pitch",
                                                       "target_yaw", "target_roll", "gripper"]
        assert "observation.ee_pose" not in info["features"]
        tables.append(pq.read_table(next((tmp_path / f"{name}-ds" / "data").rglob("*.parquet"))).to_pylist())
    assert tables[0] == tables[1] and len(tables[0]) == meta.steps + 1
