"""Knob generators: turned knobs (``knob_lathe``), prism-headed knobs (``knob_prism``) and drop rings (``knob_ring``).

All knobs are single-screw. Every mesh is in metres in the handle's mount frame: origin at the screw on the
front's outer surface, +z out of the front (the front is the half-space z < 0, which stays empty), x along the
handle's long axis. Extents: x = ``geometry.length``, y = ``geometry.width``, max z = ``geometry.projection``.

Clearance contract for the knobs (``knob_lathe``, ``knob_prism``): the head's underside is at
``z_head = max(projection * (1 - head_ratio), clearance.depth)`` (leaving the head at least :data:`MIN_HEAD`
thick); the annulus around the neck,
``neck radius < r < head half-width`` and ``base_zone(...) < z < z_head``, is free of material. Below
``base_zone`` sits the small rose (foot) that real knobs stand on. Fillets and flares that join the neck to the
head all lie above ``z_head``. The drop ring's clearance is described in :func:`knob_ring`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from rik.assets.meshkit import difference, segments, translated, union
from rik.schemas.generators import KnobLathe, KnobPrism, KnobRing
from rik.schemas.handles import HandleGeometry, Mount

if TYPE_CHECKING:
    from rik.assets.handles.generator import Generator

_EPS = 1e-9
ROSE_HEIGHT = 1.2e-3
"""Height of the plain rose (foot) under a knob's neck, m."""
ROSE_COVE = 0.8e-3
"""Radius of the concave cove joining the rose to the neck, m."""
ROSE_OVERHANG = 2.0e-3
"""How far the plain rose reaches beyond the neck, m (never beyond the head)."""
MIN_HEAD = 1.5e-3
"""Smallest head height kept when clearance and head_ratio leave less, m."""

Point = tuple[float, float, float]  # (r or x, z or y, fillet radius at this corner), metres


# ----------------------------------------------------------------------------------------------- 2-D profiles


def _fillet(points: Sequence[Point]) -> np.ndarray:
    """Replace every corner whose radius is > 0 by a tangent circular arc; return the (n, 2) polyline.

    ``points`` are (u, v, radius) in metres. Convex and concave corners are both handled. When the tangent
    lengths of two neighbouring fillets exceed their shared segment, both are shrunk in proportion.
    """
    pts = np.array([(p[0], p[1]) for p in points], dtype=float)
    radii = np.array([p[2] for p in points], dtype=float)
    n = len(pts)
    tangent = np.zeros(n)
    half = np.zeros(n)
    for i in range(1, n - 1):
        if radii[i] <= 0:
            continue
        d1 = pts[i - 1] - pts[i]
        d2 = pts[i + 1] - pts[i]
        l1, l2 = np.linalg.norm(d1), np.linalg.norm(d2)
        if l1 < _EPS or l2 < _EPS:
            continue
        cos_t = float(np.clip(np.dot(d1, d2) / (l1 * l2), -1.0, 1.0))
        theta = math.acos(cos_t)
        if theta > math.pi - 1e-6 or theta < 1e-6:
            continue
        half[i] = theta / 2
        tangent[i] = radii[i] / math.tan(theta / 2)
    # shrink tangent lengths that do not fit on their segments
    for i in range(n - 1):
        length = float(np.linalg.norm(pts[i + 1] - pts[i]))
        need = tangent[i] + tangent[i + 1]
        if need > length and need > 0:
            k = length / need
            tangent[i] *= k
            tangent[i + 1] *= k
    out: list[np.ndarray] = [pts[0]]
    for i in range(1, n - 1):
        t = tangent[i]
        if t <= _EPS:
            out.append(pts[i])
            continue
        d1 = pts[i - 1] - pts[i]
        d2 = pts[i + 1] - pts[i]
        d1 /= np.linalg.norm(d1)
        d2 /= np.linalg.norm(d2)
        r = t * math.tan(half[i])
        a = pts[i] + d1 * t
        b = pts[i] + d2 * t
        bis = d1 + d2
        bis /= np.linalg.norm(bis)
        c = pts[i] + bis * (r / math.sin(half[i]))
        a0 = math.atan2(a[1] - c[1], a[0] - c[0])
        a1 = math.atan2(b[1] - c[1], b[0] - c[0])
        sweep = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi  # the short way round
        k = segments(r, abs(sweep))
        for j in range(k + 1):
            ang = a0 + sweep * j / k
            out.append(c + r * np.array([math.cos(ang), math.sin(ang)]))
    out.append(pts[-1])
    arr = np.array(out)
    keep = np.ones(len(arr), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(arr, axis=0), axis=1) > 1e-9
    return arr[keep]


