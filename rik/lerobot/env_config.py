"""rik as a LeRobot environment: ``--env.type=rik`` for ``lerobot-train`` and ``lerobot-eval``.

Importing this module registers :class:`RikEnvConfig` with LeRobot under the name ``rik`` and rik's environment's
gymnasium id (``rik/OpenFront-v0``, by name: nothing of the environment is imported until one is made). LeRobot
0.6.1 imports it through the ``lerobot_env_rik`` plugin at start-up; ``rik eval`` imports it itself. The
environment draws each episode's variant from a catalog split by its seed (``rik.episodes.draw``), so
``lerobot-eval --seed S`` and ``rik eval --seed S`` run the same episodes.

The options that are rik's contract with the policy (:class:`~rik.lerobot.policy_io.PolicyIO`: ``--env.robot``,
``--env.action_frame``, ``--env.handle_shape``, ``--env.cameras``, ``--env.streams``, the image size) become one
contract (:attr:`RikEnvConfig.io`) that sets the features and is handed to the environment whole. ``auto`` (the
default of ``--env.action_frame``, ``--env.handle_shape`` and ``--env.cameras``) takes what the policy of
``--policy.path`` says: its contract file (:func:`rik.lerobot.policy_io.read_policy`), or, for a policy trained
before rik wrote one, the old guess from its input widths and training statistics, with a one-line note. Without a
policy: the world frame, no handle shape, no images. An option given by hand that contradicts the policy's contract
file, or cameras that leave out an image the policy reads, is refused with the names of both, before any episode
runs. Observations map onto exactly the feature names of ``rik export-lerobot`` (:data:`rik.lerobot.features.ENV_KEYS`:
``agent_pos`` -> ``observation.state``, ``environment_state`` -> ``observation.environment_state``, ``ee_pose`` ->
``observation.ee_pose`` for an arm that has one, ``pixels/<camera>[_rerendered]`` ->
``observation.images.<camera>[_rerendered]``). List-valued options are comma-separated strings
(``--env.presets=smooth,normal``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import gymnasium as gym
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig

from rik.lerobot.features import (
    ACTION,
    ENV_ENTRY_POINT,
    ENV_ID,
    ENV_KEYS,
    OBS_ENV_STATE,
    OBS_IMAGES,
    OBS_STATE,
    check_renderer,
    image_name,
)
from rik.lerobot.policy_io import AUTO, FIELD_TYPES, ContractError, PolicyIO, read_policy

__all__ = ["AUTO", "RikEnvConfig", "action_mode", "env_kwargs"]

LABELS = {"robot": "--env.robot={}", "action_frame": "--env.action_frame={}", "handle_shape": "--env.handle_shape={}",
          "cameras": "--env.cameras={}", "streams": "--env.streams={}",
          "image_size": "--env.observation_height/width {}", "fps": "--env.fps={}"}
"""How a problem names each contract option (:meth:`rik.lerobot.policy_io.PolicyIO.validate`)."""
OVERRIDABLE = ("action_frame", "handle_shape")
"""Contract options ``auto`` by default: given by hand, they must agree with the policy's contract file (and
replace a guess)."""
IMAGE_OPTIONS = ("cameras", "streams", "image_size")
"""Contract options that, with ``--env.cameras`` given by hand, render what they say (covering the policy's
images); the policy's contract says every other."""

if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point=ENV_ENTRY_POINT)


