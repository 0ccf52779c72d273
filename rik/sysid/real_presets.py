"""Real doors as resistance presets: the quasi-static fit of each measured door turned into a preset that variants
are built with, and the held-out openings to test the simulator against.

The data is ``everyday-door-force-profiles.csv`` (Jain et al., BioRob 2010; ``../shared/data/real/README.md``):
the force at the HANDLE that opened a door (N) against its angle, 36 bins of about 1° (read as 1 bin = 1°), per
opening (``trial``) and door (``mechanism``); no lever arm. :func:`read_doors` reads it, :func:`doors` leaves out
the study's ``noisy``/``known_rad`` variants (the same robot trials again).

**The split** (:func:`split_openings`, :func:`heldout_trials`): the last quarter of a door's openings in file order,
at least one, are held out -- :func:`rik.sysid.fit.heldout_trials`, the rule
:func:`rik.sysid.profile_fit.fit_profile` selects its model with. The preset is fitted on the other openings only.

**The conversion** (:func:`door_preset`): the fit's forces at the handle become hinge torques at the catalog's
lever arm r = :data:`rik.schemas.joints.CATALOG_LEVER_ARM` (0.40 m): torque = force x r, so a catch's ``force``, a
self-closing spring's ``stiffness`` (N/rad -> N·m/rad), a tilt's ``sine``, a closer spring's ``stiffness`` and the
friction level are multiplied by r; lengths along the joint (a catch's ``decay``, a zone) are angles already
(rad: the bins were read as degrees and converted). The friction level becomes ``frictionloss`` clamped at 0:
a negative level is a constant force pushing the door open, which only a tilt's constant part gives, so when the
fit has a tilt the level goes into the tilt's ``force`` (``-level x r``; its ``cos q`` falls by under 20 % over the
36°, the only change from the fit), and without one it is left out (the preset then resists by ``-level`` N more
than the fit). Damping and armature are not identifiable from quasi-static data (no velocity or acceleration):
they are the nearest paper preset's (:func:`nearest_paper_preset`). The slide side is the ``normal`` preset's (a
door has no slide). Values are rounded to 4 significant digits, and the errors stated are the rounded preset's.

**The comparison** (:func:`handle_force`): the force at the handle a preset's hinge side resists a slow opening
with, at given angles: what the simulator should need to open the door quasi-statically.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rik.errors import RikError
from rik.schemas.common import Provenance
from rik.schemas.joints import (
    CATALOG_LEVER_ARM,
    JointEffect,
    JointResistance,
    JointType,
    MagneticCatch,
    PresetSource,
    ResistancePreset,
    SelfClose,
    Spring,
    Tilt,
)
from rik.sysid.fit import heldout_trials as heldout_indices
from rik.sysid.profile import Profile, ProfileData, ProfileGroup, read_profiles
from rik.sysid.profile_fit import ProfileFit, describe, fit_profile

DATA_FILE = "everyday-door-force-profiles.csv"
"""The published name of the data file."""
REFERENCE = ("Jain, Nguyen, Rath, Okerman, Kemp: The Complex Structure of Simple Devices: A Survey of Trajectories "
             "and Forces that Open Doors and Drawers (IEEE BioRob 2010); hrl-assistive's door_opening_data.pkl")
"""The study the data comes from."""
VARIANT_MARKS = ("noisy", "known_rad")
"""Marks of the study's variants of the same robot trials (not doors of their own)."""
ID_PREFIX = "real-"
"""Prefix of a real door's preset id: ``real-hai-refrigerator``."""
BASE_SIDE = "normal"
"""The preset whose slide side a door's preset takes."""
DIGITS = 4
"""Significant digits of the values written into a preset."""
QUASI_STATIC = 1e-6
"""The opening speed :func:`handle_force` evaluates the joint laws at, rad/s: slow enough that damping adds
nothing, fast enough that friction acts opening."""


