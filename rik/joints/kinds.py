"""The one table of joint effect kinds: what each kind of :data:`rik.schemas.joints.JointEffect` is and how
rik expresses it in MuJoCo.

:data:`KINDS` maps each ``kind`` to an :class:`EffectKind`; its keys and schema classes come from the schema's
discriminated union, in the union's order, so a kind added there must be added to :data:`_HOW` here (import fails
otherwise). Every other list of kinds (the friction kinds, the native kinds, the laws, the MJCF writers, the
runtime channels, ``rik sysid``'s families and generator) derives from this table or is checked against it
(tests/test_joint_kinds.py).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

from rik.errors import RikError
from rik.schemas.joints import JointEffect, JointType

if TYPE_CHECKING:
    from pydantic import BaseModel, TypeAdapter

Mjcf = Literal["damping_quadratic", "actuator"]
"""How MuJoCo expresses a kind natively: the joint's quadratic damping term (``damping[1]``), or a passive
actuator on the joint (:func:`rik.joints.mjcf.add_effect_actuators`)."""
Channel = Literal["frictionloss", "damping", "qfrc_applied"]
"""How :class:`rik.joints.runtime.RuntimeEffects` applies a kind each step: added to the joint's
``dof_frictionloss`` (a friction magnitude on top of its Coulomb friction), to its ``dof_damping``, or as a force
in ``qfrc_applied``."""

JOINT_TYPES = tuple(t.value for t in JointType)
"""``slide``, ``hinge``."""


@dataclass(frozen=True)
class EffectKind:
    """One kind of joint effect."""

    name: str
    """The schema's ``kind``."""
    schema: type[BaseModel]
    """Its pydantic model in :mod:`rik.schemas.joints`."""
    runtime: Channel
    """How the simulator applies it when MuJoCo does not express it natively."""
    native: frozenset[str] = frozenset()
    """Joint types (``slide``, ``hinge``) on which MuJoCo expresses it in the MJCF itself."""
    mjcf: Mjcf | None = None
    """How it is written into the MJCF on those joint types (None: never native)."""

    @property
    def friction(self) -> bool:
        """True for friction magnitudes on top of the joint's Coulomb friction
        (:func:`rik.joints.laws.extra_friction`)."""
        return self.runtime == "frictionloss"


_BOTH = frozenset(JOINT_TYPES)
_HOW: dict[str, tuple[Channel, frozenset[str], Mjcf | None]] = {
    "stiction": ("frictionloss", frozenset(), None),
    "soft_close": ("damping", frozenset(), None),
    "self_close": ("qfrc_applied", _BOTH, "actuator"),
    "magnetic_catch": ("qfrc_applied", frozenset(), None),
    "tilt": ("qfrc_applied", frozenset({"slide"}), "actuator"),
    "direction_friction": ("frictionloss", _BOTH, "actuator"),
    "quadratic_damping": ("qfrc_applied", _BOTH, "damping_quadratic"),
    "load_friction": ("frictionloss", frozenset(), None),
}
"""(runtime channel, native joint types, MJCF form) per kind: the only place a kind is named by hand. Why
``stiction`` is not native: see :mod:`rik.joints.mjcf`."""


def _schemas() -> dict[str, type[BaseModel]]:
    union = get_args(JointEffect)[0]  # Annotated[Union[...], Field(discriminator="kind")]
    return {cls.model_fields["kind"].default: cls for cls in get_args(union)}


def _table() -> dict[str, EffectKind]:
    schemas = _schemas()
    if set(schemas) != set(_HOW):
        raise AssertionError(f"rik.joints.kinds: the schema's kinds {sorted(schemas)} and the table's "
                             f"{sorted(_HOW)} differ")  # pragma: no cover - a developer's error, caught on import
    return {kind: EffectKind(kind, cls, *_HOW[kind]) for kind, cls in schemas.items()}


KINDS: dict[str, EffectKind] = _table()
"""Every effect kind, in the order of the schema's union."""
EFFECT_KINDS: tuple[str, ...] = tuple(KINDS)
"""The kinds' names, in the union's order."""
FRICTION_KINDS = frozenset(k for k, how in KINDS.items() if how.friction)
"""Effects that are friction magnitudes (:func:`rik.joints.laws.extra_friction`)."""
SCHEMAS: tuple[type[BaseModel], ...] = tuple(how.schema for how in KINDS.values())
"""The kinds' pydantic models, in the union's order."""


@functools.cache
def _adapter() -> TypeAdapter[JointEffect]:
    from pydantic import TypeAdapter

    return TypeAdapter(JointEffect)


def as_effect(effect: JointEffect | Mapping[str, object]) -> JointEffect:
    """An effect model from a model or its ``model_dump()`` dict (as variants record runtime effects)."""
    if isinstance(effect, Mapping):
        try:
            return _adapter().validate_python(dict(effect))
        except ValueError as exc:  # pydantic's ValidationError: many lines; keep the first problem
            first = exc.errors()[0] if hasattr(exc, "errors") else {"loc": (), "msg": str(exc)}
            where = ".".join(str(p) for p in first.get("loc", ()))
            raise RikError(f"joint effect {dict(effect)!r}: field '{where}': {first['msg']}") from None
    return effect


def joint_type_name(joint_type: JointType | str) -> str:
    """``slide`` or ``hinge`` from a :class:`JointType` or its value; anything else is a :class:`RikError`."""
    value = getattr(joint_type, "value", joint_type)
    if value not in JOINT_TYPES:
        raise RikError(f"joint type '{value}' is not one of {', '.join(JOINT_TYPES)}")
    return str(value)


def native_kind(kind: str, joint_type: JointType | str) -> bool:
    """True when MuJoCo expresses effects of ``kind`` on a joint of ``joint_type`` in the MJCF itself."""
    return getattr(joint_type, "value", joint_type) in KINDS[kind].native


def is_native(effect: JointEffect | Mapping[str, object], joint_type: JointType | str) -> bool:
    """True when MuJoCo expresses ``effect`` on a joint of ``joint_type`` in the MJCF itself (rik writes it there);
    False when :class:`rik.joints.runtime.RuntimeEffects` applies it each step."""
    return native_kind(as_effect(effect).kind, joint_type_name(joint_type))