def _ellipse(cr: float, cz: float, a: float, b: float, t0: float, t1: float) -> list[Point]:
    """Points (r, z, 0) of the elliptic arc r = cr + a cos t, z = cz + b sin t for t in (t0, t1], m."""
    k = segments(max(a, b), abs(t1 - t0))
    return [(cr + a * math.cos(t), cz + b * math.sin(t), 0.0) for t in np.linspace(t0, t1, k + 1)[1:]]


def _sections(radius: float) -> int:
    """Segments around a full circle of ``radius`` (m), rounded up to a multiple of 4 so vertices lie on ±x, ±y."""
    return 4 * math.ceil(segments(radius) / 4)


def _lathe(profile: Sequence[Point], sections: int) -> trimesh.Trimesh:
    """Revolve a (r, z, fillet) profile running from the axis at the bottom to the axis at the top about z."""
    line = _fillet(profile) * 1e3  # revolve in mm: trimesh drops triangles under 1e-8 (its unit) in area
    mesh = trimesh.creation.revolve(line, sections=sections)
    mesh.apply_scale(1e-3)
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if mesh.volume < 0:
        mesh.invert()
    return mesh


# ----------------------------------------------------------------------------------------------- shared knob sizes


def _head_level(projection: float, head_ratio: float, geometry: HandleGeometry) -> float:
    """Height of the head's underside above the front, m.

    ``projection * (1 - head_ratio)``, raised to ``clearance.depth`` when the catalog asks for more room, and
    lowered only if the head would be thinner than :data:`MIN_HEAD` (then the clearance cannot be honoured).
    """
    z = projection * (1.0 - head_ratio)
    if geometry.clearance is not None:
        z = max(z, geometry.clearance.depth)
    z = min(z, projection - min(MIN_HEAD, 0.5 * projection))
    return max(z, 0.0) if z > 1e-4 else 0.0


def _rose_dims(neck_r: float, head_r: float, z_head: float, rosette: bool, projection: float):
    """(rose radius, rose height, cove radius) of the foot under a neck, m; (0, 0, 0) when there is none."""
    if neck_r >= head_r - 1e-6 or z_head < 1.0e-3:
        return 0.0, 0.0, 0.0
    if rosette:
        rr = 0.92 * head_r
        hb = min(max(0.08 * projection, 1.5e-3), 3.0e-3)
    else:
        rr = min(head_r, neck_r + ROSE_OVERHANG)
        hb = ROSE_HEIGHT
    cove = min(ROSE_COVE, 0.5 * (rr - neck_r))
    scale = min(1.0, 0.5 * z_head / (hb + cove))
    return rr, hb * scale, cove * scale


def base_zone(spec: KnobLathe | KnobPrism, geometry: HandleGeometry) -> float:
    """Height above the front occupied by the knob's rose (foot) and its cove into the neck, m.

    The clearance annulus under the head starts here. It is at most half the head's height above the front.
    """
    head_r = 0.5 * geometry.grip_diameter if isinstance(spec, KnobLathe) else 0.5 * geometry.width
    neck_r = spec.neck_ratio * head_r
    z_head = _head_level(geometry.projection, spec.head_ratio, geometry)
    rosette = isinstance(spec, KnobLathe) and spec.profile == "rosette"
    _, hb, cove = _rose_dims(neck_r, head_r, z_head, rosette, geometry.projection)
    return hb + cove


def _foot(neck_r: float, head_r: float, z_head: float, rosette: bool, projection: float) -> list[Point]:
    """Profile points of the foot: from the axis at z = 0 out to the neck (r, z, fillet), m."""
    rr, hb, cove = _rose_dims(neck_r, head_r, z_head, rosette, projection)
    if hb <= 0:
        return [(0.0, 0.0, 0.0), (neck_r, 0.0, 0.0)]
    edge = 0.6 * hb if rosette else 0.45 * hb  # rounded top edge of the rose (a bead on a rosette)
    return [(0.0, 0.0, 0.0), (rr, 0.0, 0.0), (rr, hb, edge), (neck_r, hb, cove)]


# ----------------------------------------------------------------------------------------------- knob_lathe


