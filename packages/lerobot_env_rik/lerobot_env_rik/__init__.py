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
``environment_state``                 ``observation.environment_state`` (the front's)
``ee_pose`` (Panda only)              ``observation.ee_pose`` (``ee.x`` .. ``ee.wz``, in the arm's base)
``pixels/front``                      ``observation.images.front``
``pixels/front_rerendered``           ``observation.images.front_rerendered``
====================================  =====================================================================

lerobot 0.6.1's ``preprocess_observation`` maps ``agent_pos``, ``environment_state`` and ``pixels`` by name and
passes any other array key ``k`` through as ``observation.k``: ``ee_pose`` becomes ``observation.ee_pose``, the
name the Panda's export gives it.

List-valued options are comma-separated strings (``--env.presets=smooth,normal``); ``--env.cameras=`` (empty)
evaluates a state-only policy without rendering.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_ENV_STATE, OBS_IMAGES, OBS_STATE

import rik.envs.open_front  # noqa: F401  (registers rik/OpenFront-v0 with gymnasium)
from rik.sim.feature_keys import EE_POSE
from rik.sim.robots.layout import EE_NAMES, RobotLayout, robot_layout

__all__ = ["RikEnvConfig", "env_kwargs", "robot_layout_of"]


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
    cameras: str = ""
    """Cameras rendered for the policy, e.g. ``front,wrist``; empty for a state-only policy."""
    streams: str = "sim"
    """Image streams of those cameras: ``sim`` (MuJoCo) and/or ``rerendered`` (Mitsuba, slow without a GPU)."""
    observation_height: int = 96
    observation_width: int = 128
    spp: int = 16
    """Samples per pixel of the ``rerendered`` stream."""
    variants_dir: str = "variants"
    """Folder of built variants (missing ones are built there)."""
    render_mode: str = "rgb_array"
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from rik.sim.observation import ENV_STATE_NAMES, image_name

        layout = robot_layout_of(self.robot)
        self.features = {ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(len(layout.action_names),)),
                         "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(len(layout.state_names),)),
                         "environment_state": PolicyFeature(type=FeatureType.ENV, shape=(len(ENV_STATE_NAMES),))}
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


def env_kwargs(cfg: RikEnvConfig) -> dict:
    """The keyword arguments of ``rik.envs.open_front.OpenFrontEnv`` for a config."""
    from rik.episodes.draw import Draw

    draw = Draw.parse(cfg.split, cfg.handle_types, cfg.presets, cfg.kinds)
    cameras = _names(cfg.cameras)
    return {"variant": None, "split": draw.split, "handle_types": draw.handle_types, "presets": draw.presets,
            "kinds": draw.kinds, "robot": cfg.robot,
            "action_mode": "absolute" if robot_layout_of(cfg.robot).is_pose else "joints",
            "streams": _names(cfg.streams) if cameras else (),
            "cameras": cameras or ("front",), "image_size": (cfg.observation_height, cfg.observation_width),
            "spp": cfg.spp, "episode_length": cfg.episode_length, "variants_dir": cfg.variants_dir,
            "render_mode": cfg.render_mode}
