"""The arms in rik's scenes: exact replay of their episodes, the measured grip forces the catalog states, joint torques
capped at the catalog's figures, the pose interface shared with the Hand-E, a five-joint arm's IK meeting the position
first, the checks, a handle out of reach, and episodes recorded before robots existed."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pyarrow.parquet as pq
import pytest
from shared import BOW, builtin_catalog, grasp_until_pull

from rik.episodes.episode import COLUMNS_2, META, STATES, meta_digest, read_episode
from rik.episodes.record import record_one
from rik.episodes.replay import verify_episode
from rik.sim.build import build_scene
from rik.sim.pose import gripper_rotation
from rik.sim.robots.arm import Placement
from rik.sim.robots.checks import reach_profile, run_checks
from rik.sim.robots.ik import FEW_JOINTS_ORIENTATION_COST, ArmIK
from rik.sim.robots.reach import REACH_TOLERANCE, reachable_opening

CAT = builtin_catalog()
ARMS = ("panda-2f85", "so100", "so101")


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants  # the demo variant, built once per test process (conftest)


def _closed_grip(variants: Path, robot: str) -> tuple[object, dict[str, float]]:
    """The scene after grasp_vertical has closed on the bow handle and held still for 1 s; normal force (N) per
    gripper body on the handle."""
    entry = CAT.robot(robot)
    scene = build_scene(variants / BOW, None, robot=entry if entry.kind.value == "arm" else None)
    op = grasp_until_pull(scene, 200)
    assert op._phase == "pull", f"{robot}: the grasp never closed ({op.log})"
    hold = op._action(scene)
    for _ in range(20):
        scene.step(hold)
    m, d = scene.model, scene.data
    forces: dict[str, float] = {}
    w = np.zeros(6)
    for i in range(d.ncon):
        g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
        if (g1 in scene.gripper_geoms) == (g2 in scene.gripper_geoms):
            continue
        ours, other = (g1, g2) if g1 in scene.gripper_geoms else (g2, g1)
        if int(m.geom_bodyid[other]) != scene.front.handle_body:
            continue
        mujoco.mj_contactForce(m, d, i, w)
        body = m.body(int(m.geom_bodyid[ours])).name
        forces[body] = forces.get(body, 0.0) + abs(float(w[0]))
    return scene, forces


@pytest.mark.parametrize("robot, jaws", [("hand-e", ("gripper/left", "gripper/right")),
                                         ("panda-2f85", ("robot/left_pad", "robot/right_pad")),
                                         ("so100", ("robot/so_arm100_left/Moving_Jaw",)),
                                         ("so101", ("robot/moving_jaw_so101_v1",))])
def test_grip_force_is_what_the_catalog_says(variants: Path, robot: str, jaws: tuple[str, ...]) -> None:
    """The catalog's grip forces of the arms are marked as measured here: the pressing jaws push the held bar with
    that force (within 20 %: a swinging jaw's force depends on where along it the bar sits). A parallel gripper's squeeze is the mean of its jaws' normal forces (a sideways load
    on the arm adds to one and takes from the other); a swinging jaw's is its own."""
    _, forces = _closed_grip(variants, robot)
    stated = CAT.robot(robot).gripper.grip_force.value
    squeeze = float(np.mean([forces.get(jaw, 0.0) for jaw in jaws]))
    assert squeeze == pytest.approx(stated, rel=0.2), (robot, forces)


@pytest.mark.parametrize("robot", ARMS)
def test_arm_episode_replays_exactly_and_records_its_joints(variants: Path, robot: str, tmp_path: Path) -> None:
    entry = CAT.robot(robot)
    meta = record_one(variants / BOW, "grasp_vertical", 3, tmp_path, robot=entry, max_seconds=4.0)
    assert meta.id.endswith(f"__grasp_vertical.{robot}__s0003")
    assert meta.robot == robot and meta.robot_base is not None
    assert meta.robot_joints == (*entry.joint_names, "gripper")
    _, table = read_episode(tmp_path / meta.id)
    joints = np.stack(table.column("robot_joints").to_numpy(zero_copy_only=False))
    assert joints.shape == (meta.steps + 1, len(entry.joint_names) + 1)
    lo = np.array([j.range[0] for j in entry.joints.joints])
    hi = np.array([j.range[1] for j in entry.joints.joints])
    assert np.all(joints[:, :-1] >= lo - 0.02) and np.all(joints[:, :-1] <= hi + 0.02)
    targets = np.stack(table.column("robot_targets").to_numpy(zero_copy_only=False))
    assert targets.shape == joints.shape and np.ptp(targets[:, 0]) > 0  # the IK commanded the arm to move
    check = verify_episode(CAT, tmp_path / meta.id, variants)
    assert check.exact and check.max_difference == 0.0