def _lathe_profile(spec: KnobLathe, geometry: HandleGeometry) -> list[Point]:
    """The knob's (r, z, fillet) outline from the axis on the front to the axis at the top, m."""
    R = 0.5 * geometry.grip_diameter
    P = geometry.projection
    rn = spec.neck_ratio * R
    zh = _head_level(P, spec.head_ratio, geometry)
    H = P - zh
    e = spec.edge_round * R
    profile = spec.profile
    if rn >= R - 1e-6:
        zh, H = 0.0, P  # neck as wide as the head: one solid body standing on the front
    if zh <= 0:
        rn = R  # the head stands on the front: no neck
    foot = _foot(rn, R, zh, profile == "rosette", P)
    rt = 0.9 * rn if profile == "peg" and zh > 0 else rn  # a peg's shaft tapers slightly towards the head
    eb_ok = zh > 0  # round the head's underside edge only when it stands clear of the front
    pts: list[Point] = []

    if profile in ("mushroom", "rosette"):
        eb = min(e, 0.4 * H) if eb_ok else 0.0
        zs = zh + max(eb, 0.45 * H)
        pts = [(rt, zh, 0.0), (R, zh, eb), (R, zs, 0.0), *_ellipse(0.0, zs, R, P - zs, 0.0, math.pi / 2)]
    elif profile in ("cylinder", "disc"):
        eb = min(e, 0.45 * H) if eb_ok else 0.0
        et = min(e, 0.45 * H, 0.9 * R)
        pts = [(rt, zh, 0.0), (R, zh, eb), (R, P, et), (0.0, P, 0.0)]
    elif profile == "ball":
        if zh > 0:
            b = 0.5 * H
            zc = zh + b
            phi = -math.acos(min(1.0, rt / R))
        else:  # no neck: the ball is flattened where it stands on the front, on a circle of radius R / 2
            phi = -math.pi / 3
            b = P / (1 - math.sin(phi))
            zc = P - b
            foot = [(0.0, 0.0, 0.0)]
        zj = zc + b * math.sin(phi)
        pts = [(R * math.cos(phi), zj, 0.0), *_ellipse(0.0, zc, R, b, phi, math.pi / 2)]
    elif profile == "cone":
        zc = zh + 0.7 * H
        ec = min(0.5 * e, 0.15 * H)
        et = min(e, 0.15 * H)
        pts = [(rt, zh, 0.0), (R, zc, ec), (R, P, et), (0.0, P, 0.0)]
    elif profile == "bell":
        eb = min(e, 0.3 * (R - rt), 0.2 * H)
        flare = max(min(R - rt - eb, 0.5 * H), 0.0)
        zf = zh + flare
        zs = zf + max(eb, 0.1 * H)
        pts = [(rt, zh, 0.0), (rt, zf, flare), (R, zf, eb), (R, zs, 0.0),
               *_ellipse(0.0, zs, R, P - zs, 0.0, math.pi / 2)]
    elif profile == "stepped":
        r2 = max(0.7 * R, rt)
        z1 = zh + 0.5 * H
        eb = min(0.5 * e, 0.2 * H) if eb_ok else 0.0
        es = min(0.5 * e, 0.2 * H, 0.4 * (R - r2))
        et = min(e, 0.4 * H, 0.5 * r2)
        pts = [(rt, zh, 0.0), (R, zh, eb), (R, z1, es), (r2, z1, 0.5 * es), (r2, P, et), (0.0, P, 0.0)]
    elif profile == "dome":
        eb = min(e, 0.25 * H) if eb_ok else 0.0
        zs = zh + max(eb, 0.1 * H)
        pts = [(rt, zh, 0.0), (R, zh, eb), (R, zs, 0.0), *_ellipse(0.0, zs, R, P - zs, 0.0, math.pi / 2)]
    elif profile == "peg":
        eb = min(e, 0.3 * H) if eb_ok else 0.0
        zs = P - min(0.6 * R, 0.6 * H)
        zs = max(zs, zh + eb)
        pts = [(rt, zh, 0.0), (R, zh, eb), (R, zs, 0.0), *_ellipse(0.0, zs, R, P - zs, 0.0, math.pi / 2)]
    else:  # pragma: no cover - the schema restricts the profile names
        raise ValueError(f"unknown knob profile {profile!r}")
    return foot + pts


