"""The resistance benchmark (the paper's section 4 and Table 3): randomised opening episodes per handle type x
resistance preset x strategy, counted as F/P/S, on the fronts of the kinds asked for (drawers, doors, flaps; a
hinge's outcome on the same fractions of its range as a slide's), with the paper's presets or, on doors, the real
doors' (``joints="measured"``), and why each episode that did not succeed missed (:func:`miss_reason`);
and a sweep of the gripper's grip force that shows how success depends on the ratio of the grasp's friction
capacity to the joint's resistance."""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.episodes.draw import DEFAULT_KINDS, DEFAULT_PRESETS, DEFAULT_TYPES, choose_variant
from rik.errors import RikError
from rik.outputs import Replaces, check_own_files, save_figure
from rik.paths import pyplot
from rik.registry.ids import parse_variant_id
from rik.schemas.joints import CATALOG_LEVER_ARM
from rik.sim.outcome import SUCCESS_OPENING
from rik.tables import MEASURED_COLUMN

if TYPE_CHECKING:
    from rik.outputs import Replaces
    from rik.registry.catalog import Catalog
    from rik.schemas.joints import JointResistance

DEFAULT_STRATEGIES = ("grasp_horizontal", "grasp_vertical", "contact_rich")
SWEEP_GRIP_FORCES = (5.0, 10.0, 20.0, 40.0, 80.0, 130.0)
"""Grip forces of ``--sweep grip-force``, N (130 N: the Hand-E's maximum)."""
MAX_SECONDS = 30.0


@dataclass(frozen=True)
class BenchTask:
    """One episode of the benchmark; the seed decides handle, base unit, front and jitter."""

    handle_type: str
    preset: str
    strategy: str
    index: int
    seed: int
    variant: str = ""
    front: str = ""
    grip_force: float | None = None
    robot: str = "hand-e"

    def encode(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)


MAX_BENCH_SEED = (2**63 - 1) // 1_000_003 - 1
"""Largest ``rik bench --seed``: episode seeds are ``seed * 1_000_003 + ...`` and must stay below 2^63."""
MAX_BENCH_EPISODES = 1_000_000
"""Most episodes one benchmark runs (every handle type x preset x strategy x grip force x ``--episodes-per-cell``):
more is a typo, refused before any episode is planned."""


def plan_tasks(catalog: Catalog, *, types: Sequence[str] = DEFAULT_TYPES, presets: Sequence[str] = DEFAULT_PRESETS,
               strategies: Sequence[str] = DEFAULT_STRATEGIES, per_cell: int = 10, seed: int = 0,
               kinds: Sequence[str] = DEFAULT_KINDS, grip_forces: Sequence[float | None] = (None,),
               robot: str = "hand-e", joints: str = "paper") -> list[BenchTask]:
    """Every episode of the benchmark. The same episode index of every strategy (and grip force, and robot) gets
    the same variant, front and start pose, so strategies and robots are compared on the same draws; with
    ``joints="measured"`` a door takes one of the real doors' presets (every one of the catalog, drawn
    from the episode's seed) and a drawer its cell's, on the same draws as with ``paper`` joints."""
    from rik.episodes.draw import Draw
    from rik.episodes.operators import make_operator
    from rik.registry.ids import select_variants

    if not 0 <= seed <= MAX_BENCH_SEED:
        raise RikError(f"--seed {seed}: the benchmark's seed must lie in 0 .. {MAX_BENCH_SEED} (each episode's seed is "
                       "derived from it and must fit in 64 bits)")
    cells = {"--types": len(types), "--presets": len(presets), "--strategies": len(strategies),
             "grip forces": len(grip_forces)}
    for option, count in cells.items():
        if count == 0:
            raise RikError(f"{option}: empty; give at least one")
    total = per_cell * math.prod(cells.values())
    if per_cell < 1 or total > MAX_BENCH_EPISODES:
        raise RikError(f"--episodes-per-cell {per_cell}: {total:,} episodes in all; give 1 or more, and at most "
                       f"{MAX_BENCH_EPISODES:,} episodes in all")
    for s in strategies:
        make_operator(s)
    draw = Draw(None, tuple(types), tuple(presets), tuple(kinds), joints)
    draw.check(catalog)  # unknown names: one line
    door_presets = draw.door_presets(catalog)
    if catalog.robot(robot).as_arm is not None and any(g is not None for g in grip_forces):
        raise RikError(f"--sweep grip-force varies the Hand-E's grip; robot {robot}'s gripper is its model's")
    compatible = {k.id for k in select_variants(catalog, handle_types=types, presets=presets)}
    tasks = []
    for ti, t in enumerate(types):
        for pi, p in enumerate(presets):
            for i in range(per_cell):
                task_seed = seed * 1_000_003 + ti * 10_007 + pi * 101 + i
                vid, front = choose_variant(catalog, t, p, np.random.default_rng(task_seed), kinds, compatible,
                                            door_presets=door_presets)
                for strategy in strategies:
                    for g in grip_forces:
                        tasks.append(BenchTask(t, p, strategy, i, task_seed, vid, front, g, robot))
    return tasks


