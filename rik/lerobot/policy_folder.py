"""What a saved LeRobot policy reads, from its folder: its ``config.json`` (checked by
:mod:`rik.lerobot.policy_files`), its inputs checked against what rik's environment supplies for a robot and a
front's-state layout, and, for policies trained before rik wrote its contract (:mod:`rik.lerobot.policy_io`), the
fallback that tells a pose action's frame from the training statistics in the folder.

``POLICY_DIR`` is a folder that ``lerobot-train`` wrote (``outputs/train/<run>/checkpoints/last/pretrained_model``)
or any folder with a policy's ``config.json``, processors and weights, of a type rik runs (``act``, ``diffusion``,
``tdmpc``, ``vqbet``). Its input features say what the environment renders: ``observation.images.<camera>`` asks
for MuJoCo's image of that camera, ``observation.images.<camera>_rerendered`` for Mitsuba's (only when the
re-render is allowed: it is slow without a GPU), at the size the policy was trained on. Its state and action must be
those of the robot it runs with (:mod:`rik.sim.robots.layout`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.lerobot.features import (
    ACTION,
    CAMERAS,
    EE_POSE,
    ENV_STATE_LAYOUTS,
    OBS_ENV_STATE,
    OBS_IMAGES,
    OBS_STATE,
    STREAM_SUFFIX,
    env_layout_of_width,
    env_state_names,
)
from rik.lerobot.policy_files import CONFIG, PROCESSORS, member, parsed_config, read_json
from rik.sim.observation import GRASP_POINT
from rik.sim.robots.layout import EE_NAMES, POSE_ACTION_NAMES

if TYPE_CHECKING:
    from rik.sim.robots.layout import RobotLayout

OLD_STATE_WIDTH = 14
"""``observation.state`` of exports made before the state split (robot and front state in one vector)."""
DEFAULT_IMAGE_SIZE = (96, 128)
"""(height, width) px of a policy that reads no image (what the environment renders for a video of it)."""


@dataclass(frozen=True)
class PolicyInputs:
    """What a policy's ``config.json`` says it reads, checked against rik's environment."""

    policy_type: str
    cameras: tuple[str, ...]
    streams: tuple[str, ...]
    image_size: tuple[int, int]
    """(height, width) of its images, px (:data:`DEFAULT_IMAGE_SIZE` when it reads none)."""
    env_layout: tuple[str, bool]
    """(handle shape, grasp point from the gripper) of the front's state it reads (:data:`ENV_STATE_LAYOUTS`)."""


def policy_config(policy_dir: Path) -> dict[str, Any]:
    """The ``config.json`` of a saved policy, checked to be one: read only when small, of a policy type rik runs, its
    fields of the types LeRobot declares (:func:`rik.lerobot.policy_files.parsed_config`)."""
    file = Path(policy_dir) / CONFIG
    if not Path(policy_dir).is_dir():
        raise RikError(f"{policy_dir}: no such folder (give a saved policy, e.g. "
                       "outputs/train/<run>/checkpoints/last/pretrained_model)")
    if not file.exists() and not file.is_symlink():
        raise RikError(f"{policy_dir}: no {CONFIG}: not a saved LeRobot policy (lerobot-train saves one in "
                       "<output_dir>/checkpoints/<step>/pretrained_model)")
    data = read_json(Path(policy_dir), CONFIG)
    if not isinstance(data, dict) or not isinstance(data.get("type"), str):
        raise RikError(f"{file}: field 'type' (the policy type, e.g. act) is missing")
    parsed_config(Path(policy_dir), data)
    return data


def env_state_width(config: dict[str, Any]) -> int | None:
    """The width of the ``observation.environment_state`` a policy's ``config.json`` reads (None: it reads none, or
    not as one vector)."""
    shape = tuple((config.get("input_features") or {}).get(OBS_ENV_STATE, {}).get("shape", ()))
    return int(shape[0]) if len(shape) == 1 else None


