"""Teleop streaming speed: frames per second the browser station streams, and input-to-frame latency (an input
until the first streamed frame that shows its motion), at 320x240 and 640x480, against MuJoCo's offscreen render
time for the same frame (the floor: the station cannot stream faster than it renders). Side by side in one run.

- **floor**: ``mujoco.Renderer`` of the demo variant's scene, the ``front`` camera at the size, rendered as the
  station renders (shadows and reflections off; also timed with them on, as the scene's own settings have it) and,
  separately, JPEG-encoded with Pillow at the station's
  quality: ms per frame, and the frames per second that render alone would allow;
- **station**: the real ``rik teleop VARIANT --web --port 0`` in its own process, a websocket client in this one
  (the ``websockets`` package, as a browser's page would talk to it). The client takes control, asks for the size,
  holds an input for ``--seconds`` and counts the ``front`` frames that arrive (streamed fps; the station sends
  ``front`` and ``wrist`` each render, the wrist with every other one while it is behind real time); then
  ``--taps`` times: waits still, sends one input with a new sequence number and measures the time until the first
  frame whose header says that input was applied and whose step advanced (input-to-frame latency, ms: median and
  90th percentile).

- **where a step's time goes** (``profile``): the station's own pipeline in this process, with the robot's scene as
  the station builds it: for ``--profile-steps`` control steps with an input held, the ms of the IK (the arm drive's
  command), the physics (the control step's ``mj_step`` calls), the rest of a recorded step (recording, grasp
  watch), each camera's render (``rik.teleop.frames.StationFrames``: the follow view and the wrist camera, painted
  as the page shows them, from the view model whose arm meshes are decimated, anti-aliased or not as the station
  decides) and its JPEG, and beside it the same camera as the station drew it before, the full-detail model
  anti-aliased (interleaved, so both see the same load); the station's ``send`` (a
  frame's header ``sent`` stamp until the client holds it) and **real time** (simulated seconds per wall second
  while the input is held, from the frames' ``t``) come from the station run.

Target: at least 15 frames/s and real time at 320x240 on this machine's 2 CPU cores (MuJoCo on llvmpipe through
EGL).

``--robot panda-2f85`` (or ``so100``) measures the station with that arm (``rik teleop --web --robot``): its
scene renders the arm's links too, and each control step runs one IK step.

Run: ``uv run python benchmarks/teleop_latency.py [--seconds 8] [--taps 15] [--robot ID] [--sizes 320x240]``
(about 2 minutes with the variant built; building it first takes up to a minute). ``--floor-only --model
FILE.mjb`` measures the floor alone from a saved model with only mujoco, numpy and Pillow installed (how the GPU
figures in docs/benchmarks.md were taken on a machine without rik).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import queue
import re
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

VARIANT = "drawer-chest-80__two_point-bow-128__normal"
SIZES = ((320, 240), (640, 480))
JPEG_QUALITY = 80


def floor(model_path: Path | None, sizes: tuple[tuple[int, int], ...], frames: int = 60,
          robot: str = "hand-e") -> list[dict[str, float]]:
    """Offscreen render and JPEG encode time per frame (ms) of the ``front`` camera at each size."""
    import mujoco
    import numpy as np
    from PIL import Image

    if model_path is not None:
        model = mujoco.MjModel.from_binary_path(str(model_path))
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
    else:
        model, data = demo_scene(robot)
    rows = []
    for w, h in sizes:
        renderer = mujoco.Renderer(model, h, w)
        out = np.empty((h, w, 3), np.uint8)
        times, encode, shadowed = [], [], []
        for i in range(frames + 5):
            t0 = time.perf_counter()
            renderer.update_scene(data, "front")
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
            renderer.render(out=out)
            t1 = time.perf_counter()
            buf = io.BytesIO()
            Image.fromarray(out).save(buf, "JPEG", quality=JPEG_QUALITY)
            t2 = time.perf_counter()
            if i % 4 == 0:  # every 4th frame also with shadows and reflections, as the scene's own settings say
                renderer.update_scene(data, "front")
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 1
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 1
                renderer.render(out=out)
                shadowed.append(time.perf_counter() - t2)
            if i >= 5:  # warm-up frames
                times.append(t1 - t0)
                encode.append(t2 - t1)
        renderer.close()
        render_ms, encode_ms = 1e3 * statistics.median(times), 1e3 * statistics.median(encode)
        rows.append({"width": w, "height": h, "render_ms": render_ms, "encode_ms": encode_ms,
                     "floor_fps": 1e3 / render_ms, "shadows_ms": 1e3 * statistics.median(shadowed[2:])})
    return rows


def profile(robot: str, size: tuple[int, int], steps: int = 60) -> dict[str, float]:
    """Median ms per control step of the station's phases (IK, physics, the rest of a recorded step, each camera's
    render and JPEG) with an input held, in this process, the scene built as the station builds it."""
    import numpy as np

    from rik.teleop.frames import ANTIALIAS_TRIAL, StationFrames
    from rik.teleop.session import TeleopSession
    from rik.teleop.station import CAMERAS, encode_jpeg
    from rik.teleop.view_model import visible_faces

    scene = demo_scene_object(robot)
    times: dict[str, list[float]] = {k: [] for k in ("ik", "physics", "tick")}
    drive_command, run = scene.robot_drive.command, scene._run

    def timed(name: str, fn):  # noqa: ANN001, ANN202 -- a stopwatch around the scene's own call
        def call(*args):  # noqa: ANN002, ANN202
            t0 = time.perf_counter()
            try:
                return fn(*args)
            finally:
                times[name].append(time.perf_counter() - t0)
        return call

    scene.robot_drive.command = timed("ik", drive_command)  # type: ignore[method-assign]
    scene._run = timed("physics", run)  # type: ignore[method-assign]
    frames = StationFrames(scene)
    full = StationFrames(scene, budget=10**9, antialias=True)  # the cameras as before: every face, anti-aliased
    with tempfile.TemporaryDirectory() as tmp:
        session = TeleopSession(scene, Path(tmp), operator="bench")
        session.set_input(np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.3]))  # roll slowly, as the station run does
        for cam in CAMERAS:
            times[f"render {cam}"], times[f"JPEG {cam}"], times[f"full-detail {cam}"] = [], [], []
        warm = 5 + ANTIALIAS_TRIAL // len(CAMERAS)  # past the station's anti-aliasing trial
        for i in range(steps + warm):
            t0 = time.perf_counter()
            session.tick()
            times["tick"].append(time.perf_counter() - t0)
            for cam in CAMERAS:
                t1 = time.perf_counter()
                rgb = frames.render(scene.data, cam, size)
                t2 = time.perf_counter()
                encode_jpeg(rgb)
                t3 = time.perf_counter()
                full.render(scene.data, cam, size)  # interleaved: the same load on both
                times[f"render {cam}"].append(t2 - t1)
                times[f"JPEG {cam}"].append(t3 - t2)
                times[f"full-detail {cam}"].append(time.perf_counter() - t3)
            if i < warm:
                for v in times.values():
                    v.clear()
    frames.close()
    full.close()
    out = {k: 1e3 * statistics.median(v) for k, v in times.items()}
    out["rest of step"] = out.pop("tick") - out["ik"] - out["physics"]
    out["total"] = sum(v for k, v in out.items() if not k.startswith("full-detail"))
    out["view faces"], out["full faces"] = visible_faces(frames.view.model), visible_faces(scene.model)
    out["antialiased"] = float(frames.antialias)
    return out


def demo_scene_object(robot: str = "hand-e"):
    """The demo variant's :class:`rik.sim.scene.SimScene` with ``robot`` (built into ``$RIK_BENCH_VARIANTS`` or
    ``variants`` if needed), as the station builds it."""
    from rik.registry import load_catalog
    from rik.teleop.station import StationConfig, build_station_scene

    config = StationConfig(load_catalog(), variants=Path(os.environ.get("RIK_BENCH_VARIANTS", "variants")))
    return build_station_scene(config, VARIANT, robot)


def demo_scene(robot: str = "hand-e"):
    """The demo variant's scene with ``robot`` (built into ``$RIK_BENCH_VARIANTS`` or ``variants`` if needed), as
    the station builds it."""
    from rik.combinator.build import ensure_variant
    from rik.registry import load_catalog
    from rik.sim.build import build_scene

    catalog = load_catalog()
    entry = catalog.robot(robot)
    scene = build_scene(ensure_variant(catalog, VARIANT, Path(os.environ.get("RIK_BENCH_VARIANTS", "variants"))),
                        robot=entry.as_arm)
    return scene.model, scene.data


def frame_header(message: bytes) -> dict:
    """The JSON header of a binary frame (4-byte big-endian length, header, JPEG)."""
    (n,) = struct.unpack(">I", message[:4])
    return json.loads(message[4:4 + n])


def station(url: str, size: tuple[int, int], seconds: float, taps: int) -> dict[str, float]:
    """Streamed fps of the ``front`` camera while an input is held, and input-to-frame latency (ms)."""
    from urllib.parse import urlsplit

    from websockets.sync.client import connect

    parts = urlsplit(url)  # the printed address carries the launch token (?token=...): the websocket shows it too
    ws_url = f"ws://{parts.netloc}{parts.path.rstrip('/')}/ws" + (f"?{parts.query}" if parts.query else "")
    with connect(ws_url, max_size=None, open_timeout=120) as ws:
        ws.send(json.dumps({"type": "size", "width": size[0], "height": size[1]}))
        seq = 0

        def send(axes: list[float]) -> int:
            nonlocal seq
            seq += 1
            ws.send(json.dumps({"type": "input", "seq": seq, "axes": axes, "grip": None, "fine": False}))
            return seq

        def front_frames(until: float):
            while time.perf_counter() < until:
                try:
                    message = ws.recv(timeout=max(0.01, until - time.perf_counter()))
                except TimeoutError:
                    return
                if isinstance(message, bytes):
                    header = frame_header(message)
                    if header["camera"] == "front":
                        yield time.perf_counter(), header

        # settle: wait until frames at the asked size arrive
        list(front_frames(time.perf_counter() + 3.0))
        # streamed fps while an input is held (re-sent at 30 Hz as the page does); simulated time per wall second
        count, start, direction = 0, time.perf_counter(), 1.0
        seen: list[tuple[float, float]] = []  # (wall s, simulated s) of each front frame
        sends: list[float] = []  # ms from a frame's "sent" stamp until this client holds it
        end = start + seconds
        next_send = start
        while time.perf_counter() < end:
            if time.perf_counter() >= next_send:
                send([0.0, 0.0, 0.0, 0.0, 0.0, 0.3 * direction])  # roll slowly: stays clear of the furniture
                next_send += 1 / 30
            for t, header in front_frames(min(end, next_send)):
                count += 1
                seen.append((t, header["t"]))
                sends.append(1e3 * (time.time() - header["sent"]))
        fps = count / seconds
        moving = [(w, t) for (w, t), (_, t0) in zip(seen[1:], seen, strict=False) if t > t0]  # after the first step
        realtime = ((moving[-1][1] - moving[0][1]) / (moving[-1][0] - moving[0][0])
                    if len(moving) > 1 and moving[-1][0] > moving[0][0] else float("nan"))
        # latency: still, then one input; first front frame that applied it and stepped
        latencies = []
        for k in range(taps):
            send([0.0] * 6)
            list(front_frames(time.perf_counter() + 0.6))
            last_step = None
            sent_at = time.perf_counter()
            s = send([0.0, 0.0, 0.0, 0.0, 0.0, 0.5 if k % 2 else -0.5])
            for t, header in front_frames(sent_at + 5.0):
                if last_step is None:
                    last_step = header["step"] - 1 if header["seq"] >= s else header["step"]
                if header["seq"] >= s and header["step"] > last_step:
                    latencies.append(1e3 * (t - sent_at))
                    break
        send([0.0] * 6)
        ws.send(json.dumps({"type": "command", "name": "discard"}))  # leave no draft for the next size's run
        list(front_frames(time.perf_counter() + 0.5))
    latencies.sort()
    return {"fps": fps, "realtime": realtime, "send_ms": statistics.median(sends) if sends else float("nan"),
            "latency_median_ms": statistics.median(latencies) if latencies else float("nan"),
            "latency_p90_ms": latencies[int(0.9 * (len(latencies) - 1))] if latencies else float("nan"),
            "taps": len(latencies)}


def start_station(work: Path, robot: str = "hand-e") -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen([sys.executable, "-m", "rik", "teleop", VARIANT, "--web", "--port", "0", "--out",
                             str(work / "episodes"), "--variants", os.environ.get("RIK_BENCH_VARIANTS", "variants"),
                             "--robot", robot],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "COLUMNS": "200"})
    assert proc.stdout is not None
    lines: queue.Queue[str] = queue.Queue()  # the address line, read with a deadline: a station that hangs ends the run
    threading.Thread(target=lambda: lines.put(proc.stdout.readline() if proc.stdout else ""), daemon=True).start()
    try:
        line = lines.get(timeout=300)
    except queue.Empty:
        line = "(no address printed in 300 s)\n"
    found = re.search(r"(http://localhost:\d+/\S+)", line)
    if not found:
        proc.kill()
        raise SystemExit(f"the station did not start: {line}{proc.stderr.read() if proc.stderr else ''}")
    return proc, found.group(1).replace("localhost", "127.0.0.1")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=8.0, help="how long an input is held for the fps count")
    parser.add_argument("--taps", type=int, default=15, help="inputs timed for the latency")
    parser.add_argument("--floor-only", action="store_true", help="measure the render floor alone")
    parser.add_argument("--model", type=Path, help="with --floor-only: a saved model (.mjb) instead of the demo")
    parser.add_argument("--robot", default="hand-e", help="the robot of the scene and the station (a catalog id)")
    parser.add_argument("--sizes", default="320x240,640x480", help="stream sizes, comma-separated WxH")
    parser.add_argument("--profile-steps", type=int, default=60, help="control steps timed phase by phase")
    args = parser.parse_args()
    sizes = tuple((int(w), int(h)) for w, h in (s.split("x") for s in args.sizes.split(",")))
    print(f"machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}, "
          f"MUJOCO_GL={os.environ.get('MUJOCO_GL', '(unset)')}; robot {args.robot}")
    floors = floor(args.model, sizes, robot=args.robot)
    if args.floor_only:
        for f in floors:
            print(f"{f['width']}x{f['height']}: render {f['render_ms']:.1f} ms ({f['floor_fps']:.0f} fps floor), "
                  f"JPEG {f['encode_ms']:.1f} ms; with shadows and reflections {f['shadows_ms']:.1f} ms")
        return
    for w, h in sizes:
        phases = profile(args.robot, (w, h), args.profile_steps)
        faces = (f"visible mesh faces drawn {phases.pop('view faces'):,.0f} of {phases.pop('full faces'):,.0f}, "
                 f"anti-aliasing {'kept' if phases.pop('antialiased') else 'off'}")
        print(f"where a step's time goes at {w}x{h} (median ms over {args.profile_steps} steps, this process; "
              f"{faces}; full-detail: the same camera as before, every face anti-aliased, not in the total): "
              + ", ".join(f"{k} {v:.1f}" for k, v in phases.items()))
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_station(Path(tmp), args.robot)
        try:
            rows = [(f, station(url, (f["width"], f["height"]), args.seconds, args.taps)) for f in floors]
        finally:
            proc.terminate()
            proc.wait(timeout=60)
    print(f"{'size':>8} {'render ms':>10} {'floor fps':>10} {'JPEG ms':>8} {'streamed fps':>13} "
          f"{'fps/floor':>10} {'real time':>10} {'send ms':>8} {'latency ms (median, p90)':>26}")
    for f, s in rows:
        print(f"{f['width']}x{f['height']:<4} {f['render_ms']:>10.1f} {f['floor_fps']:>10.1f} {f['encode_ms']:>8.1f} "
              f"{s['fps']:>13.1f} {s['fps'] / f['floor_fps']:>10.2f} {s['realtime']:>9.2f}x {s['send_ms']:>8.1f} "
              f"{s['latency_median_ms']:>12.0f}, {s['latency_p90_ms']:.0f} ({s['taps']} taps)")
    first = rows[0][1]
    ok = first["fps"] >= 15.0 and first["realtime"] >= 0.95
    print(f"target: >= 15 frames/s and real time at {rows[0][0]['width']}x{rows[0][0]['height']}: "
          f"{'met' if ok else 'NOT met'} ({first['fps']:.1f} fps, {first['realtime']:.2f}x real time); "
          f"load average now {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
