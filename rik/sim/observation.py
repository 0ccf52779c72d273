"""What a policy sees of a scene, defined once for the gym environment, the LeRobot export and evaluation.

Two state vectors, split as LeRobot's policies expect them (ACT and diffusion always read
``observation.state`` and need an image or ``observation.environment_state`` besides):

- the **robot's state** (:data:`ROBOT_STATE_NAMES`, ``observation.state``): what the robot knows of itself, the
  gripper base's pose, the jaw opening, the point between its pads and the normal force its fingers feel;
- the **front's state** (:data:`ENV_STATE_NAMES`, ``observation.environment_state``): the operated front's joint
  position and velocity and its opening, the handle's grasp point, orientation and the direction it moves in when
  the front opens. The robot's state alone does not say where the handle is;
- optionally, the **handle's shape** (:data:`HANDLE_SHAPE_NAMES`, appended to the front's state: ``rik
  export-lerobot --handle-shape full``, the environment's ``handle_shape="full"``): its type, mount and the
  catalog's grasp dimensions, constant through an episode; or its type and mount alone (``kind``: the first
  :data:`HANDLE_KIND_WIDTH` of them). The front's state alone does not say whether the grasp point is a knob's
  head, a bar or a lip.

Units are SI: m, rad, m/s or rad/s, N. How these vectors become LeRobot's features (and images, cameras and streams
are named) is :mod:`rik.lerobot.features`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.sim.scene import SimScene

ROBOT_STATE_NAMES = ("x", "y", "z", "pitch", "yaw", "roll", "jaw_opening", "tcp_x", "tcp_y", "tcp_z",
                     "contact_normal_force")
"""Gripper base pose (m, world; rad), jaw opening (m), the pads' centre (m, world), the fingers' normal force on
the front (N)."""
ENV_STATE_NAMES = ("front_qpos", "front_qvel", "opening", "grasp_x", "grasp_y", "grasp_z", "handle_qw", "handle_qx",
                   "handle_qy", "handle_qz", "pull_x", "pull_y", "pull_z")
"""The front's joint position (m or rad) and velocity (m/s or rad/s), its opening (fraction of the range), the
handle's grasp point (m, world), its orientation (unit quaternion w, x, y, z with w >= 0, world) and the unit
direction in which the grasp point moves as the front opens (world)."""
GRASP_POINT = slice(ENV_STATE_NAMES.index("grasp_x"), ENV_STATE_NAMES.index("grasp_z") + 1)
"""Where the handle's grasp point (m, world) sits in the front's state: ``environment_state(scene)[GRASP_POINT]``."""
HANDLE_SHAPE_NAMES = ("handle_knob", "handle_two_point", "handle_finger_pull", "handle_edge_clip", "handle_inset",
                      "handle_length", "handle_width", "handle_projection", "handle_grip_diameter",
                      "handle_clearance_depth", "handle_clearance_width")
"""The handle's shape: its type and mount as 0/1 flags (knob, two-point, finger pull; clipped on an edge, set into a
recess), then the catalog's geometry (:class:`rik.schemas.handles.HandleGeometry`, m): length, width, projection,
grip diameter, and the finger clearance's depth and width (0 where the catalog gives none)."""
HANDLE_KIND_WIDTH = 5
"""The type and mount flags at the start of :data:`HANDLE_SHAPE_NAMES` (``--handle-shape kind``)."""
HANDLE_SHAPES = {"none": (), "kind": HANDLE_SHAPE_NAMES[:HANDLE_KIND_WIDTH], "full": HANDLE_SHAPE_NAMES}
"""``--handle-shape`` -> the handle's numbers it appends to the front's state: none (the default), its type and
mount flags (``kind``), or those and the catalog's grasp dimensions (``full``)."""
GRIPPER_GRASP_NAMES = ("grasp_from_gripper_x", "grasp_from_gripper_y", "grasp_from_gripper_z")
"""The handle's grasp point less the gripper base's position (m, world axes): what a policy whose action is measured
from the gripper (``--action-frame gripper``) reads after the front's state, so that where to go and how far are one
input away from each other."""
MAX_DELTA = np.array([0.02, 0.02, 0.02, 0.1, 0.1, 0.1])
"""Largest change of the target pose per control step: m for x, y, z; rad for pitch, yaw, roll."""
TYPE_WORDS = {"two_point": "handle", "knob": "knob", "finger_pull": "finger pull"}


def instruction(catalog: Catalog, handle_id: str, front_kind: str) -> str:
    """The task in words, e.g. "open the drawer by its bow handle" (a dataset's task and the env's
    ``task_description`` are the same string)."""
    handle = catalog.handles[handle_id]
    design = catalog.designs[handle.design]
    shape = design.subtype.replace("_", " ").replace("-", " ")
    return f"open the {front_kind} by its {shape} {TYPE_WORDS.get(design.type.value, 'handle')}"


def robot_state(scene: SimScene) -> np.ndarray:
    """The :data:`ROBOT_STATE_NAMES` of a scene, float64."""
    return np.concatenate([scene.pose(), [scene.finger_opening()], scene.tcp(),
                           [scene.contact_summary()["normal_force"]]]).astype(np.float64)


def handle_shape_state(catalog: Catalog, handle_id: str, handle_shape: str = "full") -> np.ndarray:
    """The numbers of the handle's shape ``handle_shape`` (:data:`HANDLE_SHAPES`) of a catalog handle, float64
    (flags 0/1, lengths m); ``none`` gives no numbers."""
    handle = catalog.handles[handle_id]
    kind = catalog.handle_type(handle).value
    g = handle.geometry
    depth, width = (g.clearance.depth, g.clearance.width) if g.clearance is not None else (0.0, 0.0)
    flags = [kind == "knob", kind == "two_point", kind == "finger_pull", handle.mount.kind == "edge_clip",
             handle.mount.kind == "inset"]
    full = np.array([*map(float, flags), g.length, g.width, g.projection, g.grip_diameter, depth, width], np.float64)
    return full[:len(HANDLE_SHAPES[handle_shape])]


def environment_state(scene: SimScene, shape: np.ndarray | None = None, from_gripper: bool = False) -> np.ndarray:
    """The :data:`ENV_STATE_NAMES` of a scene, float64, followed by the grasp point from the gripper base
    (``from_gripper``: :data:`GRIPPER_GRASP_NAMES`, m) and ``shape`` where given (the handle's,
    :func:`handle_shape_state`)."""
    q, qd = scene.front_q()
    quat = scene.data.xquat[scene.front.handle_body].copy()
    if quat[0] < 0:
        quat = -quat
    parts = [[q, qd, scene.opening()], scene.grasp_point(), quat, scene.pull_direction()]
    if from_gripper:
        parts.append(scene.grasp_point() - scene.pose()[:3])
    if shape is not None:
        parts.append(shape)
    return np.concatenate(parts).astype(np.float64)


def delta_to_absolute(target: np.ndarray, action: np.ndarray) -> np.ndarray:
    """An absolute action (target pose + gripper command) from the previous target and a ``delta`` action."""
    a = np.asarray(action, np.float64)
    return np.concatenate([np.asarray(target, np.float64) + np.clip(a[:6], -1, 1) * MAX_DELTA,
                           [float(np.clip(a[6], 0.0, 1.0))]])


def state_observation(scene: SimScene) -> dict[str, Any]:
    """The state part of an observation: ``agent_pos`` and ``environment_state``, float32."""
    return {"agent_pos": robot_state(scene).astype(np.float32),
            "environment_state": environment_state(scene).astype(np.float32)}
