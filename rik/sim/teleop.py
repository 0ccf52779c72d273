"""Target-pose teleoperation: the keyboard in MuJoCo's viewer, or a 3Dconnexion SpaceMouse. Every device feeds
the same :class:`rik.sim.episode.EpisodeRecorder` at the scene's fixed control rate.

Keyboard keymap (one press moves the target one step; hold to repeat):

======================  ==============================================
I / K                   towards / away from the front (world -y / +y)
J / L                   left / right (world -x / +x)
U / O                   up / down (world +z / -z)
R / F                   pitch: fingers down / up
T / G                   yaw left / right
Y / H                   roll about the approach axis
C / V                   close / open the gripper
Enter                   finish: save the episode and quit
Backspace               discard the episode and quit
======================  ==============================================
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.scene import SimScene

POSITION_STEP = 0.005
"""m per key press."""
ANGLE_STEP = np.radians(3.0)
"""rad per key press."""
SPACEMOUSE_SPEED = (0.15, np.radians(60.0))
"""Full deflection of the SpaceMouse: m/s and rad/s."""


class DeviceError(RikError):
    """A teleoperation device is missing, not connected, or cannot run here."""


def _keymap() -> dict[int, tuple[int, float]]:
    """GLFW key code -> (action index, change)."""
    keys = {"I": (1, -POSITION_STEP), "K": (1, POSITION_STEP), "J": (0, -POSITION_STEP), "L": (0, POSITION_STEP),
            "U": (2, POSITION_STEP), "O": (2, -POSITION_STEP), "R": (3, ANGLE_STEP), "F": (3, -ANGLE_STEP),
            "T": (4, ANGLE_STEP), "G": (4, -ANGLE_STEP), "Y": (5, ANGLE_STEP), "H": (5, -ANGLE_STEP)}
    return {ord(k): v for k, v in keys.items()}


KEY_ENTER, KEY_BACKSPACE = 257, 259
"""GLFW key codes."""


@dataclass
class KeyboardDevice:
    """Key presses in the viewer window nudge the target pose (see the module docstring)."""

    name: str = "keyboard"
    target: np.ndarray = field(default_factory=lambda: np.zeros(7))
    finished: str | None = None
    """``save`` or ``discard`` once the operator ends the episode."""

    def start(self, scene: SimScene) -> None:
        self.target = np.concatenate([scene.pose(), [0.0]])

    def on_key(self, key: int) -> None:
        keymap = _keymap()
        if key in keymap:
            i, change = keymap[key]
            self.target[i] += change
        elif key == ord("C"):
            self.target[6] = 1.0
        elif key == ord("V"):
            self.target[6] = 0.0
        elif key == KEY_ENTER:
            self.finished = "save"
        elif key == KEY_BACKSPACE:
            self.finished = "discard"

    def read(self, dt: float) -> np.ndarray:
        return self.target.copy()


@dataclass
class SpaceMouseDevice:
    """A 3Dconnexion SpaceMouse through ``pyspacemouse``: deflection sets the target's velocity; the left button
    closes the gripper, the right one opens it; the keyboard's Enter and Backspace end the episode."""

    name: str = "spacemouse"
    target: np.ndarray = field(default_factory=lambda: np.zeros(7))
    finished: str | None = None
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

    def start(self, scene: SimScene) -> None:
        self.target = np.concatenate([scene.pose(), [0.0]])

    def on_key(self, key: int) -> None:
        if key == KEY_ENTER:
            self.finished = "save"
        elif key == KEY_BACKSPACE:
            self.finished = "discard"

    def read(self, dt: float) -> np.ndarray:
        s = self._mouse.read()
        lin, ang = SPACEMOUSE_SPEED
        # device axes: x right, y forward, z up -> world: forward is -y (towards the front)
        self.target[:3] += dt * lin * np.array([s.x, -s.y, s.z])
        self.target[3:6] += dt * ang * np.array([-s.pitch, -s.yaw, s.roll])
        if s.buttons and s.buttons[0]:
            self.target[6] = 1.0
        if len(s.buttons) > 1 and s.buttons[1]:
            self.target[6] = 0.0
        return self.target.copy()


DEVICES = {"keyboard": KeyboardDevice, "spacemouse": SpaceMouseDevice}


def make_device(name: str) -> KeyboardDevice | SpaceMouseDevice:
    """A device by name; a SpaceMouse is opened here, so a missing one fails before anything else happens."""
    if name not in DEVICES:
        raise DeviceError(f"unknown device '{name}' (devices: {', '.join(DEVICES)})")
    device = DEVICES[name]()
    if isinstance(device, SpaceMouseDevice):
        device.open()
    return device


def teleoperate(catalog: Catalog, variant: str, device_name: str, *, out: Path, variants: Path = Path("variants"),
                front: str | None = None, seed: int = 0, max_seconds: float = 120.0) -> EpisodeMeta | None:
    """Teleoperate ``variant`` in MuJoCo's viewer with a device, recording at the control rate; the episode is
    written when the operator presses Enter (or closes the window), not at all on Backspace or Ctrl+C.
    Returns the episode's meta, or ``None`` when discarded."""
    from rik.sim.record import check_seeds

    check_seeds(seed, 1)
    device = make_device(device_name)
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise DeviceError("teleoperation needs a display for MuJoCo's viewer (no DISPLAY is set); for headless "
                          "recording use rik record VARIANT --strategy NAME")
    import mujoco.viewer

    from rik.sim.episode import EpisodeRecorder, write_episode
    from rik.sim.record import variant_dir
    from rik.sim.scene import build_scene

    scene = build_scene(variant_dir(catalog, variant, variants), front)
    device.start(scene)
    recorder = EpisodeRecorder(scene)
    dt = 1.0 / scene.control_fps
    with mujoco.viewer.launch_passive(scene.model, scene.data, key_callback=device.on_key) as viewer:
        next_tick = time.perf_counter()
        while viewer.is_running() and device.finished is None and recorder.steps * dt < max_seconds:
            recorder.step(device.read(dt))
            viewer.sync()
            next_tick += dt
            time.sleep(max(0.0, next_tick - time.perf_counter()))
    if device.finished == "discard" or recorder.steps == 0:
        return None
    from rik.sim.episode import episode_id

    return write_episode(recorder, out, episode=episode_id(scene.info["id"], scene.front.id, device_name, seed),
                         operator=device_name, operator_kind="device", seed=seed)
