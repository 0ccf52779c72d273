"""Teleoperation in a window of its own: the keyboard (held keys move the target continuously), a 3Dconnexion
SpaceMouse or a real LeRobot leader arm (:mod:`rik.teleop.leader`: the SO-101's or SO-100's, driving the simulated
arm of its type joint by joint) drive a :class:`rik.teleop.session.TeleopSession`, which records at the scene's
control rate.

Keymap (the same as the browser station's, :mod:`rik.teleop.keys`; directions as seen facing the front):

======================  ==============================================================
W / S                   towards / away from the furniture (hold: 0.10 m/s)
A / D                   left / right
R / F                   up / down
Down / Up               pitch: fingers down / up (hold: 0.8 rad/s)
Left / Right            yaw left / right
Q / E                   roll left / right
Shift                   hold for fine motion (x0.25)
Space                   close / open the gripper
M                       W / S along the front's path while holding its handle (a door's arc), or frame-fixed
Enter                   save the episode and start the next
Backspace               discard the episode and start again
Esc (or close window)   quit; an unsaved episode is discarded
1 / 2 / 3               camera: front / wrist / free (drag: orbit, right-drag: pan, wheel: zoom)
F1                      hide / show the keymap (it folds once the episode records)
======================  ==============================================================

The keymap and the live status (episode, time and time left, opening, the grasp as contacts give it, where the
handle is, the front's angle or travel, the motion mode) are drawn in the window; the status is also printed to the
terminal about once a second. The simulation runs on real time at the control rate (20 Hz); a slow frame drops
control steps rather than catching up in a burst, so it never turns into a jump.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.teleop.feedback import front_text, grasp_text, motion_text
from rik.teleop.keys import COMMAND_KEYS, MOTION_KEYS, keymap_rows, velocity
from rik.teleop.leader import LEADERS, LeaderArm, open_leader
from rik.teleop.pacing import due_steps
from rik.teleop.session import TeleopSession, check_time_limit, handle_text, time_text
from rik.teleop.window import CAMERAS, TeleopWindow, open_display

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.schemas.robots import Robot

MAX_FPS = 60.0
"""Frames per second the window is drawn at most (no vsync under a virtual display)."""
STATUS_PERIOD = 1.0
"""Seconds between status lines in the terminal."""
EXTRA_KEYS = (("Esc", "quit (an unsaved episode is discarded)"), ("1 / 2 / 3", "camera: front / wrist / free"),
              ("drag / wheel", "orbit / zoom the free camera"), ("F1", "hide / show this keymap"))
"""Rows of the on-screen keymap beyond :func:`rik.teleop.keys.keymap_rows`."""


class DeviceError(RikError):
    """A teleoperation device is missing, not connected, or cannot run here."""


@dataclass
class SpaceMouseDevice:
    """A 3Dconnexion SpaceMouse through ``pyspacemouse``: deflection (-1..1 per axis) is the velocity command;
    the left button closes the gripper, the right one opens it. The keyboard keeps working beside it."""

    name: str = "spacemouse"
    _mouse: Any = None

    def open(self) -> None:
        try:
            import pyspacemouse
        except ImportError:
            raise DeviceError("SpaceMouse support needs the pyspacemouse package and the hidapi library: "
                              "uv sync --extra spacemouse (and apt install libhidapi-hidraw0)") from None
        try:
            ok = pyspacemouse.open()
        except Exception as exc:  # hidapi errors vary by platform
            raise DeviceError(f"cannot open the SpaceMouse: {exc}") from None
        if not ok:
            raise DeviceError("no SpaceMouse connected (pyspacemouse found none); plug one in or use "
                              "--device keyboard")
        self._mouse = pyspacemouse

    def read(self) -> tuple[np.ndarray, float | None]:
        """The velocity command (x, y, z, pitch, yaw, roll in -1..1) and the grip the buttons ask for (None:
        unchanged)."""
        s = self._mouse.read()
        # device axes: x right, y forward (towards the furniture), z up; world +x is the operator's left, -y ahead
        command = np.clip(np.array([-s.x, -s.y, s.z, -s.pitch, -s.yaw, s.roll], np.float64), -1.0, 1.0)
        buttons = list(s.buttons or [])
        grip = 1.0 if buttons[:1] == [1] else 0.0 if len(buttons) > 1 and buttons[1] else None
        return command, grip


@dataclass
class KeyboardDevice:
    """The keyboard alone (the window polls it)."""

    name: str = "keyboard"


DEVICES = {"keyboard": KeyboardDevice, "spacemouse": SpaceMouseDevice}


def make_device(name: str, robot: Robot | None = None, port: str | None = None, leader_id: str | None = None,
                calibration_dir: Path | None = None) -> KeyboardDevice | SpaceMouseDevice | LeaderArm:
    """A device by name; a SpaceMouse or a leader arm (on serial ``port``, driving ``robot``) is opened here, so a
    missing one fails before anything else happens."""
    if name not in DEVICES and name not in LEADERS:
        raise DeviceError(f"unknown device '{name}' (devices: {', '.join([*DEVICES, *LEADERS])})")
    if name in LEADERS:
        if port is None:
            raise DeviceError(f"--device {name}: give the leader arm's serial port, --port /dev/ttyACM0 "
                              "(lerobot-find-port finds it)")
        return open_leader(name, robot, port, leader_id=leader_id, calibration=calibration_dir)
    if port is not None or leader_id is not None or calibration_dir is not None:
        given = "--port" if port is not None else "--leader-id" if leader_id is not None else "--calibration-dir"
        raise DeviceError(f"{given} is for a leader arm (--device {' or '.join(LEADERS)}), not --device {name}")
    device = DEVICES[name]()
    if isinstance(device, SpaceMouseDevice):
        device.open()
    return device


def _glfw_key(name: str) -> int:
    import glfw

    return int(getattr(glfw, f"KEY_{name}"))


@dataclass
class Controls:
    """What the operator's keys do to the session (press edges) and the held-key velocity command."""

    session: TeleopSession
    device: KeyboardDevice | SpaceMouseDevice | LeaderArm
    say: Callable[[str], None]
    window: TeleopWindow | None = None
    saved: list[EpisodeMeta] = field(default_factory=list)
    quit: bool = False
    show_keys: bool | None = None
    """Whether the keymap is drawn: None (the start) shows it until the first episode records, then folds it to a
    one-line hint so that it does not hide the furniture; F1 shows or hides it from then on."""

    @property
    def keys_shown(self) -> bool:
        return self.show_keys if self.show_keys is not None else not self.session.recording

    def press(self, key: int, mods: int) -> None:
        """A key went down (GLFW key code)."""
        import glfw

        s = self.session
        if key == glfw.KEY_SPACE:
            s.toggle_grip()
        elif key == glfw.KEY_M:
            s.toggle_motion_mode()
            self.say(s.message)
        elif key in (glfw.KEY_ENTER, glfw.KEY_KP_ENTER):
            result = s.save()
            if result is not None:
                self.saved.append(result.meta)
            self.say(s.message)
        elif key == glfw.KEY_BACKSPACE:
            s.discard()
            self.say(s.message)
        elif key == glfw.KEY_ESCAPE:
            self.quit = True
        elif key == glfw.KEY_F1:
            self.show_keys = not self.keys_shown
        elif key in (glfw.KEY_1, glfw.KEY_2, glfw.KEY_3) and self.window is not None:
            self.window.camera = CAMERAS[key - glfw.KEY_1]

    def held(self) -> frozenset[str]:
        """Browser codes of the motion keys held now (Shift as ``fine``)."""
        assert self.window is not None
        codes = {k.code for k in MOTION_KEYS if self.window.held(_glfw_key(k.glfw))}
        if self.window.held(_glfw_key(COMMAND_KEYS["fine"][1])) or self.window.held(_glfw_key("RIGHT_SHIFT")):
            codes.add("fine")
        return frozenset(codes)

    def apply(self, held: frozenset[str]) -> None:
        """Set the session's velocity command from the held keys (and the SpaceMouse), or its joint targets from
        the leader arm."""
        if not isinstance(self.device, KeyboardDevice | SpaceMouseDevice):
            self.session.set_joints(*self.device.read())
            return
        command = velocity(held, fine="fine" in held)
        grip = None
        if isinstance(self.device, SpaceMouseDevice):
            deflection, grip = self.device.read()
            command = np.clip(command + deflection, -1.0, 1.0)
        self.session.set_input(command, grip)