@pytest.mark.parametrize("robot", ARMS)
def test_servo_torques_never_pass_the_catalogs(variants: Path, robot: str) -> None:
    """Pushed into the front, far past the handle, every joint's actuator force stays within its torque."""
    entry = CAT.robot(robot)
    scene = build_scene(variants / BOW, None, robot=entry)
    drive = scene.drive
    target = scene.pose()
    target[1] = scene.grasp_point()[1] - 0.3  # 30 cm into the drawer front
    limits = np.array([j.torque for j in entry.joints.joints])
    peak = np.zeros(len(limits))
    for _ in range(40):
        scene.step(np.concatenate([target, [0.0]]))
        peak = np.maximum(peak, np.abs(scene.data.qfrc_actuator[drive.dofs]))
        assert np.all(np.isfinite(scene.data.qpos))
    assert np.all(peak <= limits * (1 + 1e-6)), (peak, limits)
    assert np.max(peak / limits) > 0.5  # it did push hard


@pytest.mark.parametrize("robot", ARMS)
def test_arm_takes_the_hand_es_target_pose(variants: Path, robot: str) -> None:
    """The same target pose (x, y, z, pitch, yaw, roll) moves an arm's gripper frame where it moves the Hand-E's."""
    entry = CAT.robot(robot)
    scene = build_scene(variants / BOW, None, robot=entry)
    start = scene.pose()
    # the SO arms' five joints keep their fingers in the plane of their base: move them in that plane
    step = [0.03, -0.05, 0.02, 0.0, 0.0, 0.3] if robot == "panda-2f85" else [0.0, -0.05, 0.02, 0.0, 0.0, 0.3]
    target = start + np.array(step)
    for _ in range(40):
        scene.step(np.concatenate([target, [0.0]]))
    pose = scene.pose()
    assert np.linalg.norm(pose[:3] - target[:3]) < 0.01, (pose, target)
    assert abs(pose[5] - target[5]) < 0.05


def test_a_five_joint_arm_meets_the_position_first() -> None:
    """Where a five-joint arm cannot meet a whole pose, its IK's position-first steps (the planner's fallback) give up
    orientation for position within the reach tolerance: the SO-100 at its mount before the chest's 300 mm edge lip
    (bench seed 10008), the fingers tilted 15 degrees from above, the drawer closed. Weighing orientation at 0.2 per
    rad alone it ends 5.2 mm from this pose (0.02 rad), out of reach. A pose it meets keeps its usual weights, and a
    seven-joint arm weighs both alike."""
    entry = CAT.robot("so100")
    ik = ArmIK(entry, Placement(np.array([0.0, 0.402, 0.486]), 0.0))
    rotation = gripper_rotation(np.radians([15.0, 0.0, 90.0]))
    _, dp, da = ik.solve(np.array([0.0, 0.0469, 0.7842]), rotation)
    assert dp > REACH_TOLERANCE[0], (dp, da)  # the usual steps: out of reach
    _, dp, da = ik.solve(np.array([0.0, 0.0469, 0.7842]), rotation, position_first=True)
    assert dp <= REACH_TOLERANCE[0] and da <= REACH_TOLERANCE[1], (dp, da)
    assert ik.frame_task.cost[3:] == pytest.approx([FEW_JOINTS_ORIENTATION_COST] * 3)  # put back after the step
    # 3 cm nearer its base the usual step meets the position: the orientation is met as well as before
    _, dp, da = ik.solve(np.array([0.0, 0.0769, 0.7842]), rotation, position_first=True)
    assert dp <= REACH_TOLERANCE[0] and da < 0.01, (dp, da)
    panda = ArmIK(CAT.robot("panda-2f85"), Placement(np.zeros(3), 0.0))
    assert panda.frame_task.cost == pytest.approx([1.0] * 6) and panda.position_first_cost is None


def test_checks_measure_reach_torque_and_grip(variants: Path) -> None:
    results = {r.name: r for r in run_checks(build_scene(variants / BOW, None, robot=CAT.robot("panda-2f85")))}
    assert results["start_clear"].passed and results["reach"].passed
    assert results["reach"].values["reachable_opening"] == 1.0
    assert results["torque_headroom"].passed and 0 < results["torque_headroom"].values["largest_share"] < 1
    so100 = {r.name: r for r in run_checks(build_scene(variants / BOW, None, robot=CAT.robot("so100")))}
    # the SO-100's pinch holds 2 x 0.35 x 14 N = 9.8 N, less than the normal preset's 15.6 N
    assert not so100["grip"].passed and so100["grip"].values["capacity_N"] == pytest.approx(9.8)
    assert so100["grip"].values["resistance_N"] == pytest.approx(15.6)


