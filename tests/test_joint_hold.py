"""Issue 31's acceptance tests: a front pushed below its friction stays put, one pushed above it opens.

Real high-preset variants (built once per module), a constant generalised push on the closed front's joint through
``qfrc_applied`` for 2 s of plain MuJoCo stepping (no rik code in the loop: variants are assets people take
elsewhere). The bounds are chosen so that the model as it was before issue 31 (MuJoCo's default friction
impedance, :func:`mujoco_default_friction`) fails each hold test: the last test checks that it does, so these tests
can fail. Measured at the time of writing (``benchmarks/joint_fidelity.py``): held at 90 %, the drawer moves
0.0014 mm and the door 0.0004 deg in 2 s; before the fix 6 mm and 1.7 deg.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

DRAWER = "drawer-chest-80__two_point-bow-128__high"
DOOR = "door-base-60-left__knob-mushroom-30__high"
SECONDS = 2.0
HOLD_BOUND = {DRAWER: 0.05e-3, DOOR: 0.05 * 3.141592653589793 / 180}
"""Most a front may move held at 90 % of its friction for 2 s: 0.05 mm, 0.05 deg."""
OPEN_BOUND = {DRAWER: 5e-3, DOOR: 5.0 * 3.141592653589793 / 180}
"""Least a front must move pushed at 110 % of its friction for 2 s: 5 mm, 5 deg."""


@pytest.fixture(scope="module")
def high_variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shared import builtin_catalog

    from rik.combinator.build import ensure_variant

    out = tmp_path_factory.mktemp("high-variants")
    for variant in (DRAWER, DOOR):
        ensure_variant(builtin_catalog(), variant, out)
    return out


def mujoco_default_friction(spec: Any) -> None:
    """MuJoCo's defaults, rik before issue 31."""
    for joint in spec.joints:
        joint.solimp_friction = [0.9, 0.95, 0.001, 0.5, 2.0]
        joint.solref_friction = [0.02, 1.0]


@dataclass
class Front:
    model: Any
    data: Any
    dof: int
    qadr: int
    frictionloss: float


