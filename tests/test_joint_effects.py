"""Joint effects beyond damping and Coulomb friction: the library's laws, their materialisation (native MJCF or
per-step runtime), a variant with effects in the simulator (exact replays, gripper control), re-simulation of
measured trials, and writing a fitted preset into a user catalog."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from rik.errors import RikError
from rik.joints.kinds import FRICTION_KINDS, is_native
from rik.joints.laws import effect_force, extra_friction
from rik.joints.mjcf import DIRECTION_FRICTION_SPEED
from rik.joints.runtime import RuntimeEffects
from rik.registry import load_catalog
from rik.schemas.joints import (
    DirectionFriction,
    JointResistance,
    JointType,
    LoadFriction,
    MagneticCatch,
    QuadraticDamping,
    SelfClose,
    SoftClose,
    Stiction,
    Tilt,
)
from rik.sysid.resim import joint_spec_model, position_rmse, resimulate

SLIDE, HINGE = JointType.slide, JointType.hinge
RANGES = {SLIDE: (0.0, 0.4), HINGE: (0.0, 1.8)}
INERTIA = {SLIDE: 2.0, HINGE: 0.15}
BASE = {SLIDE: (4.0, 5.0), HINGE: (0.5, 2.0)}
"""Joint type -> (damping, frictionloss) of the resistance under the effect."""

EFFECTS = {
    "stiction": {SLIDE: Stiction(breakaway=3.0, stribeck_velocity=0.02),
                 HINGE: Stiction(breakaway=1.0, stribeck_velocity=0.05)},
    "soft_close": {SLIDE: SoftClose(zone=0.05, damping=40.0), HINGE: SoftClose(zone=0.3, damping=2.0,
                                                                                 closing_only=False)},
    "self_close": {SLIDE: SelfClose(zone=0.03, stiffness=300.0), HINGE: SelfClose(zone=0.2, stiffness=10.0)},
    "magnetic_catch": {SLIDE: MagneticCatch(force=6.0, decay=0.01), HINGE: MagneticCatch(force=2.0, decay=0.05)},
    "tilt": {SLIDE: Tilt(force=-1.5), HINGE: Tilt(force=0.8, sine=-1.2)},
    "direction_friction": {SLIDE: DirectionFriction(extra=2.0), HINGE: DirectionFriction(extra=1.0,
                                                                                        direction="opening")},
    "quadratic_damping": {SLIDE: QuadraticDamping(coefficient=30.0), HINGE: QuadraticDamping(coefficient=2.0)},
    "load_friction": {SLIDE: LoadFriction(per_extension=20.0), HINGE: LoadFriction(per_extension=1.5)},
}
NATIVE = {("quadratic_damping", SLIDE), ("quadratic_damping", HINGE), ("self_close", SLIDE), ("self_close", HINGE),
          ("direction_friction", SLIDE), ("direction_friction", HINGE), ("tilt", SLIDE)}


def _resistance(jt: JointType, *effects) -> JointResistance:
    damping, friction = BASE[jt]
    return JointResistance(damping=damping, frictionloss=friction, effects=effects, provenance="assumed")


def test_laws_follow_the_schema() -> None:
    q = np.array([0.0, 0.01, 0.02, 0.05])
    assert effect_force(MagneticCatch(force=4.0, decay=0.01), q, 0.0, SLIDE) == pytest.approx([-4, -1, -4 / 9, -4 / 36])
    assert effect_force(SelfClose(zone=0.02, stiffness=100), q, 0.3, SLIDE) == pytest.approx([-2, -1, 0, 0])
    assert effect_force(SoftClose(zone=0.03, damping=10), q, -0.1, SLIDE) == pytest.approx([1, 1, 1, 0])
    assert effect_force(SoftClose(zone=0.03, damping=10), q, 0.1, SLIDE) == pytest.approx([0, 0, 0, 0])  # closing only
    assert effect_force(Tilt(force=2.0, sine=1.0), math.pi / 2, 0.0, HINGE) == pytest.approx(1.0)
    assert effect_force(Tilt(force=2.0), 0.3, 0.0, SLIDE) == pytest.approx(2.0)
    assert effect_force(QuadraticDamping(coefficient=3.0), 0.1, [-2.0, 2.0], SLIDE) == pytest.approx([12, -12])
    stiction = Stiction(breakaway=3.0, stribeck_velocity=0.02)
    assert extra_friction(stiction, 0.1, [0.0, 0.02]) == pytest.approx([3.0, 3.0 / math.e])
    assert effect_force(stiction, 0.1, [-0.02, 0.0], SLIDE) == pytest.approx([3.0 / math.e, 0.0])
    closing = DirectionFriction(extra=2.0)
    assert extra_friction(closing, 0.1, [-0.5, 0.5]) == pytest.approx([2.0, 0.0])
    assert extra_friction(closing, 0.1, -0.0005, regularisation=0.001) == pytest.approx(1.0)
    assert extra_friction(LoadFriction(per_extension=10.0), [0.0, 0.2], 0.1) == pytest.approx([0.0, 2.0])
    assert effect_force({"kind": "load_friction", "per_extension": 10.0}, 0.2, -0.1, "slide") == pytest.approx(2.0)
    with pytest.raises(RikError, match="joint effect 'tilt' is not a friction effect"):
        extra_friction(Tilt(force=1.0), 0.0, 0.0)
    with pytest.raises(RikError, match=r"field 'stiction.stribeck_velocity': Input should be greater than 0"):
        effect_force({"kind": "stiction", "breakaway": 1.0, "stribeck_velocity": 0.0}, 0.0, 0.0, "slide")
    assert {(k, jt) for k, by in EFFECTS.items() for jt, e in by.items() if is_native(e, jt)} == NATIVE


def _forces(model, data, applier: RuntimeEffects, q: float, v: float, push: float = 0.0) -> tuple[float, float]:
    """(effect force, friction force) MuJoCo computes at (q, v): passive + actuator + applied forces less the base
    damping, and the constraint force (friction only: q is inside the range)."""
    mujoco.mj_resetData(model, data)
    data.qpos[0], data.qvel[0], data.qfrc_applied[0] = q, v, push
    applier.apply(data)
    mujoco.mj_forward(model, data)
    smooth = data.qfrc_passive[0] + data.qfrc_actuator[0] + data.qfrc_applied[0] - push + applier.base_damping * v
    friction = float(data.qfrc_constraint[0])
    applier.undo(data)
    return float(smooth), friction


@pytest.mark.parametrize("jt", [SLIDE, HINGE])
@pytest.mark.parametrize("kind", sorted(EFFECTS))
def test_materialised_joint_reproduces_the_law(kind: str, jt: JointType) -> None:
    """On a grid of (q, v), the forces of the 1-DOF model (native MJCF or runtime) equal the library law; friction
    effects as the sliding friction (saturated by a push along the motion)."""
    effect = EFFECTS[kind][jt]
    model, applier = joint_spec_model(jt, INERTIA[jt], _resistance(jt, effect), RANGES[jt])
    data = mujoco.MjData(model)
    assert is_native(effect, jt) == (not applier.effects)
    lo, hi = RANGES[jt]
    speed = DIRECTION_FRICTION_SPEED[jt.value]
    fl = BASE[jt][1]
    for q in np.linspace(lo + 0.002, hi - 0.002, 9):
        for v in (-0.5, -0.1, -0.03, -0.6 * speed, 0.6 * speed, 0.03, 0.1, 0.5):
            law = float(effect_force(effect, q, v, jt, regularisation=speed))
            if kind in FRICTION_KINDS and not is_native(effect, jt):  # runtime: MuJoCo's friction constraint
                total = fl + float(extra_friction(effect, q, v, speed))
                smooth, friction = _forces(model, data, applier, q, v, push=10 * total * np.sign(v))
                assert smooth == pytest.approx(0.0, abs=1e-9)
                assert friction == pytest.approx(-total * np.sign(v), rel=1e-6)
                assert friction + fl * np.sign(v) == pytest.approx(law, rel=1e-6, abs=1e-9)
            else:
                smooth, _ = _forces(model, data, applier, q, v)
                assert smooth == pytest.approx(law, rel=1e-6, abs=1e-9), (q, v)
                if abs(v) > speed:  # the regularised law is the library's ideal one away from rest
                    assert smooth == pytest.approx(float(effect_force(effect, q, v, jt)), rel=1e-6, abs=1e-9)
    # the model's arrays are back to the joint's own after every step
    assert model.dof_frictionloss[0] == fl and model.dof_damping[0] == BASE[jt][0]


def test_native_effects_are_in_the_model_arrays() -> None:
    effects = (QuadraticDamping(coefficient=3.0), SelfClose(zone=0.02, stiffness=100.0), Tilt(force=-1.5),
               DirectionFriction(extra=2.0, direction="opening"), MagneticCatch(force=1.0, decay=0.01))
    model, applier = joint_spec_model(SLIDE, 2.0, _resistance(SLIDE, *effects), (0.0, 0.4))
    assert model.dof_dampingpoly[0, 0] == 3.0 and model.dof_damping[0] == BASE[SLIDE][0]
    names = [model.actuator(i).name for i in range(model.nactuator)]
    assert names == ["joint/effect/self_close", "joint/effect/tilt", "joint/effect/direction_friction"]
    assert model.actuator_gainprm[:, 0].tolist() == [0.0, 0.0, 0.0]
    assert model.actuator_biasprm[0, :3].tolist() == [-2.0, 100.0, 0.0]
    assert model.actuator_forcerange[0].tolist() == [-2.0, 0.0]
    assert model.actuator_biasprm[1, :3].tolist() == [-1.5, 0.0, 0.0] and not model.actuator_forcelimited[1]
    assert model.actuator_biasprm[2, 2] == -2.0 / DIRECTION_FRICTION_SPEED["slide"]
    assert model.actuator_forcerange[2].tolist() == [-2.0, 0.0]
    assert [e.kind for e in applier.effects] == ["magnetic_catch"]
    hinge, applier = joint_spec_model(HINGE, 0.1, _resistance(HINGE, Tilt(force=1.0, sine=0.5)), (0.0, 1.5))
    assert hinge.nactuator == 0 and [e.kind for e in applier.effects] == ["tilt"]
    nothing, _ = joint_spec_model(SLIDE, 2.0, _resistance(SLIDE, SelfClose(zone=0.02, stiffness=0.0)), (0.0, 0.4))
    assert nothing.nactuator == 0  # zero magnitude: no actuator


def _terminal_velocity(jt: JointType, effect, force: float, seconds: float = 3.0) -> tuple[float, float]:
    """Velocity and travel after ``seconds`` of a constant ``force`` from rest at mid-range."""
    model, applier = joint_spec_model(jt, INERTIA[jt], _resistance(jt, effect), (-10.0, 10.0))
    data = mujoco.MjData(model)
    data.qfrc_applied[0] = force
    applier.step(data, round(seconds / model.opt.timestep))
    return float(data.qvel[0]), float(data.qpos[0])


def test_steady_sliding_and_sticking_follow_the_law() -> None:
    """Simulated: a constant pull reaches the speed where the law balances it; stiction holds below its
    breakaway and lets go above it; direction-dependent friction acts in its direction only."""
    d, fl = BASE[SLIDE]
    quad = QuadraticDamping(coefficient=30.0)
    v, _ = _terminal_velocity(SLIDE, quad, 15.0)
    assert d * v + fl + 30.0 * v * v == pytest.approx(15.0, rel=0.01)
    closing = DirectionFriction(extra=2.0)
    assert _terminal_velocity(SLIDE, closing, 12.0)[0] == pytest.approx((12.0 - fl) / d, rel=0.02)
    assert _terminal_velocity(SLIDE, closing, -12.0)[0] == pytest.approx(-(12.0 - fl - 2.0) / d, rel=0.02)
    stiction = Stiction(breakaway=3.0, stribeck_velocity=0.05)
    v, _ = _terminal_velocity(SLIDE, stiction, 9.0)
    assert d * v + fl + float(extra_friction(stiction, 0.0, v)) == pytest.approx(9.0, rel=0.01)
    # below 5 + 3 N: held (up to the creep of MuJoCo's soft friction constraint, a few mm/s); above: breaks away
    assert abs(_terminal_velocity(SLIDE, stiction, 7.0, seconds=1.0)[1]) < 0.01
    assert _terminal_velocity(SLIDE, Stiction(breakaway=0.0, stribeck_velocity=0.05), 7.0, seconds=1.0)[1] > 0.1
    assert _terminal_velocity(SLIDE, stiction, 8.5, seconds=1.0)[1] > 0.1


def test_runtime_effects_keep_other_applied_forces() -> None:
    model, applier = joint_spec_model(SLIDE, 2.0, _resistance(SLIDE, MagneticCatch(force=4.0, decay=0.01)),
                                      (0.0, 0.4))
    data = mujoco.MjData(model)
    data.qpos[0], data.qfrc_applied[0] = 0.01, 7.0
    applier.apply(data)
    applier.apply(data)  # a second apply undoes the first
    assert data.qfrc_applied[0] == 7.0 - 1.0
    applier.undo(data)
    assert data.qfrc_applied[0] == 7.0
    applier.apply(data)
    data.qfrc_applied[0] += 2.0  # another user adds its own meanwhile: kept
    applier.undo(data)
    assert data.qfrc_applied[0] == pytest.approx(9.0)


def test_resimulation_reproduces_the_model_that_made_the_data() -> None:
    """A trial made by continuous simulation of a model is re-simulated by multiple shooting with the same model
    to within interpolation error, and visibly worse with a model without the effects."""
    resistance = _resistance(SLIDE, MagneticCatch(force=6.0, decay=0.01), SelfClose(zone=0.03, stiffness=300.0),
                             SoftClose(zone=0.05, damping=40.0), Stiction(breakaway=3.0, stribeck_velocity=0.02))
    truth = joint_spec_model(SLIDE, 2.0, resistance, (0.0, 0.4))
    t = np.arange(0.0, 6.0, 0.004)
    force = 25.0 * np.sin(2 * np.pi * 0.4 * t) + 3.0
    q = resimulate(truth, t, np.zeros_like(t), np.zeros_like(t), force, window_s=100.0)
    assert q.max() > 0.1 and q.min() < 0.03  # it opens and comes back into the zones
    qd = np.gradient(q, t)
    same = position_rmse(truth, [(t, q, qd, force)])  # restarts from finite-difference velocities: not 0
    assert same < 1e-3
    plain = joint_spec_model(SLIDE, 2.0, _resistance(SLIDE), (0.0, 0.4))
    assert position_rmse(plain, [(t, q, qd, force)]) > 20 * same
    with pytest.raises(RikError, match="must have the same length"):
        resimulate(truth, t, q[:-1], qd, force)
    with pytest.raises(RikError, match="field 'range'"):
        joint_spec_model(SLIDE, 2.0, resistance, (0.1, 0.4))


# ---- a variant with effects: build, scene, episode, replay; the preset written into a user catalog ----------------
VARIANT_EFFECTS = (Stiction(breakaway=2.0, stribeck_velocity=0.02), MagneticCatch(force=3.0, decay=0.01),
                   SoftClose(zone=0.04, damping=30.0), SelfClose(zone=0.02, stiffness=100.0),
                   QuadraticDamping(coefficient=3.0), DirectionFriction(extra=2.0))


@pytest.fixture(scope="module")
def measured(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A user catalog holding preset ``fitted`` (written by write_preset) and its smallest variant, built."""
    from rik.combinator.build import build_variant
    from rik.registry.ids import VariantKey
    from rik.sysid.preset import write_preset

    root = tmp_path_factory.mktemp("measured")
    resistance = _resistance(SLIDE, *VARIANT_EFFECTS)
    write_preset(resistance, SLIDE, "fitted", root / "catalog", base_preset=load_catalog([]).preset("normal"),
                 description="fitted to a test drawer")
    catalog = load_catalog([root / "catalog"])
    result = build_variant(catalog, VariantKey("drawer/bedside-45", "knob/mushroom-30", "fitted"), root / "variants")
    assert result.status == "built", result.reason
    return root / "catalog", root / "variants"