@dataclass(frozen=True)
class DataOrigin:
    """Where a door data file comes from, as its presets' source says it."""

    reference: str
    """The publication or measurement (a preset's ``source.reference``)."""
    data: str
    """The data file's name (``source.data``)."""
    cited: str
    """How a preset's description names it ("Jain et al. (BioRob 2010)")."""

    @staticmethod
    def user(path: str | Path) -> DataOrigin:
        """A user's own measured doors in the file at ``path``."""
        name = Path(path).name
        return DataOrigin(f"the user's own measurements ({name})", name, f"the user's measurements ({name})")


JAIN = DataOrigin(REFERENCE, DATA_FILE, "Jain et al. (BioRob 2010)")
"""The study behind rik's built-in real doors."""


@dataclass(frozen=True, eq=False)
class OpeningSplit:
    """A door's openings: those fitted and those held out to test on (file order)."""

    fitted: tuple[Profile, ...]
    heldout: tuple[Profile, ...]


@dataclass(frozen=True, eq=False)
class RealDoor:
    """One real door: its openings, the fit, the preset made of it and the preset's error."""

    group: ProfileGroup
    door_class: str
    """The study's class: Fridge, Freezer, Kitchen Cabinet, Office Cabinet."""
    split: OpeningSplit
    fit: ProfileFit
    preset: ResistancePreset


def read_doors(path: str | Path, drop_nan: bool = True) -> ProfileData:
    """The force profiles of the data file at ``path`` (its columns ``trial``, ``mechanism``, ``angle bin``,
    ``force [N]``), in SI: angles in rad (1 bin = 1°), forces in N at the handle; with ``drop_nan`` the rows with a
    NaN force are left out (8 in the published file), without it a NaN is an error naming the row."""
    return read_profiles(path, "hinge", position="angle bin", position_unit="bin", force="force [N]",
                         trial="trial", group="mechanism", drop_nan=drop_nan)


def door_classes(path: str | Path) -> dict[str, str]:
    """Mechanism -> its class (the file's ``class`` column)."""
    with Path(path).open(encoding="utf-8", newline="") as handle:
        return {row["mechanism"]: row["class"] for row in csv.DictReader(handle)}


def doors(data: ProfileData) -> list[ProfileGroup]:
    """The groups of ``data`` that are doors of their own: the study's ``noisy``/``known_rad`` variants left out."""
    return [g for g in data.groups if not any(m in g.name for m in VARIANT_MARKS)]


def split_openings(group: ProfileGroup) -> OpeningSplit:
    """The openings of a door fitted and held out: the last quarter held out, at least one (the split of
    :func:`rik.sysid.profile_fit.fit_profile`). A door needs two openings at least."""
    n = len(group.profiles)
    if n < 2:
        raise RikError(f"{group.name}: {n} opening; a preset is fitted on some openings and tested on others, so "
                       "it needs at least 2")
    out = set(heldout_indices(n, None, f"its {n} openings", f"{group.name}: "))
    return OpeningSplit(tuple(p for i, p in enumerate(group.profiles) if i not in out),
                        tuple(p for i, p in enumerate(group.profiles) if i in out))


def heldout_trials(group: ProfileGroup) -> tuple[str, ...]:
    """The names (the file's ``trial`` values) of the openings of ``group`` held out of its preset's fit."""
    return tuple(p.name for p in split_openings(group).heldout)


def fit_door(group: ProfileGroup) -> ProfileFit:
    """The quasi-static fit of a door on its fitted openings (selected on the held-out ones)."""
    held = {p.name for p in split_openings(group).heldout}
    return fit_profile(group, JointType.hinge, "N at the handle",
                       heldout=[i for i, p in enumerate(group.profiles) if p.name in held])


def preset_id(mechanism: str) -> str:
    """A door's preset id: ``real-`` and its name in lower case, ``_`` and spaces as ``-``
    (``hai_refrigerator`` -> ``real-hai-refrigerator``)."""
    return ID_PREFIX + "-".join(mechanism.lower().replace("_", " ").split())