def run_task(catalog: Catalog, encoded: str, variants: Path = Path("variants")) -> dict[str, object]:
    """Run one benchmark episode (not written to disk); returns its row for the results table."""
    from rik.episodes.episode import run_operator
    from rik.episodes.operators import make_operator
    from rik.episodes.record import randomise_start
    from rik.sim.build import build_scene
    from rik.sim.outcome import classify
    from rik.sim.robots.gripper import HAND_E

    task = BenchTask(**json.loads(encoded))
    gripper = HAND_E if task.grip_force is None else HAND_E.with_(grip_force=task.grip_force)
    arm = catalog.robot(task.robot).as_arm
    scene = build_scene(variants / task.variant, task.front, gripper, robot=arm)
    gripper = scene.gripper
    reach = 1.0
    if arm is not None:
        from rik.sim.robots.checks import reach_profile
        from rik.sim.robots.reach import reachable_opening

        reach = reachable_opening(reach_profile(scene))
    rng = np.random.default_rng(task.seed)
    randomise_start(scene, rng)
    operator = make_operator(task.strategy)
    recorder = run_operator(scene, operator, rng, MAX_SECONDS)
    key = parse_variant_id(catalog, task.variant)
    front = next(f for f in catalog.base_units[key.base].fronts if f.id == task.front)
    preset = key.preset
    resistance = handle_resistance(catalog.presets[preset].for_joint(front.joint.type), front.joint.type.value)
    row = {**asdict(task), "preset": preset, "cell_preset": task.preset, "front_layout": front.layout,
           "joints": "paper" if catalog.presets[preset].in_default_set else "measured",
           "grip_force": gripper.grip_force, "pad_friction": gripper.pad_friction,
           "friction_capacity": gripper.friction_capacity(),
           "resistance": round(resistance, 4), "capacity_ratio": gripper.friction_capacity() / max(resistance, 1e-9),
           "outcome": classify(scene.opening()), "final_opening": round(scene.opening(), 4),
           "max_opening": round(recorder.max_opening, 4), "seconds": round(recorder.steps / scene.control_fps, 2),
           "reachable_opening": reach, "held_at_end": scene.handle_contact().handle_bodies >= 2,  # both jaws on it
           "log": " | ".join(operator.log)}
    return {**row, "miss": miss_reason(row)}


def handle_resistance(joint: JointResistance, joint_type: str) -> float:
    """What the front resists a pull at its handle with, N: the force to start it from rest at closed
    (:meth:`~rik.schemas.joints.JointResistance.hold_at_closed`: friction, catch, spring, minus a tilt) plus its
    damping at the strategies' pull speed; a hinge's torques at the catalog's lever arm (0.40 m)."""
    from rik.episodes.operators import PULL_SPEED

    if joint_type == "slide":
        return joint.hold_at_closed() + joint.damping * PULL_SPEED
    lever = CATALOG_LEVER_ARM
    return (joint.hold_at_closed() + joint.damping * PULL_SPEED / lever) / lever


MISS_REASONS = ("no grasp found", "slipped", "stalled", "out of reach", "time out, held", "time out, lost",
                "stopped early")
"""Why an episode that did not succeed missed (:func:`miss_reason`), in the order tables list them."""


