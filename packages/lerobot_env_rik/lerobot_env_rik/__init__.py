"""rik as a LeRobot environment: ``--env.type=rik`` for ``lerobot-train`` and ``lerobot-eval``.

LeRobot 0.6.1 imports this package at start-up (``register_third_party_plugins`` imports every installed
distribution named ``lerobot_env_*``), which registers :class:`RikEnvConfig` under the name ``rik``. The
environment is rik's ``rik/OpenFront-v0``, drawing each episode's variant from a catalog split by its seed
(``rik.episodes.draw``), so ``lerobot-eval --seed S`` and ``rik eval --seed S`` run the same episodes.

``--env.robot`` picks the robot (a catalog id: ``hand-e``, the default, ``so100`` or ``panda-2f85``); the features
follow that robot's LeRobot layout (:mod:`rik.sim.robots.layout`), so a policy trained on a robot's export runs
with that robot: the Hand-E takes the absolute action (target pose and gripper, 7 numbers), an arm its joint
action (``action_mode="joints"``: the joint targets and gripper in its export's names and units, e.g. the SO-100's
6 numbers in degrees and gripper percent). Observations map onto exactly the feature names of
``rik export-lerobot``:

====================================  =====================================================================
environment key                       dataset / policy feature
====================================  =====================================================================
``agent_pos``                         ``observation.state`` (the robot's state, in its layout)
``environment_state``                 ``observation.environment_state`` (the front's; the grasp point from the
                                      gripper after it with ``--env.action_frame=gripper``, then the handle's shape
                                      with ``--env.handle_shape``; both follow the policy by default)
``ee_pose`` (Panda only)              ``observation.ee_pose`` (``ee.x`` .. ``ee.wz``, in the arm's base)
``pixels/front``                      ``observation.images.front``
``pixels/front_rerendered``           ``observation.images.front_rerendered``
====================================  =====================================================================

lerobot 0.6.1's ``preprocess_observation`` maps ``agent_pos``, ``environment_state`` and ``pixels`` by name and
passes any other array key ``k`` through as ``observation.k``: ``ee_pose`` becomes ``observation.ee_pose``, the
name the Panda's export gives it.

List-valued options are comma-separated strings (``--env.presets=smooth,normal``); ``--env.cameras=`` (empty)
evaluates a state-only policy without rendering. The default, ``--env.cameras=auto``, renders what the policy of
``--policy.path`` reads (``lerobot-eval``: its cameras, streams and image size, from its ``config.json``), and
nothing where no policy folder is given (``lerobot-train`` of a state-only policy); cameras given by hand that
leave out an image the policy reads are refused with the names of both, before any episode runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_ENV_STATE, OBS_IMAGES, OBS_STATE

import rik.envs.open_front  # noqa: F401  (registers rik/OpenFront-v0 with gymnasium)
from rik.sim.feature_keys import EE_POSE
from rik.sim.robots.layout import EE_NAMES, RobotLayout, robot_layout

__all__ = ["AUTO", "RikEnvConfig", "action_mode", "env_kwargs", "robot_layout_of"]

AUTO = "auto"
"""``--env.cameras=auto``: the cameras of the command line's policy."""


def robot_layout_of(robot: str) -> RobotLayout:
    """The LeRobot layout of a catalog robot (an unknown id is a one-line ``UnknownIdError``)."""
    from rik.registry.load import load_catalog

    entry = load_catalog().robot(robot)
    return robot_layout(entry.as_arm)


def _names(text: str) -> tuple[str, ...]:
    return tuple(t.strip() for t in text.split(",") if t.strip())