def gripper_angles(session: TeleopSession) -> str:
    """The gripper's pitch, yaw and roll in degrees, for the operator."""
    pitch, yaw, roll = (math.degrees(a) for a in session.scene.pose()[3:6])
    return f"pitch {pitch:+.0f} yaw {yaw:+.0f} roll {roll:+.0f} deg"


def overlays(session: TeleopSession, camera: str, fps: float, show_keys: bool = True) -> list[tuple[int, str, str]]:
    """The status (top left), the camera and frame rate (top right) and the keymap (bottom left; only a hint of F1
    when hidden) for the window."""
    import mujoco

    st = session.status()
    state = st["state"] + (": Enter saves, Backspace discards" if st["state"] == "time up" else "")
    status = [("robot", st["robot"]), ("episode", st["episode"]), ("state", state), ("time", time_text(st)),
              ("opening", f"{st['opening']:.0%} (most {st['max_opening']:.0%}), {front_text(st)}"),
              ("grip", f"{st['grip']}, {grasp_text(st)}"), ("handle", handle_text(st)),
              ("gripper", gripper_angles(session)), ("motion", motion_text(st))]
    if st["message"]:
        status.append(("", st["message"]))
    keys = [*keymap_rows(), *EXTRA_KEYS] if show_keys else [("F1", "show the keymap")]
    grid = mujoco.mjtGridPos
    return [(int(grid.mjGRID_TOPLEFT), "\n".join(k for k, _ in status), "\n".join(v for _, v in status)),
            (int(grid.mjGRID_TOPRIGHT), "camera\nframes/s", f"{camera} (1/2/3)\n{fps:.0f}"),
            (int(grid.mjGRID_BOTTOMLEFT), "\n".join(k for k, _ in keys), "\n".join(v for _, v in keys))]


