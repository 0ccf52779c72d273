"""The grasp planner for a fixed and a swinging jaw (the SO arms): the frame it turns the gripper to, where it puts
the fixed pad relative to the handle, the plans only a five-joint arm's position-first reach check reaches put
after every other, and an episode on the demo's bow drawer under the smooth preset in which
both pads hold the handle while the drawer opens."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
from shared import BOW, builtin_catalog, grasp_until_pull

from rik.combinator.build import ensure_variant
from rik.episodes.operators import ScriptedGrasp
from rik.sim import grasp
from rik.sim.build import build_scene
from rik.sim.grasp import FIXED_GAP, GraspPlan, pinch_plan, swing_frame, swing_plans
from rik.sim.pose import angles_of, gripper_rotation
from rik.sim.probe import front_face_y, handle_extent, ray

CAT = builtin_catalog()
SO_ARMS = ("so100", "so101")
SMOOTH_BOW = BOW.replace("__normal", "__smooth")
PULL = np.array([0.0, 1.0, 0.0])


@pytest.mark.parametrize("side, across", [("below", np.array([0.0, 0.0, -1.0])),
                                          ("right", np.array([1.0, 0.0, 0.0]))])
@pytest.mark.parametrize("tilt_deg", [0.0, 30.0, 60.0, 90.0])
def test_swing_frame_puts_the_fixed_jaw_against_the_pull(side: str, across: np.ndarray, tilt_deg: float) -> None:
    """Fingers into the front tilted towards the handle from ``side``; the closing axis (towards the fixed jaw)
    against the pull by sin(tilt); a right-handed rotation that the target pose's angles reproduce."""
    t = math.radians(tilt_deg)
    rot = swing_frame(PULL, across, t)
    assert rot.T @ rot == pytest.approx(np.eye(3), abs=1e-12) and np.linalg.det(rot) == pytest.approx(1.0)
    closing, fingers = rot[:, 0], rot[:, 2]
    assert fingers @ PULL == pytest.approx(-math.cos(t), abs=1e-12)  # into the front
    assert fingers @ across == pytest.approx(-math.sin(t), abs=1e-12)  # towards the handle from that side
    assert closing @ PULL == pytest.approx(-math.sin(t), abs=1e-12)  # the fixed jaw on the far side
    assert gripper_rotation(angles_of(rot)) == pytest.approx(rot, abs=1e-9)


@pytest.fixture(scope="module")
def smooth_variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("smooth-bow")
    ensure_variant(CAT, SMOOTH_BOW, out)
    return out


@pytest.mark.parametrize("robot", SO_ARMS)
def test_fixed_pad_lies_against_the_handles_far_side(smooth_variants: Path, robot: str) -> None:
    """On the bow's grip bar: the fixed pad's face (``fixed_jaw`` along the closing axis from the pads' centre) is
    in the gap between the front and the bar's back, FIXED_GAP from the bar (a ray from the face towards the
    swinging jaw, from somewhere along the pad, meets the handle there), and the bar lies between it and the open
    swinging jaw."""
    scene = build_scene(smooth_variants / SMOOTH_BOW, None, robot=CAT.robot(robot))
    g = scene.gripper
    plans = swing_plans(scene, ("below", "above"), limit=20)
    assert any(not p.detail.startswith("tilt 0 ") for p in plans), f"{robot}: no tilted swinging-jaw grasp"
    lo, hi = handle_extent(scene)
    gp = scene.grasp_point()
    face = min(front_face_y(scene, gp[0], gp[2], hi[1] + 0.05), lo[1])
    back = face + 0.0005 + ray(scene, np.array([gp[0], face + 0.0005, gp[2]]), PULL)[0]
    for plan in plans:
        rot = gripper_rotation(plan.angles)
        closing = rot[:, 0]
        tilt = math.radians(float(plan.detail.split()[1]))
        # the pull presses the bar into the fixed jaw by sin(tilt) of itself (tilt 0: beside it)
        assert closing @ scene.pull_direction() == pytest.approx(-math.sin(tilt), abs=1e-6), plan
        assert g.fixed_jaw is not None
        pad = plan.tcp + g.fixed_jaw * closing
        assert face < pad[1] < hi[1], (plan, pad, face, hi)
        # the face's nearest point to the handle, over the pad's length along the fingers
        dist = min(_distance_to_handle(scene, pad + rot[:, 2] * s, -closing)
                   for s in np.linspace(-g.pad_length / 2, g.pad_length / 2, 15))
        assert FIXED_GAP - 1e-4 <= dist <= FIXED_GAP + 0.015, (plan, dist)
        assert g.fixed_jaw - g.stroke < closing @ (gp - plan.tcp) < g.fixed_jaw, plan
        assert plan.approach @ rot[:, 2] == pytest.approx(-1.0)  # it comes in along its fingers
        assert back < hi[1]