@EnvConfig.register_subclass("rik")
@dataclass
class RikEnvConfig(EnvConfig):
    """rik's drawer and door opening task (see the module docstring)."""

    task: str | None = "OpenFront-v0"
    robot: str = "hand-e"
    """The robot (rik catalog id): ``hand-e``, ``so100`` or ``panda-2f85``; its layout sets the features."""
    fps: int = 20
    """Control rate, Hz (rik's scenes step at 20 Hz; datasets exported at their own rate match it)."""
    episode_length: int = 400
    """Control steps before an episode is cut off (20 s; scripted demonstrations take up to 232)."""
    split: str = "test"
    """Catalog split the handles come from: train, val or test (``rik catalog splits``); ``all`` for every one."""
    handle_types: str = "knob,finger_pull,two_point"
    presets: str = "smooth,normal,high"
    kinds: str = "drawer"
    """Front kinds of the base units drawn (drawer, door, flap, ...)."""
    cameras: str = AUTO
    """Cameras rendered for the policy, e.g. ``front,wrist``; empty for a state-only policy; ``auto``: those the
    policy of ``--policy.path`` reads (none without one)."""
    streams: str = "sim"
    """Image streams of those cameras: ``sim`` (MuJoCo) and/or ``rerendered`` (Mitsuba, slow without a GPU)."""
    observation_height: int = 96
    observation_width: int = 128
    spp: int = 16
    """Samples per pixel of the ``rerendered`` stream."""
    variants_dir: str = "variants"
    """Folder of built variants (missing ones are built there)."""
    action_frame: str = AUTO
    """The Hand-E's action position: ``world``, ``handle`` (from the handle's grasp point: an export made with
    ``--action-frame handle``), ``gripper`` (from the gripper base: ``--action-frame gripper``; the environment
    state then holds the grasp point from the gripper too), or ``auto``: the frame of the policy of
    ``--policy.path`` (its environment state's width, else its training data's statistics tell), ``world`` without
    one."""
    handle_shape: str = AUTO
    """What of the handle's shape ends ``environment_state``: ``none``, ``kind`` or ``full``, as the export the
    policy was trained on (``--handle-shape``), or ``auto``: as the policy of ``--policy.path`` reads it (its input
    width), ``none`` without one."""
    render_mode: str = "rgb_array"
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from rik.sim.observation import HANDLE_SHAPES, env_state_names, image_name
        from rik.sim.robots.layout import ACTION_FRAMES

        layout = robot_layout_of(self.robot)
        if self.action_frame not in (AUTO, *ACTION_FRAMES):
            raise ValueError(f"--env.action_frame={self.action_frame!r}: use one of {AUTO}, {', '.join(ACTION_FRAMES)}")
        if self.handle_shape not in (AUTO, *HANDLE_SHAPES):
            raise ValueError(f"--env.handle_shape={self.handle_shape!r}: use one of {AUTO}, {', '.join(HANDLE_SHAPES)}")
        _fit_policy(self, layout)
        if self.action_frame == AUTO:
            self.action_frame = "world"
        if self.handle_shape == AUTO:
            self.handle_shape = "none"
        if self.action_frame != "world" and not layout.is_pose:
            raise ValueError(f"--env.action_frame={self.action_frame}: robot {self.robot} acts with joint targets, "
                             f"which have no {self.action_frame} frame (it is the Hand-E's pose action's)")
        env_width = len(env_state_names(self.handle_shape, self.action_frame == "gripper"))
        self.features = {ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(len(layout.action_names),)),
                         "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(len(layout.state_names),)),
                         "environment_state": PolicyFeature(type=FeatureType.ENV, shape=(env_width,))}
        self.features_map = {ACTION: ACTION, "agent_pos": OBS_STATE, "environment_state": OBS_ENV_STATE}
        if layout.ee_pose:
            self.features["ee_pose"] = PolicyFeature(type=FeatureType.STATE, shape=(len(EE_NAMES),))
            self.features_map["ee_pose"] = EE_POSE
        shape = (self.observation_height, self.observation_width, 3)
        for stream in _names(self.streams) if _names(self.cameras) else ():
            for cam in _names(self.cameras):
                name = image_name(cam, stream)
                self.features[f"pixels/{name}"] = PolicyFeature(type=FeatureType.VISUAL, shape=shape)
                self.features_map[f"pixels/{name}"] = f"{OBS_IMAGES}.{name}"

    @property
    def package_name(self) -> str:
        return "lerobot_env_rik"

    @property
    def gym_id(self) -> str:
        return "rik/OpenFront-v0"

    @property
    def gym_kwargs(self) -> dict:
        return {**env_kwargs(self), "max_episode_steps": self.episode_length}


