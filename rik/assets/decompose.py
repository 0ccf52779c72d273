"""Convex decomposition of one rigid part: CoACD with per-category parameters, and the single-hull baseline.

CoACD runs on each rigid part alone (a handle, a drawer, a door), never on a merged mesh, so no hull spans two
parts that move apart (obj2mjcf #33). Generated meshes are already manifold, so CoACD's manifold pre-processing is
off: with it on, the remesh inflates the collision by about a millimetre and can close a finger loop
(CoACD #67; measured on a 128 mm bar pull: E_Q->P 1.38 mm with it, 0.34 mm without).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np
    import trimesh

Hulls = list[tuple["np.ndarray", "np.ndarray"]]
"""Convex parts as (vertices (n, 3) float64 m, faces (m, 3) int64) pairs."""


@dataclass(frozen=True)
class CoacdParams:
    """Parameters passed to ``coacd.run_coacd`` (names as CoACD spells them)."""

    threshold: float = 0.05
    """Concavity threshold that ends the decomposition (0.01 to 1); lower means more, tighter hulls."""
    max_convex_hull: int = -1
    """Hull budget: at most this many convex parts after merging (-1: no limit)."""
    max_ch_vertex: int = 64
    """Vertex budget per convex hull (MuJoCo's collision is fastest on small hulls)."""
    preprocess_mode: str = "off"
    """``off`` for manifold input (ours), ``on`` or ``auto`` for imported meshes that may not be manifold."""
    preprocess_resolution: int = 50
    resolution: int = 2000
    """Sampling resolution of the Hausdorff distance inside CoACD."""
    mcts_iterations: int = 100
    mcts_max_depth: int = 3
    mcts_nodes: int = 20
    merge: bool = True
    decimate: bool = True
    """Reduce each hull to ``max_ch_vertex`` vertices."""
    seed: int = 0


#: Decomposition parameters per part category. Knobs are nearly convex; loops and lips need tighter cuts.
CATEGORY_PARAMS: dict[str, CoacdParams] = {
    # Knobs are few hulls over round surfaces: decimating each hull to 64 vertices costs them accuracy (cylinder-30
    # E_Q->P 0.32 mm decimated, 0.10 mm not; dome-36 1.20 against 0.82), so their hulls keep every vertex.
    "knob": CoacdParams(threshold=0.04, max_convex_hull=24, decimate=False),
    "two_point": CoacdParams(threshold=0.03, max_convex_hull=48),
    "finger_pull": CoacdParams(threshold=0.03, max_convex_hull=48),
    "base_part": CoacdParams(threshold=0.05, max_convex_hull=64),
}


def coacd_params(category: str, seed: int = 0) -> CoacdParams:
    """The parameters for ``category`` with ``seed``."""
    from dataclasses import replace

    return replace(CATEGORY_PARAMS[category], seed=seed)


def decompose(mesh: trimesh.Trimesh, params: CoacdParams) -> Hulls:
    """CoACD convex parts of ``mesh`` (m), each re-hulled so it is exactly convex; deterministic for a seed."""
    import coacd
    import numpy as np
    import trimesh

    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)), **asdict(params))
    hulls: Hulls = []
    for vertices, faces in parts:
        hull = trimesh.Trimesh(vertices, faces, process=False).convex_hull
        hulls.append((np.asarray(hull.vertices, dtype=np.float64), np.asarray(hull.faces, dtype=np.int64)))
    hulls.sort(key=lambda h: tuple(np.round(h[0].mean(axis=0), 9)))  # a stable order, whatever CoACD's is
    return hulls


def convex_hull_baseline(mesh: trimesh.Trimesh) -> Hulls:
    """The single convex hull that prior data sets use as collision (fills every loop)."""
    import numpy as np

    hull = mesh.convex_hull
    return [(np.asarray(hull.vertices, dtype=np.float64), np.asarray(hull.faces, dtype=np.int64))]


def hull_meshes(hulls: Hulls) -> list[trimesh.Trimesh]:
    """The convex parts as trimesh objects."""
    import trimesh

    return [trimesh.Trimesh(v, f, process=False) for v, f in hulls]
