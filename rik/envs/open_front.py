"""``rik/OpenFront-v0``: a gymnasium environment that asks a policy to open a front of a rik variant.

- **episodes**: one variant (``variant=``), or drawn from a catalog split by the reset's seed (``split=``,
  :mod:`rik.episodes.draw`: the same seed gives the same variant, front and start pose everywhere); a reset may also
  name ``options={"variant": ..., "front": ..., "preset": ...}``. The gripper starts at a randomised pose in front of
  the handle: a reset with seed ``S`` starts where ``rik record --seed S`` starts on that variant;
- **contract** (``io=``, a :class:`rik.lerobot.policy_io.PolicyIO`): what the policy reads and writes, at once,
  as its dataset's ``meta/rik_policy_io.json`` says it: the robot, the handle's shape, the cameras, streams and
  image size, the action frame and the rate (rik steps at 20 Hz: another is refused). The keyword arguments
  ``robot=``, ``handle_shape=``, ``streams=``, ``cameras=``, ``image_size=`` (and ``images=True``: the sim stream)
  set single fields of it, and a ``handle`` or ``gripper`` ``action_mode`` its frame;
- **robot** (``robot=``, a catalog id, :mod:`rik.sim.robots.layout`): ``hand-e`` (rik's floating gripper, the
  default), ``so100``, ``so101`` or ``panda-2f85`` (an arm at its mount beside the handle);
- **observation** (a dict, shaped as LeRobot's environments return them): ``agent_pos`` = the robot's state as
  its export's ``observation.state`` holds it (the Hand-E's :data:`rik.sim.observation.ROBOT_STATE_NAMES`; an
  arm's joint positions and gripper, in its layout's names and units, e.g. the SO-100's degrees and gripper
  percent) and ``environment_state`` = the front's state (:mod:`rik.sim.observation`), float32, followed by the
  handle's shape with ``handle_shape="kind"`` or ``"full"`` (:data:`rik.sim.observation.HANDLE_SHAPES`; the
  export's ``--handle-shape``); for a robot whose
  layout has one (the Panda), ``ee_pose`` = its gripper frame in its base frame (``ee.x`` .. ``ee.wz``: m and a
  rotation vector, rad), float32; with image streams also ``pixels`` = ``{camera: uint8 HxWx3}`` (``front``,
  ``wrist``; ``front_rerendered`` for Mitsuba's stream); ``renderer="rerendered"`` (or ``"sim"``) draws every
  stream with that renderer under the stream's own keys: a policy trained on MuJoCo's pictures shown Mitsuba's, or
  the other way (the visual gap it pays);
- **action** (``action_mode``): ``delta``, 7 numbers in [-1, 1] (the last in [0, 1]): a target-pose change scaled by
  :data:`rik.sim.observation.MAX_DELTA` (m and rad per control step) and the gripper command (0 open, 1 closed
  with full force); or
  ``absolute``, the target pose itself (x, y, z m; pitch, yaw, roll rad) and the gripper command, as rik's
  episodes and the Hand-E's LeRobot exports record them; ``handle``, the same with the position measured from the
  handle's grasp point now (``environment_state``'s ``grasp_x`` .. ``grasp_z``; the export's
  ``--action-frame handle``); ``gripper``, measured from the gripper base's position now (``agent_pos``'s ``x``,
  ``y``, ``z``; the export's ``--action-frame gripper``), whose ``environment_state`` also holds the grasp point
  from the gripper base (:data:`rik.sim.observation.GRIPPER_GRASP_NAMES`, before the handle's shape); all four
  drive any robot (an arm through its IK); or, for an
  arm only, ``joints``: its layout's action vector, the numbers (and units) an arm's export writes as ``action``
  (the servos' joint targets and the gripper's goal, e.g. the SO-100's degrees and percent open), applied joint by
  joint (:meth:`rik.sim.scene.SimScene.step_joints`);
- **reward**: the gain in opening (fraction of the range) per step; **terminated** when the front is open to
  rik's success threshold (90 % of the range; ManiSkill3's OpenCabinetDrawer-v1 counts 75 %); **truncated**
  after ``episode_length`` control steps; ``info`` holds ``is_success``, the F/P/S ``outcome``
  (rik.sim.outcome), ``opening`` and ``max_opening``, and the episode's variant, front, handle type and preset.
  The last finished episode's result stays in :attr:`OpenFrontEnv.last_result` (vector environments reset a
  finished one at once).

Use: ``import rik.envs.open_front`` (registers the id), then ``gymnasium.make("rik/OpenFront-v0", variant=...)``.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from rik.errors import RikError
from rik.lerobot.features import CAMERAS, ENV_ENTRY_POINT, ENV_ID, check_renderer, env_state_names, image_name
from rik.lerobot.policy_io import PolicyIO
from rik.sim.observation import delta_to_absolute, environment_state, handle_shape_state
from rik.sim.outcome import SUCCESS_OPENING, classify
from rik.sim.robots.layout import ACTION_FRAMES, EE_NAMES, RobotLayout, robot_layout
from rik.sim.scene import CONTROL_FPS, SimScene

if TYPE_CHECKING:
    from rik.render.renderers import FrameRenderer

DEFAULT_VARIANT = "drawer-chest-80__two_point-bow-128__normal"
EPISODE_LENGTH = 400
"""Control steps of an episode before it is truncated: 20 s at 20 Hz; scripted demonstrations take up to 232."""
DEFAULT_ROBOT = "hand-e"
FRAME_LAYOUTS = {frame: robot_layout(None, frame) for frame in ACTION_FRAMES if frame != "world"}
"""The pose layouts whose action is measured from somewhere other than the world's origin (the handle's grasp point,
the gripper base): each is an ``action_mode`` of its own name."""
ACTION_MODES = ("delta", "absolute", *FRAME_LAYOUTS, "joints")
SCENE_CACHE = 16
"""Compiled scenes kept per environment (a split draws many variants)."""


class OpenFrontEnv(gym.Env):
    """Open a front of a rik variant with the simulated gripper (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": CONTROL_FPS}

    def __init__(self, variant: str | None = DEFAULT_VARIANT, front: str | None = None, *,
                 split: str | None = None, handle_types: tuple[str, ...] | None = None,
                 presets: tuple[str, ...] | None = None, kinds: tuple[str, ...] | None = None,
                 joints: str = "paper", io: PolicyIO | None = None, action_mode: str = "delta", images: bool = False,
                 robot: str | None = None, streams: tuple[str, ...] | None = None,
                 cameras: tuple[str, ...] | None = None, image_size: tuple[int, int] | None = None,
                 handle_shape: str | None = None, spp: int = 16, episode_length: int = EPISODE_LENGTH,
                 variants_dir: str | Path = "variants", render_mode: str | None = None,
                 catalog_paths: tuple[str, ...] = (), renderer: str | None = None) -> None:
        from rik.episodes.draw import DEFAULT_KINDS, DEFAULT_PRESETS, DEFAULT_TYPES, Draw
        from rik.registry.load import load_catalog

        if action_mode not in ACTION_MODES:
            raise RikError(f"action_mode '{action_mode}': use one of {', '.join(ACTION_MODES)}")
        if isinstance(episode_length, bool) or not isinstance(episode_length, int) or episode_length < 1:
            raise RikError(f"episode_length {episode_length!r}: must be a whole number of control steps, at least 1")
        self.io = _contract(io, action_mode, images, robot=robot, streams=streams, cameras=cameras,
                            image_size=image_size, handle_shape=handle_shape)
        if self.io.fps != CONTROL_FPS:
            raise RikError(f"fps {self.io.fps}: the environment steps at {CONTROL_FPS} Hz, and a policy acts at its "
                           "dataset's rate; export the episodes at their own rate (without --fps) and train again")
        check_renderer(renderer, f"renderer {renderer!r}")
        self._drawn_by = renderer = renderer or None
        if self.io.streams:
            _check_images(self.io if renderer is None else replace(self.io, streams=(renderer,)), spp)
        if isinstance(catalog_paths, str | Path):  # one path, not a tuple of its characters
            catalog_paths = (str(catalog_paths),)
        self._catalog = load_catalog([Path(p) for p in catalog_paths])
        entry = self._catalog.robot(self.io.robot)  # an unknown id: one line with suggestions
        self._robot = entry.as_arm
        self.layout = robot_layout(self._robot)
        if action_mode == "joints" and self.layout.is_pose:
            arms = ", ".join(r for r, e in self._catalog.robots.items() if e.as_arm is not None)
            raise RikError(f"action_mode 'joints': robot {self.io.robot} takes a target pose (action_mode 'delta', "
                           f"'absolute', 'handle' or 'gripper'); joint actions are for arms ({arms})")
        self._variants = Path(variants_dir)
        self._draw = None
        if split is not None or variant is None:
            self._draw = Draw(split, tuple(handle_types or DEFAULT_TYPES), tuple(presets or DEFAULT_PRESETS),
                              tuple(kinds or DEFAULT_KINDS), joints)
            self._draw.check(self._catalog)
        self._variant, self._front = variant, front
        self.action_mode = action_mode
        self._shape: np.ndarray | None = None  # the reset handle's shape (none: no numbers)
        self._spp = spp
        self._max_episode_steps = episode_length
        self.render_mode = render_mode
        self._scenes: OrderedDict[tuple[str, str | None], SimScene] = OrderedDict()
        self._renderers: dict[str, FrameRenderer] = {}
        self._renderer_model: Any = None
        self.reads_next: Callable[[], bool] | None = None
        """Whether the policy reads the next observation's images (None: it does; :mod:`rik.lerobot.observation_use`):
        a step whose images no policy reads keeps the last frames instead of rendering new ones."""
        self._pixels: dict[str, np.ndarray] | None = None
        self.frames_rendered = 0
        """Observations whose images were rendered (every camera and stream of the contract), since the start."""
        self.last_result: dict[str, Any] | None = None
        self._episode: dict[str, Any] = {"seed": -1}
        self._current: SimScene | None = None
        if self._draw is None or self.io.streams:  # a fixed variant, or the first of the draw to check the cameras
            first = self._draw.episode(self._catalog, 0).variant if self._draw is not None else str(variant)
            self.scene = self._scene(first, front)
        # else the first reset builds the variant it draws: one built now (the draw's seed 0) served no episode, and
        # cost each evaluation worker a variant and perhaps a handle's CoACD decomposition (2026-11-29)
        if self.io.streams:
            import mujoco

            known = [mujoco.mj_id2name(self.scene.model, mujoco.mjtObj.mjOBJ_CAMERA, i)
                     for i in range(self.scene.model.ncam)]
            for cam in self.io.cameras:
                if cam not in known:
                    raise RikError(f"cameras: no camera {cam!r} in the scene (cameras: {', '.join(known)})")
        self.task_description = ""
        spaces: dict[str, gym.Space[Any]] = {
            "agent_pos": gym.spaces.Box(-np.inf, np.inf, (len(self.layout.state_names),), np.float32)}
        if self.io.environment_state:
            spaces["environment_state"] = gym.spaces.Box(
                -np.inf, np.inf, (len(env_state_names(self.handle_shape, self._from_gripper)),), np.float32)
        if self.layout.ee_pose:
            spaces["ee_pose"] = gym.spaces.Box(-np.inf, np.inf, (len(EE_NAMES),), np.float32)
        if self.io.streams:
            h, w = self.io.image_size
            spaces["pixels"] = gym.spaces.Dict({image_name(c, s): gym.spaces.Box(0, 255, (h, w, 3), np.uint8)
                                                for s in self.io.streams for c in self.io.cameras})
        self.observation_space = gym.spaces.Dict(spaces)
        if action_mode == "joints":
            low, high = joint_action_bounds(self.layout)
        else:
            bound = 1.0 if action_mode == "delta" else np.inf
            low, high = np.array([-bound] * 6 + [0.0]), np.array([bound] * 6 + [1.0])
        self.action_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)

    @property
    def robot(self) -> str:
        """The robot's catalog id."""
        return self.layout.robot_id

    @property
    def handle_shape(self) -> str:
        """What of the handle's shape ends ``environment_state`` (the contract's)."""
        return self.io.handle_shape

    @property
    def _from_gripper(self) -> bool:
        """Whether ``environment_state`` holds the grasp point from the gripper (a gripper-frame contract)."""
        return self.io.action_frame == "gripper"

    # ---- scenes and images ----------------------------------------------------------------------------------
    @property
    def scene(self) -> SimScene:
        """The scene of the current episode (of the fixed variant before the first reset; an environment that draws
        its variants has none before it)."""
        if self._current is None:
            raise RikError("the environment has no scene before its first reset(): it draws each episode's variant")
        return self._current

    @scene.setter
    def scene(self, scene: SimScene) -> None:
        self._current = scene

    def _scene(self, variant: str, front: str | None) -> SimScene:
        from rik.combinator.build import ensure_variant
        from rik.sim.build import build_scene

        key = (variant, front)
        if key in self._scenes:
            self._scenes.move_to_end(key)
        else:
            self._scenes[key] = build_scene(ensure_variant(self._catalog, variant, self._variants), front,
                                            robot=self._robot)
            while len(self._scenes) > SCENE_CACHE:
                self._scenes.popitem(last=False)
        return self._scenes[key]

    def _renderer(self, stream: str) -> FrameRenderer:
        """The renderer that draws ``stream``: its own, or the one every stream is drawn with (``renderer=``); one
        per renderer kind and scene."""
        from rik.render.renderers import make_renderer
        from rik.render.streams import StreamSpec

        if self._renderer_model is not self.scene.model:
            self._close_renderers()
            self._renderer_model = self.scene.model
        kind = self._drawn_by or stream
        if kind not in self._renderers:
            h, w = self.io.image_size
            spec = StreamSpec(kind, w, h, spp=self._spp)  # type: ignore[arg-type]
            cameras = list(self.io.cameras) or ["front"]  # a state-only contract: the front camera films it
            self._renderers[kind] = make_renderer(self.scene.model, self.scene.data, cameras, spec,
                                                  self._catalog.finishes)
        return self._renderers[kind]

    def _close_renderers(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers = {}

    # ---- gym API ----------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        from rik.episodes.record import randomise_start
        from rik.registry.ids import VariantKey, parse_variant_id
        from rik.sim.observation import instruction

        super().reset(seed=seed)
        options = options or {}
        variant, front = self._variant, self._front
        episode_seed = -1 if seed is None else int(seed)
        if self._draw is not None and "variant" not in options:
            draw_seed = episode_seed if seed is not None else int(self.np_random.integers(2**62))
            drawn = self._draw.episode(self._catalog, draw_seed)
            variant, front = drawn.variant, drawn.front
        variant = options.get("variant", variant)
        if variant is None:
            raise RikError("reset: no variant (give variant= or split= to the environment, or options['variant'])")
        key = parse_variant_id(self._catalog, variant)
        if "preset" in options:
            key = VariantKey(key.base, key.handle, options["preset"])
        self.scene = self._scene(key.id, options.get("front", front))
        self.scene.reset()  # positions computed before the start pose is read: as rik record starts
        randomise_start(self.scene, self.np_random)
        self._target = self.scene.pose()
        self._opening = self._max_opening = self.scene.opening()
        self._steps = 0
        handle = self._catalog.handles[key.handle]
        self._shape = handle_shape_state(self._catalog, key.handle, self.handle_shape)
        self._episode = {"seed": episode_seed, "variant": key.id, "front": self.scene.front.id,
                         "handle_type": self._catalog.handle_type(handle).value, "preset": key.preset}
        self.task_description = instruction(self._catalog, key.handle, self.scene.front.kind)
        return self._obs(), self._info()

    @property
    def task(self) -> str:
        return self.task_description

    def _obs(self) -> dict[str, Any]:
        obs: dict[str, Any] = {"agent_pos": self.layout.state(self.scene).astype(np.float32)}
        if self.io.environment_state:  # the simulator's state of the front: none for a policy of images only
            obs["environment_state"] = environment_state(self.scene, self._shape, self._from_gripper).astype(
                np.float32)
        if self.layout.ee_pose:
            obs["ee_pose"] = self.layout.ee(self.scene).astype(np.float32)
        if self.io.streams:
            if self._pixels is None or self._steps == 0 or self.reads_next is None or self.reads_next():
                drawn: dict[str, dict[str, np.ndarray]] = {}  # by renderer: streams drawn by one are drawn once
                for stream in self.io.streams:
                    kind = self._drawn_by or stream
                    if kind not in drawn:
                        drawn[kind] = self._renderer(stream).render(self.scene.data, self._steps)
                self._pixels = {image_name(cam, stream): img for stream in self.io.streams
                                for cam, img in drawn[self._drawn_by or stream].items()}
                self.frames_rendered += 1
            obs["pixels"] = self._pixels
        return obs

    def _info(self) -> dict[str, Any]:
        opening = self.scene.opening()
        return {**self._episode, "opening": opening, "max_opening": self._max_opening, "outcome": classify(opening),
                "is_success": bool(opening >= SUCCESS_OPENING), "steps": self._steps}

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        if self.action_mode == "joints":
            a = np.asarray(action, np.float64).reshape(-1)
            names = self.layout.action_names
            if a.shape != (len(names),) or not np.all(np.isfinite(a)):
                raise RikError(f"action {a.tolist()}: robot {self.robot}'s joint action is {len(names)} finite "
                               f"numbers ({', '.join(names)})")
            targets, grip = self.layout.joint_targets(a)
            self.scene.step_joints(targets, grip)
        else:
            if self.action_mode == "delta":
                absolute = delta_to_absolute(self._target, action)
            else:
                a = np.asarray(action, np.float64).reshape(-1)
                if a.shape != (7,) or not np.all(np.isfinite(a)):
                    raise RikError(f"action {a.tolist()}: an {self.action_mode} action is 7 finite numbers (target "
                                   "x, y, z m; pitch, yaw, roll rad; gripper 0..1)")
                if self.action_mode in FRAME_LAYOUTS:  # the target from the handle or the gripper, as the policy
                    frame = FRAME_LAYOUTS[self.action_mode]  # saw them
                    a = frame.world_action(a, frame.frame_origin(self.scene))
                absolute = np.concatenate([a[:6], [float(np.clip(a[6], 0.0, 1.0))]])
            self._target = absolute[:6]
            self.scene.step(absolute)
        self._steps += 1
        opening = self.scene.opening()
        reward = float(opening - self._opening)
        self._opening = opening
        self._max_opening = max(self._max_opening, opening)
        terminated = opening >= SUCCESS_OPENING
        truncated = self._steps >= self._max_episode_steps
        info = self._info()
        if terminated or truncated:
            self.last_result = {**info, "final_opening": opening}
        return self._obs(), reward, bool(terminated), bool(truncated and not terminated), info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        stream = self.io.streams[0] if self.io.streams else "sim"
        images = self._renderer(stream).render(self.scene.data, self._steps)
        return images.get("front", next(iter(images.values())))

    def close(self) -> None:
        self._close_renderers()


def _contract(io: PolicyIO | None, action_mode: str, images: bool, **options: Any) -> PolicyIO:
    """The environment's contract: ``io`` (default: the Hand-E's, state only, every camera where images are asked
    for), with the keyword arguments that name its fields (None: the contract's) and ``images`` (the sim stream)
    over it, and a ``handle`` or ``gripper`` ``action_mode``'s frame; its values checked (one line naming the
    keyword)."""
    base = io if io is not None else PolicyIO(cameras=CAMERAS)
    if images and not options.get("streams") and not base.streams:
        options["streams"] = ("sim",)
    if action_mode in FRAME_LAYOUTS:
        options["action_frame"] = action_mode
    return base.with_options(options).validate()


def _check_images(io: PolicyIO, spp: int) -> None:
    """The image options the contract does not check, before anything is built: at least one camera, and ``spp`` as
    a stream allows it."""
    from rik.render.streams import StreamSpec

    if not io.cameras:
        raise RikError("cameras: give at least one camera for the images (e.g. front, wrist)")
    for stream in io.streams:
        StreamSpec(stream, io.width, io.height, spp=spp)  # type: ignore[arg-type]  # spp in range


def joint_action_bounds(layout: RobotLayout) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest joint action of an arm's layout: its joints' ranges and its gripper's open..closed, in
    the layout's units."""
    assert layout.robot is not None and layout.robot.joints is not None
    lo = np.array([j.range[0] for j in layout.robot.joints.joints] + [0.0])
    hi = np.array([j.range[1] for j in layout.robot.joints.joints] + [0.0])
    ends = np.stack([layout.action(np.array([0.0] * 6 + [g]), t) for t in (lo, hi) for g in (0.0, 1.0)])
    return ends.min(axis=0), ends.max(axis=0)


if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point=ENV_ENTRY_POINT)
