"""The one mapping from rik's joint model (JointSpec + JointResistance) to MJCF.

Every variant's resistance lives in a joint default class per preset and joint type (``normal_slide``,
``normal_hinge``: Menagerie's convention), and each front's joint takes its class and adds only its own axis,
anchor and range. Everything that decides how a joint feels is set here and nowhere else, so extensions of the
joint model (springs acting in a zone, one-way damping, stiction: the calibration work of ``rik sysid``) change
this package only (:mod:`rik.joints`): effects MuJoCo has natively become attributes of the class or passive
actuators on each front's joint; effects it lacks become entries of :attr:`JointModel.runtime_effects`, which
rik's simulator applies each step (:mod:`rik.joints.runtime`).

Joint friction holds: MuJoCo's ``frictionloss`` is a soft constraint, and with its default impedance a front
pushed below its friction creeps (mm/s). Every joint class sets :data:`FRICTION_SOLIMP` and
:data:`FRICTION_SOLREF`, so a front held below breakaway stays put in plain MuJoCo too, with no rik code in the
loop (variants are assets people take elsewhere).

MuJoCo 4 spells damping and stiffness as polynomials (three coefficients: linear, quadratic, cubic); rik's
presets set the linear term, and the library's ``quadratic_damping`` the quadratic one.

Where each effect of :data:`rik.schemas.joints.JointEffect` goes (the table :data:`rik.joints.kinds.KINDS`;
:func:`rik.joints.kinds.is_native`):

- ``quadratic_damping``: the class's ``damping[1]``;
- ``self_close``: a passive actuator on the front's joint, ``general`` with gain 0, ``biastype="affine"``,
  ``biasprm="-k·z k 0"`` and ``forcerange="-k·z 0"``: F = clamp(k (q - z), -k·z, 0);
- ``tilt`` on a slide: a passive actuator with the constant bias ``biasprm="force 0 0"``;
- ``direction_friction``: a passive actuator with a clamped velocity bias, ``biasprm="0 0 -K"`` and
  ``forcerange="0 Δ"`` (closing) or ``"-Δ 0"`` (opening), K = Δ / :data:`DIRECTION_FRICTION_SPEED`:
  Coulomb friction on top of ``frictionloss`` in one direction, regularised below that speed;
- the others: :attr:`JointModel.runtime_effects`, applied around each step by
  :class:`rik.joints.runtime.RuntimeEffects` (``stiction`` and ``load_friction`` through the joint's
  ``frictionloss``, ``soft_close`` through its damping, ``magnetic_catch`` and a hinge's ``tilt`` through
  ``qfrc_applied``).

Passive actuators are per front joint, named ``<joint>/effect/<kind>``; their control (MuJoCo's affine actuators
have one) is ignored (gain 0). An effect of zero magnitude adds nothing. ``stiction`` is not native although
MuJoCo 4's ``dcmotor input="none"`` with ``lugre`` models it: LuGre needs a bristle stiffness and damping the
library does not have, is unstable with zero Coulomb level and bristle damping, and breaks away below its static
level unless the bristle damping is tuned to the moving mass (checked on a 2 kg slide at 2 ms, implicitfast).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

from rik.joints.kinds import KINDS, native_kind

if TYPE_CHECKING:
    import mujoco

    from rik.schemas import JointResistance, JointSpec, JointType, ResistancePreset
    from rik.schemas.joints import QuadraticDamping

LIMIT_MARGIN = 0.0
"""Joint-limit margin (m or rad): limits engage at the range's ends."""
DIRECTION_FRICTION_SPEED = {"slide": 1e-3, "hinge": 2.5e-3}
"""Speed (m/s, rad/s) over which direction-dependent friction ramps from 0 to its full value, natively (a clamped
velocity bias of gain ``extra / speed``) and at run time alike: the law is regularised below it. 2.5 mrad/s is
1 mm/s at a handle 0.4 m from the hinge. (Here, with everything that shapes the MJCF, so that variants' spec
hashes follow it.)"""
FRICTION_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
"""``solimpfriction`` of every front joint: the highest impedance MuJoCo allows (its ceiling is 0.9999). MuJoCo's
joint friction is a soft constraint that yields at a speed proportional to the load below breakaway
(``(1 - d) / d``: MuJoCo's default 0.9 let a high-preset drawer pushed at 90 % of its 30 N creep at 3.0 mm/s);
0.9999 cuts that 1000-fold, and motion above breakaway is unchanged (benchmarks/joint_fidelity.py). Chosen over
MuJoCo's no-slip pass, which also holds joints still but is a global option that changes every contact (the
grasps), and over LuGre (see the module docstring)."""
FRICTION_SOLREF = (0.004, 1.0)
"""``solreffriction`` of every front joint: a 4 ms time constant, MuJoCo's floor at rik's 2 ms step (the positive
form is clamped at two time steps, :data:`rik.combinator.mjcf.TIMESTEP`; MuJoCo's default is 20 ms). The creep left
at d = 0.9999 is another 5 times smaller: what remains is proportional to the load over the joint's inertia, and
the lightest fronts, the flaps (0.15 kg·m² about their hinge, a fifth of a door's), held at 90 % of the high
preset's 12 N·m crept at 0.00104 °/s with 5 ms and 0.00083 °/s with 4 ms (benchmarks/joint_fidelity.py)."""
MUJOCO_FRICTION_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
"""MuJoCo's default ``solimpfriction``: what a joint gets when nothing sets it."""
MUJOCO_FRICTION_SOLREF = (0.02, 1.0)
"""MuJoCo's default ``solreffriction`` (a 20 ms time constant)."""
JOINT_FRICTION_MODES: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {
    "held": (FRICTION_SOLIMP, FRICTION_SOLREF),
    "creeping": (MUJOCO_FRICTION_SOLIMP, MUJOCO_FRICTION_SOLREF)}