def knob_lathe(spec: KnobLathe, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A turned knob: a profile revolved about z, standing on a small rose (foot) at the screw (metres).

    Head radius R = grip_diameter / 2 (x and y extents = grip_diameter); the top reaches ``projection``.
    ``neck_ratio`` sets the neck radius (neck_ratio * R); ``head_ratio`` the head's height (head_ratio *
    projection; the underside is raised to ``clearance.depth`` if that is higher); ``edge_round`` the fillet radius
    of the head's edges (edge_round * R, clamped to fit the head's height); ``flutes`` cuts that many vertical
    grooves around the head's rim (ridges fall on the x and y axes when flutes is a multiple of 4, so the extents
    hold exactly; otherwise an extent may be short by up to the flute depth, at most 8 % of R).

    Profiles: ``mushroom`` (flat underside, rounded rim, domed cap), ``cylinder`` (a cylinder with a rounded
    top edge; with neck_ratio 1 it stands on the front without a neck), ``disc`` (a thin disc with both edges
    rounded), ``ball`` (a spheroid, R wide and head-height tall; edge_round unused), ``cone`` (a cone flaring from
    the neck to a short rim), ``bell`` (a concave trumpet flare into a rounded rim and dome), ``stepped`` (two
    tiers, the upper 0.7 R), ``dome`` (an elliptic dome on a thin rounded rim), ``peg`` (a long, slightly tapering
    shaft and a rounded end), ``rosette`` (a mushroom head on a neck standing on a 0.92 R rose plate). The mount is
    single-screw; ``mount`` is not otherwise used.
    """
    del mount
    R = 0.5 * geometry.grip_diameter
    mesh = _lathe(_lathe_profile(spec, geometry), _sections(R))
    if spec.flutes > 0:
        mesh = _cut_flutes(mesh, spec, geometry)
    return mesh


def _cut_flutes(mesh: trimesh.Trimesh, spec: KnobLathe, geometry: HandleGeometry) -> trimesh.Trimesh:
    """Cut ``spec.flutes`` vertical round grooves into the head's rim, m; they fade out over the domed top."""
    R = 0.5 * geometry.grip_diameter
    rn = spec.neck_ratio * R
    zh = _head_level(geometry.projection, spec.head_ratio, geometry)
    n = spec.flutes
    depth = 0.08 * R if zh <= 0 or rn >= R else min(0.08 * R, 0.5 * (R - rn))  # never reaching the neck
    rf = min(0.35 * 2 * math.pi * R / n, 4 * depth)
    rf = min(max(rf, depth * 1.1), 0.45 * 2 * (R - depth) * math.sin(math.pi / n))  # neighbours stay apart
    depth = min(depth, 0.9 * rf)
    if depth <= 2e-5:
        return mesh
    dc = R + rf - depth
    z0 = max(zh - 1e-3, 0.5 * zh) if zh > 0 else -1e-3
    z1 = geometry.projection + 1e-3
    cutter = _lathe([(0.0, z0, 0.0), (rf, z0, 0.0), (rf, z1, 0.0), (0.0, z1, 0.0)], segments(rf))
    cutters = []
    for k in range(n):
        ang = (k + 0.5) * 2 * math.pi / n  # grooves between the axes, ridges on them
        cutters.append(translated(cutter, [dc * math.cos(ang), dc * math.sin(ang), 0.0]))
    return difference(mesh, [union(cutters)])


# ----------------------------------------------------------------------------------------------- knob_prism