def _distance_to_handle(scene: object, origin: np.ndarray, direction: np.ndarray) -> float:
    """Along a ray, the distance to the first geom of the handle, passing through the robot (it stands at its start
    pose, in the way), m; inf if it meets none."""
    travelled = 0.0
    for _ in range(10):
        dist, geom = ray(scene, origin + direction * travelled, direction)  # type: ignore[arg-type]
        if geom < 0:
            return float("inf")
        travelled += dist
        if int(scene.model.geom_bodyid[geom]) == scene.front.handle_body:  # type: ignore[attr-defined]
            return travelled
        travelled += 1e-4
    return float("inf")


def _jaw_forces(scene: object) -> dict[str, float]:
    """Normal force (N) of each jaw on the handle: the fixed jaw's body (the one its pads are on) and the swinging
    jaw's, pads or not (the SO-100's jaw meshes stand proud of its pads in places)."""
    m, d = scene.model, scene.data  # type: ignore[attr-defined]
    bodies = {}
    for g in range(m.ngeom):
        for jaw in ("fixed", "moving"):
            if f"{jaw}_jaw_pad" in m.geom(g).name:
                bodies[int(m.geom_bodyid[g])] = jaw
    assert sorted(set(bodies.values())) == ["fixed", "moving"], bodies
    forces = {"fixed": 0.0, "moving": 0.0}
    w = np.zeros(6)
    for i in range(d.ncon):
        b1, b2 = (int(m.geom_bodyid[int(g)]) for g in (d.contact.geom1[i], d.contact.geom2[i]))
        for ours, other in ((b1, b2), (b2, b1)):
            if ours in bodies and other == scene.front.handle_body:  # type: ignore[attr-defined]
                mujoco.mj_contactForce(m, d, i, w)
                forces[bodies[ours]] += abs(float(w[0]))
    return forces


def test_position_first_plans_come_after_every_other(smooth_variants: Path, monkeypatch: pytest.MonkeyPatch
                                                   ) -> None:
    """The planner's fallback for a five-joint arm: the plans its usual reach check keeps stay as they were (set,
    order, reach) and the plans only its position-first check reaches follow them, ranked alike, within the limit;
    the operator tries them after every other plan (the pinch too). The arm's reach is faked: tilt 0 from below
    reaches 60 %, from above 90 %; every other plan only with position-first steps, 80 % (bench seed 10008:
    swing_above tilt 15 was out of reach by a fraction of a millimetre)."""
    scene = build_scene(smooth_variants / SMOOTH_BOW, None, robot=CAT.robot("so100"))
    usual = {"swing_below_0": 0.6, "swing_above_0": 0.9}
    asked: list[tuple[str, bool]] = []

    def fake_reach(_scene: object, plan: GraspPlan, position_first: bool = False) -> float:
        asked.append((plan.key, position_first))
        return 0.8 if position_first else usual.get(plan.key, -1.0)

    monkeypatch.setattr(grasp, "plan_reach", fake_reach)
    plans = swing_plans(scene, ("below", "above"), limit=20)
    assert [p.key for p in plans[:2]] == ["swing_above_0", "swing_below_0"], plans
    assert [p.detail for p in plans[:2]] == ["tilt 0 deg, reaches 90%", "tilt 0 deg, reaches 60%"]
    assert not any(p.position_first for p in plans[:2]) and all(p.position_first for p in plans[2:])
    tilts = [float(p.detail.split()[1]) for p in plans[2:]]
    assert tilts and tilts == sorted(tilts, reverse=True), plans  # steeper first among equals
    assert all(p.detail.endswith("reaches 80% position first") for p in plans[2:])
    # position-first steps only for the plans the usual check drops
    assert {k for k, first in asked if first} == {p.key for p in plans[2:]}
    assert [p.key for p in swing_plans(scene, ("below", "above"), limit=2)] == ["swing_above_0", "swing_below_0"]
    assert [p.key for p in swing_plans(scene, ("below", "above"), limit=3)] == [p.key for p in plans[:3]]
    pinch = pinch_plan(scene, vertical=True)
    op = ScriptedGrasp("t", lambda _scene: [*plans, pinch], rehearse=False)
    op.reset(scene, np.random.default_rng(0))
    assert op._plan.key == "swing_above_0"
    op._start_plan(scene)  # as a re-grasp does: the next untried plan is the usual one, then the pinch
    op._start_plan(scene)
    op._start_plan(scene)
    assert op._tried == ["swing_above_0", "swing_below_0", pinch.key, plans[2].key], op._tried


@pytest.mark.slow
@pytest.mark.parametrize("robot", [
    pytest.param("so100", marks=pytest.mark.xfail(strict=True, reason=(
        "measured: the SO-100's plan (swing_below, tilt 0, the one that reaches 90 %) jams the bow between its "
        "swinging jaw's second pad and nothing of the fixed jaw (over 1000 N on that pad, none on the fixed jaw), "
        "and the drawer still follows; not understood yet"))),
    "so101"])