"""How a front's joint friction holds (``solimpfriction``, ``solreffriction``): ``held`` (rik's, the default: a
front loaded below breakaway stays put) or ``creeping`` (MuJoCo's defaults, what rik built before: such a front
creeps at mm/s). ``creeping`` exists for the fidelity ablation (docs/policies.md); the friction levels, damping
and effects are the same in both."""
DEFAULT_JOINT_FRICTION = "held"


@dataclass(frozen=True)
class JointModel:
    """How a joint of one type feels under one preset, in MuJoCo's terms (SI units of the joint type)."""

    type: str
    """``slide`` or ``hinge``."""
    damping: float
    frictionloss: float
    armature: float
    stiffness: float = 0.0
    springref: float = 0.0
    damping_quadratic: float = 0.0
    """``damping[1]``: N·s²/m² or N·m·s²/rad² (the library's ``quadratic_damping``)."""
    actuator_effects: tuple[dict[str, Any], ...] = field(default=())
    """Native effects written as passive actuators on each front joint (``effect.model_dump()``)."""
    runtime_effects: tuple[dict[str, Any], ...] = field(default=())
    """Effects MuJoCo cannot express natively (``effect.model_dump()``), for the simulator to apply per step."""


def joint_model(resistance: JointResistance, joint_type: JointType) -> JointModel:
    """The MuJoCo joint model of a preset's resistance for one joint type."""
    spring = resistance.spring
    quadratic = 0.0
    actuators: list[dict[str, Any]] = []
    runtime: list[dict[str, Any]] = []
    for effect in resistance.effects:
        if native_kind(effect.kind, joint_type) and KINDS[effect.kind].mjcf == "damping_quadratic":
            quadratic += cast("QuadraticDamping", effect).coefficient
        elif native_kind(effect.kind, joint_type):
            actuators.append(effect.model_dump(mode="json"))
        else:
            runtime.append(effect.model_dump(mode="json"))
    return JointModel(joint_type.value, resistance.damping, resistance.frictionloss, resistance.armature,
                      spring.stiffness if spring else 0.0, spring.reference if spring else 0.0, quadratic,
                      tuple(actuators), tuple(runtime))


def joint_class(preset_id: str, joint_type: JointType | str) -> str:
    """The name of the default class that holds a preset's resistance for a joint type (``normal_slide``)."""
    return f"{preset_id}_{getattr(joint_type, 'value', joint_type)}"