def _far_overlay(tmp_path: Path) -> Path:
    """A user catalog with the SO-100 mounted 1.2 m in front of the handle."""
    import yaml

    data = yaml.safe_load((Path(__file__).parents[1] / "rik/registry/data/robots.yaml").read_text())
    so100 = next(r for r in data["robots"] if r["id"] == "so100")
    so100 = {**so100, "id": "so100-far", "mount": {**so100["mount"], "offset": [0.0, 1.2, -0.28]}}
    path = tmp_path / "far.yaml"
    path.write_text(yaml.safe_dump({"robots": [so100]}))
    return path


def test_a_handle_out_of_reach_is_refused_before_recording(rik, variants: Path, tmp_path: Path) -> None:
    overlay = _far_overlay(tmp_path)
    out = tmp_path / "episodes"
    r = rik("record", BOW, "-s", "grasp_vertical", "--robot", "so100-far", "--catalog", str(overlay),
            "--variants", str(variants), "--out", str(out))
    assert r.code == 2 and r.err.count("\n") == 1, r.err
    assert r.err.startswith("rik: error: robot so100-far cannot reach handle two_point/bow-128 of variant "
                            f"{BOW} (front drawer-1): ")
    assert "mm short of its grasp point with the front closed" in r.err
    assert not out.exists()
    profile = reach_profile(build_scene(variants / BOW, None, robot=CAT.robot("so100")))
    assert reachable_opening(profile) >= 0.5  # the catalog's own mount reaches it


@pytest.mark.parametrize("command", [("record", BOW, "-s", "grasp_vertical"), ("robot-check", BOW),
                                     ("bench", "-n", "1")])
@pytest.mark.parametrize("wanted", ["so10", "so102"])
def test_unknown_robot_is_one_line(rik, variants: Path, command: tuple[str, ...], wanted: str) -> None:
    """An unknown robot: one line with the closest ids and every robot of the catalog, exit 2."""
    r = rik(*command, "--robot", wanted, "--variants", str(variants))
    assert r.code == 2
    assert r.err == (f"rik: error: no robot '{wanted}' in the catalog; did you mean 'so101' or 'so100'? (the "
                     "catalog's robots: hand-e, panda-2f85, so100, so101)\n")


def test_robot_check_cli(rik, variants: Path) -> None:
    ok = rik("robot-check", BOW, "--robot", "panda-2f85", "--variants", str(variants))
    assert ok.code == 0, ok.out + ok.err
    assert "pass reach: reaches handle two_point/bow-128" in ok.out and "over the whole opening" in ok.out
    weak = rik("robot-check", BOW, "--robot", "so100", "--variants", str(variants))
    assert weak.code == 1 and "FAIL grip: two pads at 14 N with friction 0.35 hold 9.8 N" in weak.out
    so101 = rik("robot-check", BOW, "--robot", "so101", "--variants", str(variants))
    assert so101.code == 1 and "pass start_clear" in so101.out, so101.out + so101.err
    assert "reaches handle two_point/bow-128 of variant " + BOW + " (front drawer-1) up to 90% open" in so101.out
    assert "FAIL grip: two pads at 13 N with friction 0.35 hold 9.0 N by friction" in so101.out


def test_episodes_from_before_robots_still_read_and_replay(variants: Path, tmp_path: Path) -> None:
    """A format-2 episode (no robot fields, the old columns) is the Hand-E's: it reads and replays exactly."""
    meta = record_one(variants / BOW, "grasp_vertical", 0, tmp_path, max_seconds=2.0)
    folder = tmp_path / meta.id
    table = pq.read_table(folder / STATES).select(list(COLUMNS_2))
    pq.write_table(table, folder / STATES, compression="zstd")
    import hashlib

    data = json.loads((folder / META).read_text())  # written by hand: rik's writer seals format 3
    for key in ("robot", "robot_base", "robot_joints", "meta_sha256", "format"):
        data.pop(key)
    data["states_sha256"] = hashlib.sha256((folder / STATES).read_bytes()).hexdigest()
    data = {**data, "format": 2}
    data["meta_sha256"] = meta_digest(data)
    (folder / META).write_text(json.dumps(data))
    old, _ = read_episode(folder)
    assert old.format == 2 and old.robot == "hand-e"
    assert verify_episode(CAT, folder, variants).exact