def test_so_arm_holds_the_bow_with_both_jaws(smooth_variants: Path, robot: str) -> None:
    """grasp_vertical with an SO arm on the smooth bow drawer plans a swinging-jaw grasp; once closed, both jaws
    press the handle all through the first second of the pull, and the drawer follows."""
    scene = build_scene(smooth_variants / SMOOTH_BOW, None, robot=CAT.robot(robot))
    op = grasp_until_pull(scene, 400)
    assert op._phase == "pull" and op.log[0].startswith("attempt 1: swing_"), op.log
    weakest = {"fixed": np.inf, "moving": np.inf}
    for _ in range(scene.control_fps):
        scene.step(op.act(scene))
        forces = _jaw_forces(scene)
        weakest = {k: min(weakest[k], forces[k]) for k in weakest}
    assert weakest["fixed"] > 1.0 and weakest["moving"] > 1.0, (robot, weakest)
    assert scene.opening() > 0.05, (robot, scene.opening(), op.log)


def _derived(scene: object) -> list[np.ndarray]:
    """Every array of the scene's data that an operator or a recorder reads: the integration state and what
    ``mj_step`` derives from it (positions of sites and bodies, contacts, forces, accelerations)."""
    d = scene.data  # type: ignore[attr-defined]
    return [scene.state(), d.site_xpos.copy(), d.xpos.copy(), d.xquat.copy(), d.qacc.copy(),  # type: ignore[attr-defined]
            d.qfrc_constraint.copy(), d.contact.pos.copy(), d.sensordata.copy(), np.array([d.ncon, d.time])]


@pytest.mark.parametrize("robot", SO_ARMS)
def test_rehearsal_puts_a_grasp_that_holds_first_and_leaves_the_scene_as_it_was(smooth_variants: Path,
                                                                                robot: str) -> None:
    """A swinging-jaw arm's scripted operator tries its plans in the simulator before an attempt: a plan whose pads
    close on air (the real plan moved 6 cm off the handle) is put behind the one that holds, and afterwards every
    field of the scene's data is bit for bit what it was, so the episode goes on as if nothing had run."""
    from dataclasses import replace

    from rik.episodes.operators import make_operator
    from rik.episodes.record import randomise_start

    scene = build_scene(smooth_variants / SMOOTH_BOW, None, robot=CAT.robot(robot))
    rng = np.random.default_rng(0)
    randomise_start(scene, rng)
    op = make_operator("grasp_vertical")
    op.reset(scene, rng)  # its first attempt has started: the rehearsal runs from where its next one would
    real = op.planner(scene)[0]
    air = replace(real, tcp=real.tcp + np.array([0.0, 0.06, 0.0]), key="air")
    before = _derived(scene)
    order = op.rehearse_plans(scene, [air, real])
    after = _derived(scene)
    assert [p.key for p in order] == [real.key, "air"]
    for a, b in zip(before, after, strict=True):
        assert np.array_equal(a, b)
    assert op.rehearse_plans(scene, [air]) == [air]  # nothing holds: the order stays


def test_rehearsal_is_for_swinging_jaws_and_not_for_the_planned_strategies(smooth_variants: Path) -> None:
    """The Hand-E's parallel jaws never rehearse (their episodes are what they were), and ``planned``, whose grasps
    must not depend on the collision model (the fidelity ablation), does not rehearse on an arm either."""
    from rik.episodes.operators import STRATEGIES

    assert not any(STRATEGIES[s].make().rehearse for s in ("planned", "planned_above", "planned_typed"))
    assert all(STRATEGIES[s].make().rehearse for s in ("grasp_vertical", "grasp_horizontal", "contact_rich"))
    scene = build_scene(smooth_variants / SMOOTH_BOW, None)  # the Hand-E
    op = grasp_until_pull(scene, 400, "contact_rich")
    calls = []
    op.rehearse_plans = lambda s, plans: calls.append(plans) or plans  # type: ignore[method-assign]
    attempts = len(op.log)
    op._start_plan(scene)  # the next plan, as a re-grasp starts it
    assert calls == [] and len(op.log) == attempts + 1 and op.log[-1].startswith("attempt "), op.log


def test_a_stall_past_a_success_stops_the_pull(smooth_variants: Path) -> None:
    """A drawer whose stop sits at 93 % of its range: the Hand-E's hook pulls off the handle there (a slip; before
    this rule the re-grasps that followed left the drawer at 84 %). Past S's 90 % the closed-loop strategy stops
    instead of letting go for a re-grasp whose way in would push the front back."""
    scene = build_scene(smooth_variants / SMOOTH_BOW, None)
    lo, hi = scene.front.range
    scene.model.jnt_range[int(scene.model.dof_jntid[scene.front.dof_adr]), 1] = lo + 0.93 * (hi - lo)
    op = grasp_until_pull(scene, 400, "contact_rich")
    for _ in range(30 * scene.control_fps):
        if op.done:
            break
        scene.step(op.act(scene))
    assert op.done and op.log[-1].endswith("% open, past a success: stop"), op.log
    assert sum(line.startswith("attempt") for line in op.log) == 1
    assert 0.90 <= scene.opening() < 0.95
