"""The viewer teleop driven the way a person drives it: a real X server (Xvfb), the real ``rik teleop`` in a
subprocess, keys held down and released with xdotool, the loop closed on the status lines it prints. No wall
time is asserted: every wait is bounded and waits for a condition."""

from __future__ import annotations

import json
import os
import queue
import re
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from shared import BOW

pytestmark = pytest.mark.display  # a window under Xvfb (also slow)

VARIANT = BOW
STATUS = re.compile(r"^(?P<episode>\S+) \| (?P<state>[a-z ]+) \| [\d.]+ s \((?P<limit>[^)]*)\) \| open (?P<open>-?\d+)% "
                    r"\| grip (?P<grip>\w+) \| handle (?P<ahead>[+-][\d.]+) ahead (?P<left>[+-][\d.]+) left "
                    r"(?P<up>[+-][\d.]+) up m .* roll (?P<roll>[+-]\d+) deg")
LINEAR = 0.10
"""m/s of a held translation key (rik.teleop.keys.LINEAR_SPEED)."""
ROLL = 45.8
"""deg/s of a held rotation key (0.8 rad/s)."""


@pytest.fixture(scope="module")
def display() -> Iterator[str]:
    """A fresh Xvfb on a free display number, killed afterwards."""
    if not (shutil.which("Xvfb") and shutil.which("xdotool")):
        pytest.skip("needs the Xvfb and xdotool binaries (Debian: xvfb, xdotool)")
    for n in range(91 + os.getpid() % 50, 200):
        if Path(f"/tmp/.X11-unix/X{n}").exists() or Path(f"/tmp/.X{n}-lock").exists():
            continue
        proc = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 20
        while proc.poll() is None and not Path(f"/tmp/.X11-unix/X{n}").exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        if proc.poll() is None and Path(f"/tmp/.X11-unix/X{n}").exists():
            try:
                yield f":{n}"
            finally:
                _stop(proc)
            return
        _stop(proc)
    pytest.fail("no free X display number for Xvfb")


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Stop Xvfb so that it removes its lock and socket files (a killed one leaves them behind)."""
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(10)


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants  # the demo variant, built once per test process (conftest)


class Teleop:
    """``rik teleop VARIANT`` running in a window on ``display``; its stdout read line by line in a thread."""

    def __init__(self, display: str, out: Path, variants: Path, *options: str) -> None:
        self.env = {**os.environ, "DISPLAY": display, "MUJOCO_GL": "glfw", "PYTHONUNBUFFERED": "1"}
        rik = Path(sys.executable).parent / "rik"
        self.proc = subprocess.Popen([str(rik), "teleop", VARIANT, "--out", str(out), "--variants", str(variants),
                                      *options], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     env=self.env)
        self.lines: queue.Queue[tuple[float, str]] = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()
        found = subprocess.run(["xdotool", "search", "--sync", "--onlyvisible", "--name", f"rik teleop: {VARIANT}"], env=self.env,
                               capture_output=True, text=True, timeout=120)
        self.window = found.stdout.split()[0]
        for _ in range(20):  # a window just mapped may refuse the focus for a moment
            if subprocess.run(["xdotool", "windowfocus", "--sync", self.window], env=self.env, capture_output=True,
                              timeout=30).returncode == 0:
                break
            time.sleep(0.2)
        else:
            raise AssertionError(f"cannot focus the teleop window {self.window}")

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put((time.monotonic(), line.rstrip("\n")))

    def line(self, want: str | re.Pattern[str], *, after: float = 0.0, timeout: float = 30.0) -> str:
        """The next output line containing ``want`` (a string, or a pattern that matches) printed after ``after``
        (time.monotonic)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                at, line = self.lines.get(timeout=0.5)
            except queue.Empty:
                assert self.proc.poll() is None or not self.lines.empty(), \
                    f"rik teleop exited ({self.proc.returncode}):\n" + "\n".join(self.seen[-20:])
                continue
            self.seen.append(line)
            hit = want in line if isinstance(want, str) else want.search(line)
            if at >= after and hit:
                return line
        raise AssertionError(f"no line with {want!r} within {timeout} s:\n" + "\n".join(self.seen[-20:]))

    def status(self, after: float = 0.0) -> dict[str, str]:
        """The first status line printed after ``after`` (default: the next), parsed."""
        match = STATUS.search(self.line(STATUS, after=after))
        assert match is not None
        return match.groupdict()

    def settled(self) -> dict[str, str]:
        """The status once the gripper has caught up with its target after a key was released."""
        return self.status(after=time.monotonic() + 0.6)

    def xdotool(self, *args: str) -> None:
        subprocess.run(["xdotool", *args], env=self.env, check=True, timeout=60)

    def hold(self, key: str, seconds: float) -> None:
        """Hold ``key`` down for ``seconds``, then release it (as one xdotool run, so the hold is not stretched)."""
        self.xdotool("keydown", key, "sleep", f"{seconds:.2f}", "keyup", key)

    def press(self, key: str) -> None:
        self.xdotool("key", key)

    def quit(self) -> str:
        """Esc, and everything it printed until it exited."""
        self.press("Escape")
        self.proc.wait(60)
        rest = [line for _, line in iter_queue(self.lines)]
        self.seen += rest
        return "\n".join(self.seen)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


