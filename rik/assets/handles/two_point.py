"""Two-point handles: bar pulls (a straight bar on two legs) and bow pulls (a section swept along a loop).

All lengths are in metres, in the handle's mount frame: origin midway between the two screws on the front's
outer surface (the plane z = 0), +z out of the front, x along the handle, screws at x = +-hole_spacing/2.
Nothing is built in z < 0.

What every handle honours (each to well under 0.5 mm):

* overall x extent = ``geometry.length``, y extent = ``geometry.width``, max z = ``geometry.projection``;
* the loop ``|x| < clearance.width/2, 0 <= z <= clearance.depth`` (all y) is empty: a gripper finger goes
  through it. The section's thickness normal to the centre line is ``projection - clearance.depth`` (capped at
  ``grip_diameter`` for round and square sections), so the grip's underside lies exactly on the clearance;
* a bar's legs and a bow's feet stand at the screws and are clamped so they never reach into the loop: a leg's
  or foot's size along x is at most ``hole_spacing - clearance.width`` (and at most ``length - hole_spacing``,
  so it stays inside the overall length). Where a bow's inner corner can only be rounded by reaching into the
  loop, the loop is cut out of it (the corner is squared off along the clearance box).

Where the ratios leave the catalogued width unreached (the section and the legs or feet are all narrower than
``geometry.width``), the legs or feet grow to the width, within the same clamps: the legs and feet are what
carry a handle's width beyond its section.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import trimesh
from manifold3d import Manifold, Mesh
from shapely.geometry import LineString
from shapely.geometry import box as shapely_box

from rik.assets.meshkit import difference, segments, union
from rik.errors import RikError

if TYPE_CHECKING:
    from rik.assets.handles.generator import Generator
    from rik.schemas.generators import BarPull, BowPull
    from rik.schemas.handles import HandleGeometry, Mount

_EMBED = 0.5e-3
"""How far below the front's surface (m) legs, feet and sweeps start before the final cut at z = 0, so the
cut alone makes the flat base (no coplanar faces in the booleans)."""

_SLIVER = 1e-6
"""Largest surface movement (m) allowed when collapsing boolean slivers."""

_CARVE = 2e-6
"""How much larger (m) than the clearance box the cutter is that squares off inner corners reaching into it."""

_TOL = 0.25e-3
"""Slack (m) under which a size counts as reaching its catalogued value."""

_SIN60 = math.sin(math.radians(60.0))


# ---- cross-sections -----------------------------------------------------------------------------------------


class _Section:
    """A convex closed outline in section coordinates (u, v), metres, centred on the origin.

    It can be shrunk by an inward offset ``d`` (to ease edges at an end) and scaled by ``s`` (to close a
    rounded end), always with the same number of points in the same order, so rings of it can be lofted.
    Two kinds: a rounded polygon (a convex core polygon grown by a corner radius) and an ellipse.
    """

    def __init__(
        self, core: np.ndarray | None, radius: float, ellipse: tuple[float, float] | None = None, phase: float = 0.0
    ):
        self.core = core
        self.radius = radius
        self.ellipse = ellipse
        if ellipse is not None:
            a, b = ellipse
            # uniform parameter steps: the chord error is at most that of a circle of radius max(a, b)
            n = segments(max(a, b))
            n += -n % 4  # a count divisible by 4 puts points on both axes: symmetric, exact extents
            self._phi = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
            return
        assert core is not None
        k = len(core)
        self._arcs: list[tuple[np.ndarray, np.ndarray]] = []
        self._grow = 1.0
        if k == 1:  # a circle; ``phase`` turns its points by that share of a step
            n = segments(radius)
            n += -n % 4  # a count divisible by 4 keeps the outline symmetric about both axes
            phi = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False) + phase * 2.0 * math.pi / n
            if phase == 0.5:  # edges, not points, on the axes: push them out to the radius (exact extents)
                self._grow = 1.0 / math.cos(math.pi / n)
            self._arcs.append((core[0], phi))
            return
        for j in range(k):
            prev_edge = core[j] - core[j - 1]
            next_edge = core[(j + 1) % k] - core[j]
            a0 = math.atan2(-prev_edge[0], prev_edge[1])  # outward normal of a CCW polygon's edge
            a1 = math.atan2(-next_edge[0], next_edge[1])
            if a1 <= a0:
                a1 += 2.0 * math.pi
            phi = np.linspace(a0, a1, segments(radius, a1 - a0) + 1)
            self._arcs.append((core[j], phi))

    @property
    def max_offset(self) -> float:
        """Largest inward offset (m) that keeps the outline simple (below its smallest radius of curvature)."""
        if self.ellipse is not None:
            a, b = self.ellipse
            return min(a, b) ** 2 / max(a, b)
        return self.radius

    def ring(self, d: float = 0.0, s: float = 1.0) -> np.ndarray:
        """The outline shrunk by ``d`` (m) and scaled by ``s``, as an (N, 2) array of (u, v), counter-clockwise."""
        if self.ellipse is not None:
            a, b = self.ellipse
            c, sn = np.cos(self._phi), np.sin(self._phi)
            normal = np.column_stack([b * c, a * sn])
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
            return (np.column_stack([a * c, b * sn]) - d * normal) * s
        r = (self.radius - d) * self._grow
        parts = [centre + r * np.column_stack([np.cos(phi), np.sin(phi)]) for centre, phi in self._arcs]
        return np.vstack(parts) * s

    def extent(self) -> tuple[float, float]:
        """Full size along u and along v, m."""
        pts = self.ring()
        return float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1]))


def _circle(radius: float) -> _Section:
    """Circle of ``radius`` (m), its points half a step off the axes (so they never line up with the points of
    the bar or bow it is joined to, which would leave coincident vertices after the booleans)."""
    return _Section(np.zeros((1, 2)), radius, phase=0.5)


def _ellipse(a: float, b: float) -> _Section:
    """Ellipse with half-axes ``a`` along u and ``b`` along v, m."""
    return _Section(None, 0.0, (a, b))


def _rounded_rect(w: float, h: float, rc: float) -> _Section:
    """Rectangle ``w`` (u) by ``h`` (v), m, with corner radius ``rc`` (kept below half the smaller side)."""
    rc = min(rc, 0.45 * min(w, h))
    hx, hy = w / 2 - rc, h / 2 - rc
    core = np.array([[hx, -hy], [hx, hy], [-hx, hy], [-hx, -hy]])
    return _Section(core, rc)


def _rounded_hexagon(across_corners: float, rc: float) -> _Section:
    """Regular hexagon with corners on the u axis and flats facing +-v, corners rounded by ``rc``, m."""
    rc = min(rc, 0.2 * across_corners)
    r = across_corners / 2 - rc
    ang = np.radians(np.arange(6) * 60.0)
    return _Section(np.column_stack([r * np.cos(ang), r * np.sin(ang)]), rc)


# ---- lofts and sweeps ------------------------------------------------------------------------------------------


def _loft(rings: list[np.ndarray]) -> trimesh.Trimesh:
    """Closed mesh through a sequence of corresponding 3D rings (each (N, 3)); a ring of one point is an apex.

    Open ends are closed with a fan from the ring's centroid (the rings are convex). The result is made
    outward-facing (positive volume).
    """
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    starts = []
    count = 0
    for ring in rings:
        starts.append(count)
        verts.append(ring)
        count += len(ring)
    for i in range(len(rings) - 1):
        a, b = starts[i], starts[i + 1]
        na, nb = len(rings[i]), len(rings[i + 1])
        if na > 1 and nb > 1:
            j = np.arange(na)
            jn = (j + 1) % na
            faces.append(np.column_stack([a + j, a + jn, b + jn]))
            faces.append(np.column_stack([a + j, b + jn, b + j]))
        elif nb == 1:
            j = np.arange(na)
            faces.append(np.column_stack([a + j, a + (j + 1) % na, np.full(na, b)]))
        else:
            j = np.arange(nb)
            faces.append(np.column_stack([np.full(nb, a), b + (j + 1) % nb, b + j]))
    if len(rings[0]) > 1:
        n = len(rings[0])
        verts.append(rings[0].mean(axis=0, keepdims=True))
        j = np.arange(n)
        faces.append(np.column_stack([np.full(n, count), (j + 1) % n, j]))
        count += 1
    if len(rings[-1]) > 1:
        n = len(rings[-1])
        s = starts[-1]
        verts.append(rings[-1].mean(axis=0, keepdims=True))
        j = np.arange(n)
        faces.append(np.column_stack([np.full(n, count), s + j, s + (j + 1) % n]))
        count += 1
    mesh = trimesh.Trimesh(np.vstack(verts), np.vstack(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _post(section: _Section, x: float, top: float, ease: float, scale_top: float = 1.0) -> trimesh.Trimesh:
    """A vertical post of ``section`` ((u, v) = (x, y)) centred at ``x``, from just below z = 0 up to ``top``, m.

    ``ease`` rounds the top edge with that radius (0: plain cut); ``scale_top`` tapers the post linearly
    (ratio of the top's size to the size at z = 0).
    """

    def scale(z: float) -> float:
        """Size of the section at height ``z`` (m) relative to z = 0."""
        return 1.0 + (scale_top - 1.0) * z / top

    def place(pts: np.ndarray, z: float) -> np.ndarray:
        """Section points (u, v) as 3D points of the ring at height ``z`` (m)."""
        return np.column_stack([x + pts[:, 0], pts[:, 1], np.full(len(pts), z)])

    rings = [place(section.ring(0.0, scale(-_EMBED)), -_EMBED)]
    if ease > 0:
        n = segments(ease, math.pi / 2)
        for th in np.linspace(0.0, math.pi / 2, n + 1):
            z = top - ease + ease * math.sin(th)
            rings.append(place(section.ring(ease * (1 - math.cos(th)), scale(z)), z))
    else:
        rings.append(place(section.ring(0.0, scale(top)), top))
    return _loft(rings)


def _filleted(ctrl: list[tuple[float, float]], radii: list[float], outer: float) -> np.ndarray:
    """Dense polyline (K, 2) in (x, z) through ``ctrl`` with a circular fillet of ``radii[i]`` at each inner vertex.

    ``outer`` (m) is added to a fillet's radius when choosing its tessellation, so the swept surface's outer
    side keeps the chord error of :func:`rik.assets.meshkit.segments`.
    """
    pts = np.asarray(ctrl, dtype=float)
    out = [pts[0]]
    for i in range(1, len(pts) - 1):
        p = pts[i]
        d0 = (p - pts[i - 1]) / np.linalg.norm(p - pts[i - 1])
        d1 = (pts[i + 1] - p) / np.linalg.norm(pts[i + 1] - p)
        turn = math.atan2(d0[0] * d1[1] - d0[1] * d1[0], float(d0 @ d1))
        r = radii[i - 1]
        if r <= 0 or abs(turn) < 1e-9:
            out.append(p)
            continue
        tl = r * math.tan(abs(turn) / 2)
        t1 = p - d0 * tl
        left = np.array([-d0[1], d0[0]])
        centre = t1 + math.copysign(r, turn) * left
        a0 = math.atan2(t1[1] - centre[1], t1[0] - centre[0])
        n = segments(r + outer, abs(turn))
        for k in range(n + 1):
            ang = a0 + turn * k / n
            out.append(centre + r * np.array([math.cos(ang), math.sin(ang)]))
    out.append(pts[-1])
    dense = [out[0]]
    for q in out[1:]:
        if np.linalg.norm(q - dense[-1]) > 1e-9:
            dense.append(q)
    return np.array(dense)


def _sweep_xz(path: np.ndarray, section: _Section) -> trimesh.Trimesh:
    """Sweep ``section`` along a planar centre line ``path`` ((K, 2) points in the x-z plane, m).

    The section's u axis is the world y axis (the binormal of a planar path, so the frames are parallel
    transported exactly); its v axis is the in-plane normal, +v on the outer side of a path that runs from
    -x over the top to +x. Joints are mitred (v stretched by 1/cos of half the turn), so a finely
    tessellated curve keeps its full thickness. The path's curvature radius must exceed half the section's
    v size.
    """
    seg = np.diff(path, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    tangents = np.vstack([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    mitre = np.ones(len(path))
    mitre[1:-1] = 1.0 / np.einsum("ij,ij->i", seg[:-1], tangents[1:-1])
    normals = np.column_stack([-tangents[:, 1], tangents[:, 0]])
    base = section.ring()
    rings = []
    for p, n, m in zip(path, normals, mitre, strict=True):
        v = base[:, 1] * m
        rings.append(np.column_stack([p[0] + v * n[0], base[:, 0], p[1] + v * n[1]]))
    return _loft(rings)


# ---- shared sizing ------------------------------------------------------------------------------------------------


_THICKNESS_CAP = {"round": 1.0, "square": 1.0, "hexagon": 1.0, "oval": 0.8, "flat": 0.5, "strap": 0.25}
"""Largest thickness of each grip section, as a share of ``grip_diameter`` (its width)."""


def _grip_section(kind: str, geometry: HandleGeometry, square_round: float) -> tuple[_Section, float, float]:
    """The cross-section of a bar or bow, with its width ``w_s`` (along y) and thickness ``t`` (m).

    round and oval are ellipses; square, flat and strap rounded rectangles (corner radius ``square_round`` x the
    smaller side for square, 0.4 t for flat, 0.3 t for strap); hexagon a rounded regular hexagon with its flats
    facing the user."""
    w_s = min(geometry.grip_diameter, geometry.width)
    t = _thickness(geometry, _THICKNESS_CAP[kind] * geometry.grip_diameter)
    if kind in ("round", "oval"):
        return _ellipse(w_s / 2, t / 2), w_s, t
    if kind == "square":
        return _rounded_rect(w_s, t, square_round * min(w_s, t)), w_s, t
    if kind in ("flat", "strap"):
        return _rounded_rect(w_s, t, (0.4 if kind == "flat" else 0.3) * t), w_s, t
    f = 0.06  # corner radius / across-corners size; across flats is then (1 - 2f) sin60 + 2f of it
    across = min(w_s, t / ((1 - 2 * f) * _SIN60 + 2 * f))
    return _rounded_hexagon(across, f * across), w_s, t


def _thickness(geometry: HandleGeometry, cap: float) -> float:
    """Section thickness normal to the centre line, m: ``projection - clearance.depth`` (the grip's underside
    on the clearance), at most ``cap``; without a clearance, ``cap`` but at most 40 % of the projection."""
    if geometry.clearance is None:
        return min(cap, 0.4 * geometry.projection)
    room = geometry.projection - geometry.clearance.depth
    if room <= 0:
        raise RikError(
            f"two-point handle: clearance depth {geometry.clearance.depth} m leaves no room for the grip under "
            f"the projection {geometry.projection} m"
        )
    return min(cap, room)


def _hole_spacing(geometry: HandleGeometry) -> float:
    """Screw spacing, m (0.8 x length when the catalog gives none)."""
    return geometry.hole_spacing if geometry.hole_spacing is not None else 0.8 * geometry.length


def _cut_below(mesh: trimesh.Trimesh, geometry: HandleGeometry, extra: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """``mesh`` with everything in z < 0 removed, and the ``extra`` cutters, cleaned of boolean slivers.

    The booleans can leave sliver triangles thinner than trimesh's merge tolerance, which a later clean-up
    would drop (opening the mesh); manifold3d's own simplification collapses them first, moving no surface
    by more than :data:`_SLIVER` and keeping the mesh closed.
    """
    size = 4 * max(geometry.length, geometry.width, geometry.projection)
    below = trimesh.creation.box(extents=[size, size, size])
    below.apply_translation([0.0, 0.0, -size / 2])
    cut = difference(mesh, [below, *extra])
    solid = Manifold(
        mesh=Mesh(
            vert_properties=np.asarray(cut.vertices, dtype=np.float32),
            tri_verts=np.asarray(cut.faces, dtype=np.uint32),
        )
    ).simplify(_SLIVER)
    out = solid.to_mesh()
    return trimesh.Trimesh(vertices=np.asarray(out.vert_properties[:, :3], dtype=np.float64), faces=out.tri_verts)


# ---- bar pulls ------------------------------------------------------------------------------------------------------


def bar_pull(spec: BarPull, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A straight bar on two legs, in metres in the mount frame (screws at x = +-hole_spacing/2 on z = 0).

    The bar runs along x over the whole ``geometry.length`` with its top at ``geometry.projection``; its section
    (``spec.section``) is ``grip_diameter`` wide along y (capped at ``geometry.width``) and
    ``projection - clearance.depth`` thick along z, so its underside is the clearance's roof:

    * ``round`` (an ellipse if the thickness differs from the diameter), ``oval`` (an ellipse), ``square``
      (lightly rounded corners), ``flat`` (a strip with well-rounded edges), ``hexagon`` (a regular hexagon,
      flats facing the user, corners on the sides: its across-corners size is the width, shrunk if need be so
      that its across-flats size, about 0.88 of that with the rounded corners, fits the thickness).

    The legs (``spec.leg``: ``round`` cylinders, ``square`` posts, ``tapered`` cones narrowing to 60 % at the bar,
    ``flat`` plates as wide as the handle) stand on the screws from z = 0 into the bar's middle. Their size along
    x is ``spec.leg_ratio`` x ``grip_diameter``, clamped to at most ``hole_spacing - clearance.width`` (so the
    loop stays clear), ``length - hole_spacing`` (so they stay inside the length) and, for the symmetric legs,
    ``geometry.width``; if the bar and legs are narrower than the width, the legs grow to it within the clamps.

    ``spec.end_style``: ``flush`` cuts the bar square at +-length/2 (in the catalog that is the legs' outer
    faces), ``overhang`` runs it past the legs to +-length/2 with eased end edges, ``rounded`` closes it with
    half-ellipsoid caps (hemispheres for a round bar). ``mount`` is not used: the same shape serves any
    two-screw mount.
    """
    length, width, proj, grip = geometry.length, geometry.width, geometry.projection, geometry.grip_diameter
    hs = _hole_spacing(geometry)
    section, w_s, t = _grip_section(spec.section, geometry, square_round=0.12)
    sec_w, sec_t = section.extent()
    z_mid = proj - sec_t / 2
    x_end = length / 2

    # The bar: one loft along x, its two ends shaped by end_style.
    def place(pts: np.ndarray, x: float) -> np.ndarray:
        """Section points (u, v) = (y, z - z_mid) as 3D points of the ring at ``x`` (m)."""
        return np.column_stack([np.full(len(pts), x), pts[:, 0], z_mid + pts[:, 1]])

    end: list[tuple[float, float, float]] = []  # (distance in from the end, inward offset, scale), inner first
    if spec.end_style == "rounded":
        r_cap = min(sec_w, sec_t) / 2
        n = segments(max(sec_w, sec_t) / 2, math.pi / 2)
        for th in np.linspace(0.0, math.pi / 2, n + 1)[:-1]:
            end.append((r_cap * (1 - math.sin(th)), 0.0, math.cos(th)))
        end.append((0.0, 0.0, 0.0))
    else:
        share = 0.06 if spec.end_style == "flush" else 0.15
        r_e = min(share * sec_t, 0.8 * section.max_offset, 1.5e-3)
        n = segments(r_e, math.pi / 2)
        for th in np.linspace(0.0, math.pi / 2, n + 1):
            end.append((r_e * (1 - math.sin(th)), r_e * (1 - math.cos(th)), 1.0))

    def ring_at(inset: float, d: float, s: float, sign: float) -> np.ndarray:
        """The ring ``inset`` (m) in from the end on side ``sign``, shrunk by ``d`` (m), scaled by ``s`` (0: apex)."""
        x = sign * (x_end - inset)
        if s == 0.0:
            return np.array([[x, 0.0, z_mid]])
        return place(section.ring(d, s), x)

    rings = [ring_at(*e, -1.0) for e in reversed(end)] + [ring_at(*e, 1.0) for e in end]
    bar = _loft(rings)

    # The legs, clamped clear of the loop and inside the length.
    limit = length - hs
    if geometry.clearance is not None:
        limit = min(limit, hs - geometry.clearance.width)
    symmetric = spec.leg != "flat"
    leg_d = spec.leg_ratio * grip
    if symmetric:
        limit = min(limit, width)
        if max(sec_w, leg_d) < width - _TOL:
            leg_d = width
    if limit <= 0:
        raise RikError(f"bar pull: no room for the legs (hole spacing {hs} m, clearance width, length {length} m)")
    leg_d = min(leg_d, limit)
    if spec.leg == "round":
        leg_sec, taper = _circle(leg_d / 2), 1.0
    elif spec.leg == "tapered":
        leg_sec, taper = _circle(leg_d / 2), 0.6
    elif spec.leg == "square":
        leg_sec, taper = _rounded_rect(leg_d, leg_d, 0.12 * leg_d), 1.0
    else:
        leg_y = width
        leg_sec, taper = _rounded_rect(leg_d, leg_y, 0.25 * min(leg_d, leg_y)), 1.0
    legs = [_post(leg_sec, sx * hs / 2, z_mid, 0.0, taper) for sx in (-1.0, 1.0)]
    return _cut_below(union([bar, *legs]), geometry, [])


