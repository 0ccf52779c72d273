"""Real doors as presets (rik.sysid.real_presets): the held-out split, the conversion at the catalog's lever arm, the
built-in file generated from the data, the default variant matrix left as it was, and a variant built with one."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import mujoco
import numpy as np
import pytest
from conftest import REPO
from shared import builtin_catalog

from rik.registry.ids import select_variants
from rik.schemas.common import Provenance
from rik.schemas.joints import CATALOG_LEVER_ARM, MagneticCatch, Tilt
from rik.sysid.profile import Profile, ProfileGroup
from rik.sysid.profile_fit import predict
from rik.sysid.real_presets import (
    door_preset,
    fit_door,
    handle_force,
    heldout_trials,
    preset_id,
    split_openings,
)

CSV = REPO.parent / "shared" / "data" / "real" / "everyday-door-force-profiles.csv"
"""The shared door profiles (outside the repository: tests that need them skip without them)."""
Q = np.radians(np.arange(36.0))
"""36 bins of 1°, as the data, rad."""


def door(level: float, catch: float, decay_deg: float, sine: float, openings: int = 8) -> ProfileGroup:
    """A synthetic door: force at the handle (N) = level + a catch's pull - sine x sin(q), plus 0.2 N of noise."""
    rng = np.random.default_rng(7)
    f = level + catch / (1 + Q / math.radians(decay_deg)) ** 2 - sine * np.sin(Q)
    return ProfileGroup("test_door", tuple(Profile(str(100 + i), Q, f + rng.normal(0, 0.2, Q.size))
                                           for i in range(openings)))


def test_the_split_is_the_profile_fits() -> None:
    for openings, held in ((8, ("106", "107")), (6, ("105",)), (2, ("101",))):
        group = door(2.0, 20.0, 3.0, 0.0, openings)
        split = split_openings(group)
        assert heldout_trials(group) == held == tuple(p.name for p in split.heldout)
        assert len(split.fitted) + len(split.heldout) == openings
        if openings >= 4:  # two openings have too few points to fit on one
            fit = fit_door(group)
            assert tuple(fit.rows.names[i] for i in fit.heldout_trials) == held


def test_the_conversion_reproduces_the_fit_at_the_lever_arm() -> None:
    group = door(2.0, 20.0, 3.0, 0.0)
    fit = fit_door(group)
    preset = door_preset(group, "Fridge", builtin_catalog().presets, fit=fit)
    hinge = preset.hinge
    assert preset.id == "real-test-door" == preset_id("test_door") and not preset.in_default_set
    assert math.isclose(hinge.frictionloss, fit.level * CATALOG_LEVER_ARM, rel_tol=1e-3)
    catch = next(e for e in hinge.effects if isinstance(e, MagneticCatch))
    assert math.isclose(catch.force, 20.0 * CATALOG_LEVER_ARM, rel_tol=0.05)
    assert math.isclose(catch.decay, math.radians(3.0), rel_tol=0.1)  # an angle, unchanged
    np.testing.assert_allclose(handle_force(hinge, Q), predict(fit.selection.final, Q, fit.joint), atol=0.02)
    src = preset.source
    assert src is not None and src.kind is Provenance.measured and src.lever_arm_m == CATALOG_LEVER_ARM
    assert (src.trials_fitted, src.trials_heldout) == (6, ("106", "107"))
    assert src.fit_rms_n == pytest.approx(fit.selection.final.rmse_train, abs=0.01)
    assert src.heldout_rms_n == pytest.approx(fit.selection.final.rmse_heldout, abs=0.01)
    smooth, normal = builtin_catalog().preset("smooth"), builtin_catalog().preset("normal")
    assert (hinge.damping, hinge.armature) == (smooth.hinge.damping, smooth.hinge.armature)  # nearest to ~3 N
    assert preset.slide == normal.slide and "not identifiable" in hinge.notes


