"""Export speed: ``rik export-lerobot`` against a bare lerobot write loop on the same pre-rendered frames, and the
peak memory of each for a 1,000-frame episode.

Set-up, not timed: records one episode of ``--frames`` frames (default 1,000, 50 s at 20 Hz) on a chest of drawers
with a bow handle: the ``contact_rich`` operator pulls the drawer open again and again (a single pull ends after
about 100 frames, so whenever the operator finishes, the drawer is put back closed and the gripper back at a random
start pose, within the same recording, and a fresh operator starts), plus an 11-frame episode for the warm-up; then
renders both streams of both cameras (``front``, ``wrist``) at ``--res`` pixels: MuJoCo, and Mitsuba (``llvm_ad_rgb``
when available) at 4 spp without denoising, the two streams in two processes side by side. ``--work DIR`` keeps
the episode and its renders for the next run.

Timed, in one process after a warm-up export of the short episode with each codec (imports, codec start-up, the
timers installed), interleaved and best of ``--repeats``, for each codec of ``--codecs`` (h264, libsvtav1):

- A, ``export_lerobot``: the CLI's library call end to end with the renders present (finds them finished, restores
  every recorded state to compute ``observation.state``, reads the PNGs, writes the shard through lerobot, checks
  its frame counts by decoding, merges with ``aggregate_datasets``, loads and checks the merge, writes the card);
- B, the bare loop: ``LeRobotDataset.create`` with the same features, codec and ``image_writer_threads=4``, per
  frame the four PNGs read with PIL and ``add_frame`` with the precomputed state vectors and action, ``save_episode``,
  ``finalize``;

frames per second (frames / wall seconds), the time of each stage (exclusive, from wrappers around the functions
named) and the overhead A/B in seconds. Peak memory, measured first: each side once, alone in a child process, with
the first codec; the peak RSS of its largest process (``ru_maxrss`` from ``wait4``) and the peaks of the RSS and of
the PSS summed over its process tree (sampled every 0.1 s: lerobot's default ``save_episode`` forks an encoder
process per camera, whose summed RSS counts the shared pages again). ``--bare-serial`` makes the bare loop encode in
its own process, as rik does. Targets: overhead at most 1.25x; peak memory at most 2 GB for a 1,000-frame episode.

Run: ``uv run python benchmarks/export_speed.py [--frames 1000] [--res 128] [--codecs libsvtav1,h264]
[--repeats 2] [--work DIR] [--bare-serial]`` (about 11 minutes on 2 cores, 7 of them rendering; 5 with ``--work``
holding an earlier run's renders).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any

VARIANT = "drawer-chest-80__two_point-bow-128__normal"
STRATEGY = "contact_rich"
REPO = "local/export-speed"
VARIANTS = Path("variants")
SPP = 4
WARMUP_FRAMES = 11
GB = 1e9

for _name, _value in (("MUJOCO_GL", "egl"), ("HF_HUB_OFFLINE", "1"), ("SVT_LOG", "1")):
    os.environ.setdefault(_name, _value)


# ---- set-up -------------------------------------------------------------------------------------------------------
class Repeated:
    """A scripted operator started again whenever it finishes: the drawer closed and the gripper put back at a
    random start pose (the scene's state at the start, time kept running), all within one recording."""

    def __init__(self, strategy: str) -> None:
        self.strategy, self.done, self.log, self.pulls = strategy, False, [], 0

    def reset(self, scene: Any, rng: Any) -> None:
        self.rng, self.start = rng, scene.state()
        self._begin(scene)

    def _begin(self, scene: Any) -> None:
        from rik.episodes.operators import make_operator

        self.inner = make_operator(self.strategy)
        self.inner.reset(scene, self.rng)
        self.pulls += 1

    def act(self, scene: Any) -> Any:
        from rik.episodes.record import randomise_start

        if self.inner.done:
            self.log += [f"pull {self.pulls}: {line}" for line in self.inner.log]
            state = self.start.copy()
            state[0] = scene.data.time  # mjSTATE_INTEGRATION starts with the time
            scene.restore(state)
            randomise_start(scene, self.rng)
            self._begin(scene)
        return self.inner.act(scene)


def record_episode(catalog: Any, out: Path, frames: int, seed: int, repeat: bool) -> Path:
    """A recorded episode of exactly ``frames`` frames (rows) under ``out``, reused when already there."""
    import numpy as np

    from rik.combinator.build import ensure_variant
    from rik.episodes.episode import EpisodeRecorder, episode_id, read_meta, run_operator, write_episode
    from rik.episodes.operators import make_operator
    from rik.episodes.record import randomise_start
    from rik.sim.build import build_scene

    scene = build_scene(ensure_variant(catalog, VARIANT, VARIANTS))
    directory = out / episode_id(scene.info["id"], scene.front.id, STRATEGY, seed)
    if (directory / "meta.json").is_file() and read_meta(directory).steps + 1 == frames:
        return directory
    rng = np.random.default_rng(seed)
    randomise_start(scene, rng)
    operator = Repeated(STRATEGY) if repeat else make_operator(STRATEGY)
    recorder = run_operator(scene, operator, rng, (frames - 1) / scene.control_fps, EpisodeRecorder(scene))
    meta = write_episode(recorder, out, episode=directory.name, operator=STRATEGY, operator_kind="strategy",
                         seed=seed, log=tuple(operator.log))
    if meta.steps + 1 != frames:
        raise SystemExit(f"{directory}: recorded {meta.steps + 1} frames, wanted {frames}")
    return directory


def stream_specs(res: int, variant: str) -> dict[str, Any]:
    from rik.render.streams import StreamSpec

    return {"sim": StreamSpec("sim", res, res),
            "rerendered": StreamSpec("rerendered", res, res, spp=SPP, denoise=False, variant=variant)}


def render_stream(kind: str, res: int, variant: str, episodes: list[str], renders: str) -> tuple[str, float]:
    """Render one stream of the episodes (run in its own process); returns (kind, seconds)."""
    from rik.registry.load import load_catalog
    from rik.render.episodes import render_episode

    catalog, start = load_catalog(), time.perf_counter()
    for d in episodes:
        render_episode(catalog, Path(d), stream_specs(res, variant)[kind], renders=Path(renders), variants=VARIANTS)
    return kind, time.perf_counter() - start


class Work:
    """The recorded episodes and their finished renders."""

    def __init__(self, root: Path, frames: int, res: int, variant: str) -> None:
        self.root, self.frames, self.res, self.variant = root, frames, res, variant
        self.renders = root / "renders"
        self.episode = root / f"episodes-{frames}"
        self.warmup = root / "episodes-warmup"

    def prepare(self, catalog: Any) -> None:
        start = time.perf_counter()
        main = record_episode(catalog, self.episode, self.frames, seed=0, repeat=True)
        warm = record_episode(catalog, self.warmup, WARMUP_FRAMES, seed=1, repeat=False)
        recorded = time.perf_counter() - start
        with ProcessPoolExecutor(2, mp_context=get_context("spawn")) as pool:
            jobs = [pool.submit(render_stream, kind, self.res, self.variant, [str(main), str(warm)],
                                str(self.renders)) for kind in ("sim", "rerendered")]
            spent = dict(job.result() for job in jobs)
        print(f"set-up (not timed): recorded in {recorded:.0f} s; rendered (two processes side by side, "
              f"reused when finished) sim {spent['sim']:.0f} s, re-render {spent['rerendered']:.0f} s")

    def episode_dir(self, warmup: bool = False) -> Path:
        return next(p for p in (self.warmup if warmup else self.episode).iterdir() if (p / "meta.json").is_file())

    def spec(self, codec: str) -> Any:
        from rik.exporters.spec import ExportSpec

        return ExportSpec(REPO, width=self.res, height=self.res, codec=codec, spp=SPP, denoise=False,
                          variant=self.variant)


# ---- timers -------------------------------------------------------------------------------------------------------
class Stages:
    """Exclusive wall time per named stage, from wrappers around the functions that do the work (a stage called
    inside another is taken out of the outer one)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self._inner: list[float] = []
        self._names: list[str] = []

    def reset(self) -> None:
        self.seconds.clear()

    def wrap(self, name: Any, fn: Any) -> Any:
        def timed(*args: Any, **kwargs: Any) -> Any:
            label = name(self._names) if callable(name) else name
            self._inner.append(0.0)
            self._names.append(label)
            start = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                spent = time.perf_counter() - start
                self._names.pop()
                self.seconds[label] += spent - self._inner.pop()
                if self._inner:
                    self._inner[-1] += spent

        return timed


STAGES = Stages()
READ = "read frames (A: +state)"
ROWS = ("render check (finished)", "scene build", "create", READ, "add_frame", "save_episode (encode)",
        "finalize", "frame check (shard)", "aggregate", "load merged", "frame check (merged)", "card", "other")


def install_timers() -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    import rik.episodes.replay as replay
    import rik.exporters.lerobot_card as card
    import rik.exporters.lerobot_check as check
    import rik.exporters.lerobot_export as export
    import rik.render.episodes as episodes

    wrap = STAGES.wrap
    LeRobotDataset.create = staticmethod(wrap("create", LeRobotDataset.create))
    for method, label in (("add_frame", "add_frame"), ("save_episode", "save_episode (encode)"),
                          ("finalize", "finalize")):
        setattr(LeRobotDataset, method, wrap(label, getattr(LeRobotDataset, method)))
    episodes.render_episode = wrap("render check (finished)", episodes.render_episode)
    replay.episode_scene = wrap("scene build", replay.episode_scene)
    export.write_shard = wrap(READ, export.write_shard)  # what is left of it: the frame loop (PNGs, states)
    export.aggregate_shards = wrap("aggregate", export.aggregate_shards)
    check.check_frame_counts = wrap(lambda names: "frame check (merged)" if "load merged" in names
                                    else "frame check (shard)", check.check_frame_counts)
    check.check_dataset = wrap("load merged", check.check_dataset)
    card.write_card = wrap("card", card.write_card)


# ---- the two sides ------------------------------------------------------------------------------------------------
def run_export(catalog: Any, work: Work, codec: str, out: Path, warmup: bool = False) -> int:
    from rik.exporters.lerobot_export import export_lerobot

    shutil.rmtree(out, ignore_errors=True)
    result = export_lerobot(catalog, [work.episode_dir(warmup)], out, work.spec(codec), renders=work.renders,
                            variants=VARIANTS)
    return result.frames


def bare_inputs(catalog: Any, work: Work, warmup: bool = False) -> dict[str, Any]:
    """What the bare loop is given, computed beforehand: the features, the task, the state vectors and action of
    every frame (rik's own per-frame dicts without images) and the PNG paths of every frame and image key."""
    from rik.episodes.episode import read_meta
    from rik.exporters.lerobot_frames import episode_frames, load_episode
    from rik.lerobot.features import image_key
    from rik.lerobot.policy_io import PolicyIO
    from rik.render.streams import frame_name, read_manifest, stream_dir

    directory = work.episode_dir(warmup)
    meta = read_meta(directory)
    folders = {kind: stream_dir(work.renders, meta.id, spec) for kind, spec in stream_specs(work.res,
                                                                                            work.variant).items()}
    cameras = list(read_manifest(folders["sim"])["cameras"])
    task, frames, _ = episode_frames(catalog, load_episode(catalog, directory, meta), {}, cameras, meta.fps,
                                     VARIANTS)
    rows = list(frames)  # every vector feature of the frame (state, environment state, action; an arm's ee pose)
    paths = [[(image_key(cam, kind), folders[kind] / cam / frame_name(k)) for kind in folders for cam in cameras]
             for k in range(len(rows))]
    io = PolicyIO(cameras=tuple(cameras), streams=tuple(folders), image_size=(work.res, work.res))
    return {"features": io.features(), "fps": meta.fps, "task": task,
            "rows": rows, "paths": paths}


def bare_loop(inputs: dict[str, Any], codec: str, out: Path, parallel_encoding: bool = True) -> int:
    """lerobot's documented write loop and nothing else (``parallel_encoding``: lerobot's default, one encoder
    process per camera; rik encodes in its own process)."""
    import numpy as np
    from lerobot.configs import RGBEncoderConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from PIL import Image

    from rik.exporters.lerobot_frames import ROBOT_TYPE

    def loop() -> int:
        ds = LeRobotDataset.create(repo_id=REPO, fps=inputs["fps"], features=inputs["features"], root=out,
                                   robot_type=ROBOT_TYPE, use_videos=True, video_backend="pyav",
                                   rgb_encoder=RGBEncoderConfig(vcodec=codec), image_writer_threads=4)
        for row, files in zip(inputs["rows"], inputs["paths"], strict=True):
            frame = {**row, "task": inputs["task"]}
            for key, path in files:
                with Image.open(path) as img:
                    frame[key] = np.asarray(img.convert("RGB"))
            ds.add_frame(frame)
        ds.save_episode(parallel_encoding=parallel_encoding)
        ds.finalize()
        return len(inputs["rows"])

    shutil.rmtree(out, ignore_errors=True)
    return STAGES.wrap(READ, loop)()


# ---- memory -------------------------------------------------------------------------------------------------------
def _tree(pid: int) -> list[int]:
    children: dict[int, list[int]] = defaultdict(list)
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            children[ppid].append(int(entry))
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        todo += children.get(p, [])
    return found


def _memory(pid: int) -> tuple[int, int]:
    """(RSS, PSS) of a process, bytes (0 once it is gone)."""
    found = {}
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            for line in f:
                if line.startswith(("Rss:", "Pss:")):
                    found[line[:3]] = int(line.split()[1]) * 1024
    except OSError:
        pass
    return found.get("Rss", 0), found.get("Pss", 0)


def measure_child(side: str, args: argparse.Namespace, work: Work, codec: str) -> dict[str, Any]:
    """Run one side once in a child process; its peak memory: largest process's RSS and the tree's summed PSS."""
    report = work.root / f"child-{side}.json"
    log = work.root / f"child-{side}.log"
    cmd = [sys.executable, __file__, "--child", side, "--work", str(work.root), "--frames", str(args.frames),
           "--res", str(args.res), "--codecs", codec, "--variant", work.variant] + (["--bare-serial"] if
                                                                                     args.bare_serial else [])
    with open(log, "w") as err:
        proc = subprocess.Popen(cmd, stdout=err, stderr=subprocess.STDOUT)
    peak = {"rss": 0, "pss": 0, "processes": 0}
    stop = threading.Event()

    def sample() -> None:
        while not stop.wait(0.1):
            pids = _tree(proc.pid)
            rss, pss = (sum(m) for m in zip(*(_memory(p) for p in pids), strict=True))
            peak["rss"], peak["pss"] = max(peak["rss"], rss), max(peak["pss"], pss)
            peak["processes"] = max(peak["processes"], len(pids))

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    _, status, usage = os.wait4(proc.pid, 0)
    stop.set()
    sampler.join()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit(f"the {side} child failed ({proc.returncode}); see {log}:\n" + log.read_text()[-3000:])
    out = json.loads(report.read_text())
    out.update(maxrss=usage.ru_maxrss * 1024, tree_rss=peak["rss"], tree_pss=peak["pss"], processes=peak["processes"])
    return out


def child(args: argparse.Namespace) -> None:
    from rik.registry.load import load_catalog

    work = Work(Path(args.work), args.frames, args.res, args.variant)
    catalog = load_catalog()
    import lerobot.datasets.lerobot_dataset  # noqa: F401  (imports counted in the baseline, not the peak's growth)

    inputs = bare_inputs(catalog, work) if args.child == "bare" else None
    with open("/proc/self/status") as f:
        baseline = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmRSS:"))
    out = work.root / f"out-child-{args.child}"
    start = time.perf_counter()
    frames = (bare_loop(inputs, args.codecs, out, not args.bare_serial) if inputs is not None else
              run_export(catalog, work, args.codecs, out))
    seconds = time.perf_counter() - start
    shutil.rmtree(out, ignore_errors=True)
    (work.root / f"child-{args.child}.json").write_text(json.dumps({"frames": frames, "seconds": seconds,
                                                                   "baseline_rss": baseline}))


# ---- main ---------------------------------------------------------------------------------------------------------
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1000, help="frames of the timed episode")
    parser.add_argument("--res", type=int, default=128, help="image size, pixels a side")
    parser.add_argument("--codecs", default="libsvtav1,h264", help="codecs timed; the first also for memory")
    parser.add_argument("--repeats", type=int, default=2, help="interleaved runs per side and codec; best kept")
    parser.add_argument("--work", help="folder keeping the episodes and renders between runs (default: temporary)")
    parser.add_argument("--variant", default="", help="Mitsuba variant (default: llvm_ad_rgb when available)")
    parser.add_argument("--bare-serial", action="store_true",
                        help="the bare loop encodes in its own process, as rik does (save_episode(parallel_encoding="
                             "False)), rather than lerobot's default process per camera")
    parser.add_argument("--child", choices=("export", "bare"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return
    started = time.perf_counter()

    from rik.registry.load import load_catalog
    from rik.render.backend import available_variants

    args.variant = args.variant or ("llvm_ad_rgb" if "llvm_ad_rgb" in available_variants() else "scalar_rgb")
    codecs = args.codecs.split(",")
    catalog = load_catalog()
    tmp = None if args.work else tempfile.TemporaryDirectory(prefix="export-speed-")
    root = Path(args.work or tmp.name).resolve()  # type: ignore[union-attr]
    root.mkdir(parents=True, exist_ok=True)
    try:
        work = Work(root, args.frames, args.res, args.variant)
        work.prepare(catalog)
        print(f"CPU cores: {os.cpu_count()}; episode: {args.frames} frames at 20 Hz, cameras front and wrist, "
              f"streams sim and rerendered ({args.variant}, {SPP} spp, raw), {args.res}x{args.res} px: "
              f"{4 * args.frames} images; bare loop encodes "
              f"{'in its own process' if args.bare_serial else 'with a process per camera (lerobot default)'}")

        print(f"load average before timing: {', '.join(f'{x:.1f}' for x in os.getloadavg())}")
        # Memory first, while this process has not loaded lerobot (it would share, and so shrink, their PSS).
        mem = {side: measure_child(side, args, work, codecs[0]) for side in ("export", "bare")}

        # Warm-up: imports, codecs, timers; not counted.
        start = time.perf_counter()
        import lerobot.datasets.lerobot_dataset  # noqa: F401

        imported = time.perf_counter() - start
        install_timers()
        warm_inputs = bare_inputs(catalog, work, warmup=True)
        for codec in codecs:
            run_export(catalog, work, codec, root / "out-warmup-a", warmup=True)
            bare_loop(warm_inputs, codec, root / "out-warmup-b", not args.bare_serial)
        print(f"warm-up (not timed): lerobot import {imported:.1f} s, then one export and one bare loop of the "
              f"{WARMUP_FRAMES}-frame episode per codec, {time.perf_counter() - start:.1f} s in all")

        inputs = bare_inputs(catalog, work)
        best: dict[tuple[str, str], dict[str, Any]] = {}
        for _ in range(args.repeats):  # interleaved, so drift of the machine hits both sides alike
            for codec in codecs:
                for side in ("A", "B"):
                    STAGES.reset()
                    start = time.perf_counter()
                    frames = (run_export(catalog, work, codec, root / "out-a") if side == "A" else
                              bare_loop(inputs, codec, root / "out-b", not args.bare_serial))
                    seconds = time.perf_counter() - start
                    stages = dict(STAGES.seconds)
                    stages["other"] = seconds - sum(stages.values())
                    if (side, codec) not in best or seconds < best[(side, codec)]["seconds"]:
                        best[(side, codec)] = {"seconds": seconds, "frames": frames, "stages": stages}
        for out in ("out-a", "out-b", "out-warmup-a", "out-warmup-b"):
            shutil.rmtree(root / out, ignore_errors=True)

        cols = [(side, codec) for codec in codecs for side in ("A", "B")]
        head = "".join(f"{f'{side} {codec}':>16}" for side, codec in cols)
        print(f"\nseconds per stage, best of {args.repeats} (A: rik export_lerobot, B: bare lerobot loop)")
        print(f"{'stage':<26}{head}")
        for row in ROWS:
            cells = [best[c]["stages"].get(row) for c in cols]
            if any(cells):
                print(f"{row:<26}" + "".join(f"{v:>16.2f}" if v is not None else f"{'-':>16}" for v in cells))
        print(f"{'total s':<26}" + "".join(f"{best[c]['seconds']:>16.2f}" for c in cols))
        print(f"{'frames':<26}" + "".join(f"{best[c]['frames']:>16}" for c in cols))
        print(f"{'frames/s':<26}" + "".join(f"{best[c]['frames'] / best[c]['seconds']:>16.1f}" for c in cols))
        print()
        post = ("frame check (shard)", "aggregate", "load merged", "frame check (merged)", "card")
        for codec in codecs:
            a, b = best[("A", codec)], best[("B", codec)]
            ratio = a["seconds"] / b["seconds"]
            checks = sum(a["stages"].get(s, 0.0) for s in post)
            print(f"{codec}: A {a['frames'] / a['seconds']:.1f} frames/s, B {b['frames'] / b['seconds']:.1f} "
                  f"frames/s; overhead A/B {ratio:.2f}x ({'met' if ratio <= 1.25 else 'NOT met'}, target <= 1.25); "
                  f"without the checks, merge and card ({checks:.1f} s) {(a['seconds'] - checks) / b['seconds']:.2f}x")

        print(f"\npeak memory, one {args.frames}-frame episode, {codecs[0]}, each side alone in a child process")
        print(f"{'':<44}{'A export':>12}{'B bare':>12}")
        for label, key in (("RSS after imports (main process)", "baseline_rss"),
                           ("peak RSS, largest process (ru_maxrss)", "maxrss"),
                           ("peak RSS, summed over the process tree", "tree_rss"),
                           ("peak PSS, summed over the process tree", "tree_pss")):
            print(f"{label:<44}" + "".join(f"{mem[s][key] / GB:>10.2f}GB" for s in ("export", "bare")))
        print(f"{'processes at most':<44}" + "".join(f"{mem[s]['processes']:>12}" for s in ("export", "bare")))
        print(f"{'seconds (cold: no warm-up)':<44}"
              + "".join(f"{mem[s]['seconds']:>12.1f}" for s in ("export", "bare")))
        # Memory the export really holds: the summed PSS of its process tree (forked encoders share their parent's
        # pages, which summed RSS counts once per process), or its largest process, whichever is larger.
        peak = max(mem["export"]["tree_pss"], mem["export"]["maxrss"])
        print(f"target: at most 2 GB for a {args.frames}-frame episode -> rik export {peak / GB:.2f} GB "
              f"(the larger of summed PSS and the largest process's RSS): {'met' if peak <= 2 * GB else 'NOT met'}")
        print("(RSS and PSS sampled every 0.1 s; PSS shares the pages that forked encoder processes share with "
              "their parent)")
        print(f"\ntotal run time {time.perf_counter() - started:.0f} s; load average now "
              f"{', '.join(f'{x:.1f}' for x in os.getloadavg())} (other work on the machine skews every number)")
    finally:
        if tmp is not None:
            tmp.cleanup()


if __name__ == "__main__":
    main()
