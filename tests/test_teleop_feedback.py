"""What a teleoperation session tells the operator and how W/S move along a front's path: the grasp from contacts
(holding, touching, slipped), "blocked", the hint per handle, and a door that opens with one held key in path
motion where frame-fixed motion loses the knob (rik.teleop.feedback, rik.teleop.session)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from shared import BOW, builtin_catalog

from rik.combinator.build import ensure_variant
from rik.sim.build import build_scene
from rik.sim.grasp import pinch_fits, pinch_plan
from rik.sim.pose import base_for_tcp
from rik.sim.robots.gripper import HAND_E
from rik.teleop.feedback import BLOCKED_LEAD, GRASP_STATES, front_path_step
from rik.teleop.keys import COMMAND_KEYS
from rik.teleop.session import TeleopSession

CAT = builtin_catalog()
DOOR = "door-base-60-left__knob-mushroom-30__normal"
HOLD_S = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
"""The command of a held S (away from the furniture: opens)."""


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("variants")
    for vid in (DOOR, BOW):
        ensure_variant(CAT, vid, out)
    return out


def _session(variants: Path, vid: str, tmp_path: Path) -> TeleopSession:
    return TeleopSession(build_scene(variants / vid, None, HAND_E, 20), tmp_path / "episodes")


def _hold(session: TeleopSession, steps: int) -> list[dict]:
    """Hold the session's current input for ``steps`` control steps; the status after each."""
    out = []
    for _ in range(steps):
        session.tick()
        out.append(session.status())
    return out


def _grasp_the_handle(session: TeleopSession) -> None:
    """Put the jaws round the handle as the scripted pinch would (from the handle's own geometry) and close them,
    driving the session's target there as held keys would, until the contacts read ``holding``."""
    scene = session.scene
    plan = pinch_plan(scene, pinch_fits(scene, "visual"), "visual")
    for tcp, steps in ((plan.tcp + 0.05 * plan.approach, 30), (plan.tcp, 30)):
        session.target[:6] = base_for_tcp(scene.gripper, tcp, plan.angles)
        for _ in range(steps):
            session.recorder.step(session.target.copy())
    session.set_input(np.zeros(6), grip=1.0)
    states = [s["grasp"] for s in _hold(session, 15)]
    assert states[-1] == "holding", states


def test_a_held_s_opens_a_door_along_its_arc_where_frame_motion_loses_the_knob(variants: Path,
                                                                              tmp_path: Path) -> None:
    path = _session(variants, DOOR, tmp_path)
    assert path.motion_mode == "path"
    _grasp_the_handle(path)
    path.set_input(HOLD_S)
    statuses = _hold(path, 200)  # 10 s of one held key
    opened = [s for s in statuses if s["grasp"] == "holding"]
    assert all(s["motion"]["on_path"] for s in opened)
    assert opened[-1]["opening"] > 0.9, opened[-1]["front_position"]  # the knob stays in the jaws past 90 %
    assert statuses[-1]["front_position"]["angle_deg"] > 95

    frame = _session(variants, DOOR, tmp_path / "frame")
    frame.toggle_motion_mode()
    assert frame.motion_mode == "frame" and frame.message == "motion: frame"
    _grasp_the_handle(frame)
    frame.set_input(HOLD_S)
    statuses = _hold(frame, 200)
    assert not any(s["motion"]["on_path"] for s in statuses)
    assert statuses[-1]["opening"] < 0.5  # straight back, the knob leaves the jaws on the arc...
    assert statuses[-1]["grasp"] == "slipped"  # ...and the page says so while the grip is still closed
    frame.set_input(np.zeros(6), grip=0.0)
    assert _hold(frame, 1)[-1]["grasp"] in ("touching", "free")  # opening the grip fully ends "slipped"


def test_loosening_the_grip_mid_pull_reads_slipped(variants: Path, tmp_path: Path) -> None:
    session = _session(variants, DOOR, tmp_path)
    _grasp_the_handle(session)
    session.set_input(HOLD_S)
    assert {s["grasp"] for s in _hold(session, 20)} == {"holding"}
    session.set_input(HOLD_S, grip=0.05)  # the jaws open most of the way (a trigger let go): the knob leaves them
    states = [s["grasp"] for s in _hold(session, 20)]
    assert states[-1] == "slipped" and "slipped" in session.status_line()
    assert set(states) <= set(GRASP_STATES)