def iter_queue(q: queue.Queue[tuple[float, str]]) -> Iterator[tuple[float, str]]:
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            yield q.get(timeout=0.5)
        except queue.Empty:
            return


def episodes(out: Path) -> list[Path]:
    return sorted(p for p in out.iterdir() if not p.name.startswith(".")) if out.exists() else []


def test_hold_keys_to_open_the_drawer_save_and_replay(display: str, variants: Path, tmp_path: Path, rik) -> None:
    """Roll 90 deg (Q), approach until the handle is between the pads (W), grip (Space), pull until the drawer is
    90 % open (S), save (Enter), quit (Esc): one episode, which replays exactly."""
    out = tmp_path / "episodes"
    t = Teleop(display, out, variants)
    try:
        st = t.status()
        assert st["state"] == "waiting for input" and st["limit"] == "no limit"
        assert float(st["ahead"]) > 0.1 and abs(float(st["left"])) < 0.01 and abs(float(st["up"])) < 0.01, st
        for _ in range(10):
            if int(st["roll"]) >= 87:
                break
            t.hold("q", (90 - int(st["roll"])) / ROLL)
            st = t.settled()
        assert 85 <= int(st["roll"]) <= 95, st
        for _ in range(15):
            if float(st["ahead"]) <= 0.0:
                break
            t.hold("w", float(st["ahead"]) / LINEAR + 0.05)
            st = t.settled()
        assert float(st["ahead"]) <= 0.0, st
        t.press("space")
        assert t.settled()["grip"] == "closed"
        for _ in range(15):  # 91: the status rounds to whole percent (89.8 % shows as 90 %), and a drawer whose
            if int(st["open"]) >= 91:  # friction holds stays where the pull left it (it no longer creeps on)
                break
            t.hold("s", 1.5)
            st = t.settled()
        assert int(st["open"]) >= 91, st
        t.press("Return")
        t.line("saved ")
        text = t.quit()
    finally:
        t.kill()
    assert t.proc.returncode == 0, text
    saved = episodes(out)
    assert len(saved) == 1, text
    meta = json.loads((saved[0] / "meta.json").read_text())
    assert meta["final_opening"] >= 0.9 and meta["operator"] == "keyboard"
    r = rik("replay", str(saved[0]), "--variants", str(variants))
    assert r.code == 0 and "exact" in r.out, r.out + r.err


def test_quit_discards_and_sessions_take_new_ids(display: str, variants: Path, tmp_path: Path) -> None:
    """Esc with an unsaved episode writes nothing and says so; two sessions saving into the same folder get two
    episode ids (the seed advances), never overwriting."""
    out = tmp_path / "episodes"
    t = Teleop(display, out, variants)
    try:
        t.hold("d", 0.3)
        assert t.settled()["state"] == "recording"
        text = t.quit()
    finally:
        t.kill()
    assert "discarded" in text and "no episode saved" in text, text
    assert episodes(out) == []
    ids = []
    for _ in range(2):
        t = Teleop(display, out, variants)
        try:
            t.hold("a", 0.3)
            # as a person does, save once the window says it records: on a starved machine the hold and Enter
            # can arrive in one poll of events, Enter first, before any step was recorded ("nothing recorded yet")
            assert t.settled()["state"] == "recording"
            t.press("Return")
            ids.append(t.line("saved ").split("saved ", 1)[1].split(":")[0])
            t.quit()
        finally:
            t.kill()
    assert ids[0] != ids[1] and [p.name for p in episodes(out)] == sorted(ids)


