"""The finger test: can a gripper finger pass through a two-point handle's loop, as MuJoCo sees the collision?

The probe is a capsule of radius :data:`FINGER_RADIUS` (a 10 mm thick finger, about the thickness of the
fingertips of common parallel-jaw grippers; assumed, and a parameter) lying through the loop: along the handle's
y axis, at half the catalogued clearance depth above the front (z), and slid along x over the middle half of the
clearance width. MuJoCo's own convex collision (``mj_geomDistance``) gives the signed distance from the probe to
every convex part. With CoACD's parts the probe must be free at every position; with the single convex hull of
prior data sets the loop is filled and the probe is blocked.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rik.assets.decompose import Hulls

if TYPE_CHECKING:
    from rik.schemas.handles import HandleGeometry

FINGER_RADIUS = 0.005
"""Probe capsule radius, m (10 mm finger)."""
POSITIONS = 5
"""Probe positions along x, spread over the middle half of the clearance width."""


@dataclass(frozen=True)
class FingerResult:
    """Smallest signed distance from the probe to the collision over all positions, m (< 0: penetrating)."""

    min_distance: float
    passes: bool
    """True when the probe is free (distance > 0) at every position."""


def probe_segments(geometry: HandleGeometry, radius: float = FINGER_RADIUS) -> list[tuple[tuple[float, ...], ...]]:
    """End points of the probe's axis at each position, mount frame, m."""
    assert geometry.clearance is not None, "the finger test needs a clearance"
    z = geometry.clearance.depth / 2
    half_len = geometry.width / 2 + 2 * radius + 0.01
    xs = [geometry.clearance.width / 4 * (2 * i / (POSITIONS - 1) - 1) for i in range(POSITIONS)]
    return [((x, -half_len, z), (x, half_len, z)) for x in xs]


def finger_test(hulls: Hulls, geometry: HandleGeometry, radius: float = FINGER_RADIUS) -> FingerResult:
    """Place the probe at every position and measure its distance to ``hulls`` with MuJoCo."""
    import mujoco
    import numpy as np

    spec = mujoco.MjSpec()
    spec.option.timestep = 0.001
    body = spec.worldbody
    for i, (v, f) in enumerate(hulls):
        spec.add_mesh(name=f"hull{i}", uservert=np.asarray(v, dtype=float).ravel().tolist(),
                      userface=np.asarray(f, dtype=int).ravel().tolist())
        body.add_geom(name=f"hull{i}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"hull{i}")
    probe = body.add_body(name="probe", mocap=True)
    probe.add_geom(name="finger", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[radius, 0, 0],
                   fromto=[0, -1, 0, 0, 1, 0])
    model = spec.compile()
    data = mujoco.MjData(model)
    finger = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "finger")
    worst = float("inf")
    for (x0, y0, z0), (_, y1, _) in probe_segments(geometry, radius):
        half = (y1 - y0) / 2
        model.geom_size[finger] = [radius, half, 0]
        data.mocap_pos[0] = [x0, 0.0, z0]
        mujoco.mj_forward(model, data)
        for i in range(len(hulls)):
            worst = min(worst, mujoco.mj_geomDistance(model, data, i, finger, 0.05, None))
    return FingerResult(worst, worst > 0)
