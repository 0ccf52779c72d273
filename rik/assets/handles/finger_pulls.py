"""Finger-pull generators: edge profiles (``edge_profile``), tabs (``tab_pull``), cup and hood pulls
(``cup_pull``) and inset grips (``recess_lip``).

Every length is in metres; every mesh is one closed solid in the handle's mount frame (+z out of the front,
x along the handle's long axis). Extents: x = ``geometry.length``, y = ``geometry.width``, max z =
``geometry.projection``. The wall (sheet) thickness of every shell, profile or tab is ``geometry.grip_diameter``.

Frames per mount:

* ``edge_clip`` (``edge_profile``, ``tab_pull``): origin at the middle of the front's edge line on its outer face;
  y points from the edge into the front (down for a top edge, inward for a side edge), so the front occupies
  ``z < 0 and y > 0`` and ``y < 0`` is beyond the edge. Material may wrap over the edge (``y <= 0``) down to
  ``z = -EDGE_CAP_DEPTH`` (the thinnest front) but never enters the front. Top and side edges get the same shape.
* ``two_screw`` (``cup_pull``): origin midway between the screws at ``x = +-hole_spacing/2``; nothing below z = 0;
  the hood opens toward +y (downward on an upright front).
* ``inset`` (``recess_lip``): a tray set into a routed recess; it is the only family with material at ``z < 0``,
  all of it inside the footprint :func:`recess_cutout`, which the front must be cut with (the combinator does it).

The free finger region each generator guarantees is returned by :func:`clearance_box` (an axis-aligned box in the
mount frame); tests check it holds no material.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, cast

import numpy as np
import shapely
import trimesh
from shapely.geometry import LineString, MultiPolygon, Polygon, box

from rik.assets.meshkit import difference, segments, union
from rik.errors import RikError
from rik.schemas.generators import CupPull, EdgeProfile, RecessLip, TabPull
from rik.schemas.handles import HandleGeometry, Mount

if TYPE_CHECKING:
    from rik.assets.handles.generator import Generator

EDGE_CAP_DEPTH = 0.016
"""How far an edge profile's cap lies over the front's edge, from the face toward the back, m (the thinnest
front allowed, so the cap never overhangs the back of a front)."""
MIN_LIP_ANGLE_DEG = 30.0
"""Smallest flange angle an edge profile is built with; smaller ``lip_angle_deg`` is clamped to it, degrees."""
SCREW_HOLE_RADIUS = 2.2e-3
"""Radius of the screw holes through a cup pull's ears, m (M4 clearance)."""
SCREW_HEAD_RADIUS = 4.0e-3
"""Radius of the screw head a cup pull's ear must carry beside the hood, m."""
ROUTER_RADIUS = 8.0e-3
"""Corner radius of a recess's routed footprint, seen from the front, m (largest used)."""
MIN_NOSE = 1.2e-3
"""Thinnest hook nose kept on a recess lip, m."""

_BIG = 1.0
"""A length far beyond any handle, used for half-open cutting regions, m."""
_OVER = 1.0e-3
"""Overlap given to cutting prisms so booleans never meet coplanar faces, m."""


# --------------------------------------------------------------------------------------------- 2-D helpers


def _quad(radius: float) -> int:
    """Segments per quarter circle for a shapely buffer of ``radius`` (m), fine enough for the chord bound."""
    return max(2, segments(radius, math.pi / 2))


def _arc(cu: float, cv: float, r: float, a0: float, a1: float) -> list[tuple[float, float]]:
    """Points on a circular arc (centre ``(cu, cv)``, radius ``r`` m) from angle ``a0`` to ``a1`` (rad), ends
    included; angle 0 is +u, pi/2 is +v."""
    return [(cu + r * _snap(math.cos(a)), cv + r * _snap(math.sin(a))) for a in _angles(r, a0, a1)]


def _angles(r: float, a0: float, a1: float) -> np.ndarray:
    """Angles from ``a0`` to ``a1`` (rad) for an arc of radius ``r`` (m), with every multiple of pi/2 in between
    included so the arc's extreme points are exact."""
    base = np.linspace(a0, a1, segments(r, abs(a1 - a0)) + 1)
    lo, hi = min(a0, a1), max(a0, a1)
    quads = [k * math.pi / 2 for k in range(math.ceil(lo / (math.pi / 2)), math.floor(hi / (math.pi / 2)) + 1)]
    extra = [q for q in quads if np.min(np.abs(base - q)) > 1e-9]
    return np.array(sorted([*base, *extra], reverse=a1 < a0))