def test_blocked_reads_when_the_target_leads_a_gripper_pushed_into_the_front(variants: Path,
                                                                            tmp_path: Path) -> None:
    session = _session(variants, BOW, tmp_path)
    session.set_input(np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]))  # A: left, in free space
    free = _hold(session, 20)
    assert not any(s["blocked"] for s in free)
    session.set_input(np.array([0.0, -1.0, 0.0, 0.0, 0.0, 0.0]))  # W: into the furniture, until it stops
    pushed = _hold(session, 80)
    assert pushed[-1]["blocked"] and "blocked" in session.status_line()
    lead = np.linalg.norm(session.target[:3] - session.scene.pose()[:3])
    assert lead > BLOCKED_LEAD
    session.set_input(np.zeros(6))
    assert not _hold(session, 1)[-1]["blocked"]  # no key held: nothing is blocked


def test_the_hint_says_which_roll_each_handle_needs(variants: Path, tmp_path: Path) -> None:
    bar = _session(variants, BOW, tmp_path).status()
    assert bar["steps"] == 0 and "140 mm wide, 12 mm tall" in bar["hint"] and "roll 90 deg" in bar["hint"]
    assert "pull the drawer out" in bar["hint"]
    knob = _session(variants, DOOR, tmp_path / "door").status()
    assert "30 mm wide" in knob["hint"] and "follows the front's arc" in knob["hint"]
    assert knob["front_position"] == {"kind": "door", "angle_deg": 0.0}
    assert bar["front_position"] == {"kind": "drawer", "travel_mm": 0.0}


def test_a_path_step_keeps_the_pose_on_the_hinges_circle_and_its_angle_to_the_door(variants: Path) -> None:
    scene = build_scene(variants / DOOR, None, HAND_E, 20)
    d, joint = scene.data, scene.front.joint
    pose = scene.pose()
    moved = pose
    for _ in range(50):
        moved = front_path_step(scene, moved, 0.01)
    anchor, axis = d.xanchor[joint], d.xaxis[joint]

    def radius(p: np.ndarray) -> float:
        arm = p[:3] - anchor
        return float(np.linalg.norm(arm - (arm @ axis) * axis))

    assert radius(moved) == pytest.approx(radius(pose), abs=1e-9)
    turned = 0.5 / radius(pose)  # 50 steps of 10 mm along the arc, rad
    assert abs(abs(moved[4] - pose[4]) - turned) < 1e-6  # a vertical hinge turns the gripper's yaw with the door
    assert np.allclose(front_path_step(scene, moved, -0.5)[:3], pose[:3], atol=1e-6)  # W goes back the same way


def _seen(scene, camera) -> set[str]:
    """Which of the gripper, the handle and the front a 64 x 48 render through ``camera`` shows (MuJoCo's
    segmentation: the geoms drawn in each pixel)."""
    import mujoco

    with mujoco.Renderer(scene.model, 48, 64) as r:
        r.enable_segmentation_rendering()
        r.update_scene(scene.data, camera=camera)
        geoms = {int(g) for g in np.unique(r.render()[..., 0]) if g >= 0}
    from rik.teleop.view import gripper_bodies

    bodies = {int(scene.model.geom_bodyid[g]) for g in geoms}
    return ({"gripper"} if bodies & gripper_bodies(scene) else set()) | \
        ({"handle"} if scene.front.handle_body in bodies else set()) | \
        ({"front"} if scene.front.body in bodies else set())


def test_the_follow_view_keeps_gripper_handle_and_door_in_frame_where_the_fixed_camera_loses_them(
        variants: Path, tmp_path: Path) -> None:
    from rik.teleop.view import FOLLOWED, FollowView

    session = _session(variants, DOOR, tmp_path)
    view = FollowView(session.scene)
    assert _seen(session.scene, view.at(session.scene.data)) == {"gripper", "handle", "front"}  # closed: all three
    _grasp_the_handle(session)
    session.set_input(HOLD_S)
    for _ in range(200):
        session.tick()
        if session.scene.opening() >= 0.8:
            break
    assert 0.8 <= session.scene.opening() < 0.85
    assert _seen(session.scene, view.at(session.scene.data)) == {"gripper", "handle", "front"}
    assert "gripper" not in _seen(session.scene, FOLLOWED)  # the scene's fixed camera: the work left its picture


