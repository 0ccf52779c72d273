"""The one table of joint effect kinds (rik.joints.kinds.KINDS): every list of kinds in rik derives from it or
matches it, and every kind has a law, a way into MuJoCo and a sysid family."""

from __future__ import annotations

from pydantic import TypeAdapter

from rik.joints.kinds import EFFECT_KINDS, FRICTION_KINDS, KINDS, native_kind
from rik.joints.laws import FORCE_LAWS, FRICTION_LAWS
from rik.joints.mjcf import ACTUATOR_BIAS
from rik.joints.runtime import CHANNELS
from rik.schemas.joints import JointEffect
from rik.sysid import generate
from rik.sysid.effects import FAMILIES


def test_the_table_holds_the_schemas_kinds() -> None:
    mapping = TypeAdapter(JointEffect).json_schema()["discriminator"]["mapping"]
    assert EFFECT_KINDS == tuple(KINDS) and set(KINDS) == set(mapping)
    for kind, how in KINDS.items():
        assert how.name == kind and how.schema.model_fields["kind"].default == kind


def test_every_kind_has_one_law() -> None:
    assert set(FRICTION_LAWS) == FRICTION_KINDS == {k for k, how in KINDS.items() if how.runtime == "frictionloss"}
    assert set(FORCE_LAWS) == set(KINDS) - FRICTION_KINDS


def test_every_kind_reaches_mujoco() -> None:
    """Natively where the table says so (with a writer for its MJCF form), at run time through a channel the
    simulator applies everywhere else."""
    for kind, how in KINDS.items():
        assert how.runtime in CHANNELS, kind
        assert (how.mjcf is None) == (not how.native), kind
        assert how.native <= {"slide", "hinge"}, kind
        for joint_type in ("slide", "hinge"):
            assert native_kind(kind, joint_type) == (joint_type in how.native)
    assert set(ACTUATOR_BIAS) == {k for k, how in KINDS.items() if how.mjcf == "actuator"}


def test_sysid_lists_derive_from_the_table() -> None:
    assert [f.kind for f in FAMILIES if f.kind != "spring"] == list(KINDS)
    assert generate.EFFECT_KINDS == (*KINDS, "spring")
    assert set(generate.EFFECT_RANGES[generate.JointType.slide]) == set(generate.EFFECT_KINDS)
    assert set(generate.EFFECT_RANGES[generate.JointType.hinge]) == set(generate.EFFECT_KINDS)