def front(variants: Path, variant: str, before: bool = False) -> Front:
    """The variant's first front (closed, at rest), as built or with MuJoCo's default friction impedance."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(variants / variant / "model.xml"))
    if before:
        mujoco_default_friction(spec)
    model = spec.compile()
    dof = int(model.jnt_dofadr[0])
    return Front(model, mujoco.MjData(model), dof, int(model.jnt_qposadr[0]), float(model.dof_frictionloss[dof]))


def moved(f: Front, load: float) -> float:
    """How far the front moves from closed in :data:`SECONDS` under a constant push of ``load`` times its friction."""
    import mujoco

    q0 = float(f.data.qpos[f.qadr])
    f.data.qfrc_applied[f.dof] = load * f.frictionloss
    for _ in range(int(round(SECONDS / f.model.opt.timestep))):
        mujoco.mj_step(f.model, f.data)
    return float(f.data.qpos[f.qadr]) - q0


@pytest.mark.parametrize("variant", [DRAWER, DOOR])
def test_a_front_held_at_90_percent_of_its_friction_stays_put(high_variants: Path, variant: str) -> None:
    f = front(high_variants, variant)
    assert f.frictionloss == (30.0 if variant == DRAWER else 12.0)  # the high preset
    assert abs(moved(f, 0.9)) < HOLD_BOUND[variant]


@pytest.mark.parametrize("variant", [DRAWER, DOOR])
def test_a_front_pushed_at_110_percent_of_its_friction_opens(high_variants: Path, variant: str) -> None:
    assert moved(front(high_variants, variant), 1.1) > OPEN_BOUND[variant]


@pytest.mark.parametrize("variant", [DRAWER, DOOR])
def test_the_model_before_issue_31_fails_the_hold_test(high_variants: Path, variant: str) -> None:
    """The hold bound is tight enough to catch the creep of MuJoCo's default friction impedance (at least ten
    times over), and that model still opens above breakaway."""
    before = front(high_variants, variant, before=True)
    assert moved(before, 0.9) > 10 * HOLD_BOUND[variant]
    assert moved(front(high_variants, variant, before=True), 1.1) > OPEN_BOUND[variant]


def test_a_creeping_folder_builds_mujocos_default_friction(high_variants: Path, tmp_path: Path) -> None:
    """``--joint-friction creeping`` (the fidelity ablation's other side) builds exactly the model before issue 31:
    the same creep under the same push, its mode in the report, the model's text and the folder's marker."""
    import json

    from shared import builtin_catalog

    from rik.combinator.build import build_variants, spec_hash
    from rik.registry.ids import parse_variant_id

    key = parse_variant_id(builtin_catalog(), DRAWER)
    creep = tmp_path / "variants-creep"
    [result] = build_variants(builtin_catalog(), [key], creep, joint_friction="creeping")
    assert result.status == "built", result
    assert json.loads((creep / "joint_friction.json").read_text(encoding="utf-8")) == {"joint_friction": "creeping"}
    assert json.loads((creep / DRAWER / "report.json").read_text(encoding="utf-8"))["joint_friction"] == "creeping"
    assert '"joint_friction":"creeping"' in (creep / DRAWER / "model.xml").read_text(encoding="utf-8")
    assert not (high_variants / "joint_friction.json").exists()  # a held folder needs no marker
    assert spec_hash(builtin_catalog(), key, joint_friction="creeping") != spec_hash(builtin_catalog(), key)
    crept = moved(front(creep, DRAWER), 0.9)
    assert crept > 10 * HOLD_BOUND[DRAWER]
    assert crept == pytest.approx(moved(front(high_variants, DRAWER, before=True), 0.9), rel=1e-9)


def test_joint_friction_modes_are_checked_and_episodes_keep_theirs(rik, knob_recording: Path, tmp_path: Path) -> None:
    """A bad mode, a folder of the other mode, and an episode replayed in variants of the other mode: one line each."""
    import shutil

    from conftest import SHORT_KNOB

    out = tmp_path / "v"
    r = rik("variants", "build", SHORT_KNOB, "--joint-friction", "sticky", "--out", str(out))
    assert r.code == 2 and not out.exists()
    assert r.err.strip() == "rik: error: --joint-friction 'sticky': not a joint-friction mode; valid modes are held, " \
                            "creeping"
    r = rik("variants", "build", SHORT_KNOB, "--joint-friction", "creeping", "--out", str(out))
    assert r.code == 0 and "joint friction: creeping" in r.out, r.err
    r = rik("variants", "build", SHORT_KNOB, "--joint-friction", "held", "--out", str(out))
    assert r.code == 2
    assert r.err.strip() == f"rik: error: {out}: this folder holds creeping joint friction variants, not held (its " \
                            "joint_friction.json); build --joint-friction held variants into another --out folder"
    (out / "joint_friction.json").write_text('{"joint_friction": 1}', encoding="utf-8")
    r = rik("variants", "build", SHORT_KNOB, "--out", str(out))
    assert r.code == 2 and r.err.strip() == f"rik: error: {out / 'joint_friction.json'}: field joint_friction 1: " \
                                            "not a joint-friction mode; valid modes are held, creeping"
    (out / "joint_friction.json").write_text('{"joint_friction": "creeping"}', encoding="utf-8")
    [episode] = [d for d in (knob_recording / "episodes").iterdir() if (d / "meta.json").is_file()]
    copy = shutil.copytree(episode, tmp_path / "episodes" / episode.name)
    r = rik("replay", str(copy), "--variants", str(out))
    assert r.code == 2
    assert r.err.strip() == f"rik: error: {copy / 'meta.json'}: field 'joint_friction': held, but {out} holds variants " \
                            "whose joint friction is creeping (pass --variants with a held folder)"
