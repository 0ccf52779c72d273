"""Simulation speed: real-time factor of a drawer pull with CoACD collision, against one convex hull and none.

Prints, side by side in one run and per variant, for three collision set-ups of the same variant:

- ``coacd``: the scene as built (each handle collides through its CoACD convex parts, ``<front>/handle/hull-NN``);
- ``hull``: every handle's parts replaced by one convex hull of all their vertices (the baseline);
- ``no handle``: the handles' collision geoms switched off (contype and conaffinity 0; the floor of the cost);

the real-time factor (simulated seconds per wall second, one process) of a ``grasp_vertical`` episode (up to
``--seconds`` of simulated time, timed as a whole: operator and physics), the wall time per physics step of
``SimScene.step`` and of ``mujoco.mj_step`` alone, the collision geoms (contype or conaffinity set), the mean contacts
per physics step and the opening reached; best of ``--repeats`` interleaved runs. Targets: real-time factor at least
10 with CoACD; CoACD/hull ``mj_step`` time ratio at most 2.

A second table runs the same episodes (CoACD) with each robot of the catalog (``--robots``, default all): the real-time
factor per robot (target at least 20 on one core), the wall time of a control step, and the share of it that the
arm's inverse kinematics takes (``ArmIK.step``, timed by wrapping it).

Run: ``uv run python benchmarks/sim_speed.py [--variant ID:FRONT ...] [--repeats 3] [--seconds 10] [--robots
hand-e,panda-2f85,so100] [--robots-only]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

VARIANTS = ("drawer-chest-80__two_point-bow-128__normal:drawer-2",
            "drawer-kitchen-60__knob-mushroom-30__normal:drawer-1",
            "drawer-chest-80__finger_pull-cup-64__normal:drawer-1")
SETUPS = ("coacd", "hull", "no handle")


def modified_copy(src: Path, dst: Path, setup: str) -> tuple[Path, int]:
    """Copy the variant directory ``src`` to ``dst`` with its handles' collision changed; returns the directory
    and the vertices of the largest single hull written (0 for none)."""
    import mujoco
    import numpy as np
    import trimesh

    shutil.copytree(src, dst, symlinks=False)
    spec = mujoco.MjSpec.from_file(str(dst / "model.xml"))
    info = json.loads(spec.text("rik.variant").data)
    meshdir = dst / spec.meshdir
    largest = 0
    for front in info["fronts"]:
        body = spec.body(front["handle_body"])
        hulls = [g for g in body.geoms if "/hull-" in g.name]
        points = []
        for g in hulls:
            mesh = trimesh.load(meshdir / spec.mesh(g.meshname).file, force="mesh")
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, g.quat)
            points.append(mesh.vertices * spec.mesh(g.meshname).scale @ rot.reshape(3, 3).T + g.pos)
            if setup == "hull":
                spec.delete(g)
            else:  # kept in group 3, so the grasp planner still sees the handle, but colliding with nothing
                g.contype = g.conaffinity = 0
        if setup == "hull":
            hull = trimesh.PointCloud(np.concatenate(points)).convex_hull
            largest = max(largest, len(hull.vertices))
            name = front["handle_body"].replace("/", "-") + "-one-hull"
            hull.export(meshdir / f"{name}.stl")
            spec.add_mesh(name=name, file=f"{name}.stl")
            body.add_geom(default=spec.find_default("collision"), name=front["handle_body"] + "/one-hull",
                          type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)
    spec.compile()  # MuJoCo must accept the modified model
    (dst / "model.xml").write_text(spec.to_xml())
    return dst, largest


def episode(directory: Path, front: str, seconds: float) -> dict[str, float]:
    """One grasp_vertical episode on a freshly built scene, timed as a whole; ``mujoco.mj_step`` is wrapped for
    the episode to time the physics alone and count contacts after every physics step."""
    import mujoco
    import numpy as np

    from rik.episodes.operators import make_operator
    from rik.sim.build import build_scene

    scene = build_scene(directory, front)
    m = scene.model
    op = make_operator("grasp_vertical")
    op.reset(scene, np.random.default_rng(0))
    acc = {"mj": 0.0, "steps": 0, "ncon": 0, "scene": 0.0}
    mj_step, clock = mujoco.mj_step, time.perf_counter

    def timed(model, data):  # scene.step looks mujoco.mj_step up at every call
        s = clock()
        mj_step(model, data)
        acc["mj"] += clock() - s
        acc["steps"] += 1
        acc["ncon"] += data.ncon

    mujoco.mj_step = timed
    try:
        sim, wall, acc["scene"], _ = run_episode(scene, op, seconds)
    finally:
        mujoco.mj_step = mj_step
    n = max(acc["steps"], 1)
    colliders = sum(1 for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g])
    return {"rtf": sim / wall, "sim": sim, "scene_us": 1e6 * acc["scene"] / n,
            "mj_us": 1e6 * acc["mj"] / n, "geoms": colliders, "ncon": acc["ncon"] / n, "opening": scene.opening()}


def run_episode(scene, op, seconds: float) -> tuple[float, float, float, int]:  # type: ignore[no-untyped-def]
    """Run the operator ``op`` (reset) on ``scene`` for at most ``seconds`` of simulated time; (simulated s, wall s,
    wall s inside ``scene.step``, control steps)."""
    clock = time.perf_counter
    d = scene.data
    in_steps, steps = 0.0, 0
    t0, start = d.time, clock()
    while not op.done and d.time - t0 < seconds - 1e-9:
        action = op.act(scene)
        s = clock()
        scene.step(action)
        in_steps += clock() - s
        steps += 1
    return d.time - t0, clock() - start, in_steps, steps


def robot_episode(directory: Path, front: str, seconds: float, robot: object | None) -> dict[str, float]:
    """One grasp_vertical episode with ``robot`` (an arm's catalog entry, None for the Hand-E), timed as a whole,
    with the arm's IK steps timed apart."""
    import numpy as np

    from rik.episodes.operators import make_operator
    from rik.sim.build import build_scene
    from rik.sim.robots import drive, ik

    scene = build_scene(directory, front, robot=robot)  # type: ignore[arg-type]
    op = make_operator("grasp_vertical")
    op.reset(scene, np.random.default_rng(0))
    ik_time, commanding = [0.0], [False]
    command, step, clock = drive.ArmDrive.command, ik.ArmIK.step, time.perf_counter

    def timed_command(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        commanding[0] = True  # only the IK of control steps counts (a planner's probes solve it too)
        try:
            command(self, *args, **kwargs)
        finally:
            commanding[0] = False

    def timed_step(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        s = clock()
        out = step(self, *args, **kwargs)
        if commanding[0]:
            ik_time[0] += clock() - s
        return out

    drive.ArmDrive.command, ik.ArmIK.step = timed_command, timed_step  # type: ignore[method-assign]
    try:
        sim, wall, control, steps = run_episode(scene, op, seconds)
    finally:
        drive.ArmDrive.command, ik.ArmIK.step = command, step  # type: ignore[method-assign]
    n = max(steps, 1)
    return {"rtf": sim / wall, "sim": sim, "control_ms": 1e3 * control / n, "ik_ms": 1e3 * ik_time[0] / n,
            "ik_share": ik_time[0] / max(control, 1e-12), "opening": scene.opening(), "nq": scene.model.nq}


def robots_table(variants: list[str], robots: list[str], repeats: int, seconds: float) -> None:
    """Real-time factor and the IK's share of a control step per robot (see the module docstring)."""
    from rik.combinator.build import ensure_variant
    from rik.registry.load import load_catalog

    catalog = load_catalog()
    header = (f"{'variant':<44} {'robot':<11} {'nq':>3} {'sim s':>5} {'opened':>6} {'control ms':>10} {'IK ms':>6} "
              f"{'IK share':>8} {'RTF':>5}")
    print(header)
    print("-" * len(header))
    worst: dict[str, float] = {}
    for item in variants:
        variant, front = item.split(":")
        src = ensure_variant(catalog, variant, Path("variants"))
        best: dict[str, dict[str, float]] = {}
        for _ in range(repeats):
            for rid in robots:
                r = robot_episode(src, front, seconds, catalog.robot(rid).as_arm)
                if rid not in best or r["rtf"] > best[rid]["rtf"]:
                    best[rid] = r
        for rid in robots:
            r = best[rid]
            worst[rid] = min(worst.get(rid, float("inf")), r["rtf"])
            print(f"{variant:<44} {rid:<11} {r['nq']:>3.0f} {r['sim']:>5.2f} {r['opening']:>6.0%} "
                  f"{r['control_ms']:>10.2f} {r['ik_ms']:>6.2f} {r['ik_share']:>8.0%} {r['rtf']:>5.1f}")
    print()
    for rid, rtf in worst.items():
        verdict = "met" if rtf >= 20 else "MISSED"
        print(f"{rid}: lowest real-time factor {rtf:.1f} ({verdict}, target >= 20 on one core)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", action="append", help="VARIANT:FRONT (repeatable; default: three drawers)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per set-up; the best is kept")
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per episode at most")
    parser.add_argument("--robots", default="hand-e,panda-2f85,so100", help="robots of the second table (comma-"
                        "separated catalog ids; empty: none)")
    parser.add_argument("--robots-only", action="store_true", help="only the robots' table")
    args = parser.parse_args()
    robots = [r.strip() for r in args.robots.split(",") if r.strip()]
    if args.robots_only:
        robots_table(args.variant or list(VARIANTS), robots, args.repeats, args.seconds)
        return

    from rik.combinator.build import ensure_variant
    from rik.registry.load import load_catalog

    catalog = load_catalog()
    header = (f"{'variant':<44} {'set-up':<9} {'colliders':>9} {'hull verts':>10} {'contacts':>8} {'sim s':>5} "
              f"{'opened':>6} {'step us':>7} {'mj_step us':>10} {'RTF':>5}")
    print(header)
    print("-" * len(header))
    summary = []
    with tempfile.TemporaryDirectory() as tmp:
        for item in args.variant or VARIANTS:
            variant, front = item.split(":")
            src = ensure_variant(catalog, variant, Path("variants"))
            dirs = {"coacd": (src, 0)}
            for setup in SETUPS[1:]:
                dirs[setup] = modified_copy(src, Path(tmp) / setup.replace(" ", "_") / variant, setup)
            best = {}
            for _ in range(args.repeats):  # interleaved, so drift of the machine hits every set-up alike
                for setup in SETUPS:
                    r = episode(dirs[setup][0], front, args.seconds)
                    if setup not in best or r["rtf"] > best[setup]["rtf"]:
                        best[setup] = r
            for setup in SETUPS:
                r = best[setup]
                verts = str(dirs[setup][1]) if setup == "hull" else "-"
                print(f"{variant:<44} {setup:<9} {r['geoms']:>9} {verts:>10} {r['ncon']:>8.1f} {r['sim']:>5.2f} "
                      f"{r['opening']:>6.0%} {r['scene_us']:>7.1f} {r['mj_us']:>10.1f} {r['rtf']:>5.1f}")
            summary.append((variant, best["coacd"]["rtf"], best["coacd"]["mj_us"] / best["hull"]["mj_us"],
                            best["coacd"]["scene_us"] / best["hull"]["scene_us"]))
    print()
    for variant, rtf, ratio, scene_ratio in summary:
        print(f"{variant}: CoACD real-time factor {rtf:.1f} ({'met' if rtf >= 10 else 'MISSED'}, target >= 10); "
              f"CoACD/hull mj_step time {ratio:.2f} ({'met' if ratio <= 2 else 'MISSED'}, target <= 2), "
              f"scene.step time {scene_ratio:.2f}")
    if robots:
        print()
        robots_table(args.variant or list(VARIANTS), robots, args.repeats, args.seconds)


if __name__ == "__main__":
    main()
