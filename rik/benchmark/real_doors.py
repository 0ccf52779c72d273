"""The simulator's force error against real doors: each measured door pulled in rik's simulator the way it was
pulled for real, compared with its held-out openings.

For every door of the real data (:mod:`rik.sysid.real_presets`: Jain et al., BioRob 2010; forces at the handle
against the angle, no time axis) a door variant is built twice, once with the door's fitted preset
(``real-<door>``) and once with the paper preset nearest to it (the one whose damping and armature the fitted
preset took), and each is opened quasi-statically through its handle by :func:`rik.sim.pull.pull_profile` (a
hook on the grasp site moving at 5 °/s). The hook's force times the handle's lever arm is the torque the door
resisted with; divided by the catalog's lever arm (:data:`rik.schemas.joints.CATALOG_LEVER_ARM`, 0.40 m, at
which the presets were converted from handle forces) it is the force at the handle the measured profile gives,
so the variant's own handle position does not enter. The error is the RMS difference, in N, between that
simulated force and every sample of the door's **held-out** openings (never the ones its preset was fitted on),
at the measured angles.

Units: angles rad, forces N at the handle (at the catalog's lever arm), torques N·m, speeds rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.outputs import RECORDED, save_figure
from rik.paths import pyplot
from rik.registry.ids import variant_id
from rik.schemas.joints import CATALOG_LEVER_ARM

if TYPE_CHECKING:
    from rik.outputs import Replaces
    from rik.registry.catalog import Catalog
    from rik.sysid.real_presets import RealDoor

DOOR_BASE = "door/base-60-left"
"""The base unit the doors are simulated in: a single hinged door."""
DOOR_HANDLE = "knob/mushroom-30"
"""Its handle: a knob, which a force gauge's hook holds as well as a bar."""
PULL_SPEED = math.radians(5.0)
"""rad/s: the quasi-static opening speed (the speed of :func:`rik.sim.pull.pull_profile` and of the joint-fidelity
benchmark's force profiles)."""
SAMPLE_SPACING = math.radians(0.1)
"""rad between the simulated samples: fine enough that a catch, whose pull is strongest at closed and falls to a
quarter within 2-8°, is sampled next to closed (the measured profiles' first bin is where the door starts to
open), where the pull's default spacing of 1° would miss its peak."""
STROKE_MARGIN = math.radians(1.0)
"""rad pulled past the last measured angle, so that every measured sample lies inside the simulated profile."""


@dataclass(frozen=True, eq=False)
class SimulatedDoor:
    """One door's held-out openings against the simulator, with the fitted and the nearest paper preset."""

    door: str
    door_class: str
    fitted_preset: str
    paper_preset: str
    heldout: tuple[str, ...]
    """The held-out openings' trial names."""
    angles: tuple[np.ndarray, ...]
    """rad, per held-out opening."""
    measured: tuple[np.ndarray, ...]
    """N at the handle, per held-out opening."""
    sim_q: dict[str, np.ndarray]
    """Preset id -> the simulated pull's angles (rad)."""
    sim_force: dict[str, np.ndarray]
    """Preset id -> the simulated force at the catalog's lever arm (N) at those angles."""
    rms_paper_n: float
    """RMS error of the simulated door with the nearest paper preset against the held-out samples, N."""
    rms_fitted_n: float
    """The same with the door's fitted preset, N."""
    rms_law_n: float
    """The fitted preset's own law (no simulation) against the same samples, N: its source's ``heldout_rms_n``."""


def simulated_force(catalog: Catalog, preset: str, variants: Path, stroke: float, *,
                    base: str = DOOR_BASE, handle: str = DOOR_HANDLE,
                    speed: float = PULL_SPEED) -> tuple[np.ndarray, np.ndarray]:
    """Build the door variant of ``base`` and ``handle`` with ``preset`` into ``variants`` (reused when valid) and
    pull it open to ``stroke`` rad at ``speed`` rad/s: (angles in rad, force at the catalog's lever arm in N)."""
    from rik.combinator.build import ensure_variant
    from rik.sim.pull import pull_profile

    folder = ensure_variant(catalog, variant_id(base, handle, preset), variants)
    pull = pull_profile(folder, speed=speed, stroke=stroke, spacing=SAMPLE_SPACING)
    if pull.joint != "hinge":
        raise RikError(f"{variant_id(base, handle, preset)}: the real doors are hinges; its front is a {pull.joint}")
    return pull.q, pull.joint_force / CATALOG_LEVER_ARM


def _rms(angles: Sequence[np.ndarray], measured: Sequence[np.ndarray], q: np.ndarray, force: np.ndarray) -> float:
    residual = np.concatenate([np.interp(a, q, force) - f for a, f in zip(angles, measured, strict=True)])
    return float(np.sqrt(np.mean(residual * residual)))