def policy_inputs(policy_dir: Path, config: dict[str, Any], layout: RobotLayout, env_layout: tuple[str, bool] | None,
                  *, allow_rerendered: bool = False, said: str = "") -> PolicyInputs:
    """The inputs of the policy in ``policy_dir`` (its ``config``), checked against what rik's environment supplies
    with the robot of ``layout`` and the front's state ``env_layout`` (None: the one its width names, a policy
    trained before rik wrote its contract); ``said``: where ``env_layout`` comes from, named when they disagree."""
    file = Path(policy_dir) / CONFIG
    inputs = config.get("input_features") or {}
    cameras: list[str] = []
    streams: list[str] = []
    size: tuple[int, int] | None = None
    robot = layout.robot_id
    hint = ("a policy trained on an arm's export runs with --robot and that arm" if layout.is_pose else
            "a policy trained on another robot's export runs with --robot and that robot; the Hand-E's with "
            "--robot hand-e")
    action = (config.get("output_features") or {}).get(ACTION)
    if action is not None and tuple(action.get("shape", ())) != (len(layout.action_names),):
        raise RikError(f"{file}: output 'action' has shape {list(action.get('shape', ()))}; robot {robot} takes "
                       f"[{len(layout.action_names)}] ({hint})")
    width = env_state_width(config)
    guessed = env_layout is None
    if env_layout is None:
        env_layout = (env_layout_of_width(width) if width is not None else None) or ("none", False)
    widths = {OBS_STATE: len(layout.state_names), OBS_ENV_STATE: len(env_state_names(*env_layout))}
    if layout.ee_pose:
        widths[EE_POSE] = len(EE_NAMES)
    for key, feature in inputs.items():
        shape = tuple(feature.get("shape", ()))
        if key == EE_POSE and key not in widths:
            raise RikError(f"{file}: input '{key}' is not something rik's environment supplies for robot {robot} "
                           f"(only arms whose layout has an end-effector pose, such as panda-2f85; {hint})")
        if key in widths:
            if key == OBS_STATE and shape == (OLD_STATE_WIDTH,) and layout.is_pose:
                raise RikError(f"{file}: input 'observation.state' has {OLD_STATE_WIDTH} numbers: the policy was "
                               "trained on an export made before rik split the robot's and the front's state; "
                               "re-export the episodes (rik export-lerobot) and train again")
            if key == OBS_STATE and shape != (widths[key],):
                raise RikError(f"{file}: input '{key}' has shape {list(shape)}; robot {robot} supplies "
                               f"[{widths[key]}] ({hint})")
            if key == OBS_ENV_STATE and shape != (widths[key],) and not guessed:
                shape_name, from_gripper = env_layout
                raise RikError(f"{file}: input '{key}' has shape {list(shape)}; {said} says [{widths[key]}] "
                               f"(handle shape {shape_name}"
                               f"{', the grasp point from the gripper' if from_gripper else ''}): the policy was "
                               "not trained on that dataset")
            if shape != (widths[key],):
                raise RikError(f"{file}: input '{key}' has shape {list(shape)}; rik's environment supplies "
                               f"[{widths[key]}]" + (" (or " + " or ".join(
                                   f"[{len(names)}]" for s, names in ENV_STATE_LAYOUTS.items()
                                   if s != ("none", False))
                                   + " with the handle's shape or the grasp point from the gripper)"
                                   if key == OBS_ENV_STATE else ""))
            continue
        camera, stream = image_feature(key)
        if camera is None:
            raise RikError(f"{file}: input '{key}' is not something rik's environment supplies (it gives "
                           "observation.state, observation.environment_state, observation.ee_pose for arms that "
                           f"have one, and observation.images.<camera>[_rerendered] for cameras {', '.join(CAMERAS)})")
        if stream == "rerendered" and not allow_rerendered:
            raise RikError(f"{file}: input '{key}' is a Mitsuba re-render, which the environment is not asked to "
                           "render; pass --rerendered (slow without a GPU) or train without the _rerendered keys "
                           "(--policy.input_features)")
        if len(shape) != 3 or shape[0] != 3:
            raise RikError(f"{file}: input '{key}' has shape {list(shape)}; images are [3, height, width]")
        if size is not None and size != (shape[1], shape[2]):
            raise RikError(f"{file}: input '{key}' is {shape[1]}x{shape[2]} px where another image is "
                           f"{size[0]}x{size[1]}; rik renders all cameras at one size")
        size = (int(shape[1]), int(shape[2]))
        cameras.append(camera)
        streams.append(stream)
    if OBS_STATE not in inputs:
        raise RikError(f"{file}: the policy takes no 'observation.state'; rik's policies read the robot's state")
    return PolicyInputs(config["type"], tuple(dict.fromkeys(cameras)), tuple(dict.fromkeys(streams)),
                        size or DEFAULT_IMAGE_SIZE, env_layout)


