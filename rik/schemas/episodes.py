"""What an episode's ``meta.json`` holds (``episodes/<id>/meta.json`` next to ``states.parquet``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from rik.schemas.common import CatalogId, Frozen, PathComponent, SimpleId

EPISODE_FORMAT = 3
"""3: the robot (``robot``, ``robot_base``) and its joints (``states.parquet``'s ``robot_joints``, ``robot_targets``,
``tcp_quat``); 2: ``meta_sha256`` seals meta.json itself. Older episodes are still read (they are the Hand-E's)."""
MAX_SEED = 2**63 - 1
"""Largest seed: seeds are stored as signed 64-bit integers (Parquet, LeRobot's episode columns)."""


class GripperInfo(Frozen):
    """The gripper an episode was recorded with (SI units)."""

    name: str
    stroke: float = Field(description="m")
    grip_force: float = Field(description="N")
    pad_friction: float
    arm_force: float = Field(description="N; the Hand-E's base (an arm's joint torques are in the catalog)")


class RobotBase(Frozen):
    """Where an arm's base stood (world frame)."""

    pos: tuple[float, float, float] = Field(description="m")
    yaw: float = Field(description="rad, about +z")


class EpisodeMeta(Frozen):
    """One recorded episode. ``states.parquet`` has ``steps + 1`` rows: the state before each control step with
    the action applied during it, then the final state (its action repeats the last one)."""

    format: int = Field(default=EPISODE_FORMAT, ge=1, le=EPISODE_FORMAT)
    id: PathComponent
    """The episode's folder name, also the name of its render folder."""
    variant: PathComponent
    base_unit: CatalogId
    handle: CatalogId
    handle_type: str
    preset: SimpleId
    collision: Literal["coacd", "hull"] = "coacd"
    """The handle's collision mode in the simulator it was recorded in (``rik variants build --collision``);
    episodes recorded before modes existed are ``coacd``."""
    joint_friction: Literal["held", "creeping"] = "held"
    """How the front's joint friction held in that simulator (``rik variants build --joint-friction``); episodes
    without the field are read as ``held``."""
    front: SimpleId
    operator: str = Field(description="strategy, device or policy name")
    operator_kind: Literal["strategy", "device", "policy"]
    seed: int = Field(ge=0, le=MAX_SEED)
    fps: int = Field(ge=1, le=10_000, description="control and recording rate, Hz")
    timestep: float = Field(gt=0, allow_inf_nan=False, description="physics step, s")
    steps: int = Field(ge=0, description="control steps taken")
    state_spec: str = "mjSTATE_INTEGRATION"
    state_size: int = Field(ge=1)
    outcome: Literal["F", "P", "S"]
    final_opening: float = Field(allow_inf_nan=False, description="fraction of the front's range")
    max_opening: float = Field(allow_inf_nan=False)
    gripper: GripperInfo
    robot: SimpleId = "hand-e"
    """The catalog robot that opened the front (episodes before robots existed are the Hand-E's)."""
    robot_base: RobotBase | None = None
    """An arm's base placement (None for the floating Hand-E)."""
    robot_joints: tuple[str, ...] = ()
    """Names of ``states.parquet``'s ``robot_joints`` and ``robot_targets`` (the robot's joints, then its
    gripper's: rad or m for joints, the gripper in its actuator's units); empty before format 3."""
    versions: dict[str, str]
    log: tuple[str, ...] = ()
    states_sha256: str = Field(pattern=r"^[0-9a-f]{64}$")
    action_noise: float | None = Field(default=None, ge=0, allow_inf_nan=False)
    """Standard deviation of the noise added to the executed target position (m) for an episode recorded with
    noise (DART-style: ``states.parquet``'s ``action`` holds the operator's own action, ``executed_action`` what
    the robot was sent); absent (None) where every action ran as recorded."""
    action_kind: Literal["pose", "joints"] = "pose"
    """What ``states.parquet``'s ``action`` holds: ``pose``, the target pose and gripper command every strategy,
    keyboard and policy records (:data:`rik.exporters.lerobot_frames.ACTION_NAMES`; absent from meta.json); or
    ``joints``, an arm driven joint by joint (a leader arm): its joint targets as commanded (rad, in ``robot_joints``'
    order) and the gripper command (0 open .. 1 closed) last, one number per ``robot_joints`` entry."""
    meta_sha256: str | None = Field(default=None, pattern=r"^[0-9a-f]{64}$")
    """sha256 of this file's other fields (:func:`rik.episodes.episode.meta_digest`); required from format 2 on."""