def _snap(c: float) -> float:
    """``c`` (a cosine or sine) with round-off at the quadrant points removed, so arcs meet straight parts exactly."""
    return 0.0 if abs(c) < 1e-12 else c


def _ellipse_arc(cu: float, cv: float, a: float, b: float, t0: float, t1: float) -> list[tuple[float, float]]:
    """Points on an elliptic arc (centre ``(cu, cv)``, semi-axes ``a`` along u and ``b`` along v, m) from
    parameter ``t0`` to ``t1`` (rad), ends included."""
    n = segments(max(a, b), abs(t1 - t0))
    return [(cu + a * _snap(math.cos(t)), cv + b * _snap(math.sin(t))) for t in np.linspace(t0, t1, n + 1)]


def _opened(poly: Polygon, r: float) -> Polygon:
    """``poly`` with every convex corner rounded to radius ``r`` (m); concave corners stay sharp."""
    if r <= 0:
        return poly
    out = poly.buffer(-r, quad_segs=_quad(r), join_style="round").buffer(r, quad_segs=_quad(r), join_style="round")
    return _single(out.intersection(poly))  # clip the buffer's round-off at concave corners back to the original


def _single(geom: shapely.Geometry) -> Polygon:
    """The largest polygon of ``geom`` (a union or a rounding may leave specks), simplified of collinear points."""
    if isinstance(geom, MultiPolygon):
        geom = max(geom.geoms, key=lambda g: g.area)
    if not isinstance(geom, Polygon) or geom.is_empty:
        raise RikError("finger pull: a cross-section came out empty; the handle's sizes are inconsistent")
    return cast(Polygon, shapely.set_precision(geom, 1e-9).simplify(1e-9))  # a polygon simplifies to a polygon


def _rounded_rect(x0: float, y0: float, x1: float, y1: float, r: float) -> Polygon:
    """Rectangle ``[x0, x1] x [y0, y1]`` (m) with every corner rounded to ``r`` (clamped to half the short side)."""
    r = min(r, 0.5 * (x1 - x0), 0.5 * (y1 - y0)) * 0.999
    if r <= 0:
        return box(x0, y0, x1, y1)
    return box(x0 + r, y0 + r, x1 - r, y1 - r).buffer(r, quad_segs=_quad(r))


# --------------------------------------------------------------------------------------------- 3-D helpers