def _outline(spec: KnobPrism, half_l: float, half_w: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Outline of the head seen from the front: (points (n, 2), outward unit normals (n, 2), corner radius), m.

    Polygons are a sharp core polygon offset outwards by the corner radius, the core scaled so the outline's
    extents are exactly ±half_l by ±half_w. The oval is an ellipse with those semi-axes.
    """
    if spec.outline == "oval":
        k = _sections(max(half_l, half_w))
        t = np.linspace(0, 2 * np.pi, k, endpoint=False)
        p = np.column_stack([half_l * np.cos(t), half_w * np.sin(t)])
        nrm = np.column_stack([half_w * np.cos(t), half_l * np.sin(t)])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        return p, nrm, min(half_l, half_w) ** 2 / max(half_l, half_w)  # least radius of curvature
    rc = min(spec.corner_round * half_w, 0.98 * min(half_l, half_w))
    if spec.outline in ("square", "t_bar"):
        unit = np.array([[1, -1], [1, 1], [-1, 1], [-1, -1]], dtype=float)
    elif spec.outline == "hexagon":
        a = np.arange(6) * np.pi / 3
        unit = np.column_stack([np.cos(a), np.sin(a) / math.sin(math.pi / 3)])
    else:  # octagon, flats on the axes
        a = np.pi / 8 + np.arange(8) * np.pi / 4
        unit = np.column_stack([np.cos(a), np.sin(a)]) / math.cos(math.pi / 8)
    core = unit * np.array([half_l - rc, half_w - rc])
    m = len(core)
    edge_n = []
    for i in range(m):
        d = core[(i + 1) % m] - core[i]
        edge_n.append(np.array([d[1], -d[0]]) / np.linalg.norm(d))  # outward for a counter-clockwise polygon
    pts, nrms = [], []
    for i in range(m):
        n0, n1 = edge_n[i - 1], edge_n[i]
        a0, a1 = math.atan2(n0[1], n0[0]), math.atan2(n1[1], n1[0])
        sweep = (a1 - a0) % (2 * math.pi)
        k = segments(rc, sweep) if rc > 1e-6 else 1
        for j in range(k + 1) if k > 1 else [0]:
            ang = a0 + sweep * (j / k if k > 1 else 0.5)
            nv = np.array([math.cos(ang), math.sin(ang)])
            pts.append(core[i] + rc * nv)
            nrms.append(nv)
    return np.array(pts), np.array(nrms), rc


def _loft(rings: Sequence[tuple[np.ndarray, float]]) -> trimesh.Trimesh:
    """Closed solid through rings of equally many (x, y) points at heights z, capped by fans at both ends."""
    count = len(rings[0][0])
    verts = [np.column_stack([xy, np.full(count, z)]) for xy, z in rings]
    z_bot, z_top = rings[0][1], rings[-1][1]
    verts.append(np.array([[0.0, 0.0, z_bot], [0.0, 0.0, z_top]]))
    v = np.vstack(verts)
    nr = len(rings)
    bot_c, top_c = nr * count, nr * count + 1
    faces = []
    idx = np.arange(count)
    nxt = (idx + 1) % count
    for r in range(nr - 1):
        a, b = r * count + idx, (r + 1) * count + idx
        an, bn = r * count + nxt, (r + 1) * count + nxt
        faces.append(np.column_stack([a, an, bn]))
        faces.append(np.column_stack([a, bn, b]))
    faces.append(np.column_stack([np.full(count, bot_c), nxt, idx]))
    top = (nr - 1) * count
    faces.append(np.column_stack([np.full(count, top_c), top + idx, top + nxt]))
    mesh = trimesh.Trimesh(v, np.vstack(faces), process=True)
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def knob_prism(spec: KnobPrism, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A knob whose head is an extruded outline (seen from the front) on a round neck and rose (metres).

    The head's inner face fills ``length`` (x) by ``width`` (y) exactly; its outer face is at ``projection``.
    ``outline``: ``square`` / ``t_bar`` (a rounded rectangle), ``hexagon`` (corners on ±x, flats on ±y; a regular
    hexagon cannot have equal extents, so the hexagon is scaled to fit length x width), ``octagon`` (flats on the
    axes), ``oval`` (an ellipse). ``corner_round`` sets the corner radius (corner_round * width / 2; unused for the
    oval); ``neck_ratio`` the neck diameter (neck_ratio * width); ``head_ratio`` the head height (head_ratio *
    projection, underside raised to ``clearance.depth`` if higher); ``taper`` the outer face's size relative to
    the inner face (clamped to at least 0.3; the head's sides are straight between them). The head's front and
    underside edges are rounded with the corner radius (at most 0.3 of the head height, and for the oval at most
    its least radius of curvature), so a sharp outline (corner_round 0) gives sharp edges.
    """
    del mount
    half_l, half_w = 0.5 * geometry.length, 0.5 * geometry.width
    P = geometry.projection
    rn = spec.neck_ratio * half_w
    zh = _head_level(P, spec.head_ratio, geometry)
    if zh <= 0:
        zh = min(0.3 * P, 2e-3)  # a head cannot stand on the front with a neck under it; keep a short neck
    H = P - zh
    taper = max(spec.taper, 0.3)
    s0, s1 = 1.0, taper
    pts, nrm, rc = _outline(spec, half_l, half_w)
    if spec.outline == "oval":
        rho = min(spec.corner_round * half_w, 0.3 * H, 0.9 * s1 * rc)
    else:
        rho = min(rc * 0.9 * s1, 0.3 * H)

    z_lo, z_hi = zh + rho, P - rho  # the straight sides run between the two rounded edges

    def ring(z: float, inset: float) -> tuple[np.ndarray, float]:
        """The outline at height z (m), scaled for the taper and moved ``inset`` (m) inwards along its normals."""
        s = s0 + (s1 - s0) * min(max((z - z_lo) / max(z_hi - z_lo, 1e-9), 0.0), 1.0)
        return s * pts - inset * nrm, z

    rings = []
    if rho > 1e-5:
        k = segments(rho, math.pi / 2)
        for u in np.linspace(0, math.pi / 2, k + 1):
            rings.append(ring(zh + rho * (1 - math.cos(u)), rho * (1 - math.sin(u))))
        for u in np.linspace(0, math.pi / 2, k + 1):
            rings.append(ring(P - rho + rho * math.sin(u), rho * (1 - math.cos(u))))
    else:
        rings = [ring(zh, 0.0), ring(P, 0.0)]
    head = _loft(rings)
    # round neck and rose, reaching into the head
    neck_top = zh + min(0.5 * H, 2e-3)
    profile = [*_foot(rn, half_w, zh, False, P), (rn, neck_top, 0.0), (0.0, neck_top, 0.0)]
    neck = _lathe(profile, _sections(max(rn, 1e-3)))
    return union([head, neck])


# ----------------------------------------------------------------------------------------------- knob_ring


def knob_ring(spec: KnobRing, geometry: HandleGeometry, mount: Mount) -> trimesh.Trimesh:
    """A drop-ring pull: a ring threaded through the head of a round boss at the screw (metres).

    The ring's outer diameter D = ``length`` and its wire diameter w = ``section_ratio`` * D, lowered to
    ``projection - clearance.depth`` when the catalog's clearance asks for more room behind the ring. The ring lies
    in a plane parallel to the front, its top face at z = ``projection`` and its back at z = projection - w; it
    hangs towards -y, its outer top edge at y = 0 (the boss's axis), so its centre is at (0, -D/2). The boss
    (diameter ``boss_ratio`` * D, at least 3 w) stands from the front to just under the ring's top, with a waist
    below its head; the ring's top passes through the head. Extents: x = D, y = D + boss radius (the catalog's
    ``width``), max z = projection.

    Clearance (where a finger hooks behind the ring): every point with 0 < z < projection - w (the catalog's
    ``clearance.depth``) whose (x, y) lies inside the ring's outer circle and outside the boss's circle is empty.
    The ring's inner diameter D - 2 w is the catalog's ``clearance.width``. ``mount`` is not used.
    """
    del mount
    D = geometry.length
    P = geometry.projection
    w = spec.section_ratio * D
    if geometry.clearance is not None:
        w = min(w, P - geometry.clearance.depth)
    w = max(min(w, 0.45 * D, 0.8 * P), 1e-4)
    rb = max(0.5 * spec.boss_ratio * D, 1.5 * w)
    zc = P - 0.5 * w  # the ring's mid-plane
    # boss: a foot at full radius, a waist, and a head holding the ring
    waist = 0.72 * rb
    z_head = max(zc - 0.5 * w - 0.6 * rb, 0.45 * P)
    top = P - 0.2 * w
    e = min(0.3 * rb, 0.3 * (top - z_head))
    foot_h = min(1.2e-3, 0.2 * z_head)
    profile = [
        (0.0, 0.0, 0.0),
        (rb, 0.0, 0.0),
        (rb, foot_h, 0.5 * foot_h),
        (waist, foot_h, min(0.25 * rb, 0.4 * (z_head - foot_h))),
        (waist, z_head, min(0.25 * rb, 0.4 * (z_head - foot_h))),
        (rb, z_head + min(0.25 * rb, 0.4 * (top - z_head)), 0.0),
        (rb, top, e),
        (0.0, top, 0.0),
    ]
    boss = _lathe(profile, _sections(rb))
    major, minor = 0.5 * (D - w), 0.5 * w
    ring = trimesh.creation.torus(1e3 * major, 1e3 * minor, major_sections=_sections(0.5 * D),
                                  minor_sections=_sections(minor))  # built in mm, as in _lathe
    ring.apply_scale(1e-3)
    ring = translated(ring, [0.0, -0.5 * D, zc])
    return union([boss, ring])


GENERATORS: dict[str, Generator] = {"knob_lathe": knob_lathe, "knob_prism": knob_prism, "knob_ring": knob_ring}
"""The generators of this module by name."""