@pytest.mark.parametrize("robot", ["panda-2f85", "so100"])
def test_with_an_arm_the_follow_view_shows_its_gripper_at_the_start(variants: Path, tmp_path: Path,
                                                                      robot: str) -> None:
    from rik.teleop.view import FollowView

    scene = build_scene(variants / DOOR, None, HAND_E, 20, robot=CAT.robot(robot).as_arm)
    TeleopSession(scene, tmp_path / "episodes")  # at the start pose, in front of the handle
    assert _seen(scene, FollowView(scene).at(scene.data)) == {"gripper", "handle", "front"}


def test_the_operators_view_paints_jaws_and_handle_in_colours_of_their_own(variants: Path, tmp_path: Path) -> None:
    """The demo's white bow handle on its white drawer: painted, the view shows the jaws' orange and the handle's
    blue; the scene's own materials (what recorded streams use) are untouched."""
    import mujoco

    from rik.teleop.view import HANDLE_RGBA, JAWS_RGBA, FollowView, paint_for_contrast

    session = _session(variants, BOW, tmp_path)
    scene = session.scene
    materials = scene.model.mat_rgba.copy()

    def pixels_near(image: np.ndarray, rgba: tuple[float, ...]) -> int:
        return int((np.abs(image.astype(int) - np.array(rgba[:3]) * 255).max(axis=-1) < 60).sum())

    with mujoco.Renderer(scene.model, 120, 160) as r:
        r.update_scene(scene.data, camera=FollowView(scene).at(scene.data))
        plain = r.render().copy()
        paint_for_contrast(r.scene, scene)
        painted = r.render()
    assert pixels_near(painted, JAWS_RGBA) > pixels_near(plain, JAWS_RGBA) + 20
    assert pixels_near(painted, HANDLE_RGBA) > pixels_near(plain, HANDLE_RGBA) + 5
    assert np.array_equal(scene.model.mat_rgba, materials)


@pytest.mark.parametrize(("robot", "jaws"), [("so100", "JAWS_ALT_RGBA"), ("panda-2f85", "JAWS_RGBA")])
def test_an_arm_painted_like_the_jaws_gets_jaws_of_another_colour(variants: Path, robot: str, jaws: str) -> None:
    """The SO-100's own paint is orange, the jaws' colour: on it the jaws are magenta; the Panda's white and black
    arm keeps the orange jaws."""
    import mujoco

    import rik.teleop.view as view

    scene = build_scene(variants / DOOR, None, HAND_E, 20, robot=CAT.robot(robot).as_arm)
    with mujoco.Renderer(scene.model, 120, 160) as r:
        r.update_scene(scene.data, camera=view.FollowView(scene).at(scene.data))
        view.paint_for_contrast(r.scene, scene)
        hand = view.gripper_bodies(scene)
        colours = [r.scene.geoms[i].rgba.copy() for i in range(r.scene.ngeom)
                   if r.scene.geoms[i].objtype == mujoco.mjtObj.mjOBJ_GEOM
                   and int(scene.model.geom_bodyid[r.scene.geoms[i].objid]) in hand]
    assert colours and np.allclose(colours, getattr(view, jaws), atol=1e-6)


@pytest.mark.parametrize("msg", [{"azimuth": "left"}, {"azimuth": float("nan")}, {"elevation": True},
                                 {"azimuth": 1e9}, {"azimuth": [1]}, {"reset": "yes", "azimuth": None}])
def test_a_bad_view_message_is_refused_with_a_notice(msg: dict) -> None:
    from rik.teleop.station import BAD_VIEW, parse_view

    assert parse_view(msg) == BAD_VIEW


def test_a_view_message_turns_and_reset_puts_back() -> None:
    from rik.teleop.station import parse_view

    assert parse_view({"type": "view", "azimuth": -12.5, "elevation": 4}) == (-12.5, 4.0)
    assert parse_view({"type": "view", "azimuth": 3}) == (3.0, 0.0)
    assert parse_view({"type": "view", "reset": True}) is None


def test_m_switches_the_motion_in_the_keymap() -> None:
    assert COMMAND_KEYS["motion"][:3] == ("KeyM", "M", "M")