VARIANT = "drawer-bedside-45__knob-mushroom-30__fitted"


def test_write_preset_round_trip_and_refusals(measured: tuple[Path, Path], tmp_path: Path) -> None:
    from rik.sysid.preset import write_preset

    catalog_dir, _ = measured
    catalog = load_catalog([catalog_dir])
    preset, normal = catalog.preset("fitted"), catalog.preset("normal")
    assert preset.slide == _resistance(SLIDE, *VARIANT_EFFECTS).model_copy(update={"provenance": "measured"})
    assert preset.hinge == normal.hinge and preset.description == "fitted to a test drawer"
    assert catalog.origins[("presets", "fitted")].file.endswith("preset-fitted.yaml")
    args = {"base_preset": normal, "description": "again"}
    with pytest.raises(RikError) as err:
        write_preset(preset.slide, SLIDE, "normal", catalog_dir, **args)
    assert str(err.value).endswith("preset-normal.yaml: preset 'normal' is a built-in preset "
                                   "(rik/registry/data/presets.yaml); choose another name")
    with pytest.raises(RikError) as err:
        write_preset(preset.slide, SLIDE, "fitted", catalog_dir, **args)
    assert str(err.value).endswith("preset-fitted.yaml: preset 'fitted' is already in the user catalog "
                                   f"({catalog_dir / 'preset-fitted.yaml'}); choose another name or remove it there")
    with pytest.raises(RikError, match=r"preset id 'my/preset' is not valid: use lower case letters"):
        write_preset(preset.slide, SLIDE, "my/preset", tmp_path, **args)
    assert sorted(p.name for p in catalog_dir.iterdir()) == ["preset-fitted.yaml"]  # nothing else left behind
    hinge = write_preset(_resistance(HINGE, Tilt(force=0.5, sine=0.2)), HINGE, "door-fit", tmp_path / "c", **args)
    door = load_catalog([tmp_path / "c"]).preset("door-fit")
    assert door.hinge.provenance == "measured" and door.hinge.effects == (Tilt(force=0.5, sine=0.2),)
    assert door.slide == normal.slide and hinge.name == "preset-door-fit.yaml"