def handle_force(resistance: JointResistance, q: Sequence[float] | np.ndarray,
                 lever_arm: float = CATALOG_LEVER_ARM) -> np.ndarray:
    """The force at the handle (N), ``lever_arm`` m from the axis, that a hinge with ``resistance`` needs to open
    slowly at angles ``q`` (rad, 0 closed): its friction plus every effect's and the spring's resistance (minus
    their force, :func:`rik.joints.laws.effect_force`, at :data:`QUASI_STATIC` rad/s), over the lever arm.
    Damping and inertia add nothing at that speed."""
    from rik.joints.laws import effect_force

    angles = np.asarray(q, dtype=np.float64)
    torque = np.full_like(angles, resistance.frictionloss)
    for effect in resistance.effects:
        torque -= effect_force(effect, angles, QUASI_STATIC, JointType.hinge)
    if resistance.spring is not None:
        torque += resistance.spring.stiffness * (angles - resistance.spring.reference)
    return torque / lever_arm


def nearest_paper_preset(mean_force: float, presets: Mapping[str, ResistancePreset],
                         lever_arm: float = CATALOG_LEVER_ARM) -> ResistancePreset:
    """The paper preset (``source.kind: paper``) whose hinge friction is nearest, as a ratio (on a log scale: 5, 15
    and 30 N are levels), to a door's mean opening force ``mean_force`` (N at the handle) x ``lever_arm``."""
    paper = [p for p in presets.values() if p.source is not None and p.source.kind is Provenance.paper]
    if not paper:
        raise RikError("the catalog has no paper preset (source kind: paper) to take damping and armature from")
    torque = max(mean_force * lever_arm, 1e-9)
    return min(paper, key=lambda p: abs(math.log(max(p.hinge.frictionloss, 1e-9) / torque)))


def door_paper_preset(split: OpeningSplit, presets: Mapping[str, ResistancePreset],
                      lever_arm: float = CATALOG_LEVER_ARM) -> ResistancePreset:
    """The paper preset a door's preset takes its damping and armature from (:func:`door_preset`), and the one
    to compare it with: the nearest (:func:`nearest_paper_preset`) to the mean force of its fitted openings."""
    return nearest_paper_preset(float(np.mean(np.concatenate([p.f for p in split.fitted]))), presets, lever_arm)


def _round(x: float) -> float:
    return float(f"{x:.{DIGITS}g}")


def _rms(residual: np.ndarray) -> float:
    return round(float(np.sqrt(np.mean(residual * residual))), 3)


def _convert(fit: ProfileFit, r: float) -> tuple[float, tuple[JointEffect, ...], Spring | None, str]:
    """The fit's hinge at lever arm ``r``: (frictionloss, effects, spring, a note on the friction level)."""
    level = fit.level
    effects: list[JointEffect] = []
    spring = None
    tilt_force = -level * r if level < 0 else 0.0
    for e in fit.effects:
        if isinstance(e, MagneticCatch):
            effects.append(MagneticCatch(force=_round(e.force * r), decay=_round(e.decay)))
        elif isinstance(e, SelfClose):
            effects.append(SelfClose(zone=_round(e.zone), stiffness=_round(e.stiffness * r)))
        elif isinstance(e, Tilt):
            effects.append(Tilt(force=_round(e.force * r + tilt_force), sine=_round(e.sine * r)))
        elif isinstance(e, Spring):
            spring = Spring(stiffness=_round(e.stiffness * r), reference=_round(e.reference))
        else:  # pragma: no cover - the profile fit names only the kinds above
            raise RikError(f"{fit.group}: a quasi-static fit cannot name a {type(e).__name__}")
    if level >= 0:
        return _round(level * r), tuple(effects), spring, f"friction level {level:.4g} N, the frictionloss"
    if any(isinstance(e, Tilt) for e in effects):
        note = (f"friction level {level:.4g} N, negative: it carries the tilt's constant part, so frictionloss is 0 "
                f"and the level is the tilt's force ({-level * r:.4g} N·m pushing open; its cos q changes the fit "
                f"by at most {-level * (1 - math.cos(fit.rows.q.max())):.2g} N at the handle)")
    else:
        note = (f"friction level {level:.4g} N, negative (the catch's tail carries the sliding force): clamped, "
                f"frictionloss 0, so the preset resists {-level:.3g} N more than the fit throughout")
    return 0.0, tuple(effects), spring, note