def trained_action_frame(policy_dir: Path) -> str:
    """The frame of a pose policy's action, from its training data's statistics in its own folder (the
    unnormaliser's state file holds the dataset's): ``handle`` where the actions' mean position lies nearer the
    origin than to the handle's mean grasp point (a handle-frame action is a few centimetres from the handle; a
    world-frame one is where the handle is), else ``world`` (also where the statistics, or the postprocessor that
    names their file, are not there). Only the fallback for policies trained before rik wrote its contract."""
    import numpy as np

    post_file = Path(policy_dir) / PROCESSORS[1]
    if not post_file.exists() and not post_file.is_symlink():
        return "world"  # no statistics to tell (a folder of config.json alone): the frame of every older policy
    post = read_json(Path(policy_dir), PROCESSORS[1])
    steps = post.get("steps") if isinstance(post, dict) else None
    states = [str(s["state_file"]) for s in steps or [] if isinstance(s, dict)
              and s.get("registry_name") == "unnormalizer_processor" and isinstance(s.get("state_file"), str)]
    if not states:
        return "world"
    file = member(Path(policy_dir), states[0], f"{Path(policy_dir) / PROCESSORS[1]}: field 'state_file'")
    centre: dict[str, np.ndarray] = {}
    try:
        from safetensors import safe_open

        with safe_open(str(file), framework="numpy") as f:
            names = set(f.keys())
            for key, widths in ((ACTION, (len(POSE_ACTION_NAMES),)),
                                (OBS_ENV_STATE, tuple(len(names) for names in ENV_STATE_LAYOUTS.values()))):
                if f"{key}.mean" in names:
                    centre[key] = np.asarray(f.get_tensor(f"{key}.mean"), np.float64).reshape(-1)
                elif {f"{key}.min", f"{key}.max"} <= names:
                    centre[key] = (np.asarray(f.get_tensor(f"{key}.min"), np.float64).reshape(-1)
                                   + np.asarray(f.get_tensor(f"{key}.max"), np.float64).reshape(-1)) / 2
                if key in centre and centre[key].shape[0] not in widths:
                    del centre[key]
    except Exception as e:  # not safetensors, truncated: the folder check names it; here only the frame is asked
        raise RikError(f"{file}: not readable statistics ({str(e).splitlines()[0] if str(e) else type(e).__name__})"
                       ) from None
    if ACTION not in centre or OBS_ENV_STATE not in centre:
        return "world"
    position, grasp = centre[ACTION][:3], centre[OBS_ENV_STATE][GRASP_POINT]
    return "handle" if np.linalg.norm(position) < np.linalg.norm(position - grasp) else "world"


def image_feature(key: str) -> tuple[str | None, str]:
    """(camera, stream) of an image feature ``observation.images.<camera>[_rerendered]``; (None, "") for any other
    key."""
    prefix = OBS_IMAGES + "."
    if not key.startswith(prefix):
        return None, ""
    name = key[len(prefix):]
    for stream, suffix in sorted(STREAM_SUFFIX.items(), key=lambda kv: -len(kv[1])):
        if name.endswith(suffix) and name[:len(name) - len(suffix)] in CAMERAS:
            return name[:len(name) - len(suffix)], stream
    return None, ""
