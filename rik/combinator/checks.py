"""Named validation checks of a variant, each with a pass or fail and a reason in words.

Two kinds: checks of the pairing's geometry (before MuJoCo sees it) and checks of the compiled model. A variant
is valid when every check passes; the first failing check names why it is rejected. The documented test pull
(:func:`check_opens_under_pull`) is 1.5 times the quasi-static force the front needs at its handle (friction
plus any gravity or spring it must lift against, over the whole range), and at least :data:`MIN_TEST_PULL`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import mujoco
    import numpy as np

    from rik.combinator.mjcf import FrontLayout, VariantModel
    from rik.joints.runtime import RuntimeEffects
    from rik.registry.catalog import Catalog
    from rik.schemas import BaseUnit, Front

MIN_GRASP_DEPTH = 0.010
"""m: how far a handle must stand off the face (or, for an inset grip, reach into the front) for a fingertip or
a gripper finger to engage it; about a fingertip's thickness."""
MIN_RECESS_FLOOR = 0.004
"""m: board left behind a routed recess."""
PENETRATION_TOL = 0.00005
"""m: the deepest overlap between two bodies that counts as touching (numerical noise). Any deeper overlap makes
contact forces, so it is interference: a drawer rubbing on its neighbour does not open freely."""
HANDLE_SINK_TOL = 0.001
"""m: how deep a handle's collision may reach into its own front (they are one rigid body, so MuJoCo never
collides them): CoACD's hulls stand off the true surface by a fraction of a millimetre (mean 0.39 mm over the
catalog, docs/catalog/fidelity.csv)."""
SEATED_TOL = 0.001
"""m: the largest gap between a handle's collision and its front that counts as mounted."""
SWEEP_SAMPLES = 24
"""Joint positions per front in the collision sweep (evenly over the range, the closed end excluded)."""
REST_SECONDS = 2.0
"""s of free stepping in the rest check."""
DRIFT_FRACTION = 0.02
"""Largest opening, as a fraction of the range, that a front may drift to in the rest check."""
MIN_TEST_PULL = 10.0
"""N: the smallest test pull."""
PULL_FACTOR = 1.5
"""Test pull = this times the quasi-static force to open, N."""
PULL_SECONDS = 5.0
"""s the test pull may take to open a front fully."""
OPEN_FRACTION = 0.98
"""A front is fully open at this fraction of its range."""


@dataclass
class CheckResult:
    name: str
    passed: bool
    reason: str
    details: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        return {"name": self.name, "passed": self.passed, "reason": self.reason, "details": self.details}


@dataclass
class ModelContext:
    """A compiled variant and what the checks need to know about its names."""

    variant: VariantModel
    unit: BaseUnit
    model: mujoco.MjModel
    data: mujoco.MjData
    metrics: dict[str, Any] = field(default_factory=dict)
    """Timings and forces the checks measure, for the report."""
    runtime_effects: dict[int, RuntimeEffects] | None = field(default=None, repr=False)
    """Appliers of the fronts' runtime joint effects by dof address (built on first use by :meth:`effects`)."""

    def joint(self, front: str) -> tuple[int, int, int]:
        """(joint id, qpos address, dof address) of a front's joint."""
        import mujoco

        jid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, front)
        return jid, int(self.model.jnt_qposadr[jid]), int(self.model.jnt_dofadr[jid])

    def effects(self) -> dict[int, RuntimeEffects]:
        """Appliers of the fronts' runtime joint effects (the effects MuJoCo lacks), by dof address."""
        if self.runtime_effects is None:
            from rik.joints.runtime import front_effects

            self.runtime_effects = {e.dof: e for e in front_effects(self.model, self.variant.info()["fronts"])}
        return self.runtime_effects

    def body_label(self, geom: int) -> str:
        """Who a geom belongs to, in words: ``carcass``, a front's id, or ``<front>/handle``."""
        import mujoco

        body = mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, int(self.model.geom_bodyid[geom]))
        return "carcass" if body == "base_unit" else body

    def geom_name(self, geom: int) -> str:
        import mujoco

        return mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, geom) or f"geom {geom}"

    def pose(self, positions: dict[str, float]) -> None:
        """Set joint positions (others closed), zero velocity, and run kinematics and collision."""
        import mujoco

        self.data.qpos[:] = 0.0
        self.data.qvel[:] = 0.0
        for front, q in positions.items():
            self.data.qpos[self.joint(front)[1]] = q
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_collision(self.model, self.data)


