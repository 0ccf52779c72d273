"""The LeRobot feature keys and layouts of rik's datasets, named once for the export, the environment, the
``--env.type=rik`` config and evaluation.

The keys (:data:`OBS_STATE`, :data:`OBS_ENV_STATE`, :data:`OBS_IMAGES`, :data:`ACTION`) equal lerobot 0.6.1's
constants of the same name (``lerobot.utils.constants``), which are not imported here because importing lerobot
loads torch; ``tests/test_export.py`` checks that they agree. LeRobot has no constant for :data:`EE_POSE` and
:data:`TASK`: those are rik's. The numbers each vector holds are the simulation's (:mod:`rik.sim.observation`,
:mod:`rik.sim.robots.layout`); here they are put together into features: the front's state followed by the grasp
point from the gripper (a gripper-frame action's) and the handle's shape, image features per camera and stream, and
the environment's observation keys that LeRobot maps onto them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.sim.observation import ENV_STATE_NAMES, GRIPPER_GRASP_NAMES, HANDLE_SHAPES
from rik.sim.robots.layout import ACTION_FRAMES, EE_NAMES, FRAME_ACTION_NAMES

if TYPE_CHECKING:
    from rik.sim.robots.layout import RobotLayout

__all__ = ["ACTION", "ACTION_FRAMES", "CAMERAS", "EE_POSE", "ENV_ID", "ENV_KEYS", "ENV_STATE_LAYOUTS",
           "HANDLE_SHAPES", "OBS_ENV_STATE", "OBS_IMAGES", "OBS_STATE", "STREAMS", "STREAM_SUFFIX", "TASK",
           "action_frame_of", "check_renderer", "dataset_features", "env_layout_of_width", "env_state_names",
           "image_key", "image_name"]

OBS_STATE = "observation.state"
"""The robot's state (:data:`rik.sim.observation.ROBOT_STATE_NAMES`, or an arm's joints)."""
OBS_ENV_STATE = "observation.environment_state"
"""The front's state (:data:`rik.sim.observation.ENV_STATE_NAMES`, then :data:`ENV_STATE_LAYOUTS`' extras)."""
OBS_IMAGES = "observation.images"
"""The prefix of the image features: ``observation.images.<camera>[_rerendered]``."""
ACTION = "action"
"""The action: the Hand-E's target pose and gripper command, an arm's joint targets."""
EE_POSE = "observation.ee_pose"
"""The feature of an arm's end-effector pose in its base frame (:data:`rik.sim.robots.layout.EE_NAMES`), where its
catalog entry asks for one (lerobot passes the environment's ``ee_pose`` through under this name)."""
TASK = "task"
"""The key of a frame's task string in lerobot's ``add_frame`` (lerobot writes it as a literal)."""

ENV_KEYS = {OBS_STATE: "agent_pos", OBS_ENV_STATE: "environment_state", EE_POSE: "ee_pose"}
"""Dataset feature -> the key of ``rik/OpenFront-v0``'s observation that LeRobot's ``preprocess_observation`` maps
onto it (images: ``pixels/<name>``, :func:`image_name`)."""
ENV_ID = "rik/OpenFront-v0"
"""The gymnasium id of rik's environment, which ``--env.type=rik`` makes."""
ENV_ENTRY_POINT = "rik.envs.open_front:OpenFrontEnv"
"""Where gymnasium finds it (registered lazily, by name, so that registering imports nothing)."""

CAMERAS = ("front", "wrist")
"""The scene's cameras: ``front`` looks at the base unit, ``wrist`` rides on the gripper."""
STREAM_SUFFIX = {"sim": "", "rerendered": "_rerendered"}
"""Image stream -> suffix of its camera names: ``front`` is MuJoCo's image, ``front_rerendered`` Mitsuba's."""
STREAMS = tuple(STREAM_SUFFIX)
"""The image streams: ``sim`` (MuJoCo) and ``rerendered`` (Mitsuba)."""


def check_renderer(renderer: str | None, option: str) -> None:
    """Refuse a renderer that draws every image stream (``rik eval --renderer``) unless it is one of :data:`STREAMS`;
    empty or ``None``: each stream drawn by its own. ``option`` names the setting in the one-line error."""
    if renderer and renderer not in STREAMS:
        raise RikError(f"{option}: use one of {', '.join(STREAMS)}, or none (each stream drawn by its own renderer)")

ENV_STATE_LAYOUTS = {(shape, from_gripper): ENV_STATE_NAMES + (GRIPPER_GRASP_NAMES if from_gripper else ()) + names
                     for from_gripper in (False, True) for shape, names in HANDLE_SHAPES.items()}
"""(handle shape, grasp point from the gripper) -> the names of ``observation.environment_state``: the front's
state, then :data:`rik.sim.observation.GRIPPER_GRASP_NAMES` where asked (a gripper-frame action's), then the handle
shape's (:data:`rik.sim.observation.HANDLE_SHAPES`). Every layout has its own width."""


def image_name(camera: str, stream: str) -> str:
    """A camera's image of a stream, as the environment's ``pixels`` key (``front_rerendered``)."""
    return f"{camera}{STREAM_SUFFIX[stream]}"


def image_key(camera: str, stream: str) -> str:
    """The dataset feature of a camera's stream, e.g. ``observation.images.front_rerendered``."""
    return f"{OBS_IMAGES}.{image_name(camera, stream)}"


def env_state_names(handle_shape: str = "none", from_gripper: bool = False) -> tuple[str, ...]:
    """The names of the front's state, followed by the grasp point from the gripper (``from_gripper``) and those of
    the handle's shape ``handle_shape``."""
    return ENV_STATE_LAYOUTS[(handle_shape, from_gripper)]


def env_layout_of_width(width: int) -> tuple[str, bool] | None:
    """(handle shape, grasp point from the gripper) of the front's state that is ``width`` numbers wide (None: no
    such width)."""
    return next((key for key, names in ENV_STATE_LAYOUTS.items() if len(names) == width), None)


def action_frame_of(names: Sequence[str]) -> str | None:
    """The frame of a pose action from its names (a dataset's ``action`` names, :data:`ACTION_FRAMES`); None for
    any others (an arm's joints)."""
    return next((frame for frame, known in FRAME_ACTION_NAMES.items() if tuple(names) == known), None)


def _vector(names: Sequence[str]) -> dict[str, Any]:
    return {"dtype": "float32", "shape": (len(names),), "names": list(names)}


def dataset_features(layout: RobotLayout, handle_shape: str, cameras: Sequence[str], streams: Sequence[str],
                     size: tuple[int, int], *, environment_state: bool = True) -> dict[str, dict[str, Any]]:
    """The LeRobot feature dict of a dataset of one robot's episodes (``layout``, whose action frame says whether
    the grasp point from the gripper follows the front's state), the front's state with the handle's shape
    ``handle_shape`` at its end (none with ``environment_state`` False: a policy of the robot's state and images
    only), and one video per camera and stream of ``size`` (height, width) px."""
    out: dict[str, dict[str, Any]] = {OBS_STATE: _vector(layout.state_names)}
    if layout.ee_pose:
        out[EE_POSE] = _vector(EE_NAMES)
    if environment_state:
        out[OBS_ENV_STATE] = _vector(env_state_names(handle_shape, layout.action_frame == "gripper"))
    out[ACTION] = _vector(layout.action_names)
    height, width = size
    for cam in cameras:
        for stream in streams:
            out[image_key(cam, stream)] = {"dtype": "video", "shape": (height, width, 3),
                                           "names": ["height", "width", "channels"]}
    return out