def test_a_negative_level_becomes_the_tilts_constant_part() -> None:
    group = door(-4.0, 40.0, 6.0, -12.0)  # a fridge: its seal, and gravity closing it at wide angles
    fit = fit_door(group)
    assert fit.level < 0 and sorted(type(e).__name__ for e in fit.effects) == ["MagneticCatch", "Tilt"]
    hinge = door_preset(group, "Fridge", builtin_catalog().presets, fit=fit).hinge
    tilt = next(e for e in hinge.effects if isinstance(e, Tilt))
    assert hinge.frictionloss == 0.0
    assert math.isclose(tilt.force, -fit.level * CATALOG_LEVER_ARM, rel_tol=1e-3)  # pushing open
    gap = np.abs(handle_force(hinge, Q) - predict(fit.selection.final, Q, fit.joint))
    assert gap.max() <= -fit.level * (1 - math.cos(Q.max())) + 0.02  # only the tilt's cos q differs from the fit
    assert "carries the tilt's constant part" in hinge.notes


def test_measured_presets_are_built_only_when_named() -> None:
    catalog = builtin_catalog()
    measured = [p for p in catalog.presets.values() if p.source is not None and p.source.kind is Provenance.measured]
    assert len(measured) == 16 and all(p.id.startswith("real-") and not p.in_default_set for p in measured)
    assert all(p.source is not None and p.source.mechanism and p.source.trials_heldout
               and p.hinge.provenance is Provenance.measured for p in measured)
    assert catalog.default_presets == ["smooth", "normal", "high"]
    assert len(select_variants(catalog)) == 3 * 1079
    named = select_variants(catalog, bases=["door/base-60-left"], presets=["real-hai-refrigerator"])
    assert len(named) == 83 and {k.preset for k in named} == {"real-hai-refrigerator"}


def test_stats_and_list_say_where_presets_come_from(rik) -> None:
    stats = json.loads(rik("catalog", "stats", "-f", "json").out)
    assert stats["presets"] == ["smooth", "normal", "high"] and len(stats["named_presets"]) == 16
    listed = rik("catalog", "list", "--kind", "presets").out
    row = next(line for line in listed.splitlines() if line.startswith("real-hai-refrigerator "))
    assert "measured: everyday-door-force-profiles.csv hai_refrigerator; RMS" in row and "held out" in row
    assert next(line for line in listed.splitlines() if line.startswith("smooth ")).endswith("paper")


@pytest.mark.skipif(not CSV.is_file(), reason=f"no {CSV}")
def test_the_measured_presets_file_is_what_the_data_gives() -> None:
    result = subprocess.run([sys.executable, str(REPO / "scripts" / "real_door_presets.py"), str(CSV), "--check"],
                            capture_output=True, text=True, cwd=REPO, timeout=300)
    assert result.returncode == 0, result.stderr


def test_a_variant_with_a_measured_preset_builds_and_loads(rik, tmp_path) -> None:
    variant = "door-base-60-left__knob-mushroom-30__real-hai-refrigerator"
    result = rik("variants", "build", variant, "--out", str(tmp_path))
    assert result.code == 0, result.err
    report = json.loads((tmp_path / variant / "report.json").read_text())
    assert report["status"] == "valid"
    model = mujoco.MjModel.from_xml_path(str(tmp_path / variant / "scene.xml"))
    hinge = builtin_catalog().preset("real-hai-refrigerator").hinge
    dof = model.jnt_dofadr[model.joint("door").id]
    assert (model.dof_frictionloss[dof], model.dof_damping[dof]) == pytest.approx((hinge.frictionloss, hinge.damping))
    front = report["fronts"][0]
    kinds = {e["kind"] for e in front["runtime_effects"]}
    assert kinds == {"magnetic_catch", "tilt"}  # a hinge's tilt and a catch: applied by rik's simulator each step
    # what holds it shut (catch minus the tilt's push) at this variant's own handle, 0.53 m from the axis
    assert front["force_to_open_n"] == pytest.approx(hinge.hold_at_closed() / front["lever_arm_m"], rel=1e-3)