def door_preset(group: ProfileGroup, door_class: str, presets: Mapping[str, ResistancePreset], *,
                fit: ProfileFit | None = None, lever_arm: float = CATALOG_LEVER_ARM,
                origin: DataOrigin | None = None) -> ResistancePreset:
    """The resistance preset of a real door (module docstring): its hinge side the quasi-static fit on its fitted
    openings (:func:`fit_door`, or ``fit``) at ``lever_arm`` (m), damping and armature the nearest paper preset's,
    its slide side :data:`BASE_SIDE`'s (from ``presets``, the catalog's); its source names the data, the door, the
    trials and the preset's RMS error at the handle over the fitted and the held-out openings (N); ``origin``:
    where the data comes from (default: the study of Jain et al., :data:`JAIN`)."""
    origin = origin or JAIN
    split = split_openings(group)
    fit = fit if fit is not None else fit_door(group)
    friction, effects, spring, level_note = _convert(fit, lever_arm)
    q_fit = np.concatenate([p.q for p in split.fitted])
    f_fit = np.concatenate([p.f for p in split.fitted])
    nearest = door_paper_preset(split, presets, lever_arm)
    hinge = JointResistance(damping=nearest.hinge.damping, frictionloss=friction, armature=nearest.hinge.armature,
                            spring=spring, effects=effects, provenance=Provenance.measured, notes="")
    q_out = np.concatenate([p.q for p in split.heldout])
    f_out = np.concatenate([p.f for p in split.heldout])
    rms_fit = _rms(handle_force(hinge, q_fit, lever_arm) - f_fit)
    rms_out = _rms(handle_force(hinge, q_out, lever_arm) - f_out)
    found = "; ".join(describe(e, JointType.hinge, "N") for e in fit.effects) or "no position-dependent effect"
    notes = (f"fitted (rik.sysid.profile_fit, quasi-static) to {len(split.fitted)} openings of door "
             f"'{group.name}', forces at the handle x {lever_arm:.2f} m (the catalog's lever arm) as torques: "
             f"{found}; {level_note}. Damping and armature: the '{nearest.id}' preset's, nearest to the door's mean "
             f"opening force {np.mean(f_fit):.3g} N at the handle (not identifiable from quasi-static data: no "
             f"velocity or acceleration)")
    source = PresetSource(kind=Provenance.measured, reference=origin.reference, data=origin.data,
                          mechanism=group.name,
                          trials_fitted=len(split.fitted), trials_heldout=tuple(p.name for p in split.heldout),
                          fit_rms_n=rms_fit, heldout_rms_n=rms_out, lever_arm_m=lever_arm)
    base = presets[BASE_SIDE]
    return ResistancePreset(
        id=preset_id(group.name), name=f"{group.name} ({door_class})",
        description=(f"The hinge of a real {door_class.lower()} door, '{group.name}' of {origin.cited}, "
                     f"fitted to its measured opening forces; the slide is the {base.id} preset's (a door has none)."),
        slide=base.slide, hinge=hinge.model_copy(update={"notes": notes}), source=source)


def real_door_presets(path: str | Path, presets: Mapping[str, ResistancePreset],
                      origin: DataOrigin | None = None) -> list[RealDoor]:
    """Every door of the data file at ``path`` (variants left out) with its fit and preset, in file order;
    ``presets``: the catalog's (for the paper presets and :data:`BASE_SIDE`); ``origin``: where the data comes from
    (default :data:`JAIN`, whose 8 NaN forces are left out; a user's own doors, :meth:`DataOrigin.user`, where a NaN
    is an error)."""
    data = read_doors(path, drop_nan=origin is None or origin == JAIN)  # a user's own data: every value counts
    classes = door_classes(path)
    out = []
    for group in doors(data):
        fit = fit_door(group)
        out.append(RealDoor(group, classes[group.name], split_openings(group), fit,
                            door_preset(group, classes[group.name], presets, fit=fit, origin=origin)))
    return out