@EnvConfig.register_subclass("rik")
@dataclass
class RikEnvConfig(EnvConfig):
    """rik's drawer and door opening task (see the module docstring)."""

    task: str | None = "OpenFront-v0"
    robot: str = "hand-e"
    """The robot (rik catalog id): ``hand-e``, ``so100``, ``so101`` or ``panda-2f85``; its layout sets the
    features."""
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
    joints: str = "paper"
    """The hinges of doors: ``paper`` (the cell's preset) or ``measured`` (the split's real doors,
    ``rik catalog splits``); drawers and flaps keep the paper's presets."""
    cameras: str = AUTO
    """Cameras rendered for the policy, e.g. ``front,wrist``; empty for a state-only policy; ``auto``: those the
    policy of ``--policy.path`` reads (none without one)."""
    streams: str = "sim"
    """Image streams of those cameras: ``sim`` (MuJoCo) and/or ``rerendered`` (Mitsuba, slow without a GPU)."""
    observation_height: int = 96
    observation_width: int = 128
    spp: int = 16
    """Samples per pixel of the ``rerendered`` stream."""
    renderer: str = ""
    """Empty: each stream drawn by its own renderer. ``rerendered`` or ``sim``: every stream drawn by that one,
    under the stream's own keys (a policy of MuJoCo's pictures shown Mitsuba's, or the other way: the visual gap it
    pays)."""
    variants_dir: str = "variants"
    """Folder of built variants (missing ones are built there)."""
    action_frame: str = AUTO
    """The Hand-E's action position: ``world``, ``handle`` (from the handle's grasp point), ``gripper`` (from the
    gripper base; the environment state then holds the grasp point from the gripper too), or ``auto``: as the
    policy of ``--policy.path`` says (``world`` without one)."""
    handle_shape: str = AUTO
    """What of the handle's shape ends ``environment_state``: ``none``, ``kind`` or ``full``, or ``auto``: as the
    policy of ``--policy.path`` says (``none`` without one)."""
    environment_state: bool = True
    """Whether the environment gives ``environment_state`` (the simulator's state of the front): false for a policy
    of the robot's state and images only (its contract says so)."""
    render_mode: str = "rgb_array"
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from rik.episodes.draw import Draw
        from rik.errors import RikError
        from rik.sim.scene import CONTROL_FPS

        try:
            io = _fit_policy(self)
            io.validate(_catalog(), LABELS)
        except ContractError as exc:
            raise ValueError(str(exc)) from None
        try:  # the draw's names (split, types, presets, kinds, joints), before any environment is built
            Draw.parse(self.split, self.handle_types, self.presets, self.kinds, self.joints).check(_catalog())
        except RikError as exc:
            raise ValueError(f"--env.*: {exc}") from None
        try:
            check_renderer(self.renderer, f"--env.renderer={self.renderer}")
        except RikError as exc:
            raise ValueError(str(exc)) from None
        if io.fps != CONTROL_FPS:
            raise ValueError(f"--env.fps={io.fps}: rik's environment steps at {CONTROL_FPS} Hz, and a policy acts at "
                             "its dataset's rate; export the episodes at their own rate (without --fps) and train "
                             "it again")
        for name, value in _as_options(io).items():  # auto resolved: the options say the contract
            setattr(self, name, value)
        self.features, self.features_map = env_features(io)

    @property
    def io(self) -> PolicyIO:
        """The contract these options say (resolved by ``__post_init__``): every option named as a field of
        :class:`~rik.lerobot.policy_io.PolicyIO`, and the image size; no streams without cameras."""
        io = PolicyIO().with_options(_options(self), LABELS, auto=True)
        return io if io.cameras else replace(io, streams=())

    @classmethod
    def for_contract(cls, io: PolicyIO, **settings: Any) -> RikEnvConfig:
        """The config whose contract options say ``io`` (every field of it that is an option of the same name, list
        fields comma-separated, and the image size), with the environment's other ``settings``."""
        return cls(**_as_options(io), **settings)

    @property
    def package_name(self) -> str:
        return "lerobot_env_rik"

    @property
    def gym_id(self) -> str:
        return ENV_ID

    @property
    def gym_kwargs(self) -> dict:
        return {**env_kwargs(self), "max_episode_steps": self.episode_length}

    def create_envs(self, n_envs: int, use_async_envs: bool = False) -> dict[str, dict[int, gym.vector.VectorEnv]]:
        """The vector environment of ``lerobot-eval`` and ``lerobot-train``'s evaluation, as LeRobot's default but
        with Gymnasium's autoreset on the next step and each environment frozen once its episode ends
        (:class:`lerobot.envs.utils.FreezeAfterEpisodeEnd`, LeRobot's own, as its LIBERO environment has it).
        LeRobot's default resets a finished environment in the same step, without a seed: rik's environment then
        drew and built a variant that no episode used (for 4 episodes, 5 unused variants and a handle's CoACD
        decomposition, 2026-11-29). A rollout's explicit reset still starts each episode."""
        from lerobot.envs.utils import freeze_after_episode_end

        def make_one() -> gym.Env:
            return gym.make(self.gym_id, disable_env_checker=self.disable_env_checker, **self.gym_kwargs)

        make = [freeze_after_episode_end(make_one) for _ in range(n_envs)]
        mode = gym.vector.AutoresetMode.NEXT_STEP
        if use_async_envs and n_envs > 1:
            vec: gym.vector.VectorEnv = gym.vector.AsyncVectorEnv(make, autoreset_mode=mode, context="forkserver")
        else:
            vec = gym.vector.SyncVectorEnv(make, autoreset_mode=mode)
        return {self.type: {0: vec}}


def _catalog() -> Any:
    from rik.registry.load import load_catalog

    return load_catalog()


def _as_options(io: PolicyIO) -> dict[str, Any]:
    """The options of :class:`RikEnvConfig` that say ``io``: each field of it that is an option of the same name
    (list fields comma-separated), and the image size."""
    names = {f.name for f in fields(RikEnvConfig)}
    options = {name: ",".join(value) if isinstance(value, tuple) else value
               for name in FIELD_TYPES if name in names and (value := getattr(io, name)) is not None}
    return {**options, "observation_height": io.height, "observation_width": io.width}


def _options(cfg: RikEnvConfig) -> dict[str, Any]:
    """The contract's options of a config: its fields named as the contract's, and the image size."""
    options = {name: getattr(cfg, name) for name in FIELD_TYPES if name != "image_size" and hasattr(cfg, name)}
    return {**options, "image_size": (cfg.observation_height, cfg.observation_width)}