_FRAMES = {
    # local (u, v, w) of an extruded polygon -> mount frame; w is the extrusion direction
    "x": np.array([[0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float),  # (u,v)=(y,z)
    "y": np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float),  # (u,v)=(x,z)
    "z": np.eye(4),  # (u,v)=(x,y)
}


def _prism(poly: Polygon, axis: str, lo: float, hi: float) -> trimesh.Trimesh:
    """Extrude ``poly`` along ``axis`` from ``lo`` to ``hi`` (m). The polygon's (u, v) coordinates are
    (y, z) for axis x, (x, z) for axis y and (x, y) for axis z."""
    mesh = trimesh.creation.extrude_polygon(poly, hi - lo, engine="manifold")
    mesh.apply_translation([0.0, 0.0, lo])
    mesh.apply_transform(_FRAMES[axis])
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _intersection(meshes: Sequence[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Boolean intersection of closed meshes (manifold3d)."""
    return trimesh.boolean.intersection(list(meshes), engine="manifold")


def _clearance(geometry: HandleGeometry) -> tuple[float, float]:
    """(depth, width) of the handle's finger clearance, m; a missing clearance defaults to a fingertip's
    (half the width deep, the full length wide)."""
    c = geometry.clearance
    if c is None:
        return 0.5 * geometry.width, geometry.length
    return c.depth, min(c.width, geometry.length)


# ============================================================================================ edge_profile


def _edge_ymin_estimate(section: str, t: float, p: float, alpha: float) -> float:
    """How far (m, negative) an edge section reaches beyond the edge before its corners are rounded."""
    sa, ca = math.sin(alpha), math.cos(alpha)
    if section in ("lip", "bevel"):
        return -(p - 2 * t) * ca / sa - t
    if section == "l_angle":
        return min(-t, -t * sa - (p - t + t * ca) * ca / sa)
    if section == "j_hook":
        return -0.5 * p
    return -(p - t)  # rounded_bead


def _edge_layout(spec: EdgeProfile, geometry: HandleGeometry) -> dict[str, float]:
    """Key levels of an edge profile's cross-section (m): wall ``t``, flange angle ``alpha`` (rad), pocket depth
    ``depth`` (the lip ends at y = depth), the profile's extreme ``y_min`` beyond the edge and ``y_max`` at the
    plate's end (``y_max - y_min = width``)."""
    w, p = geometry.width, geometry.projection
    t = min(geometry.grip_diameter, 0.3 * p)  # leave a pocket between plate and lip
    depth, _ = _clearance(geometry)
    alpha = math.radians(min(max(MIN_LIP_ANGLE_DEG, spec.lip_angle_deg), 90.0))
    # a flat flange reaches far over the edge; steepen it until the plate still reaches the lip's end
    while alpha < math.pi / 2 and w + _edge_ymin_estimate(spec.section, t, p, alpha) < depth:
        alpha = min(alpha + math.radians(1.0), math.pi / 2)
    depth = max(min(depth, w + _edge_ymin_estimate(spec.section, t, p, alpha)), t)
    # the rounded corners can pull the extreme in: measure it on the built section
    upper = _edge_polygon(spec.section, t, p, alpha, depth, depth + 2 * t)
    y_min = upper.bounds[0]
    return {"t": t, "p": p, "alpha": alpha, "depth": depth, "y_min": y_min, "y_max": w + y_min}


def _edge_section(spec: EdgeProfile, geometry: HandleGeometry) -> Polygon:
    """The edge profile's cross-section in the (y, z) plane, m (see :func:`edge_profile`)."""
    lay = _edge_layout(spec, geometry)
    return _edge_polygon(spec.section, lay["t"], lay["p"], lay["alpha"], lay["depth"], lay["y_max"])


def _edge_polygon(section: str, t: float, p: float, alpha: float, depth: float, y_max: float) -> Polygon:
    """Cross-section (y, z) of an edge profile with wall ``t``, projection ``p``, flange angle ``alpha`` (rad),
    lip end at ``y = depth`` and plate end at ``y = y_max`` (m), convex corners rounded."""
    sa, ca = math.sin(alpha), math.cos(alpha)
    cap = box(-t, -EDGE_CAP_DEPTH, 0.0, t)
    round_r = 0.4 * t
    if section in ("lip", "bevel"):
        cot = ca / sa
        q = (-(p - 2 * t) * cot, p - t)  # inner corner: pocket roof meets the lip's inner face
        g_y = t * (ca - 1.0) / sa  # flange's outer line at z = 0
        t2_angle = 1.5 * math.pi - alpha  # direction of the flange's outward normal
        outline = [(g_y, 0.0), (y_max, 0.0), (y_max, t), (depth, t), (depth, p)]
        outline += _arc(q[0], q[1], t, 0.5 * math.pi, t2_angle)  # the rounded outer corner, concentric
        main = Polygon(outline)
        pocket = Polygon([(0.0, t), (_BIG, t), (_BIG, p - t), q])
        solid = main.union(cap).difference(pocket)
    elif section == "l_angle":
        s = (p - t + t * ca) / sa
        top_out = (-t * sa - s * ca, p)
        top_in = (-(p - t) * ca / sa, p)
        g_y = t * (ca - 1.0) / sa
        main = Polygon([(g_y, 0.0), (y_max, 0.0), (y_max, t), (0.0, t), top_in, top_out])
        solid = main.union(cap)
    elif section == "j_hook":
        r_o = 0.5 * p
        r_i = r_o - t
        ring = _arc(0.0, r_o, r_o, 0.5 * math.pi, 1.5 * math.pi) + _arc(0.0, r_o, r_i, 1.5 * math.pi, 0.5 * math.pi)
        solid = shapely.union_all([Polygon(ring), box(0.0, 0.0, y_max, t), box(0.0, p - t, depth, p)])
    elif section == "rounded_bead":
        r_o = p - t
        r_i = p - 2 * t
        ring = _arc(0.0, t, r_o, 0.5 * math.pi, math.pi) + _arc(0.0, t, r_i, math.pi, 0.5 * math.pi)
        plate = box(-r_o, 0.0, y_max, t)
        solid = shapely.union_all([Polygon(ring), plate, box(0.0, p - t, depth, p), box(-t, -EDGE_CAP_DEPTH, 0.0, 0.0)])
        round_r = 0.45 * t
    else:  # pragma: no cover - the schema admits no other section
        raise ValueError(f"unknown edge section {section!r}")
    return _opened(_single(solid), round_r)


def edge_profile(spec: EdgeProfile, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """An aluminium-style finger-pull profile fixed on a front's edge, extruded along x (m, edge-clip frame).

    The cross-section (y, z) is a plate on the face (``0 <= z <= t``, from the profile's top down to
    ``y = y_max``) joined at the edge to a wall standing out to ``z = projection``; ``t`` = ``grip_diameter``
    (the catalogued thickness wins over the design's ``wall_ratio``, which is only the nominal wall / projection
    and does not change the mesh). ``geometry.width`` is the whole y extent, ``length`` the extrusion length.
    The finger pocket is ``|x| <= clearance.width/2, 0 <= y <= depth, t <= z <= projection - t`` (to
    ``projection`` for ``l_angle``): its roof is the edge line y = 0, the lip ends at ``y = clearance.depth``.

    ``section``:

    * ``lip``: flange out along +z at the edge, lip hanging back down (+y) to ``y = depth``; outer corner rounded
      concentric with the pocket's inner corner; a cap lies on the front's edge (``-t <= y <= 0``) down to
      ``z = -EDGE_CAP_DEPTH``.
    * ``j_hook``: the flange and lip become a semicircular hook (outer radius projection/2) standing above the edge;
      no cap (screwed through the plate).
    * ``l_angle``: plate + flange only; fingertips pull on the flange's underside; with the edge cap.
    * ``rounded_bead``: a quarter-round bead (outer radius projection - t, centred on the plate's face at the edge)
      with a half-round lip end, over a cove that continues the pocket above the edge; with the edge cap.
    * ``bevel``: like ``lip`` with the flange rising outward at ``lip_angle_deg`` to the face over the edge,
      giving a bevelled top.

    ``lip_angle_deg`` tilts the flange of ``lip``, ``l_angle`` and ``bevel`` (90 = perpendicular; clamped to at
    least :data:`MIN_LIP_ANGLE_DEG`, and steepened further, degree by degree, while the flange would reach so far over
    the edge that the plate no longer spans the pocket); it does not apply to ``j_hook`` and ``rounded_bead``.
    Clamps: ``t`` at most 0.3 x projection; the pocket depth at most ``y_max`` when even a perpendicular flange
    leaves the width too short for the full lip.
    Convex corners are rounded to 0.4 t (0.45 t for the bead); the pocket's inner corners stay sharp.
    """
    section = _edge_section(spec, geometry)
    half = 0.5 * geometry.length
    return _prism(section, "x", -half, half)


# ================================================================================================ tab_pull


def _tab_layout(spec: TabPull, geometry: HandleGeometry) -> dict[str, float]:
    """Key levels of a tab (m): top ``y_top`` (above the edge), foot end ``y_max``, the offset bend from
    ``bend_top`` to ``bend_bottom``, thickness ``t`` and the finger depth ``depth`` behind the tab."""
    w = geometry.width
    p = geometry.projection
    t = min(geometry.grip_diameter, 0.4 * p)
    depth, _ = _clearance(geometry)
    overhang = min(max(spec.overhang_ratio, 0.15), 0.85)
    y_top = -overhang * w
    y_max = y_top + w
    rise = p - t
    foot_min = min(0.008, 0.5 * y_max)
    # the finger region behind the standing part reaches down to y_top + depth, at most to the edge line
    depth = min(depth, -y_top)
    bend_top = y_top + depth
    run = min(1.2 * rise, max(y_max - foot_min - bend_top, 0.5 * rise), y_max - bend_top - 0.5 * t)
    return {"t": t, "p": p, "depth": depth, "y_top": y_top, "y_max": y_max, "bend_top": bend_top,
            "bend_bottom": bend_top + run}


def _tab_outline(spec: TabPull, geometry: HandleGeometry, y_top: float, y_max: float) -> Polygon:
    """The tab seen from the front, in the (x, y) plane, m: full length at its free top edge."""
    half = 0.5 * geometry.length
    w = y_max - y_top
    if spec.outline == "rectangle":
        return _rounded_rect(-half, y_top, half, y_max, 1.0e-3)
    if spec.outline == "rounded":
        return _rounded_rect(-half, y_top, half, y_max, 0.3 * min(geometry.length, w))
    # trapezoid: the free top edge keeps the full length, the foot narrows to 60 %
    r = min(1.5e-3, 0.1 * w)
    foot = 0.6 * half
    shoulder = y_top + 3 * r  # a short straight side keeps the full length after the corners are rounded
    trap = Polygon([(-half, y_top), (half, y_top), (half, shoulder), (foot, y_max), (-foot, y_max), (-half, shoulder)])
    return _opened(trap, r)


def tab_pull(spec: TabPull, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A bent sheet tab over a front's top edge (m, edge-clip frame).

    The tab (thickness t = ``grip_diameter``) has a foot flat on the face (``0 <= z <= t``) from the bend down to
    ``y_max``; a smooth offset bend (a half-cosine ramp over about 1.2 x (projection - t)) lifts it so the part
    above the edge stands at ``projection - t <= z <= projection`` up to ``y_top = -overhang_ratio * width``.
    ``outline`` shapes the tab seen from the front: ``rectangle`` (1 mm corners), ``rounded`` (corner radius 0.3 x
    the smaller of length and width), ``trapezoid`` (full length at the free top, 60 % at the foot).
    ``overhang_ratio`` is the part of the width above the edge (clamped to 0.15..0.85). The finger region behind
    the standing part, ``|x| <= clearance.width/2, y_top <= y <= y_top + depth, 0 <= z <= projection - t``, is free
    (depth clamped to the overhang); the bend lies below it. Nothing enters the front (all z >= 0).
    """
    lay = _tab_layout(spec, geometry)
    t, p = lay["t"], lay["p"]
    z_lo, z_hi = 0.5 * t, p - 0.5 * t
    y0, y1 = lay["bend_top"], lay["bend_bottom"]
    n = max(24, segments(max(y1 - y0, p), math.pi))
    ramp = [(y0 + (y1 - y0) * u, z_hi - (z_hi - z_lo) * 0.5 * (1 - math.cos(math.pi * u)))
            for u in np.linspace(0, 1, n + 1)]
    centre = LineString([(lay["y_top"], z_hi), *ramp, (lay["y_max"], z_lo)])
    section = _single(centre.buffer(0.5 * t, quad_segs=_quad(0.5 * t), cap_style="flat", join_style="round"))
    half = 0.5 * geometry.length
    sheet = _prism(section, "x", -half - _OVER, half + _OVER)
    outline = _prism(_tab_outline(spec, geometry, lay["y_top"], lay["y_max"]), "z", -_OVER, p + _OVER)
    return _intersection([sheet, outline])


# ================================================================================================= cup_pull


def _cup_layout(spec: CupPull, geometry: HandleGeometry) -> dict[str, float]:
    """Key sizes of a cup pull (m): wall ``t``, hood outer half-length ``a_o``, hood top ``y_top`` (lower edge of
    the flange band), rim ``y_rim`` (= width/2), projection ``p``, pocket ``depth``, ``half_w`` and height ``z_b``,
    roof radii ``ry, rz`` and the hood's end radius ``r_end`` (seen from above)."""
    if geometry.hole_spacing is None:
        raise RikError("cup pull: a two-screw cup pull needs geometry.hole_spacing")
    w, p, length = geometry.width, geometry.projection, geometry.length
    t = min(geometry.grip_diameter, 0.3 * p)
    depth, cw = _clearance(geometry)
    half_w = 0.5 * cw
    # hood ends 1 mm beyond the pocket's half width, never over the screw heads nor past the ears
    room = 0.5 * geometry.hole_spacing - SCREW_HEAD_RADIUS - (half_w + t)
    a_o = half_w + t + min(1.0e-3, max(room, 0.0))
    a_o = min(a_o, 0.5 * length - t)
    half_w = min(half_w, a_o - t - 2.0e-4)
    y_rim = 0.5 * w
    z_b = 0.5 * (p - t)
    hood = spec.hood
    # the hood's height (flange band lower edge to rim) must hold the pocket under the roof at z_b
    need = t + depth * (2 / math.sqrt(3) if hood != "rectangular" else 1.0) + 0.5e-3
    band = min(spec.flange_ratio * w, max(w - need, 0.0))
    y_top = -0.5 * w + band
    h = y_rim - y_top
    depth = min(depth, (h - t - 0.5e-3) * (math.sqrt(3) / 2 if hood != "rectangular" else 1.0))
    if hood == "rectangular":
        ry = rz = min(0.35 * p, 0.5 * h)
        r_end = 1.5 * t
    else:
        ry, rz = h, p  # quarter-elliptic roof from the band out to the rim
        r_end = 0.5 * p if hood == "half_moon" else 0.6 * p
    return {"t": t, "a_o": a_o, "y_top": y_top, "y_rim": y_rim, "p": p, "depth": depth, "half_w": half_w,
            "z_b": z_b, "ry": ry, "rz": rz, "r_end": r_end, "band": band, "hole_spacing": geometry.hole_spacing}


def _roof(y_top: float, y_end: float, z_max: float, ry: float, rz: float, z_lo: float) -> Polygon:
    """Side profile (y, z) of a hood: from the face at ``y_top`` a quarter-elliptic roof (semi-axes ``ry`` along
    y, ``rz`` along z) rises to ``z_max``, then runs flat to ``y_end``; ``z_lo`` closes it below (m)."""
    cy, cz = y_top + ry, z_max - rz
    pts = [(y_top, z_lo), (y_top, cz)] if cz > 0 else [(y_top, z_lo)]
    arc = _ellipse_arc(cy, cz, ry, rz, math.pi, 0.5 * math.pi)
    pts += arc + [(y_end, z_max), (y_end, z_lo)]
    return _single(Polygon(pts))


def _plan(a: float, z_max: float, r: float, z_lo: float) -> Polygon:
    """Hood seen from above, (x, z): ``|x| <= a``, ``z_lo <= z <= z_max``, outer corners rounded to ``r`` (m)."""
    r = max(min(r, a, z_max - max(z_lo, 0.0)) * 0.999, 0.0)
    if r <= 0:
        return box(-a, z_lo, a, z_max)
    core = box(-a, z_lo, a, z_max - r).union(box(-a + r, z_lo, a - r, z_max))
    return _single(core.union(shapely.Point(-a + r, z_max - r).buffer(r, quad_segs=_quad(r)))
                   .union(shapely.Point(a - r, z_max - r).buffer(r, quad_segs=_quad(r))))


def cup_pull(spec: CupPull, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A cup (bin) or hood pull on two screws (m, two-screw frame, nothing below z = 0).

    A flange plate (thickness t = ``grip_diameter``) on the face: a band along the top (``-width/2 <= y <=
    -width/2 + flange_ratio * width``) joined to two ears at the ends, each drilled for a screw at
    ``x = +-hole_spacing/2, y = 0``. Between the ears a shell hood (wall t) stands out to ``projection``, open
    toward +y (its rim at ``y = width/2``) and at the back, so the front's face is the pocket's back wall. The hood
    ends 1 mm beyond the pocket's half width (never over the screw heads). ``hood``:

    * ``half_moon``: the rim seen from the front is a half-ellipse (flat top on the band, deepest at the middle);
      quarter-elliptic roof; hood ends rounded (radius projection/2) seen from above.
    * ``rectangular``: straight rim, boxy hood (roof and end radii 0.35 x projection and 1.5 t).
    * ``long_hood``: straight rim, quarter-elliptic roof, ends rounded (radius 0.6 x projection).

    The pocket ``|x| <= clearance.width/2, width/2 - depth <= y <= width/2, 0 <= z <= (projection - t)/2`` is free
    (see :func:`clearance_box`). ``flange_ratio`` (band height / width) is clamped so that the hood stays deep
    enough for that pocket; the pocket width is clamped to the hood's inside when the screws leave less room.
    """
    lay = _cup_layout(spec, geometry)
    t, a_o, y_top, y_rim, p = lay["t"], lay["a_o"], lay["y_top"], lay["y_rim"], lay["p"]
    half_l, half_wd = 0.5 * geometry.length, 0.5 * geometry.width
    hood_h = y_rim - y_top
    # outer hood: front outline (x, y) & side profile (y, z) & plan (x, z)
    if spec.hood == "half_moon":
        rim = _ellipse_arc(0.0, y_top, a_o, hood_h, 0.0, math.pi)
        front = Polygon([(a_o, y_top - _OVER), *rim, (-a_o, y_top - _OVER)])
    else:
        front = _rounded_rect(-a_o - _OVER, y_top - 2 * t, a_o + _OVER, y_rim, 0.0)
    o_front = _prism(front, "z", -_OVER, p + _OVER)
    o_side = _prism(_roof(y_top, y_rim + _OVER, p, lay["ry"], lay["rz"], 0.0), "x", -a_o - _OVER, a_o + _OVER)
    o_plan = _prism(_plan(a_o, p, lay["r_end"], 0.0), "y", y_top - _OVER, y_rim + _OVER)
    outer = _intersection([o_front, o_side, o_plan])
    # inner cavity: offset by t, open below the rim and through the back
    i_side = _prism(
        _roof(y_top + t, y_rim + 2 * _OVER, p - t, max(lay["ry"] - t, 1e-4), max(lay["rz"] - t, 1e-4), -2 * _OVER),
        "x", -a_o, a_o,
    )
    i_plan = _prism(_plan(a_o - t, p - t, max(lay["r_end"] - t, 0.0), -2 * _OVER), "y", y_top, y_rim + 3 * _OVER)
    inner = _intersection([i_side, i_plan])
    # flange: band + ears (the region under the hood is left open)
    ear_r = half_wd if spec.hood == "half_moon" else min(0.3 * geometry.width, 6.0e-3)
    plate = _rounded_rect(-half_l, -half_wd, half_l, half_wd, ear_r)
    plate = _single(plate.difference(box(-a_o + 0.5 * t, y_top + 0.5 * t, a_o - 0.5 * t, _BIG)))
    flange = _prism(plate, "z", 0.0, t)
    hs = 0.5 * lay["hole_spacing"]
    holes = [
        trimesh.creation.cylinder(SCREW_HOLE_RADIUS, t + 4 * _OVER, sections=segments(SCREW_HOLE_RADIUS),
                                  transform=trimesh.transformations.translation_matrix([sx, 0.0, 0.5 * t]))
        for sx in (-hs, hs)
    ]
    return difference(union([outer, flange]), [inner, *holes])


# =============================================================================================== recess_lip


def recess_cutout(geometry: HandleGeometry) -> tuple[Polygon, float]:
    """The routed recess a ``recess_lip`` grip needs in the front: its footprint in the (x, y) plane of the mount
    frame (a ``length`` x ``width`` rectangle with rounded corners, m) and its depth below the face (m)."""
    lay = _recess_layout(geometry)
    half_l, half_w = 0.5 * geometry.length, 0.5 * geometry.width
    return _rounded_rect(-half_l, -half_w, half_l, half_w, lay["r_c"]), lay["depth"] + lay["t"]


def _recess_layout(geometry: HandleGeometry) -> dict[str, float]:
    """Key sizes of a recess grip (m): wall ``t``, cavity ``depth``, footprint corner radius ``r_c`` (small enough
    that the pocket box fits the cavity's straight part) and the free pocket's half length ``half_w``."""
    depth, cw = _clearance(geometry)
    t = min(geometry.grip_diameter, 0.25 * geometry.width)
    half_l = 0.5 * geometry.length
    r_c = max(min(ROUTER_RADIUS, 0.5 * (geometry.length - cw), 0.5 * geometry.width), 0.0)
    half_w = min(0.5 * cw, half_l - max(r_c, t))
    return {"t": t, "depth": depth, "r_c": r_c, "half_w": half_w}


def recess_lip(spec: RecessLip, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """An inset grip (m, inset frame): a thin tray in a routed recess, with a hooked lip standing proud.

    The tray's outer footprint is :func:`recess_cutout` (``length`` x ``width``, router-rounded corners); it runs
    from the face (z = 0) down to ``z = -(clearance.depth + t)`` with walls and floor t = ``grip_diameter``; its
    cavity (open toward +z, ``clearance.depth`` deep) is free. Along the long edge at ``y = -width/2`` (the top
    on a drawer) a lip of thickness t stands on the tray's wall to ``z = projection``, with a hook nose
    overhanging the cavity by t whose underside is at ``lip_ratio * projection`` above the face: that is the lip
    height fingertips hook (clamped to at least a quarter of the projection, and so that the nose keeps at least
    :data:`MIN_NOSE`; the nose's top is the projection). The lip runs along the straight
    part of the edge, its ends rounded down to the face. Only this family has material at z < 0, all inside the
    footprint: the front must be cut with :func:`recess_cutout` (the combinator does it).
    """
    lay = _recess_layout(geometry)
    t, depth, r_c = lay["t"], lay["depth"], lay["r_c"]
    p = geometry.projection
    half_l, half_w = 0.5 * geometry.length, 0.5 * geometry.width
    footprint, total_depth = recess_cutout(geometry)
    inner = _rounded_rect(-half_l + t, -half_w + t, half_l - t, half_w - t, max(r_c - t, 0.0))
    tray = difference(_prism(footprint, "z", -total_depth, 0.0), [_prism(inner, "z", -depth, _OVER)])
    # lip cross-section (y, z): post on the wall, nose toward the cavity; buried t/2 into the wall
    h = min(max(spec.lip_ratio * p, 0.25 * p), p - MIN_NOSE)
    y0 = -half_w
    nose = min(t, 0.5 * (geometry.width - 2 * t))
    y1, y2 = y0 + t, y0 + t + nose
    section = Polygon([(y0, -0.5 * t), (y1, -0.5 * t), (y1, h), (y2, h), (y2, p), (y0, p)])
    section = _opened(section, 0.4 * min(t, p - h))
    lip_half = max(half_l - r_c, 0.5 * half_l)
    lip = _intersection([
        _prism(section, "x", -lip_half - _OVER, lip_half + _OVER),
        _prism(_plan(lip_half, p, min(0.5 * p, 0.5 * lip_half), -t), "y", y0 - _OVER, y0 + t + nose + _OVER),
    ])
    return union([tray, lip])


# ============================================================================================ clearance box


def clearance_box(spec: EdgeProfile | TabPull | CupPull | RecessLip, geometry: HandleGeometry,
                  mount: Mount) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The finger region a finger-pull generator keeps free, as ``(lo, hi)`` corners of a box in the mount frame (m).

    Its x size is ``clearance.width`` and its depth ``clearance.depth`` (less only where a generator documents a
    clamp): along y for edge profiles (up from the lip's end), tabs (down from the tab's top) and cup pulls (up from
    the rim); along -z for recess grips.
    """
    depth, cw = _clearance(geometry)
    hw = 0.5 * cw
    if isinstance(spec, EdgeProfile):
        lay = _edge_layout(spec, geometry)
        z_hi = lay["p"] if spec.section == "l_angle" else lay["p"] - lay["t"]
        return (-hw, 0.0, lay["t"]), (hw, lay["depth"], z_hi)
    if isinstance(spec, TabPull):
        lay = _tab_layout(spec, geometry)
        return (-hw, lay["y_top"], 0.0), (hw, lay["y_top"] + lay["depth"], lay["p"] - lay["t"])
    if isinstance(spec, CupPull):
        lay = _cup_layout(spec, geometry)
        hw = lay["half_w"]
        return (-hw, lay["y_rim"] - lay["depth"], 0.0), (hw, lay["y_rim"], lay["z_b"])
    if isinstance(spec, RecessLip):
        lay = _recess_layout(geometry)
        hwy = 0.5 * geometry.width - lay["t"]
        return (-lay["half_w"], -hwy, -lay["depth"]), (lay["half_w"], hwy, 0.0)
    raise ValueError(f"not a finger-pull generator: {spec!r}")


GENERATORS: dict[str, Generator] = {
    "edge_profile": edge_profile,
    "tab_pull": tab_pull,
    "cup_pull": cup_pull,
    "recess_lip": recess_lip,
}
"""Finger-pull generators by name."""
