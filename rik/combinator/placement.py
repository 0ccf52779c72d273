"""Where a handle goes on a front: rik's placement rules, and the per-front overrides of the catalog.

Coordinates ``(u, v)`` are in the front's mount-site frame (u along the site's x: the front's width; v along
the site's y: down on upright fronts), in metres, relative to the centre of the mount rectangle. The rules:

- **Slides (drawers)**: centred on the mount rectangle; two-point handles horizontal.
- **Side-hung doors** (hinge axis along the front's height): near the opening edge (the handle's footprint
  :data:`EDGE_INSET` inside the mount rectangle's edge on the side away from the hinge), centred at
  :data:`GRIP_HEIGHT` above the floor or as close to it as the rectangle allows (near the top of a base cabinet's
  door, near the bottom of a wall cabinet's); two-point handles vertical.
- **Lift-up and drop-down fronts** (hinge axis along the front's width): centred on the free edge, the footprint
  :data:`EDGE_INSET` inside the mount rectangle's edge; horizontal.
- **Edge pulls** (``edge_clip`` finger-pulls) sit on an edge of the front: a ``side`` profile on a door's
  opening edge; a ``top`` profile on the top edge (the bottom edge on wall units, whose top is out of reach);
  on lift-up and drop-down fronts, either on the free edge. Along the edge: centred, or near the opening side
  on doors.

A front's ``placements`` in the catalog override the position (and optionally the rotation) per handle type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rik.registry.fit import footprint
from rik.registry.geometry import dot, site_axes, sub, vec3

if TYPE_CHECKING:
    from rik.schemas import BaseUnit, Front, Handle, HandleType

EDGE_INSET = 0.035
"""Distance from the mount rectangle's edge to a door or flap handle's footprint, m (the rectangle itself keeps
15 mm from the front's edges, so a handle's edge sits about 50 mm from the door's edge, a common kitchen rule)."""
EDGE_RUNNING_CLEARANCE = 0.001
"""m left between an edge pull's overhang and the next front (or the next front's pull)."""
MAX_EDGE_TRIM = 0.025
"""m: the most the combinator cuts a front back to make room for an edge pull; more and the pairing is left to
the checks to reject."""
GRIP_HEIGHT = 1.0
"""Height above the floor that door handles are centred at when the door allows it, m."""


@dataclass(frozen=True)
class HandlePlacement:
    """A handle's mount frame on a front: in the site frame and in the base unit's frame (front closed)."""

    front: str
    u: float
    """Site-frame x of the mount point relative to the mount rectangle's centre, m."""
    v: float
    """Site-frame y of the mount point relative to the mount rectangle's centre, m."""
    rotation: int
    """Degrees about the site's z (0, 90, 180 or 270) from the site frame to the handle's mount frame."""
    pos: tuple[float, float, float]
    """Mount point in the base unit's frame, m."""
    quat: tuple[float, float, float, float]
    """Rotation from the base unit's frame to the handle's mount frame (w, x, y, z)."""
    rule: str
    """Which rule placed it, in words (shown in reports)."""
    edge: str | None = None
    """For edge pulls: the front's edge it sits on (``top``, ``bottom``, ``opening side``, ``free edge``)."""
    trim: float = 0.0
    """For edge pulls: how much the front was cut back at that edge to make room for the pull in the gap, m."""
    edge_axis: tuple[float, float, float] | None = None
    """For edge pulls: the outward direction of that edge, base-unit frame."""


def front_motion(front: Front) -> str:
    """``slide``, ``side_hinge`` (a door turning about an axis along its height) or ``flap_hinge`` (about an axis
    along its width), from the joint's axis in the mount site's frame."""
    if front.joint.type.value == "slide":
        return "slide"
    ex, ey, _ = site_axes(front.mount.quat)
    axis = front.joint.axis
    return "side_hinge" if abs(dot(axis, ey)) >= abs(dot(axis, ex)) else "flap_hinge"


def free_side(front: Front) -> float:
    """For hinged fronts: +1 or -1, the side (along site x for doors, site y for flaps) away from the hinge."""
    ex, ey, _ = site_axes(front.mount.quat)
    rel = sub(front.joint.anchor, front.mount.pos)
    along = dot(rel, ex) if front_motion(front) == "side_hinge" else dot(rel, ey)
    return -1.0 if along > 0 else 1.0


def _toward(value: float, limit: float) -> float:
    """``value`` clamped to [-limit, limit] (``limit`` < 0 means no room: 0)."""
    limit = max(limit, 0.0)
    return min(max(value, -limit), limit)


def _near_edge(side: float, size: float, extent: float) -> float:
    """Centre coordinate of a footprint of ``extent`` kept :data:`EDGE_INSET` inside the rectangle's edge on
    ``side`` (less when the rectangle is too small)."""
    room = (size - extent) / 2
    return side * min(max(size / 2 - EDGE_INSET - extent / 2, 0.0), max(room, 0.0))


def _grip_v(unit: BaseUnit, front: Front, extent_v: float) -> float:
    """Site v that puts the handle's centre nearest :data:`GRIP_HEIGHT` above the floor, with the footprint
    :data:`EDGE_INSET` inside the rectangle when it can be."""
    _, ey, _ = site_axes(front.mount.quat)
    target_z = GRIP_HEIGHT - unit.install_height
    v = (target_z - front.mount.pos[2]) * ey[2] if abs(ey[2]) > 1e-9 else 0.0
    size_v = front.mount.size[1]
    limit = size_v / 2 - EDGE_INSET - extent_v / 2
    if limit < 0:
        limit = (size_v - extent_v) / 2
    return _toward(v, limit)


def _edge_direction(unit: BaseUnit, front: Front, handle: Handle, motion: str) -> tuple[str, float, float]:
    """For an edge pull: (edge name, du, dv), the site-frame unit direction from the front's centre to the edge."""
    _, ey, _ = site_axes(front.mount.quat)
    if motion == "flap_hinge":
        return "free edge", 0.0, free_side(front)
    if motion == "side_hinge" and handle.mount.edge == "side":
        return "opening side", free_side(front), 0.0
    up = -1.0 if ey[2] < 0 else 1.0  # the site's v direction that points up
    if unit.install == "wall":
        return "bottom", 0.0, -up
    return "top", 0.0, up


_ROTATION_FOR_EDGE = {(0.0, -1.0): 0, (0.0, 1.0): 180, (1.0, 0.0): 90, (-1.0, 0.0): 270}
"""Rotation that points an edge pull's +y (into the front) away from the edge at site direction (du, dv)."""


def _front_half_extents(front: Front) -> tuple[float, float, float, float]:
    """The front's centre (u, v) relative to the mount rectangle's centre, and its half extents along u and v."""
    ex, ey, _ = site_axes(front.mount.quat)
    rel = sub(front.center, front.mount.pos)
    return dot(rel, ex), dot(rel, ey), _half_extent(front, ex), _half_extent(front, ey)


def _edge_trim(unit: BaseUnit, front: Front, direction: tuple[float, float, float], overhang: float,
               edge_of: dict[str, tuple[float, float, float]]) -> float:
    """How far to cut ``front`` back at its edge facing ``direction`` (base frame) so that a pull overhanging the
    edge by ``overhang`` (m) fits the gap to the next front with :data:`EDGE_RUNNING_CLEARANCE` to spare. A
    neighbour whose own pull faces this gap shares it (both are cut back by half the shortfall)."""
    if overhang <= 0:
        return 0.0

    def span(f: Front, axis: tuple[float, float, float]) -> tuple[float, float]:
        half = _half_extent(f, axis)
        c = dot(f.center, axis)
        return c - half, c + half

    edge = span(front, direction)[1]
    trim = 0.0
    for other in unit.fronts:
        if other.id == front.id:
            continue
        near = span(other, direction)[0]
        if near < edge - 1e-6 or near - edge > 2 * overhang + EDGE_RUNNING_CLEARANCE:
            continue
        across = [a for a in ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)) if abs(dot(a, direction)) < 0.5]
        if any(span(front, a)[1] <= span(other, a)[0] or span(other, a)[1] <= span(front, a)[0] for a in across):
            continue
        facing = edge_of.get(other.id)
        shared = facing is not None and dot(facing, direction) < -0.99
        needed = overhang * (2 if shared else 1) + EDGE_RUNNING_CLEARANCE
        trim = max(trim, (needed - (near - edge)) / (2 if shared else 1))
    return max(trim, 0.0)