def test_variant_with_effects_in_mjcf_and_info(measured: tuple[Path, Path]) -> None:
    import json

    _, variants = measured
    text = (variants / VARIANT / "model.xml").read_text()
    # quadratic damping is damping[1]; joint friction holds (rik.joints.mjcf.FRICTION_SOLIMP / FRICTION_SOLREF)
    assert ('<joint type="slide" solreffriction="0.004" solimpfriction="0.9999 0.9999" damping="4 3" '
            'frictionloss="5" limited="true"/>') in text
    assert '<general name="drawer/effect/self_close" joint="drawer"' in text
    assert '<general name="drawer/effect/direction_friction" joint="drawer"' in text
    spec = mujoco.MjSpec.from_file(str(variants / VARIANT / "model.xml"))
    info = json.loads(spec.text("rik.variant").data)
    assert info["fronts"][0]["runtime_effects"] == [e.model_dump(mode="json") for e in VARIANT_EFFECTS[:3]]


def test_scene_with_effects_records_replays_exactly_and_opens(measured: tuple[Path, Path], tmp_path: Path) -> None:
    from rik.episodes.record import record
    from rik.episodes.replay import verify_episode
    from rik.sim.build import build_scene

    catalog_dir, variants = measured
    catalog = load_catalog([catalog_dir])
    scene = build_scene(variants / VARIANT)
    m = scene.model
    names = [m.actuator(i).name for i in range(m.nactuator)]
    assert names[:2] == ["drawer/effect/self_close", "drawer/effect/direction_friction"]
    assert scene.jaw_ctrl == names.index("gripper/jaw") == 8 and scene.arm_ctrl.tolist() == list(range(2, 8))
    assert [e.kind for e in scene.effects[0].effects] == ["stiction", "magnetic_catch", "soft_close"]
    # the gripper's servos follow their commands: the base moves to a new pose and the jaws close
    target = scene.pose() + np.array([0.0, 0.03, 0.02, 0.0, 0.0, 0.0])
    start = scene.pose()
    for _ in range(40):
        scene.step(np.concatenate([target, [0.5]]))
    assert scene.data.ctrl[scene.arm_ctrl].tolist() == target.tolist() and scene.data.ctrl[:2].tolist() == [0, 0]
    assert np.abs(scene.pose() - target).max() < 0.25 * np.abs(target - start).max()
    assert scene.finger_opening() < 0.005
    assert m.dof_frictionloss[scene.front.dof_adr] == BASE[SLIDE][1]  # the runtime friction is put back
    # held shut by the self-closing spring and the magnet
    assert abs(scene.front_q()[0]) < 1e-3
    metas = record(catalog, VARIANT, "grasp_vertical", out=tmp_path, variants=variants, max_seconds=6.0)
    assert metas[0].outcome == "S"
    check = verify_episode(catalog, tmp_path / metas[0].id, variants)
    assert check.exact and check.rows == metas[0].steps + 1


def test_variant_checks_and_report_count_the_effects(measured: tuple[Path, Path]) -> None:
    """The test pull is sized with the effects that resist opening from closed (friction 5 N + stiction 2 N +
    self-closing pull 100 N/m x 0.02 m + magnet 3 N = 12 N), and report.json lists the runtime effects."""
    import json

    _, variants = measured
    report = json.loads((variants / VARIANT / "report.json").read_text())
    front = report["fronts"][0]
    assert front["force_to_open_n"] == pytest.approx(12.0, abs=0.05)
    assert [e["kind"] for e in front["runtime_effects"]] == ["stiction", "magnetic_catch", "soft_close"]
    assert report["status"] == "valid"