def _print(line: str) -> None:
    print(line, flush=True)


def teleoperate(catalog: Catalog, variant: str, device_name: str, *, out: Path, variants: Path = Path("variants"),
                front: str | None = None, seed: int = 0, max_seconds: float | None = None,
                on_message: Callable[[str], None] | None = None, robot: Robot | None = None, port: str | None = None,
                leader_id: str | None = None, calibration_dir: Path | None = None) -> list[EpisodeMeta]:
    """Teleoperate ``variant`` in a window with a device, episode after episode (see the module docstring), with
    the Hand-E or the arm ``robot`` (a catalog entry; one that cannot reach the handle is refused before the
    window opens): Enter saves an episode to ``out/<id>`` (each with its own id: nothing is overwritten),
    Backspace discards it, Esc or closing the window quits and discards the unsaved one. A leader arm device
    (``so101-leader``: serial ``port``, LeRobot's calibration ``leader_id`` in ``calibration_dir``) drives the
    arm joint by joint instead of the motion keys. Returns the saved episodes' metas."""
    from rik.episodes.record import check_seeds

    say = on_message or _print
    check_seeds(seed, 1)
    check_time_limit(max_seconds)
    device = make_device(device_name, robot, port, leader_id, calibration_dir)
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        _close(device)
        raise DeviceError("teleoperation needs a display for its window (no DISPLAY is set); use rik teleop "
                          "VARIANT --web for the browser station, or rik record VARIANT --strategy NAME")
    if "mujoco" not in sys.modules:
        os.environ["MUJOCO_GL"] = "glfw"  # the window's own OpenGL context, not an offscreen one
    from rik.combinator.build import ensure_variant
    from rik.sim.build import build_scene
    from rik.sim.robots.checks import require_reach

    open_display()  # before the (slow) scene: a display that cannot take a window fails at once
    try:
        scene = build_scene(ensure_variant(catalog, variant, variants), front, robot=robot)
        require_reach(scene)  # an arm that cannot reach the handle: refused before the window opens
    except BaseException:
        import glfw

        glfw.terminate()
        _close(device)
        raise
    session = TeleopSession(scene, out, operator=device_name, seed=seed, max_seconds=max_seconds)
    controls = Controls(session, device, say)
    window = TeleopWindow(scene, f"rik teleop: {variant} ({scene.robot_id})", controls.press)
    controls.window = window
    if isinstance(device, KeyboardDevice | SpaceMouseDevice):
        say(f"teleop window open: episode {session.episode}; hold W/A/S/D/R/F to move, arrows and Q/E to turn, "
            "Space grips, Enter saves, Backspace discards, Esc quits")
    else:
        say(f"teleop window open: episode {session.episode}; the {device_name} arm drives the {scene.robot_id} "
            "(recording starts when it moves), Enter saves, Backspace discards, Esc quits")
    try:
        _loop(session, controls, window)
    except KeyboardInterrupt:
        controls.quit = True
    finally:
        window.close()
        _close(device)
    if session.recording:
        say(f"quit without saving: episode {session.episode} ({session.recorder.steps / scene.control_fps:.1f} s) "
            "discarded")
    return controls.saved


def _close(device: KeyboardDevice | SpaceMouseDevice | LeaderArm) -> None:
    if not isinstance(device, KeyboardDevice | SpaceMouseDevice):
        device.close()


def _loop(session: TeleopSession, controls: Controls, window: TeleopWindow) -> None:
    """Poll, step on real time at the control rate (dropping steps when behind), draw, until the operator quits."""
    dt = 1.0 / session.scene.control_fps
    next_tick = last_status = time.perf_counter()
    frames, fps, fps_since = 0, 0.0, next_tick
    last_held: frozenset[str] = frozenset()
    was_up = False
    while not (controls.quit or window.closing):
        window.poll()
        held = controls.held()
        controls.apply(held)
        steps, next_tick = due_steps(time.perf_counter(), next_tick, dt)
        for _ in range(steps):
            session.tick()
        window.render(overlays(session, window.camera, fps, controls.keys_shown))
        frames += 1
        now = time.perf_counter()
        if now - fps_since >= 1.0:
            fps, frames, fps_since = frames / (now - fps_since), 0, now
        if session.time_up and not was_up:
            controls.say(f"time up ({session.max_seconds:g} s): Enter saves the episode, Backspace discards it")
        was_up = session.time_up
        if now - last_status >= STATUS_PERIOD or held != last_held:
            _print(f"{session.status_line()} | {gripper_angles(session)} | {fps:.0f} frames/s")
            last_status, last_held = now, held
        time.sleep(max(0.0, min(next_tick, now + 1.0 / MAX_FPS) - time.perf_counter()))
