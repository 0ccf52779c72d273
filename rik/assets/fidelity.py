"""Collision fidelity (paper section 3.2): how far the collision shell strays from the visual surface.

P is the visual surface; Q the collision shell, the boundary of the union of the convex parts. Q is sampled by
sampling every part's surface uniformly (by area) and dropping the points that lie inside another part. Then

- E_Q->P: for each shell point, the distance to the visual surface: how far the collision bulges out of, or
  cuts into, the real part;
- E_P->Q: for each visual point, the distance to the shell: which real surface the collision misses (a filled
  loop shows up in both).

As in the paper, a distance is the distance to the nearest of a dense set of samples of the other surface
(:data:`REFERENCE_FACTOR` times as many as the measured points). That overestimates the true point-to-surface
distance by about half the sample spacing, in quadrature: at the defaults a 128 mm bar is sampled every 0.15 mm,
and a 1 mm offset measures 1.00 to 1.04 mm (tests/test_assets_core.py).

Both are reported as mean, 95th percentile and maximum in millimetres, for the CoACD collision and for the
single convex hull that prior data sets use (the baseline, Q').
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rik.assets.decompose import Hulls
from rik.errors import RikError

if TYPE_CHECKING:
    import numpy as np
    import trimesh

DEFAULT_POINTS = 20_000
"""Measured points per surface (P, Q and Q' each)."""
MAX_POINTS = 1_000_000
"""Most surface samples per shell (``--points``): each sample costs a distance query against every convex part."""


def check_points(points: int) -> int:
    """``points`` when it lies in 1,000 .. :data:`MAX_POINTS`, else a one-line :class:`rik.errors.RikError`."""

    if not 1000 <= points <= MAX_POINTS:
        raise RikError(f"--points {points}: give 1,000 to {MAX_POINTS:,} surface samples per shell")
    return points


REFERENCE_FACTOR = 10
"""Reference samples per measured point: distances are taken to the nearest of these."""
INSIDE_TOLERANCE = 1e-7
"""A shell sample counts as inside another part when it is deeper than this below all its planes, m."""


@dataclass(frozen=True)
class Deviation:
    """Distances of one direction of the metric, mm."""

    mean: float
    p95: float
    max: float

    @classmethod
    def of(cls, distances_m: np.ndarray) -> Deviation:
        import numpy as np

        d = np.asarray(distances_m) * 1e3
        return cls(float(d.mean()), float(np.percentile(d, 95)), float(d.max()))


@dataclass(frozen=True)
class Fidelity:
    """Both directions for a collision and its convex-hull baseline."""

    q_to_p: Deviation
    p_to_q: Deviation
    baseline_q_to_p: Deviation
    baseline_p_to_q: Deviation


@dataclass(frozen=True)
class FidelitySamples:
    """Points and per-point distances (m), kept for the heatmap figure."""

    p: np.ndarray
    p_to_q: np.ndarray
    q: np.ndarray
    q_to_p: np.ndarray
    baseline_q: np.ndarray
    baseline_q_to_p: np.ndarray


def _planes(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals and offsets of a convex hull's faces (n . x <= d inside)."""
    import numpy as np

    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 1e-18
    normals = normals[keep] / lengths[keep, None]
    centre = vertices.mean(axis=0)
    offsets = np.einsum("ij,ij->i", normals, tri[keep, 0])
    flip = normals @ centre > offsets  # make every normal point away from the hull's centre
    normals[flip] *= -1
    offsets[flip] *= -1
    return normals, offsets


def inside_any(points: np.ndarray, hulls: Hulls, skip: int | None = None) -> np.ndarray:
    """Mask of points strictly inside at least one hull (other than hull ``skip``)."""
    import numpy as np

    mask = np.zeros(len(points), dtype=bool)
    for j, (v, f) in enumerate(hulls):
        if j == skip:
            continue
        lo, hi = v.min(axis=0), v.max(axis=0)
        near = np.all((points >= lo) & (points <= hi), axis=1) & ~mask
        if not near.any():
            continue
        normals, offsets = _planes(v, f)
        inside = np.all(points[near] @ normals.T - offsets < -INSIDE_TOLERANCE, axis=1)
        mask[np.flatnonzero(near)[inside]] = True
    return mask


def sample_surface(mesh: trimesh.Trimesh, count: int, seed: int) -> np.ndarray:
    """``count`` points uniformly by area on ``mesh`` (m), reproducible for a seed."""
    import trimesh

    points, _ = trimesh.sample.sample_surface(mesh, count, seed=seed)
    return points


def sample_shell(hulls: Hulls, count: int, seed: int) -> np.ndarray:
    """About ``count`` points on the boundary of the union of ``hulls``: each hull's surface sampled by area,
    minus the points inside another hull."""
    import numpy as np
    import trimesh

    meshes = [trimesh.Trimesh(v, f, process=False) for v, f in hulls]
    areas = np.array([m.area for m in meshes])
    counts = np.maximum(16, np.round(count * areas / areas.sum()).astype(int))
    kept = []
    for i, (mesh, n) in enumerate(zip(meshes, counts, strict=True)):
        points = sample_surface(mesh, int(n), seed + i)
        kept.append(points[~inside_any(points, hulls, skip=i)])
    return np.concatenate(kept)


def distance_to_samples(points: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """Distance from each point to its nearest sample, m (exact). The k-d tree splits at sliding midpoints, not at
    medians (``balanced_tree=False``): on the metric's shells, whose points partly lie far from the other surface
    (a convex hull over a handle's hollows), its queries took a third of the balanced tree's time for the same
    distances (benchmarks/fidelity_speed.py)."""
    from scipy.spatial import cKDTree

    return cKDTree(samples, balanced_tree=False, compact_nodes=False).query(points)[0]


def measure(visual: trimesh.Trimesh, hulls: Hulls, baseline: Hulls, points: int = DEFAULT_POINTS,
            seed: int = 0) -> tuple[Fidelity, FidelitySamples]:
    """E_Q->P and E_P->Q of ``hulls`` and of ``baseline`` against ``visual``."""
    dense = points * REFERENCE_FACTOR
    p, p_ref = sample_surface(visual, points, seed), sample_surface(visual, dense, seed + 10)
    q, q_ref = sample_shell(hulls, points, seed + 1), sample_shell(hulls, dense, seed + 11)
    qb, qb_ref = sample_shell(baseline, points, seed + 2), sample_shell(baseline, dense, seed + 12)
    d_qp, d_qbp = distance_to_samples(q, p_ref), distance_to_samples(qb, p_ref)
    d_pq, d_pqb = distance_to_samples(p, q_ref), distance_to_samples(p, qb_ref)
    fid = Fidelity(Deviation.of(d_qp), Deviation.of(d_pq), Deviation.of(d_qbp), Deviation.of(d_pqb))
    return fid, FidelitySamples(p, d_pq, q, d_qp, qb, d_qbp)