# ---- bow pulls ------------------------------------------------------------------------------------------------------


def _intrudes(path: np.ndarray, half_t: float, xi: float, zi: float) -> bool:
    """Whether a section of half-thickness ``half_t`` swept along ``path`` reaches into the clearance box, m."""
    return LineString(path).distance(shapely_box(-xi, 0.0, xi, zi)) < half_t - 1e-7


def _mirror(half: np.ndarray) -> np.ndarray:
    """Full path from the right half (which runs from (0, top) to the right foot): left foot over to right foot."""
    left = half[::-1].copy()
    left[:, 0] *= -1.0
    return np.vstack([left, half[1:]])


def bow_pull(spec: BowPull, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A bow: a section swept over a loop between two feet, in metres in the mount frame.

    The centre line lies in the x-z plane and runs from one foot (vertical, standing on z = 0) over the top to
    the other. Its top is straight across the clearance at ``projection - thickness/2``; the section
    (``spec.section``) is ``grip_diameter`` wide along y (capped at ``geometry.width``) and
    ``projection - clearance.depth`` thick normal to the path: ``round`` (an ellipse if those differ),
    ``oval`` (ellipse), ``square`` (lightly rounded), ``flat`` (well-rounded edges), ``strap`` (a thin band with
    burnished edges).

    The legs stand on the screws where they can; when the feet do not reach the catalogued length they move
    outwards until the bow's outer side does, never inside the clearance. ``spec.path`` shapes the shoulders:

    * ``rectangle``: tight bends (inner bend radius up to half the thickness);
    * ``d_shape``: a bent-rod D (inner bend radius up to one thickness);
    * ``bridge``: tight bends on tall posts (the feet are 45 % of the clearance depth high);
    * ``arc``: the roundest circular shoulders the clearance allows;
    * ``ellipse``: quarter-ellipse shoulders, taller than wide;
    * ``trapezoid``: legs that lean in at 60 degrees to a shorter top.

    Where the clearance leaves no room for a rounded inner corner (the bow's inner faces lie on the clearance)
    the inner corner is cut square along the clearance box, which also holds for the trapezoid's lean
    (limited to cutting 30 % of the thickness there).

    ``spec.foot`` stands at each screw: ``plain`` (a low round pad, left out when the bow's own end covers it),
    ``round_boss`` or ``square_boss`` (posts a quarter of the clearance depth high, rounded top edge). The foot's
    size is ``spec.foot_ratio`` x ``grip_diameter``, grown to ``geometry.width`` when nothing else reaches it,
    and clamped to at most ``hole_spacing - clearance.width`` (the loop stays clear), ``length - hole_spacing``
    and ``geometry.width``. ``mount`` is not used.
    """
    length, width, proj, grip = geometry.length, geometry.width, geometry.projection, geometry.grip_diameter
    hs = _hole_spacing(geometry)
    xs = hs / 2
    xo = length / 2
    section, w_s, t = _grip_section(spec.section, geometry, square_round=0.15)
    half_t = t / 2
    zc = proj - half_t

    # Feet: sized, clamped clear of the loop and inside the length and width.
    foot_d = spec.foot_ratio * grip
    if max(w_s, foot_d) < width - _TOL:
        foot_d = width
    limit = min(length - hs, width)
    if geometry.clearance is not None:
        limit = min(limit, hs - geometry.clearance.width)
    if limit <= 0:
        raise RikError(f"bow pull: no room for the feet (hole spacing {hs} m, clearance width, length {length} m)")
    foot_d = min(foot_d, limit)
    if geometry.clearance is not None:
        xi, zi = geometry.clearance.width / 2, geometry.clearance.depth
    else:
        xi, zi = max(xs - max(t, foot_d) / 2, 0.2 * xs), proj - t  # a loop to shape the bow around
    if spec.foot == "plain":
        has_foot = foot_d > min(t, w_s) + 0.2e-3  # else the bow's own end covers the pad's footprint
        foot_h = min(max(0.08 * zi, 0.8e-3), 2e-3) if has_foot else 0.0
    else:
        has_foot = True
        foot_h = (0.45 if spec.path == "bridge" else 0.25) * zi

    # Where the legs stand: at the screws, or further out when only they can make the length.
    reach = xs + foot_d / 2 if has_foot else 0.0
    lo, hi = xi + half_t, xo - half_t
    xl = hi if reach < xo - _TOL else min(max(xs, lo), hi)
    slack = xl - lo  # room between the clearance and the legs' inner faces
    r_min = max(0.04 * t, 0.2e-3)
    room_z = zc - foot_h  # the shoulders start above the feet
    rho_max = max(min(xl * 0.999, room_z), half_t + r_min)

    def corner(inner: float) -> np.ndarray:
        """Path with circular shoulders of inner bend radius ``inner`` (m), kept within the room there is."""
        rho = min(half_t + max(inner, r_min), rho_max)
        return _mirror(_filleted([(0.0, zc), (xl, zc), (xl, -_EMBED)], [rho], half_t))

    if spec.path == "rectangle":
        path = corner(min(slack, 0.5 * t))
    elif spec.path == "bridge":
        path = corner(min(slack, 0.5 * t))
    elif spec.path == "d_shape":
        path = corner(min(slack, t))
    elif spec.path == "arc":
        path = corner(slack)
    elif spec.path == "ellipse":
        a = min(half_t + max(slack, r_min), rho_max)

        def ellipse_path(b: float) -> np.ndarray:
            """Path with quarter-ellipse shoulders, ``a`` wide and ``b`` (m) tall."""
            n = min(segments(b * b / a + half_t, math.pi / 2), 64)
            tau = np.linspace(0.0, math.pi / 2, n + 1)
            arc = np.column_stack([xl - a + a * np.sin(tau), zc - b + b * np.cos(tau)])
            return _mirror(np.vstack([[[0.0, zc]], arc, [[xl, -_EMBED]]]))

        b_hi = max(a, min(2.2 * a, room_z, a * a / (0.55 * t)))
        b_lo = a
        if not _intrudes(ellipse_path(b_hi), half_t, xi, zi):
            b_lo = b_hi
        else:
            for _ in range(30):
                mid = 0.5 * (b_lo + b_hi)
                if _intrudes(ellipse_path(mid), half_t, xi, zi):
                    b_hi = mid
                else:
                    b_lo = mid
        path = ellipse_path(b_lo)
    else:  # trapezoid: legs lean in at 60 degrees from z1 up to the top at x1
        beta = math.radians(60.0)
        nx, nz = math.sin(beta), math.cos(beta)
        z1 = max(foot_h + half_t, 0.45 * zc)
        c = nx * xl + nz * z1
        reach_in = nx * xi + nz * zi + half_t - c  # how far the leaning line would cut into the clearance
        if reach_in > 0.3 * t:
            c = nx * xi + nz * zi + half_t - 0.3 * t
        z1 = (c - nx * xl) / nz
        x1 = (c - nz * zc) / nx
        rho = half_t + max(min(slack, 0.3 * t), r_min)
        if z1 >= zc - 1e-6 or x1 >= xl - 1e-6 or x1 < rho or z1 < rho:  # no room to lean: a plain bend
            path = corner(min(slack, 0.5 * t))
        else:
            path = _mirror(_filleted([(0.0, zc), (x1, zc), (xl, z1), (xl, -_EMBED)], [rho, rho], half_t))

    parts = [_sweep_xz(path, section)]
    if has_foot:
        if spec.foot == "square_boss":
            foot_sec = _rounded_rect(foot_d, foot_d, 0.15 * foot_d)
            ease = min(0.3 * foot_h, 0.8 * foot_sec.radius)
        else:
            foot_sec = _circle(foot_d / 2)
            share = 0.6 if spec.foot == "plain" else 0.3
            ease = min(share * foot_h, 0.4 * foot_d / 2)
        parts += [_post(foot_sec, sx * xs, foot_h, ease) for sx in (-1.0, 1.0)]
    cutters = []
    if geometry.clearance is not None and _intrudes(path, half_t, xi, zi):
        # cut the clearance out, a hair (_CARVE) larger so its faces never coincide with the bow's inner faces
        top = zi + _CARVE
        loop = trimesh.creation.box(extents=[2 * (xi + _CARVE), 4 * width, top + 0.01])
        loop.apply_translation([0.0, 0.0, (top - 0.01) / 2])
        cutters.append(loop)
    return _cut_below(union(parts), geometry, cutters)


GENERATORS: dict[str, Generator] = {"bar_pull": bar_pull, "bow_pull": bow_pull}
"""The two-point generators by name."""