def miss_reason(row: dict[str, Any]) -> str:
    """Why the episode of a benchmark row did not succeed (``""`` where it did), from its outcome, the strategy's
    log and the arm's reach: ``no grasp found`` (no plan left to try), ``slipped`` or ``stalled`` (the last attempt's
    closed-loop check: the handle left the pads, or the front stopped moving), ``out of reach`` (the arm cannot
    reach a success's opening), ``time out, held`` or ``time out, lost`` (still pulling at the episode's end, the
    handle between both pads or not: an open-loop pinch pulls on whether it holds or not), or ``stopped early``
    (the strategy ended its pull below a success for another reason)."""
    if row["outcome"] == "S":
        return ""
    events = [e.strip() for e in str(row.get("log", "")).split("|") if e.strip()]
    last = events[-1] if events else ""
    if float(row.get("reachable_opening", 1.0)) < SUCCESS_OPENING:
        return "out of reach"
    if last == "no grasp found":
        return "no grasp found"
    if last.startswith("slip"):
        return "slipped"
    if last.startswith("stall"):
        return "stalled"
    if float(row.get("seconds", 0.0)) >= MAX_SECONDS - 0.05:
        return "time out, held" if str(row.get("held_at_end", "False")) == "True" else "time out, lost"
    return "stopped early"


def run_bench(catalog: Catalog, tasks: Sequence[BenchTask], *, workers: int = 1, variants: Path = Path("variants"),
              overlays: Sequence[Path] = (), progress: Callable[[dict[str, Any]], None] | None = None
              ) -> list[dict[str, Any]]:
    """Build the variants the tasks need, then run the episodes (in ``workers`` processes); rows in task order."""
    import functools

    from rik.combinator.build import require_variants
    from rik.workers import map_ids

    require_variants(catalog, (t.variant for t in tasks), variants, workers=workers, overlays=overlays)
    order = {t.encode(): i for i, t in enumerate(tasks)}
    rows: list[dict[str, Any] | None] = [None] * len(tasks)
    fn = functools.partial(run_task, variants=variants)
    for encoded, row in map_ids(fn, catalog, list(order), workers=workers, overlays=overlays):
        rows[order[encoded]] = row
        if progress is not None:
            progress(row)
    return [r for r in rows if r is not None]


LAYOUTS = ("drawer", "door-left", "door-right", "flap-lift-up", "flap-drop-down")
"""Front layouts (:attr:`rik.schemas.base_units.Front.layout`) in the order the tables list them."""


