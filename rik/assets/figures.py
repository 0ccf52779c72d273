"""Pictures of assets: a shaded thumbnail of a handle and the collision-error heatmaps of paper Figure 5.

Drawn with matplotlib's Agg backend (headless, deterministic); written atomically as PNG.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from rik.outputs import Replaces, holds_only, save_figure
from rik.paths import pyplot as _pyplot

if TYPE_CHECKING:
    import numpy as np
    import trimesh

    from rik.assets.fidelity import Fidelity, FidelitySamples

VIEW = {"elev": 28.0, "azim": -62.0}
"""Camera of every picture: from above-front-left, so loops and lips show."""
HEAT_MAX_MM = 5.0
"""Top of the colour scale, mm: the same for every handle, so pictures compare; larger deviations saturate."""
HEAT_POINTS = 6000
"""Points drawn per heatmap panel (a random subset of the samples)."""


def _is_pictures(folder: Path) -> bool:
    """Whether ``folder`` holds a handle's pictures rik drew: its ``asset.key`` stamp and nothing but the pictures."""

    try:
        with open(folder / "asset.key", "rb") as handle:
            stamp = handle.read(200).split()
    except OSError:
        return False
    return len(stamp) == 2 and holds_only(folder, PICTURE_FILES)


PICTURE_FILES = frozenset({"asset.key", "fidelity.png", "thumbnail.png"})
"""What ``rik assets fidelity`` writes into each handle's picture folder."""
PICTURE = Replaces.when("a picture rik drew of a handle (its folder's asset.key)", lambda p: _is_pictures(p.parent))
"""What a handle's picture may replace: one in a folder of pictures rik drew (:func:`_is_pictures`)."""


def _frame(ax, points: np.ndarray, zoom: float = 1.0) -> None:
    """Equal scale on all axes, the box shaped like the object (so long bars fill the picture), no axes."""
    import numpy as np

    lo, hi = points.min(axis=0), points.max(axis=0)
    span = np.maximum(hi - lo, 0.15 * float((hi - lo).max()))  # keep flat objects from collapsing
    centre = (lo + hi) / 2
    for setter, c, s in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, span, strict=True):
        setter(c - s / 2, c + s / 2)
    ax.set_box_aspect(tuple(span / span.max()), zoom=zoom)
    ax.view_init(**VIEW)
    ax.set_axis_off()


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    import numpy as np

    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb(c: np.ndarray) -> np.ndarray:
    import numpy as np

    c = np.clip(c, 0, 1)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def thumbnail(mesh: trimesh.Trimesh, base_color: tuple[float, float, float], metallic: float, path: Path,
              size_px: int = 160) -> None:
    """A small shaded picture of ``mesh`` in its finish's colour (two lights, Lambert plus a metallic sheen)."""
    import numpy as np
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    plt = _pyplot()
    fig = plt.figure(figsize=(size_px / 80, size_px / 80))
    ax = fig.add_axes((0, 0, 1, 1), projection="3d")
    normals = mesh.face_normals
    lights = np.array([[-0.4, -0.6, 0.7], [0.6, -0.2, 0.4]])
    lights /= np.linalg.norm(lights, axis=1, keepdims=True)
    lambert = np.clip(normals @ lights.T, 0, None) @ np.array([0.75, 0.35])
    sheen = metallic * np.clip(normals @ np.array([0.0, -0.3, 0.95]), 0, None) ** 12
    base = _srgb_to_linear(np.asarray(base_color, dtype=float))
    colour = _linear_to_srgb(base[None, :] * (0.18 + lambert[:, None]) + 0.5 * sheen[:, None])
    ax.add_collection3d(Poly3DCollection(mesh.triangles, facecolors=colour, edgecolors="none", linewidths=0,
                                        antialiased=False))
    _frame(ax, mesh.vertices, zoom=1.05)
    save_figure(fig, path, PICTURE, dpi=80)


def heatmap(samples: FidelitySamples, fidelity: Fidelity, title: str, path: Path, seed: int = 0) -> None:
    """Three panels like paper Figure 5: H_P->Q (visual points coloured by their distance to the CoACD shell),
    H_Q->P (shell points coloured by their distance to the visual surface) and H_Q'->P (the convex-hull
    baseline), on one colour scale in millimetres."""
    import numpy as np

    plt = _pyplot()
    rng = np.random.default_rng(seed)
    panels = [
        ("$H_{P\\to Q}$ CoACD", samples.p, samples.p_to_q, fidelity.p_to_q.mean),
        ("$H_{Q\\to P}$ CoACD", samples.q, samples.q_to_p, fidelity.q_to_p.mean),
        ("$H_{Q'\\to P}$ convex hull", samples.baseline_q, samples.baseline_q_to_p, fidelity.baseline_q_to_p.mean),
    ]
    vmax = HEAT_MAX_MM
    fig = plt.figure(figsize=(9.0, 3.3))
    everything = np.concatenate([samples.p, samples.baseline_q])
    scatter = None
    for i, (name, points, dist, mean) in enumerate(panels):
        ax = fig.add_subplot(1, 3, i + 1, projection="3d")
        pick = rng.choice(len(points), size=min(HEAT_POINTS, len(points)), replace=False)
        scatter = ax.scatter(*points[pick].T, c=dist[pick] * 1e3, cmap="turbo", vmin=0, vmax=vmax, s=1.2,
                             linewidths=0, depthshade=False)
        _frame(ax, everything)
        ax.set_title(f"{name}\nmean {mean:.2f} mm", fontsize=9)
    fig.suptitle(title, fontsize=10)
    bar = fig.colorbar(scatter, ax=fig.axes, shrink=0.7, pad=0.02, extend="max")
    bar.set_label("deviation, mm", fontsize=8)
    save_figure(fig, path, PICTURE, dpi=90)