def _policy_folder() -> Path | None:
    """The local folder of the policy named on the command line (``--policy.path``, as LeRobot's own parser reads
    it), or None (no policy, or a hub id)."""
    from lerobot.configs.parser import get_path_arg

    path = get_path_arg("policy")
    return Path(path) if path and (Path(path) / "config.json").is_file() else None


def _fit_policy(cfg: RikEnvConfig) -> PolicyIO:
    """The contract of ``cfg``'s options, ``auto`` ones resolved from the command line's policy (its contract, or
    the guess for an older policy, noted in one line), refused where it contradicts the policy's contract file or
    leaves out an image the policy reads: otherwise ``lerobot-eval`` of an image policy on the state-only default
    ends in a ``KeyError`` inside the policy."""
    options = _options(cfg)
    folder = _policy_folder()
    if folder is None:
        cameras = "" if cfg.cameras == AUTO else cfg.cameras
        return PolicyIO().with_options({**options, "cameras": cameras}, LABELS, auto=True)
    contract = read_policy(folder, robot=cfg.robot, allow_rerendered=True)
    if contract.note:
        logging.getLogger(__name__).warning(contract.note)
    policy = contract.io
    for name in OVERRIDABLE:
        given = options[name]
        if contract.source is not None and given != AUTO and given != getattr(policy, name):
            raise ValueError(f"{LABELS[name].replace('{}', str(given))}: the policy's {contract.source} says "
                             f"{getattr(policy, name)}; leave it out (auto) or pass {getattr(policy, name)}")
    if cfg.cameras == AUTO:
        return policy.with_options({n: v for n, v in options.items() if n in OVERRIDABLE}, LABELS, auto=True)
    io = policy.with_options({n: v for n, v in options.items() if n in IMAGE_OPTIONS + OVERRIDABLE}, LABELS, auto=True)
    missing = [f"{OBS_IMAGES}.{m}" for m in policy.images if m not in io.images]
    if missing:
        raise ValueError(f"--env.cameras={cfg.cameras!r} --env.streams={cfg.streams!r}: the policy in {folder} "
                         f"reads {', '.join(missing)}, which they do not render; leave --env.cameras out (it then "
                         f"follows the policy) or pass --env.cameras={','.join(policy.cameras)}")
    if policy.images and io.image_size != policy.image_size:
        h, w = policy.image_size
        raise ValueError(f"--env.observation_height/width {io.height}x{io.width}: the policy in {folder} reads "
                         f"{h}x{w} images; pass --env.observation_height={h} --env.observation_width={w}, or leave "
                         "them and --env.cameras out")
    return io


def env_features(io: PolicyIO) -> tuple[dict[str, PolicyFeature], dict[str, str]]:
    """LeRobot's ``features`` (environment key -> feature) and ``features_map`` (environment key -> dataset feature)
    of a contract: the dataset's features (:meth:`PolicyIO.features`) under the environment's keys."""
    dataset = io.features()
    kinds = {OBS_STATE: FeatureType.STATE, OBS_ENV_STATE: FeatureType.ENV, "observation.ee_pose": FeatureType.STATE}
    features = {ACTION: PolicyFeature(type=FeatureType.ACTION, shape=tuple(dataset[ACTION]["shape"]))}
    features_map = {ACTION: ACTION}
    for key, env_key in ENV_KEYS.items():
        if key in dataset:
            features[env_key] = PolicyFeature(type=kinds[key], shape=tuple(dataset[key]["shape"]))
            features_map[env_key] = key
    for stream in io.streams:
        for camera in io.cameras:
            name = image_name(camera, stream)
            features[f"pixels/{name}"] = PolicyFeature(type=FeatureType.VISUAL, shape=(io.height, io.width, 3))
            features_map[f"pixels/{name}"] = f"{OBS_IMAGES}.{name}"
    return features, features_map


def action_mode(cfg: RikEnvConfig) -> str:
    """The environment's ``action_mode`` for a config: an arm's ``joints``; the Hand-E's ``absolute`` target pose,
    or ``handle`` / ``gripper`` where its action is measured from the handle or the gripper."""
    if not cfg.io.layout().is_pose:
        return "joints"
    return "absolute" if cfg.action_frame == "world" else cfg.action_frame


def env_kwargs(cfg: RikEnvConfig) -> dict[str, Any]:
    """The keyword arguments of ``rik.envs.open_front.OpenFrontEnv`` for a config: the draw, the contract whole
    (``io``), the action mode and the environment's own settings."""
    from rik.episodes.draw import Draw

    draw = Draw.parse(cfg.split, cfg.handle_types, cfg.presets, cfg.kinds, cfg.joints)
    return {"variant": None, "split": draw.split, "handle_types": draw.handle_types, "presets": draw.presets,
            "kinds": draw.kinds, "joints": draw.joints, "io": cfg.io, "action_mode": action_mode(cfg), "spp": cfg.spp,
            "episode_length": cfg.episode_length, "variants_dir": cfg.variants_dir, "render_mode": cfg.render_mode,
            "renderer": cfg.renderer or None}
