"""The one mapping from rik's joint model (JointSpec + JointResistance) to MJCF.

Every variant's resistance lives in a joint default class per preset and joint type (``normal_slide``,
``normal_hinge``: Menagerie's convention), and each front's joint takes its class and adds only its own axis,
anchor and range. Everything that decides how a joint feels is set here and nowhere else, so extensions of the
joint model (springs acting in a zone, one-way damping, stiction: the calibration work of ``rik sysid``) change
this module only: effects MuJoCo has natively become attributes of the class; effects it lacks become entries
of :attr:`JointModel.runtime_effects`, which rik's simulator applies each step.

MuJoCo 4 spells damping and stiffness as polynomials (three coefficients: linear, quadratic, cubic); rik's
presets set the linear term.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rik.schemas import JointResistance, JointSpec, JointType, ResistancePreset

LIMIT_MARGIN = 0.0
"""Joint-limit margin (m or rad): limits engage at the range's ends."""


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
    runtime_effects: tuple[dict[str, Any], ...] = field(default=())
    """Effects MuJoCo cannot express natively, for the simulator to apply per step (none in rik's presets yet)."""


def joint_model(resistance: JointResistance, joint_type: JointType) -> JointModel:
    """The MuJoCo joint model of a preset's resistance for one joint type."""
    spring = resistance.spring
    return JointModel(joint_type.value, resistance.damping, resistance.frictionloss, resistance.armature,
                      spring.stiffness if spring else 0.0, spring.reference if spring else 0.0)


def joint_class(preset_id: str, joint_type: JointType | str) -> str:
    """The name of the default class that holds a preset's resistance for a joint type (``normal_slide``)."""
    return f"{preset_id}_{getattr(joint_type, 'value', joint_type)}"


def add_joint_classes(spec: Any, preset: ResistancePreset, joint_types: list[JointType]) -> dict[str, Any]:
    """Add one default class per joint type holding ``preset``'s resistance; returns the classes by type."""
    import mujoco

    classes = {}
    for joint_type in joint_types:
        model = joint_model(preset.for_joint(joint_type), joint_type)
        default = spec.add_default(joint_class(preset.id, joint_type), spec.default)
        joint = default.joint
        joint.type = mujoco.mjtJoint.mjJNT_SLIDE if model.type == "slide" else mujoco.mjtJoint.mjJNT_HINGE
        joint.damping[0] = model.damping
        joint.frictionloss = model.frictionloss
        joint.armature = model.armature
        joint.stiffness[0] = model.stiffness
        joint.springref = model.springref
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.margin = LIMIT_MARGIN
        classes[joint_type.value] = default
    return classes


def add_front_joint(body: Any, name: str, joint: JointSpec, default: Any) -> Any:
    """A front's joint: its class (the resistance), axis, anchor (the body sits at the base unit's origin, so
    the anchor is the joint's position) and range."""
    return body.add_joint(name=name, default=default, pos=list(joint.anchor), axis=list(joint.axis),
                          range=list(joint.range))