def _layouts(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The front layouts of ``rows`` in table order: :data:`LAYOUTS`, then any other, sorted."""
    present = {r["front_layout"] for r in rows}
    return [lay for lay in LAYOUTS if lay in present] + sorted(present - set(LAYOUTS))


def layout_summary(rows: Sequence[dict[str, Any]]) -> str:
    """S per strategy and front layout (every handle type and preset pooled): successes of episodes, the rate and
    its 95 % Wilson interval; with measured joints, the paper presets' and the real doors' apart."""
    from rik.tables import rate_text

    groups = [(lay, j) for lay in _layouts(rows) for j in ("paper", "measured")
              if any(r["front_layout"] == lay and r.get("joints", "paper") == j for r in rows)]
    head = [lay if j == "paper" else f"{lay} (real doors)" for lay, j in groups]
    lines = ["| strategy | " + " | ".join(head) + " |", "|---|" + "---:|" * len(groups)]
    for s in dict.fromkeys(r["strategy"] for r in rows):
        cells = []
        for lay, j in groups:
            sel = [r["outcome"] == "S" for r in rows
                   if r["strategy"] == s and r["front_layout"] == lay and r.get("joints", "paper") == j]
            cells.append(rate_text(sum(sel), len(sel), "/") if sel else "-")
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def layout_tables(rows: Sequence[dict[str, Any]], presets: Sequence[str] = DEFAULT_PRESETS) -> str:
    """The summary (:func:`layout_summary`), then Table 3 per front layout (drawers, left and right doors, lift-up
    and drop-down flaps; those present), the paper presets' columns then the measured doors'
    (:func:`rik.tables.joint_columns`), each followed by the misses' reasons."""
    from rik.tables import joint_columns, table_markdown

    columns = joint_columns(rows, presets)
    out = ["### S per front layout (every handle type and preset)", "", layout_summary(rows), ""]
    for layout in _layouts(rows):
        mine = [r for r in columns if r["front_layout"] == layout]
        out += [f"### {layout} ({len(mine)} episodes)", "", table_markdown(mine, presets),
                miss_markdown(mine, [*presets, MEASURED_COLUMN]), ""]
    return "\n".join(out)


def miss_markdown(rows: Sequence[dict[str, Any]], presets: Sequence[str]) -> str:
    """How many episodes of each strategy and column missed, and why (:data:`MISS_REASONS`); one line per
    strategy that missed."""
    lines = ["| misses: strategy | column | " + " | ".join(MISS_REASONS) + " |",
             "|---|---|" + "---:|" * len(MISS_REASONS)]
    for s in dict.fromkeys(r["strategy"] for r in rows):
        for p in presets:
            missed = [r["miss"] for r in rows if r["strategy"] == s and r["preset"] == p and r["miss"]]
            if missed:
                lines.append(f"| {s} | {p} | " + " | ".join(str(missed.count(m) or "") for m in MISS_REASONS)
                             + " |")
    return "\n".join(lines) + "\n" if len(lines) > 2 else "No misses.\n"


def sweep_plot(rows: Sequence[dict[str, Any]], png: Path) -> Path:
    """Success rate against the friction-capacity ratio (2 x pad friction x grip force / joint resistance), one
    line per strategy."""

    fig, ax = pyplot().subplots(figsize=(6.4, 4.0), dpi=120)
    for s in dict.fromkeys(r["strategy"] for r in rows):
        pts: dict[float, list[int]] = {}
        for r in rows:
            if r["strategy"] == s:
                pts.setdefault(round(r["capacity_ratio"], 3), []).append(r["outcome"] == "S")
        xs = sorted(pts)
        ax.plot(xs, [float(np.mean(pts[x])) for x in xs], marker="o", label=s)
    ax.axvline(1.0, color="grey", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_xlabel("friction capacity / joint resistance  (2 μ F_grip / (F_friction + c v))")
    ax.set_ylabel("success rate (S)")
    ax.set_ylim(-0.03, 1.03)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, png, bench_file())


def sweep_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Success rate per strategy against grip force and friction-capacity ratio (all presets pooled)."""
    strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    keys = sorted({(r["grip_force"], r["preset"], round(r["capacity_ratio"], 2)) for r in rows})
    lines = ["| grip force (N) | preset | capacity / resistance | " + " | ".join(strategies) + " |",
             "|---:|---|---:|" + "---:|" * len(strategies)]
    for g, p, ratio in keys:
        cells = []
        for s in strategies:
            sel = [r["outcome"] == "S" for r in rows if (r["grip_force"], r["preset"], r["strategy"]) == (g, p, s)]
            cells.append(f"{np.mean(sel):.2f}" if sel else "-")
        lines.append(f"| {g:g} | {p} | {ratio:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


BENCH_FILES = ("results.csv", "table.md", "sweep.png", "sweep.md")
"""What ``rik bench`` writes into ``--out``."""
BENCH_COLUMNS = {"variant", "strategy", "preset", "outcome"}
"""Columns every ``results.csv`` of ``rik bench`` has."""


def is_bench_out(folder: Path) -> bool:
    """Whether ``folder`` holds an earlier ``rik bench``'s results (its ``results.csv`` with the bench's columns)."""
    try:
        with (Path(folder) / "results.csv").open(encoding="utf-8") as handle:
            return BENCH_COLUMNS <= set(handle.readline().strip().split(","))
    except (OSError, UnicodeDecodeError):
        return False


def bench_file() -> Replaces:
    """What a file ``rik bench`` writes into ``--out`` may replace: the same file of an earlier rik bench there."""

    return Replaces.when("a file of an earlier rik bench (its results.csv beside it)", lambda p: is_bench_out(p.parent))


def check_bench_out(out: Path) -> None:
    """Refuse an ``--out`` where a file ``rik bench`` writes is there and the folder is not one rik bench wrote."""

    check_own_files(out, BENCH_FILES, is_bench_out, "rik bench", "results.csv")