def test_the_window_opens_with_an_arm_and_esc_closes_it(display: str, variants: Path, tmp_path: Path) -> None:
    """``--robot so100``: the window opens on the arm's scene (the status names it in the episode id), shows the
    arm's wrist camera (2) and the free camera (3) while the loop goes on, and Esc closes it, nothing saved."""
    t = Teleop(display, tmp_path / "episodes", variants, "--robot", "so100")
    try:
        assert f"{VARIANT}__drawer-1__keyboard.so100__s0000" == t.status()["episode"]
        t.press("2")
        t.press("3")
        assert t.status(after=time.monotonic())["state"] == "waiting for input"
        text = t.quit()
    finally:
        t.kill()
    assert t.proc.returncode == 0 and "no episode saved" in text, text


def test_an_arms_wrist_camera_rides_on_its_wrist(variants: Path) -> None:
    """Key 2 and the station's wrist stream ask for the camera ``wrist``: an arm's is called that too (not
    ``robot/wrist``, as attaching its model would name it; an id of -1 would render a fixed camera that is not
    there), and it moves with the arm's gripper."""
    import mujoco

    from rik.registry import load_catalog
    from rik.sim.build import build_scene

    scene = build_scene(variants / VARIANT, robot=load_catalog().robot("so100"))
    model = scene.model
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "wrist")
    assert cam >= 0 and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "front") >= 0
    assert model.body(int(model.cam_bodyid[cam])).name == "robot/so_arm100_left/Fixed_Jaw"


def test_a_display_without_an_x_server_is_one_line(rik, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """A DISPLAY with no X server behind it: one line naming the display, before any scene is built."""
    free = next(n for n in range(1999, 2999) if not Path(f"/tmp/.X11-unix/X{n}").exists())
    monkeypatch.setenv("DISPLAY", f":{free}")
    r = rik("teleop", VARIANT, "--variants", str(tmp_path / "variants"), "--out", str(tmp_path / "episodes"))
    assert r.code == 2 and f"teleoperation cannot open a window on display :{free}" in r.err, r.err
    assert "Traceback" not in r.err and len(r.err.strip().splitlines()) == 1, r.err
    assert not (tmp_path / "variants").exists()  # it failed before building the scene


def test_a_late_frame_drops_steps_instead_of_jumping() -> None:
    """The loop's pacing: steps due on time run; after a late frame at most CATCH_UP run and the rest are dropped,
    so the next frame is on time again (no burst)."""
    from rik.teleop.pacing import CATCH_UP, due_steps

    assert due_steps(now=10.0, next_tick=10.01, dt=0.05) == (0, 10.01)
    assert due_steps(now=10.0, next_tick=9.96, dt=0.05) == (1, pytest.approx(10.01))
    steps, next_tick = due_steps(now=10.0, next_tick=8.0, dt=0.05)  # a frame 2 s late
    assert steps == CATCH_UP <= 2 and next_tick == 10.0
    assert due_steps(now=10.02, next_tick=next_tick, dt=0.05)[0] == 1


def test_the_station_keeps_real_time_when_its_renders_are_slower_than_a_control_period() -> None:
    """The browser station's pacing (up to MAX_CATCH_UP steps per render): with renders of 80 ms against 50 ms
    control steps, the 25 renders of 2 s (at 0, 0.08 .. 1.92 s) run the 39 control steps due by then (at 0, 0.05
    .. 1.90 s: none dropped), never more than the cap at once; a 1 s stall runs the cap and the clock starts again from then (no burst)."""
    from rik.teleop.pacing import due_steps
    from rik.teleop.station import MAX_CATCH_UP

    now, next_tick, total, renders = 0.0, 0.0, 0, 0
    while now < 2.0 - 1e-9:
        steps, next_tick = due_steps(now, next_tick, 0.05, MAX_CATCH_UP)
        assert 1 <= steps <= MAX_CATCH_UP
        total, renders, now = total + steps, renders + 1, now + 0.08
    assert (total, renders) == (39, 25)
    steps, next_tick = due_steps(now + 1.0, next_tick, 0.05, MAX_CATCH_UP)
    assert steps == MAX_CATCH_UP and next_tick == now + 1.0


def test_a_station_behind_real_time_renders_the_wrist_on_every_other_frame_and_catches_up_at_rest() -> None:
    """On time, both stale cameras render; behind, the wrist is left out of every other render; a scene at rest
    (only the wrist stale) renders the wrist, behind or not."""
    from rik.teleop.station import cameras_due

    both = ["front", "wrist"]
    assert cameras_due(both, behind=False, skipped=False) == both
    assert cameras_due(both, behind=True, skipped=False) == ["front"]
    assert cameras_due(both, behind=True, skipped=True) == both
    assert cameras_due(["wrist"], behind=True, skipped=False) == ["wrist"]
    assert cameras_due([], behind=True, skipped=True) == []
