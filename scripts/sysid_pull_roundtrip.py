"""The quasi-static round trip before and after rik's joint-friction fix: ``rik sysid`` fitted to pulls of rik's own
simulator, against the preset the variant was built with.

    uv run --locked python scripts/sysid_pull_roundtrip.py [--out DIR] [--speeds 1,0.1] [--trials 4]

Builds the drawer and the door of tests/test_sysid_roundtrip.py (same presets, in a user catalog under ``--out``,
default a temporary folder), pulls each front ``--trials`` times through its handle (:func:`rik.sim.pull.pull_profile`)
at speeds spread ±20 % around each fraction of the default (5 mm/s, 5 °/s), fits the pulls as a quasi-static profile
(:mod:`rik.sysid.profile_fit`) and prints a markdown table: the fitted friction level and effects against the
preset, in %. Each case runs twice: with today's joints (:data:`rik.joints.mjcf.FRICTION_SOLIMP`,
``FRICTION_SOLREF``) and with the joints before the fix (MuJoCo's defaults, set on the loaded spec: solimpfriction
0.9 0.95 0.001 0.5 2, solreffriction 0.02 1), whose friction yields below breakaway: a front pulled slowly is held
back by less than its friction, which the round trip reports as a low friction level.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from rik.schemas.joints import JointResistance, MagneticCatch, SelfClose, Spring

DRAWER = JointResistance(damping=5.0, frictionloss=15.0, effects=(SelfClose(zone=0.03, stiffness=300.0),),
                         provenance="assumed")
DOOR = JointResistance(damping=0.8, frictionloss=6.0, spring=Spring(stiffness=3.0),
                       effects=(MagneticCatch(force=4.0, decay=0.05),), provenance="assumed")
CASES = {"slide": ("rt-drawer", DRAWER, "drawer-bedside-45__knob-mushroom-30__rt-drawer", 0.06),
         "hinge": ("rt-door", DOOR, "door-base-40-right__knob-mushroom-30__rt-door", math.radians(36.0))}
"""joint -> (preset id, its resistance, the variant, the stroke in m or rad): tests/test_sysid_roundtrip.py's."""
MUJOCO_SOLIMP = [0.9, 0.95, 0.001, 0.5, 2.0]
MUJOCO_SOLREF = [0.02, 1.0]
"""MuJoCo's default friction impedance and reference: rik's joints before FRICTION_SOLIMP/FRICTION_SOLREF."""


def build(out: Path) -> dict[str, Path]:
    """The two variants, built under ``out``: joint -> folder."""
    from rik.combinator.build import ensure_variant
    from rik.registry import load_catalog
    from rik.schemas.joints import JointType
    from rik.sysid.preset import preset_file, write_preset

    base = load_catalog([]).preset("normal")
    for joint, (name, resistance, _, _) in CASES.items():
        if not preset_file(out / "catalog", name).exists():
            write_preset(resistance, JointType(joint), name, out / "catalog", base_preset=base,
                         description=f"round-trip {joint}")
    catalog = load_catalog([out / "catalog"])
    return {joint: ensure_variant(catalog, case[2], out / "variants") for joint, case in CASES.items()}


def source(folder: Path, before: bool):
    """The variant's model, as a spec with the pre-fix joint friction when ``before``."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(folder / "model.xml"))
    if before:
        for joint in spec.joints:
            joint.solimp_friction = MUJOCO_SOLIMP
            joint.solref_friction = MUJOCO_SOLREF
    return spec


def _pct(value: float, truth: float) -> str:
    return f"{value:.4g} ({100 * (value / truth - 1):+.1f} %)"


def round_trip(folder: Path, joint: str, fraction: float, trials: int, before: bool, work: Path) -> list[str]:
    """One row of the table."""
    from rik.sim.pull import DEFAULT_SPEED, pull_profile, write_profiles
    from rik.sysid.profile import read_profiles
    from rik.sysid.profile_fit import fit_profile

    _, preset, _, stroke = CASES[joint]
    speed = fraction * DEFAULT_SPEED[joint]
    spread = np.linspace(0.8, 1.2, trials) if trials > 1 else np.ones(1)
    start = time.perf_counter()
    pulls = [pull_profile(source(folder, before), speed=float(s * speed), stroke=stroke) for s in spread]
    data = read_profiles(write_profiles(work / f"{joint}.csv", pulls), joint)
    fit = fit_profile(data.groups[0], data.joint, data.force_unit)
    seconds = time.perf_counter() - start
    # what an ideal joint reads: friction plus damping at the training openings' mean speed (the level is fitted
    # on them); the rest of the level's error is the joint's friction yielding (creep)
    train = [p.speed for i, p in enumerate(pulls) if i not in fit.heldout_trials]
    bias = fit.level - (preset.frictionloss + preset.damping * float(np.mean(train)))
    found = {getattr(e, "kind", "spring"): e for e in fit.effects}
    parts = []
    for kind, effect in found.items():
        if isinstance(effect, SelfClose):
            parts.append(f"self_close pull {_pct(effect.stiffness * effect.zone, 9.0)}, zone "
                         f"{effect.zone * 1e3:.3g} mm")
        elif isinstance(effect, MagneticCatch):
            parts.append(f"catch {_pct(effect.force, 4.0)}, decay {math.degrees(effect.decay):.3g}°")
        elif isinstance(effect, Spring):
            parts.append(f"spring {_pct(effect.stiffness, 3.0)}")
        else:
            parts.append(kind)
    unit = "mm/s" if joint == "slide" else "°/s"
    shown = speed * 1e3 if joint == "slide" else math.degrees(speed)
    force = "N" if joint == "slide" else "N·m"
    return [joint, "before (MuJoCo default)" if before else "today", f"{shown:.3g} {unit}",
            f"{_pct(fit.level, preset.frictionloss)} {force}", f"{bias:+.2g} {force}", "; ".join(parts) or "none",
            f"{seconds:.1f}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="folder for the catalog and variants (default: temp)")
    parser.add_argument("--speeds", default="1,0.1", help="fractions of the default pull speed (5 mm/s, 5 °/s)")
    parser.add_argument("--trials", type=int, default=4, help="openings per case (speeds spread ±20 %%)")
    args = parser.parse_args()
    fractions = [float(s) for s in args.speeds.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        folders = build(out)
        print("| joint | joints | mean speed | friction level (preset: 15 N, 6 N·m) | level - (friction + damping × "
              "speed) | effects (preset: pull 9 N, zone 30 mm; catch 4 N·m, 2.86°; spring 3 N·m/rad) | s |")
        print("|---|---|---|---|---:|---|---:|")
        for joint, folder in folders.items():
            for fraction in fractions:
                for before in (False, True):
                    row = round_trip(folder, joint, fraction, args.trials, before, Path(tmp))
                    print("| " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
