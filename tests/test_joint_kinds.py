"""The one table of joint effect kinds (rik.joints.kinds.KINDS): every list of kinds in rik derives from it or
matches it, and every kind has a law, a way into MuJoCo and a sysid family."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from pydantic import TypeAdapter

from rik.joints.kinds import EFFECT_KINDS, FRICTION_KINDS, KINDS, native_kind
from rik.joints.laws import DAMPING_LAWS, FORCE_LAWS, FRICTION_LAWS
from rik.joints.mjcf import ACTUATOR_BIAS
from rik.joints.runtime import CHANNELS
from rik.schemas.joints import JointEffect, JointType
from rik.sysid.effects import FAMILIES
from rik.sysid.synthetic import generate
from rik.sysid.synthetic.foreign import FOREIGN_KINDS


def test_the_table_holds_the_schemas_kinds() -> None:
    mapping = TypeAdapter(JointEffect).json_schema()["discriminator"]["mapping"]
    assert EFFECT_KINDS == tuple(KINDS) and set(KINDS) == set(mapping)
    for kind, how in KINDS.items():
        assert how.name == kind and how.schema.model_fields["kind"].default == kind


def test_every_kind_has_one_law() -> None:
    assert set(FRICTION_LAWS) == FRICTION_KINDS == {k for k, how in KINDS.items() if how.runtime == "frictionloss"}
    assert set(FORCE_LAWS) == set(KINDS) - FRICTION_KINDS
    assert set(DAMPING_LAWS) == {k for k, how in KINDS.items() if how.runtime == "damping"}


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
    assert set(FOREIGN_KINDS) - {"none"} <= set(generate.EFFECT_KINDS)  # its laws are its own; its kinds are rik's
    for joint in JointType:
        assert set(generate.EFFECT_RANGES[joint]) == set(generate.EFFECT_KINDS) == set(generate.JOINT_KINDS[joint])


def test_variants_spec_hashes_follow_the_joint_package(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """rik.joints decides how a variant's joints are written, so its code is part of every spec hash: a copy of
    the package with one file changed gives another code digest."""
    from rik.combinator import build

    before = build._code_digest.__wrapped__()
    for name in ("COMBINATOR_DIR", "JOINTS_DIR"):  # copies side by side, as in rik/ (the digest sorts by path)
        copy = tmp_path / getattr(build, name).name
        shutil.copytree(getattr(build, name), copy, ignore=shutil.ignore_patterns("__pycache__"))
        monkeypatch.setattr(build, name, copy)
    assert build._code_digest.__wrapped__() == before
    mjcf = tmp_path / "joints" / "mjcf.py"
    mjcf.write_text(mjcf.read_text(encoding="utf-8") + "\n# changed\n", encoding="utf-8")
    assert build._code_digest.__wrapped__() != before