def _policy_folder() -> Path | None:
    """The local folder of the policy named on the command line (``--policy.path``, as LeRobot's own parser reads
    it), or None (no policy, or a hub id)."""
    from lerobot.configs.parser import get_path_arg

    path = get_path_arg("policy")
    return Path(path) if path and (Path(path) / "config.json").is_file() else None


def _fit_policy(cfg: RikEnvConfig, layout: RobotLayout) -> None:
    """Resolve ``cameras=auto`` from the command line's policy, and refuse cameras that leave out one of its
    images: otherwise ``lerobot-eval`` of an image policy on the state-only default ends in a ``KeyError`` inside
    the policy."""
    folder = _policy_folder()
    if folder is None:
        if cfg.cameras == AUTO:
            cfg.cameras = ""
        return
    from rik.evaluation.load import policy_needs
    from rik.sim.observation import image_name

    needs = policy_needs(folder, allow_rerendered=True, layout=layout)
    if cfg.action_frame == AUTO:
        cfg.action_frame = needs.action_frame
    if cfg.handle_shape == AUTO:
        cfg.handle_shape = needs.handle_shape
    if cfg.cameras == AUTO:
        cfg.cameras = ",".join(needs.cameras)
        if needs.cameras:
            cfg.streams = ",".join(needs.streams)
            cfg.observation_height, cfg.observation_width = needs.image_size
        return
    given = {image_name(c, s) for c in _names(cfg.cameras) for s in _names(cfg.streams)}
    wanted = [image_name(c, s) for c in needs.cameras for s in needs.streams]
    missing = [w for w in wanted if w not in given]
    if missing:
        raise ValueError(f"--env.cameras={cfg.cameras!r} --env.streams={cfg.streams!r}: the policy in {folder} "
                         f"reads {', '.join(f'{OBS_IMAGES}.{m}' for m in missing)}, which they do not render; "
                         f"leave --env.cameras out (it then follows the policy) or pass "
                         f"--env.cameras={','.join(needs.cameras)}")
    if needs.cameras and (cfg.observation_height, cfg.observation_width) != needs.image_size:
        h, w = needs.image_size
        raise ValueError(f"--env.observation_height/width {cfg.observation_height}x{cfg.observation_width}: the "
                         f"policy in {folder} reads {h}x{w} images; pass --env.observation_height={h} "
                         f"--env.observation_width={w}, or leave them and --env.cameras out")


def action_mode(cfg: RikEnvConfig) -> str:
    """The environment's ``action_mode`` for a config: an arm's ``joints``; the Hand-E's ``absolute`` target pose,
    or ``handle`` / ``gripper`` where its action is measured from the handle or the gripper."""
    if not robot_layout_of(cfg.robot).is_pose:
        return "joints"
    return "absolute" if cfg.action_frame == "world" else cfg.action_frame


def env_kwargs(cfg: RikEnvConfig) -> dict:
    """The keyword arguments of ``rik.envs.open_front.OpenFrontEnv`` for a config."""
    from rik.episodes.draw import Draw

    draw = Draw.parse(cfg.split, cfg.handle_types, cfg.presets, cfg.kinds)
    cameras = _names(cfg.cameras)
    return {"variant": None, "split": draw.split, "handle_types": draw.handle_types, "presets": draw.presets,
            "kinds": draw.kinds, "robot": cfg.robot,
            "action_mode": action_mode(cfg),
            "streams": _names(cfg.streams) if cameras else (),
            "cameras": cameras or ("front",), "image_size": (cfg.observation_height, cfg.observation_width),
            "spp": cfg.spp, "episode_length": cfg.episode_length, "variants_dir": cfg.variants_dir,
            "render_mode": cfg.render_mode, "handle_shape": cfg.handle_shape}
