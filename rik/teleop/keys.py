"""The teleoperation keymap, one table for the viewer window and the browser station, and the speeds a held key
or a full stick deflection commands. Pure data: no simulator imports.

A held key commands a velocity of the target pose (continuous motion while it is held), not a step per press.
Directions are as the operator sees the furniture from its front: +x is on the operator's left (rik's base-unit
frame has +y out of the front).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LINEAR_SPEED = 0.10
"""Target speed of a held translation key or a full stick deflection, m/s."""
ANGULAR_SPEED = 0.8
"""Target speed of a held rotation key or a full stick deflection, rad/s."""
FINE_FACTOR = 0.25
"""Speed factor while the fine-motion modifier (Shift, or a shoulder button) is held."""
LEAD = (0.06, 0.15)
"""How far the target may run ahead of the gripper: m for the position, rad per angle. A target pushed into the
furniture waits there instead of winding up (beyond this the servo's force cap is reached anyway)."""
AXES = ("x", "y", "z", "pitch", "yaw", "roll")
"""The six velocity axes of the target pose, in the order of a pose vector."""


@dataclass(frozen=True)
class KeyBinding:
    """A key that moves the target along ``axis`` (index into :data:`AXES`) in the direction ``sign`` while held."""

    code: str
    """The key as the browser's ``KeyboardEvent.code`` names it (``KeyW``, ``ArrowUp``)."""
    glfw: str
    """The key's name in GLFW (``W``, ``UP``): ``glfw.KEY_<name>``."""
    label: str
    """The key as printed on the keymap."""
    axis: int
    sign: float
    does: str


MOTION_KEYS = (
    KeyBinding("KeyW", "W", "W", 1, -1.0, "towards the furniture"),
    KeyBinding("KeyS", "S", "S", 1, 1.0, "away from the furniture"),
    KeyBinding("KeyA", "A", "A", 0, 1.0, "left"),
    KeyBinding("KeyD", "D", "D", 0, -1.0, "right"),
    KeyBinding("KeyR", "R", "R", 2, 1.0, "up"),
    KeyBinding("KeyF", "F", "F", 2, -1.0, "down"),
    KeyBinding("ArrowDown", "DOWN", "Down", 3, 1.0, "pitch: fingers down"),
    KeyBinding("ArrowUp", "UP", "Up", 3, -1.0, "pitch: fingers up"),
    KeyBinding("ArrowLeft", "LEFT", "Left", 4, 1.0, "yaw left"),
    KeyBinding("ArrowRight", "RIGHT", "Right", 4, -1.0, "yaw right"),
    KeyBinding("KeyQ", "Q", "Q", 5, 1.0, "roll left"),
    KeyBinding("KeyE", "E", "E", 5, -1.0, "roll right"),
)
"""Held keys that move the target (WASD + R/F for position, arrows + Q/E for orientation)."""

COMMAND_KEYS = {
    "grip": ("Space", "SPACE", "Space", "close / open the gripper"),
    "motion": ("KeyM", "M", "M", "W / S along the front's path while holding its handle, or frame-fixed"),
    "fine": ("ShiftLeft", "LEFT_SHIFT", "Shift", "hold for fine motion (x0.25)"),
    "save": ("Enter", "ENTER", "Enter", "save the episode and start the next"),
    "discard": ("Backspace", "BACKSPACE", "Backspace", "discard the episode and start again"),
}
"""Command -> (browser code, GLFW name, label, what it does)."""


def velocity(held: set[str] | frozenset[str], *, fine: bool = False) -> np.ndarray:
    """The target's velocity command in [-1, 1] per :data:`AXES` from the held keys' browser codes (opposite keys
    cancel); scaled by :data:`FINE_FACTOR` with ``fine``."""
    command = np.zeros(6)
    for key in MOTION_KEYS:
        if key.code in held:
            command[key.axis] += key.sign
    return np.clip(command, -1.0, 1.0) * (FINE_FACTOR if fine else 1.0)


def keymap_rows() -> list[tuple[str, str]]:
    """(keys, what they do) for an on-screen keymap: paired keys share a row."""
    rows = []
    for a, b in zip(MOTION_KEYS[::2], MOTION_KEYS[1::2], strict=True):
        rows.append((f"{a.label} / {b.label}", f"{a.does} / {b.does}"))
    rows += [(label, does) for _, _, label, does in COMMAND_KEYS.values()]
    return rows