def simulate_door(catalog: Catalog, door: RealDoor, variants: Path) -> SimulatedDoor:
    """Pull ``door``'s variants (its fitted preset, which must be in ``catalog``, and the nearest paper preset) and
    compare both with its held-out openings."""
    from rik.sysid.real_presets import door_paper_preset

    fitted = door.preset
    if fitted.id not in catalog.presets:
        raise RikError(f"preset '{fitted.id}' of door '{door.group.name}' is not in the catalog; write the doors' "
                       "presets with scripts/real_door_presets.py DATA.csv --out FILE and give the file with "
                       "--catalog (rik's own doors: regenerate rik/registry/data/presets_measured.yaml)")
    fitted_q = np.concatenate([p.q for p in door.split.fitted])
    paper = door_paper_preset(door.split, catalog.presets)
    angles = tuple(np.asarray(p.q, np.float64) for p in door.split.heldout)
    measured = tuple(np.asarray(p.f, np.float64) for p in door.split.heldout)
    stroke = float(max(np.max(fitted_q), *(np.max(a) for a in angles))) + STROKE_MARGIN
    sim_q, sim_force = {}, {}
    for preset in (paper.id, fitted.id):
        sim_q[preset], sim_force[preset] = simulated_force(catalog, preset, variants, stroke)
    assert fitted.source is not None and fitted.source.heldout_rms_n is not None  # door_preset states both
    return SimulatedDoor(door.group.name, door.door_class, fitted.id, paper.id,
                         tuple(p.name for p in door.split.heldout), angles, measured, sim_q, sim_force,
                         _rms(angles, measured, sim_q[paper.id], sim_force[paper.id]),
                         _rms(angles, measured, sim_q[fitted.id], sim_force[fitted.id]), fitted.source.heldout_rms_n)


def simulate_doors(catalog: Catalog, data: Path, variants: Path,
                   progress: Callable[[str], None] | None = None) -> list[SimulatedDoor]:
    """Every door of the real data file ``data`` (the study's variants left out), in file order; ``progress`` is
    called with each door's name before it is simulated."""
    from rik.sysid.real_presets import real_door_presets

    out = []
    for door in real_door_presets(data, catalog.presets):
        if progress is not None:
            progress(door.group.name)
        out.append(simulate_door(catalog, door, variants))
    return out


def error_table(results: Sequence[SimulatedDoor]) -> str:
    """A markdown table: per door, the RMS force error of the simulator against its held-out openings with the
    nearest paper preset and with its fitted preset (and the fitted law's own), then the medians."""
    rows = ["| door | class | held-out openings | paper preset | RMS, paper preset (N) | fitted preset | "
            "RMS, fitted preset (N) | RMS, fitted law alone (N) |",
            "|---|---|---:|---|---:|---|---:|---:|"]
    for r in results:
        rows.append(f"| {r.door} | {r.door_class} | {len(r.heldout)} | {r.paper_preset} | {r.rms_paper_n:.2f} | "
                    f"`{r.fitted_preset}` | {r.rms_fitted_n:.2f} | {r.rms_law_n:.2f} |")
    if results:
        median = {k: float(np.median([getattr(r, k) for r in results]))
                  for k in ("rms_paper_n", "rms_fitted_n", "rms_law_n")}
        rows.append(f"| **median of {len(results)} doors** | | | | **{median['rms_paper_n']:.2f}** | | "
                    f"**{median['rms_fitted_n']:.2f}** | {median['rms_law_n']:.2f} |")
    return "\n".join(rows) + "\n"


def plot_grid(results: Sequence[SimulatedDoor], path: Path, columns: int = 4, replaces: Replaces | None = None) -> Path:
    """A grid of plots, one per door: the held-out openings (grey), the simulated pull with the nearest paper preset
    (dashed) and with the fitted preset (solid), force at the handle against the angle in degrees. A file at
    ``path`` is replaced as ``replaces`` says (default: rik's own earlier plot there, :data:`rik.outputs.RECORDED`)."""

    plt = pyplot()
    rows = max(1, math.ceil(len(results) / columns))
    fig, axes = plt.subplots(rows, columns, figsize=(3.4 * columns, 2.6 * rows), squeeze=False)
    for ax, r in zip(axes.flat, results, strict=False):
        for a, f in zip(r.angles, r.measured, strict=True):
            ax.plot(np.degrees(a), f, color="0.6", lw=0.8)
        top = max(float(np.max(f)) for f in r.measured)
        for preset, style, label in ((r.paper_preset, "--", f"{r.paper_preset} {r.rms_paper_n:.1f} N"),
                                     (r.fitted_preset, "-", f"fitted {r.rms_fitted_n:.1f} N")):
            q, force = r.sim_q[preset], r.sim_force[preset]
            keep = q >= 0.0
            ax.plot(np.degrees(q[keep]), force[keep], style, lw=1.4, label=label)
            top = max(top, float(np.max(force[keep])))
        ax.set_title(f"{r.door} ({r.door_class})", fontsize=8)
        ax.set_ylim(min(0.0, *(float(np.min(f)) for f in r.measured)), top * 1.1)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="upper right")
    for ax in list(axes.flat)[len(results):]:
        ax.axis("off")
    fig.supxlabel("door angle (°)")
    fig.supylabel(f"force at the handle (N, at {CATALOG_LEVER_ARM:.2f} m)")
    fig.tight_layout()
    return save_figure(fig, path, replaces or RECORDED)
