"""Every catalog robot's model, as MuJoCo Menagerie tests its models: the scene of a small variant compiles and holds
its start pose for 1 s (20 control steps) without a MuJoCo warning or a NaN, has the ``front`` and ``wrist``
cameras, and an arm's model files are read from its installed package's folder, with the network shut."""

from __future__ import annotations

import socket
from pathlib import Path

import numpy as np
import pytest

from rik.combinator.build import ensure_variant
from rik.registry import load_catalog
from rik.sim.build import build_scene

CAT = load_catalog([])
VARIANT = "drawer-bedside-45__knob-mushroom-30__normal"
STEPS = 20
"""Control steps held: 1 s at rik's 20 Hz."""


@pytest.fixture(scope="module")
def variant(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return ensure_variant(CAT, VARIANT, tmp_path_factory.mktemp("variants"))


@pytest.fixture
def offline(monkeypatch: pytest.MonkeyPatch) -> None:
    """No socket may connect anywhere while the scene is built: a model fetched at run time fails the test."""

    def refuse(self: socket.socket, *args: object) -> None:
        raise AssertionError(f"a network connection was attempted: {args}")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket.socket, "connect_ex", refuse)


@pytest.mark.parametrize("robot_id", list(CAT.robots))
def test_robot_scene_compiles_and_holds_still(robot_id: str, variant: Path, offline: None) -> None:
    import mujoco

    robot = CAT.robot(robot_id)
    scene = build_scene(variant, robot=None if robot.kind.value == "floating" else robot)
    m, d = scene.model, scene.data
    assert scene.robot_id == robot_id
    cameras = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(m.ncam)}
    assert {"front", "wrist"} <= cameras, cameras
    start, tcp = scene.pose(), scene.tcp()
    for k in range(STEPS):
        scene.step(np.array([*start, 0.0]))
        if k == STEPS // 2 - 1:
            halfway = scene.tcp()
    assert d.time == pytest.approx(STEPS / scene.control_fps)
    warnings = {mujoco.mjtWarning(i).name: d.warning[i].number for i in range(int(mujoco.mjtWarning.mjNWARNING))}
    assert not any(warnings.values()), warnings
    for name in ("qpos", "qvel", "qacc", "ctrl", "act", "qfrc_constraint"):
        assert np.isfinite(getattr(d, name)).all(), name
    # an arm whose servos do not compensate gravity sags on their stiffness (the SO-100 4.2 mm, the SO-101 5.7 mm
    # here): within 1 cm, and settled over the second half second
    sag = 0.005 if robot.joints is None or robot.joints.gravity_compensation else 0.010
    assert np.linalg.norm(scene.tcp() - tcp) < sag, "the gripper frame drifts from the held start pose"
    assert np.linalg.norm(scene.tcp() - halfway) < 0.0005, "the gripper frame still moves after 0.5 s"
    assert scene.opening() == pytest.approx(0.0, abs=1e-3)


@pytest.mark.parametrize("robot_id", [r.id for r in CAT.robots.values() if r.kind.value == "arm"])
def test_arm_model_files_come_from_the_installed_package(robot_id: str, offline: None) -> None:
    from rik.sim.robots.arm import package_dir, robot_spec

    robot = CAT.robot(robot_id)
    folder = package_dir(robot).resolve()
    assert all((folder / f).is_file() for f in robot.model.files)
    spec = robot_spec(robot)
    files = [Path(mesh.file) for mesh in spec.meshes] + [Path(tex.file) for tex in spec.textures if tex.file]
    assert files, "the model reads no mesh"
    outside = [f for f in files if not (f.is_absolute() and f.resolve().is_relative_to(folder) and f.is_file())]
    assert not outside, outside
    spec.compile()  # the files are all there is: the model compiles from them