def _fmt_q(layout: FrontLayout, q: float) -> str:
    return f"{q * 1000:.0f} mm" if layout.motion == "slide" else f"{math.degrees(q):.0f}°"


def _mm(x: float) -> str:
    return f"{x * 1000:.1f} mm"


# ---- geometry checks --------------------------------------------------------------------------------------------
def handle_footprint(variant: VariantModel, layout: FrontLayout) -> tuple[np.ndarray, np.ndarray]:
    """The handle's bounds projected on the front (site frame u, v, m): (low corner, high corner)."""
    import numpy as np

    lo, hi = variant.handle_bounds[0][:2], variant.handle_bounds[1][:2]
    corners = np.array([[x, y] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    a = math.radians(layout.placement.rotation)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    pts = corners @ rot.T + np.array([layout.placement.u, layout.placement.v])
    return pts.min(axis=0), pts.max(axis=0)


def check_mount_fit(catalog: Catalog, variant: VariantModel) -> CheckResult:
    """The handle's footprint lies in each front's mount rectangle (for edge pulls: along the edge)."""
    unit = catalog.base_units[variant.key.base]
    worst = math.inf
    for layout, front in zip(variant.fronts, unit.fronts, strict=True):
        sx, sy = front.mount.size
        lo, hi = handle_footprint(variant, layout)
        # edge pulls overhang their edge by design: only their extent along the edge (their x) must fit
        edge_axis = 0 if layout.placement.rotation % 180 == 0 else 1
        axes = [0, 1] if layout.placement.edge is None else [edge_axis]
        for axis in axes:
            half = (sx, sy)[axis] / 2
            margin = min(half - hi[axis], lo[axis] + half)
            worst = min(worst, margin)
            if margin < -1e-4:
                what = "width" if axis == 0 else "height"
                size = f"{(hi[0] - lo[0]) * 1000:.0f} x {(hi[1] - lo[1]) * 1000:.0f} mm"
                return CheckResult("mount_fit", False,
                                   f"{variant.key.handle} ({size} on the front) overruns {front.id}'s mount "
                                   f"rectangle ({sx * 1000:.0f} x {sy * 1000:.0f} mm) by {_mm(-margin)} along its "
                                   f"{what}", {"front": front.id, "overrun_m": -margin})
    return CheckResult("mount_fit", True, f"every front's handle lies in its mount rectangle with at least "
                       f"{_mm(worst)} to spare", {"min_margin_m": worst})


def check_grasp_depth(catalog: Catalog, variant: VariantModel) -> CheckResult:
    """The handle stands off the face (plus, inset, its recess) by at least :data:`MIN_GRASP_DEPTH`."""
    projection = float(variant.handle_bounds[1][2])
    depth = projection + (variant.recess[4] if variant.recess else 0.0)
    what = f"stands {_mm(projection)} off the face" + (f" over a {_mm(variant.recess[4])} recess"
                                                       if variant.recess else "")
    ok = depth >= MIN_GRASP_DEPTH - 1e-6
    return CheckResult("grasp_depth", ok, f"{variant.key.handle} {what}" + (
        "" if ok else f": a finger needs {_mm(MIN_GRASP_DEPTH)}"), {"grasp_depth_m": depth})


def check_recess_depth(catalog: Catalog, variant: VariantModel) -> CheckResult:
    """An inset grip's recess leaves at least :data:`MIN_RECESS_FLOOR` of board behind it."""
    if variant.recess is None:
        return CheckResult("recess_depth", True, "no recess (the handle is not inset)")
    unit = catalog.base_units[variant.key.base]
    depth = variant.recess[4]
    for front in unit.fronts:
        if unit.meshes is not None:
            return CheckResult("recess_depth", False, f"{variant.key.handle} is inset, and rik cuts recesses into "
                               "generated fronts only; this base unit's fronts are imported meshes")
        floor = front.size[2] - depth
        if floor < MIN_RECESS_FLOOR:
            return CheckResult("recess_depth", False, f"{variant.key.handle}'s recess is {_mm(depth)} deep, {front.id} "
                               f"is {_mm(front.size[2])} thick: it leaves {_mm(floor)} of board, at least "
                               f"{_mm(MIN_RECESS_FLOOR)} is needed", {"front": front.id, "floor_m": floor})
    return CheckResult("recess_depth", True, f"the {_mm(depth)} recess leaves at least "
                       f"{_mm(min(f.size[2] for f in unit.fronts) - depth)} of board")


GEOMETRY_CHECKS: tuple[Callable[[Catalog, VariantModel], CheckResult], ...] = (
    check_mount_fit, check_grasp_depth, check_recess_depth)


# ---- model checks -----------------------------------------------------------------------------------------------
def check_inertia(ctx: ModelContext) -> CheckResult:
    """Every moving body has a positive mass and a physical inertia (positive, triangle inequality)."""
    m = ctx.model
    for body in range(1, m.nbody):
        if m.body_weldid[body] == 0:
            continue
        mass, (a, b, c) = float(m.body_mass[body]), m.body_inertia[body]
        ok = mass > 0 and min(a, b, c) > 0 and a + b >= c * (1 - 1e-9) and a + c >= b * (1 - 1e-9) \
            and b + c >= a * (1 - 1e-9) and all(map(math.isfinite, (mass, a, b, c)))
        if not ok:
            import mujoco

            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, body)
            return CheckResult("inertia_valid", False, f"body {name} has mass {mass:g} kg and principal inertia "
                               f"({a:g}, {b:g}, {c:g}) kg·m²: not a physical rigid body")
    masses = {f.id: float(m.body_subtreemass[_body(ctx, f.id)]) for f in ctx.variant.fronts}
    return CheckResult("inertia_valid", True, "moving bodies have positive masses and physical inertias ("
                       + ", ".join(f"{k} {v:.2f} kg" for k, v in masses.items()) + ")", {"front_mass_kg": masses})


def _body(ctx: ModelContext, name: str) -> int:
    import mujoco

    return mujoco.mj_name2id(ctx.model, mujoco.mjtObj.mjOBJ_BODY, name)


def _site(ctx: ModelContext, name: str) -> int:
    import mujoco

    return mujoco.mj_name2id(ctx.model, mujoco.mjtObj.mjOBJ_SITE, name)


def _grasp_velocity(ctx: ModelContext, front: str) -> np.ndarray:
    """d(grasp site position)/dq of the front's joint at the current pose (m per m, or m per rad)."""
    import mujoco
    import numpy as np

    jacp = np.zeros((3, ctx.model.nv))
    mujoco.mj_jacSite(ctx.model, ctx.data, jacp, None, _site(ctx, f"{front}/grasp"))
    return jacp[:, ctx.joint(front)[2]].copy()


def check_opens_outward(ctx: ModelContext) -> CheckResult:
    """Opening each joint moves its handle out of the front (along the front's outward normal), not into the
    carcass."""
    import mujoco
    import numpy as np

    from rik.registry.geometry import site_axes

    unit = ctx.variant.key.base
    ctx.pose({})
    mujoco.mj_forward(ctx.model, ctx.data)
    for layout in ctx.variant.fronts:
        normal = np.asarray(site_axes(_front(ctx, layout.id).mount.quat)[2])
        v = _grasp_velocity(ctx, layout.id)
        speed = float(np.dot(v, normal))
        if speed <= 1e-6:
            return CheckResult("opens_outward", False, f"opening {layout.id} of {unit} moves its handle into the "
                               "carcass (its joint axis points the wrong way: flip the axis)",
                               {"front": layout.id, "outward_speed": speed})
    return CheckResult("opens_outward", True, "every front's handle moves outward as its joint opens")


def _front(ctx: ModelContext, front_id: str) -> Front:
    return next(f for f in ctx.unit.fronts if f.id == front_id)


def _penetrations(ctx: ModelContext) -> list[tuple[float, int, int]]:
    """(depth, geom1, geom2) of contacts deeper than the tolerance, deepest first."""
    import numpy as np

    d = ctx.data
    if d.ncon == 0:
        return []
    depth = -np.asarray(d.contact.dist[: d.ncon])
    deep = np.flatnonzero(depth > PENETRATION_TOL)
    geoms = np.asarray(d.contact.geom[: d.ncon])
    return sorted(((float(depth[i]), int(geoms[i, 0]), int(geoms[i, 1])) for i in deep), reverse=True)


def _describe(ctx: ModelContext, depth: float, g1: int, g2: int) -> str:
    return (f"{ctx.geom_name(g1)} ({ctx.body_label(g1)}) and {ctx.geom_name(g2)} ({ctx.body_label(g2)}) overlap "
            f"by {_mm(depth)}")


def check_closed_contact_free(ctx: ModelContext) -> CheckResult:
    """With every front closed, no two bodies interpenetrate."""
    ctx.pose({})
    hits = _penetrations(ctx)
    if hits:
        return CheckResult("closed_contact_free", False, "closed: " + _describe(ctx, *hits[0]),
                           {"contacts": len(hits)})
    return CheckResult("closed_contact_free", True, "closed, no two bodies overlap")


def check_handle_seated(ctx: ModelContext) -> CheckResult:
    """Each handle touches its front (mounted, not floating) and does not sink into it."""
    import mujoco
    import numpy as np

    m, d = ctx.model, ctx.data
    ctx.pose({})
    fromto = np.zeros(6)
    worst_gap, worst_pen = 0.0, 0.0
    for layout in ctx.variant.fronts:
        hbody, fbody = _body(ctx, f"{layout.id}/handle"), _body(ctx, layout.id)
        hulls = [g for g in range(m.ngeom) if m.geom_bodyid[g] == hbody and m.geom_contype[g]]
        boards = [g for g in range(m.ngeom) if m.geom_bodyid[g] == fbody and m.geom_contype[g]]
        dists = [mujoco.mj_geomDistance(m, d, h, b, 0.05, fromto) for h in hulls for b in boards]
        gap, pen = min(dists), -min(dists)
        if gap > SEATED_TOL:
            return CheckResult("handle_seated", False, f"{layout.id}'s handle floats {_mm(gap)} off the front",
                               {"front": layout.id, "gap_m": gap})
        if pen > HANDLE_SINK_TOL:
            return CheckResult("handle_seated", False, f"{layout.id}'s handle sinks {_mm(pen)} into the front",
                               {"front": layout.id, "penetration_m": pen})
        worst_gap, worst_pen = max(worst_gap, gap), max(worst_pen, pen)
    return CheckResult("handle_seated", True, f"every handle touches its front (deepest overlap {_mm(worst_pen)})",
                       {"max_penetration_m": worst_pen})


def check_sweep_clear(ctx: ModelContext) -> CheckResult:
    """Across each joint's range (alone, and all fronts together), no moving body interpenetrates another."""
    sweeps = [{layout.id: layout.joint_range[1] * k / SWEEP_SAMPLES for layout in ctx.variant.fronts}
              for k in range(1, SWEEP_SAMPLES + 1)]
    singles = [{layout.id: layout.joint_range[1] * k / SWEEP_SAMPLES}
               for layout in ctx.variant.fronts for k in range(1, SWEEP_SAMPLES + 1)]
    for positions in singles + (sweeps if len(ctx.variant.fronts) > 1 else []):
        ctx.pose(positions)
        hits = _penetrations(ctx)
        if hits:
            where = ", ".join(f"{f} at {_fmt_q(_layout(ctx, f), q)}" for f, q in positions.items())
            return CheckResult("sweep_clear", False, f"with {where}: " + _describe(ctx, *hits[0]),
                               {"positions": positions})
    fronts = len(ctx.variant.fronts)
    return CheckResult("sweep_clear", True, f"{SWEEP_SAMPLES} poses per front"
                       + (" (alone and all open together)" if fronts > 1 else "") + ": nothing overlaps")


def _layout(ctx: ModelContext, front: str) -> FrontLayout:
    return next(f for f in ctx.variant.fronts if f.id == front)


def _finite(ctx: ModelContext) -> bool:
    import numpy as np

    return bool(np.all(np.isfinite(ctx.data.qpos)) and np.all(np.isfinite(ctx.data.qvel)))


def _warnings(ctx: ModelContext) -> list[str]:
    import mujoco

    return [mujoco.mjtWarning(i).name for i, w in enumerate(ctx.data.warning) if w.number > 0]


def check_rest_stable(ctx: ModelContext) -> CheckResult:
    """A few seconds of free stepping from closed: finite, no MuJoCo warnings, no front drifts open."""
    import time

    import mujoco

    m, d = ctx.model, ctx.data
    mujoco.mj_resetData(m, d)
    steps = round(REST_SECONDS / m.opt.timestep)
    drift = {f.id: 0.0 for f in ctx.variant.fronts}
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    ctx.metrics["step_seconds"] = (time.perf_counter() - t0) / steps
    warnings = _warnings(ctx)
    if not _finite(ctx) or warnings:
        what = "state became non-finite" if not _finite(ctx) else "MuJoCo warned " + ", ".join(warnings)
        return CheckResult("rest_stable", False, f"{REST_SECONDS:g} s of stepping from closed: {what}")
    worst, worst_fraction = ctx.variant.fronts[0], -1.0
    for layout in ctx.variant.fronts:
        q = float(d.qpos[ctx.joint(layout.id)[1]])
        drift[layout.id] = q
        fraction = abs(q) / (layout.joint_range[1] - layout.joint_range[0])
        if fraction > DRIFT_FRACTION:
            return CheckResult("rest_stable", False, f"{layout.id} drifts open to {_fmt_q(layout, q)} in "
                               f"{REST_SECONDS:g} s without a pull", {"drift": drift})
        if fraction > worst_fraction:
            worst, worst_fraction = layout, fraction
    return CheckResult("rest_stable", True, f"{REST_SECONDS:g} s without a pull: finite, no warnings, largest drift "
                       f"{_fmt_q(worst, abs(drift[worst.id]))} ({worst.id})", {"drift": drift})


def force_to_open(ctx: ModelContext, layout: FrontLayout) -> tuple[float, float]:
    """The quasi-static force (N) along the handle's path that opens a front anywhere in its range (friction,
    plus gravity, springs and the joint's effects where they resist: passive actuators such as a self-closing
    spring, and the runtime effects' forces and extra friction when just opening), and the handle's lever arm at
    closed (m; 1 for slides)."""
    import mujoco
    import numpy as np

    m, d = ctx.model, ctx.data
    _, qadr, dof = ctx.joint(layout.id)
    effects = ctx.effects().get(dof)
    need, lever0 = 0.0, 1.0
    for k in range(SWEEP_SAMPLES + 1):
        q = layout.joint_range[1] * k / SWEEP_SAMPLES
        d.qpos[:] = 0.0
        d.qvel[:] = 0.0
        d.qpos[qadr] = q
        mujoco.mj_forward(m, d)
        lever = float(np.linalg.norm(_grasp_velocity(ctx, layout.id)))
        if k == 0:
            lever0 = lever
        resisting = float(d.qfrc_bias[dof] - d.qfrc_passive[dof] - d.qfrc_actuator[dof])
        friction = float(m.dof_frictionloss[dof])
        if effects:
            resisting -= effects.force(q, 1e-9)
            friction = effects.frictionloss(q, 1e-9)
        load = max(0.0, resisting) + friction
        need = max(need, load / max(lever, 1e-6))
    return need, lever0


def check_opens_under_pull(ctx: ModelContext) -> CheckResult:
    """Every front, pulled at its handle along the handle's path with its test pull, opens fully. The fronts are
    pulled at the same time (each by its own pull), so neighbours that rub on each other show up too."""
    import mujoco

    m, d = ctx.model, ctx.data
    forces: dict[str, dict[str, Any]] = {}
    pulls = []
    for layout in ctx.variant.fronts:
        need, lever = force_to_open(ctx, layout)
        pull = max(MIN_TEST_PULL, PULL_FACTOR * need)
        _, qadr, dof = ctx.joint(layout.id)
        pulls.append((layout, qadr, dof, pull * lever, OPEN_FRACTION * layout.joint_range[1]))
        forces[layout.id] = {"force_to_open_n": round(need, 3), "test_pull_n": round(pull, 3),
                             "lever_arm_m": round(lever, 4) if layout.motion != "slide" else None,
                             "seconds_to_open": None}
    mujoco.mj_resetData(m, d)
    # the pull acts along the handle's path: a generalised force of pull x lever arm, constant because a slide's
    # handle moves 1 m per m and a hinge's handle stays at the same distance from the axis
    for _, _, dof, generalised, _ in pulls:
        d.qfrc_applied[dof] = generalised
    waiting = list(pulls)
    effects = tuple(ctx.effects().values())
    for step in range(round(PULL_SECONDS / m.opt.timestep)):
        for e in effects:
            e.apply(d)
        mujoco.mj_step(m, d)
        for e in effects:
            e.undo(d)
        for item in [p for p in waiting if d.qpos[p[1]] >= p[4]]:
            forces[item[0].id]["seconds_to_open"] = round((step + 1) * m.opt.timestep, 4)
            waiting.remove(item)
        if not waiting:
            break
    if waiting or not _finite(ctx):
        layout, qadr = (waiting or pulls)[0][:2]
        reached, full = _fmt_q(layout, float(d.qpos[qadr])), _fmt_q(layout, layout.joint_range[1])
        pull = forces[layout.id]["test_pull_n"]
        return CheckResult("opens_under_pull", False, f"{layout.id} pulled with {pull:.1f} N at its handle reaches "
                           f"{reached} of {full} in {PULL_SECONDS:g} s", {"fronts": forces})
    ctx.metrics["pull"] = forces
    slowest = max(forces.items(), key=lambda kv: kv[1]["seconds_to_open"])
    return CheckResult("opens_under_pull", True, "every front opens fully under its test pull (" + ", ".join(
        f"{k}: {v['force_to_open_n']:.1f} N to open, pulled with {v['test_pull_n']:.1f} N" for k, v in forces.items())
        + f"; slowest {slowest[0]} in {slowest[1]['seconds_to_open']:.2f} s)", {"fronts": forces})


MODEL_CHECKS: tuple[Callable[[ModelContext], CheckResult], ...] = (
    check_inertia, check_opens_outward, check_closed_contact_free, check_handle_seated, check_sweep_clear,
    check_rest_stable, check_opens_under_pull)

def run_model_checks(ctx: ModelContext, stop_at_failure: bool = True) -> list[CheckResult]:
    results = []
    for check in MODEL_CHECKS:
        result = check(ctx)
        results.append(result)
        if not result.passed and stop_at_failure:
            break
    return results