def add_joint_classes(spec: mujoco.MjSpec, preset: ResistancePreset, joint_types: list[JointType],
                      friction: str = DEFAULT_JOINT_FRICTION) -> dict[str, mujoco.MjsDefault]:
    """Add one default class per joint type holding ``preset``'s resistance, its friction holding as
    ``friction`` says (:data:`JOINT_FRICTION_MODES`); returns the classes by type."""
    import mujoco

    solimp, solref = JOINT_FRICTION_MODES[friction]
    classes: dict[str, mujoco.MjsDefault] = {}
    for joint_type in joint_types:
        model = joint_model(preset.for_joint(joint_type), joint_type)
        default = spec.add_default(joint_class(preset.id, joint_type), spec.default)
        joint = default.joint
        joint.type = mujoco.mjtJoint.mjJNT_SLIDE if model.type == "slide" else mujoco.mjtJoint.mjJNT_HINGE
        joint.damping[0] = model.damping
        joint.damping[1] = model.damping_quadratic
        joint.frictionloss = model.frictionloss
        joint.solimp_friction = list(solimp)
        joint.solref_friction = list(solref)
        joint.armature = model.armature
        joint.stiffness[0] = model.stiffness
        joint.springref = model.springref
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.margin = LIMIT_MARGIN
        classes[joint_type.value] = default
    return classes


def add_front_joint(body: mujoco.MjsBody, name: str, joint: JointSpec, default: mujoco.MjsDefault) -> mujoco.MjsJoint:
    """A front's joint: its class (the resistance), axis, anchor (the body sits at the base unit's origin, so
    the anchor is the joint's position) and range."""
    return body.add_joint(name=name, default=default, pos=list(joint.anchor), axis=list(joint.axis),
                          range=list(joint.range))


def effect_actuator_name(joint_name: str, kind: str) -> str:
    """The name of the passive actuator that carries effect ``kind`` on a joint (``drawer-1/effect/self_close``)."""
    return f"{joint_name}/effect/{kind}"


Bias = tuple[list[float], tuple[float, float] | None]
"""An actuator's ``biasprm[:3]`` and its force range (None: not force-limited)."""


def _self_close_bias(effect: dict[str, Any], joint_type: str) -> Bias:
    k, zone = float(effect["stiffness"]), float(effect["zone"])
    return [-k * zone, k, 0.0], (-k * zone, 0.0)


def _tilt_bias(effect: dict[str, Any], joint_type: str) -> Bias:
    return [float(effect["force"]), 0.0, 0.0], None


def _direction_friction_bias(effect: dict[str, Any], joint_type: str) -> Bias:
    extra = float(effect["extra"])
    gain = extra / DIRECTION_FRICTION_SPEED[joint_type]
    return [0.0, 0.0, -gain], ((0.0, extra) if effect["direction"] == "closing" else (-extra, 0.0))


ACTUATOR_BIAS: dict[str, Callable[[dict[str, Any], str], Bias]] = {
    "self_close": _self_close_bias, "tilt": _tilt_bias, "direction_friction": _direction_friction_bias}
"""kind → (effect dump, joint type) → the passive actuator of a native effect, for the kinds the table
(:data:`rik.joints.kinds.KINDS`) writes as ``actuator``."""


def add_effect_actuators(spec: mujoco.MjSpec, joint_name: str, model: JointModel) -> list[mujoco.MjsActuator]:
    """Add the passive actuators of ``model``'s native effects (:attr:`JointModel.actuator_effects`) to the joint
    ``joint_name``; returns them (none for effects of zero magnitude)."""
    import mujoco

    added = []
    for effect in model.actuator_effects:
        kind = effect["kind"]
        if kind not in ACTUATOR_BIAS:  # pragma: no cover - joint_model sends only these here
            raise ValueError(f"effect '{kind}' has no passive actuator")
        bias, limits = ACTUATOR_BIAS[kind](effect, model.type)
        if not any(bias) or (limits is not None and limits[0] == limits[1]):
            continue  # zero magnitude: no force (and MuJoCo refuses an empty force range)
        act = spec.add_actuator(name=effect_actuator_name(joint_name, kind), target=joint_name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = 0.0
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.biasprm[:3] = bias
        if limits is not None:
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = list(limits)
        added.append(act)
    return added
