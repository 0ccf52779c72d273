"""``rik/OpenFront-v0``: a gymnasium environment that asks a policy to open a front of a rik variant.

- **reset** by variant, front and seed (``options={"variant": ..., "front": ..., "preset": ...}``); the gripper
  starts at a randomised pose in front of the handle;
- **observation** (a dict): ``state`` = gripper base pose (x, y, z m; pitch, yaw, roll rad), jaw opening (m),
  front joint position and velocity, pads' centre (m, world), opening (fraction of the range), normal force of
  the gripper on the front (N); with ``images=True`` also ``front`` and ``wrist`` camera images (uint8 HxWx3);
- **action**: 7 numbers in [-1, 1] (the last in [0, 1]): a target-pose change (scaled by :data:`MAX_DELTA`,
  m and rad per control step) and the gripper command (0 open, 1 closed with full force);
- **reward**: the gain in opening (fraction of the range) per step; **terminated** when the front is open to the
  success threshold; **truncated** after ``max_seconds``; ``info["outcome"]`` is F, P or S (rik.sim.outcome).

Use: ``import rik.sim.env`` (registers the id), then ``gymnasium.make("rik/OpenFront-v0", variant=...)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from rik.sim.outcome import SUCCESS_OPENING, classify
from rik.sim.scene import SimScene

if TYPE_CHECKING:
    import mujoco

ENV_ID = "rik/OpenFront-v0"
MAX_DELTA = np.array([0.02, 0.02, 0.02, 0.1, 0.1, 0.1])
"""Largest change of the target pose per control step: m for x, y, z; rad for pitch, yaw, roll."""
STATE_NAMES = ("x", "y", "z", "pitch", "yaw", "roll", "jaw_opening", "front_qpos", "front_qvel", "tcp_x", "tcp_y",
               "tcp_z", "opening", "contact_normal_force")
DEFAULT_VARIANT = "drawer-chest-80__two_point-bow-128__normal"


def observe_state(scene: SimScene) -> np.ndarray:
    """The proprioceptive and front state of :data:`STATE_NAMES`."""
    q, qd = scene.front_q()
    return np.concatenate([scene.pose(), [scene.finger_opening(), q, qd], scene.tcp(),
                           [scene.opening(), scene.contact_summary()["normal_force"]]]).astype(np.float64)


def observe(scene: SimScene, renderer: mujoco.Renderer | None = None) -> dict[str, np.ndarray]:
    """The observation dict (images when a renderer is given)."""
    obs = {"state": observe_state(scene)}
    if renderer is not None:
        for cam in ("front", "wrist"):
            renderer.update_scene(scene.data, camera=cam)
            obs[cam] = renderer.render().copy()
    return obs


def delta_to_absolute(target: np.ndarray, action: np.ndarray) -> np.ndarray:
    """An absolute action (target pose + gripper command) from the previous target and an environment action."""
    a = np.asarray(action, np.float64)
    return np.concatenate([np.asarray(target, np.float64) + np.clip(a[:6], -1, 1) * MAX_DELTA,
                           [float(np.clip(a[6], 0.0, 1.0))]])


class OpenFrontEnv(gym.Env):
    """Open a front of a rik variant with the simulated gripper (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, variant: str = DEFAULT_VARIANT, front: str | None = None, *, images: bool = False,
                 image_size: tuple[int, int] = (96, 128), max_seconds: float = 20.0,
                 variants_dir: str | Path = "variants", render_mode: str | None = None,
                 catalog_paths: tuple[str, ...] = ()) -> None:
        from rik.registry.load import load_catalog

        self._catalog = load_catalog([Path(p) for p in catalog_paths])
        self._variants = Path(variants_dir)
        self._variant, self._front = variant, front
        self._images, self._size = images, image_size
        self._max_seconds = max_seconds
        self.render_mode = render_mode
        self._scenes: dict[tuple[str, str | None], SimScene] = {}
        self._renderer: mujoco.Renderer | None = None
        self._renderer_model: mujoco.MjModel | None = None
        self.scene = self._scene(variant, front)
        n = len(STATE_NAMES)
        spaces: dict[str, gym.Space[Any]] = {"state": gym.spaces.Box(-np.inf, np.inf, (n,), np.float64)}
        if images:
            h, w = image_size
            spaces |= {c: gym.spaces.Box(0, 255, (h, w, 3), np.uint8) for c in ("front", "wrist")}
        self.observation_space = gym.spaces.Dict(spaces)
        self.action_space = gym.spaces.Box(np.array([-1.0] * 6 + [0.0], np.float32), np.ones(7, np.float32),
                                           dtype=np.float32)

    def _scene(self, variant: str, front: str | None) -> SimScene:
        from rik.sim.record import variant_dir
        from rik.sim.scene import build_scene

        key = (variant, front)
        if key not in self._scenes:
            self._scenes[key] = build_scene(variant_dir(self._catalog, variant, self._variants), front)
        return self._scenes[key]

    def _get_renderer(self) -> mujoco.Renderer:
        import mujoco

        if self._renderer_model is not self.scene.model:
            h, w = self._size
            self._renderer = mujoco.Renderer(self.scene.model, h, w)
            self._renderer_model = self.scene.model
        return self._renderer

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        from rik.combinator.ids import VariantKey, parse_variant_id
        from rik.sim.record import randomise_start

        super().reset(seed=seed)
        options = options or {}
        variant = options.get("variant", self._variant)
        if "preset" in options:
            key = parse_variant_id(self._catalog, variant)
            variant = VariantKey(key.base, key.handle, options["preset"]).id
        self.scene = self._scene(variant, options.get("front", self._front))
        self.scene.reset()  # positions computed before the start pose is read: as rik record starts
        randomise_start(self.scene, self.np_random)
        self._target = self.scene.pose()
        self._opening = self.scene.opening()
        self._max_opening = self._opening
        self._steps = 0
        return self._obs(), self._info()

    def _obs(self) -> dict[str, np.ndarray]:
        return observe(self.scene, self._get_renderer() if self._images else None)

    def _info(self) -> dict[str, object]:
        return {"variant": self.scene.info["id"], "front": self.scene.front.id, "opening": self.scene.opening(),
                "max_opening": self._max_opening, "outcome": classify(self.scene.opening())}

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        absolute = delta_to_absolute(self._target, action)
        self._target = absolute[:6]
        self.scene.step(absolute)
        self._steps += 1
        opening = self.scene.opening()
        reward = float(opening - self._opening)
        self._opening = opening
        self._max_opening = max(self._max_opening, opening)
        terminated = opening >= SUCCESS_OPENING
        truncated = self._steps >= int(self._max_seconds * self.scene.control_fps)
        return self._obs(), reward, bool(terminated), bool(truncated), self._info()

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        r = self._get_renderer()
        r.update_scene(self.scene.data, camera="front")
        return r.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point="rik.sim.env:OpenFrontEnv")