def _half_extent(front: Front, axis: tuple[float, float, float]) -> float:
    """Half the front panel's extent along ``axis`` (a base-frame direction), m."""
    w, h, t = front.size
    return abs(axis[0]) * w / 2 + abs(axis[1]) * t / 2 + abs(axis[2]) * h / 2


def edge_directions(unit: BaseUnit, handle: Handle) -> dict[str, tuple[float, float, float]]:
    """For an edge pull: the outward direction (base frame) of the edge it goes on, per front."""
    if handle.mount.kind != "edge_clip":
        return {}
    out = {}
    for front in unit.fronts:
        _, du, dv = _edge_direction(unit, front, handle, front_motion(front))
        ex, ey, _ = site_axes(front.mount.quat)
        out[front.id] = vec3(du * ex[i] + dv * ey[i] for i in range(3))
    return out


def place_handle(unit: BaseUnit, front: Front, handle: Handle, handle_type: HandleType,
                 overhang: float = 0.0) -> HandlePlacement:
    """The placement of ``handle`` on ``front``: the catalog's override for its type, else rik's rule.

    ``overhang`` (m): how far an edge pull reaches beyond its edge (from its mesh); the front is cut back where
    the gap to the next front is smaller (:func:`_edge_trim`)."""
    motion = front_motion(front)
    override = next((p for p in front.placements if handle_type in p.handle_types), None)
    size_u, size_v = front.mount.size
    edge, trim, axis = None, 0.0, None
    if handle.mount.kind == "edge_clip":
        edge, du, dv = _edge_direction(unit, front, handle, motion)
        rotation = _ROTATION_FOR_EDGE[(du, dv)]
        axis = edge_directions(unit, handle)[front.id]
        trim = min(_edge_trim(unit, front, axis, overhang, edge_directions(unit, handle)), MAX_EDGE_TRIM)
        cu, cv, hu, hv = _front_half_extents(front)
        hu, hv = (hu - trim, hv) if du != 0.0 else (hu, hv - trim)
        along = footprint(handle, 0)[0]
        if du == 0.0:  # a horizontal edge: the mount point is on it, the position along it is u
            v = cv + dv * hv
            u = _near_edge(free_side(front), size_u, along) if motion == "side_hinge" else 0.0
        else:  # the opening edge of a door: u is on it, the position along it is v
            u = cu + du * hu
            v = _grip_v(unit, front, along)
        rule = f"edge pull on the {edge} edge" + (f", the front cut back {trim * 1000:.1f} mm to make room"
                                                  if trim > 0 else "")
        if override is not None:
            u, v = (u, override.at[1]) if du != 0.0 else (override.at[0], v)
            rule = f"catalog placement along the {edge} edge"
    else:
        two_point = handle_type.value == "two_point"
        if motion == "slide":
            rotation, u, v, rule = 0, 0.0, 0.0, "drawer: centred, horizontal"
        elif motion == "side_hinge":
            rotation = 90 if two_point else 0
            fu, fv = footprint(handle, rotation)
            u = _near_edge(free_side(front), size_u, fu)
            v = _grip_v(unit, front, fv)
            rule = f"door: near the opening edge, {'vertical, ' if two_point else ''}at grip height"
        else:
            rotation = 0
            fu, fv = footprint(handle, rotation)
            u, v = 0.0, _near_edge(free_side(front), size_v, fv)
            rule = "flap: centred on the free edge, horizontal"
        if override is not None:
            u, v = override.at
            rotation = override.rotation if override.rotation is not None else rotation
            rule = "catalog placement"
    ex, ey, _ = site_axes(front.mount.quat)
    m = front.mount.pos
    pos = vec3(m[i] + u * ex[i] + v * ey[i] for i in range(3))
    quat = _compose(front.mount.quat, _z_rotation(rotation))
    return HandlePlacement(front.id, u, v, rotation, pos, quat, rule, edge, trim, axis)


def _z_rotation(degrees: int) -> tuple[float, float, float, float]:
    half = math.radians(degrees) / 2
    return (math.cos(half), 0.0, 0.0, math.sin(half))


def _compose(a: tuple[float, float, float, float],
             b: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """Quaternion product a * b (apply b, then a), normalised; (w, x, y, z)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    q = (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
         aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)
    n = math.sqrt(sum(c * c for c in q))
    return q[0] / n, q[1] / n, q[2] / n, q[3] / n
