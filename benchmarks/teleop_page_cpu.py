"""What the browser teleop page costs the operator's machine: Chromium's CPU (every process of the browser: the
page's renderer, the GPU and browser processes) and the station's, per second of wall time, side by side in one run:

- **blank**: an empty page in the same browser (the floor: what a headless Chromium costs doing nothing);
- **idle**: the station's page (``rik teleop VARIANT --web``), this tab controlling, nothing held: the station sends
  its status about 20 times a second and no frame (nothing moves);
- **moving**: the same page with W and S held in turn (a second each): the gripper moves, the station renders and
  streams both cameras, the page decodes and shows them.

The page once rewrote its whole status panel and some 40 data attributes with their same values at each status,
and the gamepad line at every animation frame; Chromium restyled and repainted for each (docs/benchmarks.md, "The
teleop page's CPU"). Debian's ``chromium`` through Playwright, with the test suite's flags (headless, one raster
thread, software rendering), at the tests' window size.

Run: ``uv run python benchmarks/teleop_page_cpu.py [--seconds 15] [--size 320x240]`` (about a minute with the
variant built; building it first takes up to a minute).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
import uuid
from pathlib import Path

from teleop_latency import VARIANT, start_station

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from web_fixtures import browser  # noqa: E402  (the suite's Chromium and flags, one definition)

HZ = os.sysconf("SC_CLK_TCK")


def _processes() -> dict[int, tuple[int, float]]:
    """Every process: pid -> (parent pid, CPU-s so far)."""
    found = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                stat = Path(f"/proc/{name}/stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()
            found[int(name)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / HZ)
    return found


def tree_cpu(root: int) -> float:
    """CPU-s so far of ``root`` and every process below it (live ones; Chromium keeps its processes for the run)."""
    procs, total = _processes(), 0.0
    for pid, (_, cpu) in procs.items():
        up = pid
        while up in procs and up != root:
            up = procs[up][0]
        total += cpu if up == root else 0.0
    return total


def browser_pid(marker: str) -> int:
    """The browser process: the one whose command line holds ``marker`` (a flag only this run passes)."""
    for name in os.listdir("/proc"):
        try:
            if name.isdigit() and marker in Path(f"/proc/{name}/cmdline").read_text(errors="replace"):
                return int(name)
        except OSError:
            continue
    raise SystemExit("the browser's process was not found")


def measure(seconds: float, browser: int, station: int, act=None) -> tuple[float, float]:
    """Chromium's and the station's CPU-s per wall s over ``seconds``; ``act(t)`` is called about every 50 ms."""
    b0, s0, start = tree_cpu(browser), tree_cpu(station), time.monotonic()
    while (t := time.monotonic() - start) < seconds:
        if act:
            act(t)
        time.sleep(0.05)
    wall = time.monotonic() - start
    return (tree_cpu(browser) - b0) / wall, (tree_cpu(station) - s0) / wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=15.0, help="wall seconds of each phase")
    parser.add_argument("--size", default="320x240", choices=("320x240", "640x480"), help="the stream's size")
    args = parser.parse_args()
    if shutil.which("chromium") is None:
        raise SystemExit("Debian's chromium is not installed (bash scripts/setup.sh installs it)")
    print(f"machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; {VARIANT}, stream {args.size}, "
          f"{args.seconds:.0f} s a phase")
    work = Path(tempfile.mkdtemp(prefix="rik-page-cpu-"))
    proc, url = start_station(work)
    marker = f"--rik-benchmark={uuid.uuid4().hex}"
    rows = []
    try:
        with browser(marker) as b:
            pid = browser_pid(marker)
            page = b.new_page(viewport={"width": 1400, "height": 1000})
            page.goto("about:blank")
            time.sleep(2)
            rows.append(("blank", *measure(args.seconds, pid, proc.pid)))
            page.goto(url)
            page.wait_for_function("document.getElementById('station').dataset.ready === 'true' && "
                                   "document.getElementById('cam-front').dataset.step !== ''", timeout=300_000)
            page.select_option("#size", args.size)
            time.sleep(3)
            rows.append(("idle", *measure(args.seconds, pid, proc.pid)))
            held = {"key": None}

            def alternate(t: float) -> None:
                key = "w" if int(t) % 2 else "s"
                if key != held["key"]:
                    if held["key"]:
                        page.keyboard.up(held["key"])
                    page.keyboard.down(key)
                    held["key"] = key

            before = page.evaluate("window.rikTest.frames.front")
            rows.append(("moving", *measure(args.seconds, pid, proc.pid, alternate)))
            if held["key"]:
                page.keyboard.up(held["key"])
            fps = (page.evaluate("window.rikTest.frames.front") - before) / args.seconds
    finally:
        proc.terminate()
        proc.wait(timeout=60)
        shutil.rmtree(work, ignore_errors=True)
    print("| phase | Chromium, CPU-s per s (% of a core) | station, CPU-s per s (% of a core) |")
    print("|---|---:|---:|")
    for name, browser_cpu, station_cpu in rows:
        cells = [f"{cpu:.3f} ({100 * cpu:.0f} %)" for cpu in (browser_cpu, station_cpu)]
        print(f"| {name} | {' | '.join(cells)} |")
    print(f"moving: the page showed {fps:.1f} front frames per second")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
