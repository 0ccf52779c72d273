"""What an episode's ``meta.json`` holds (``episodes/<id>/meta.json`` next to ``states.parquet``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from rik.schemas.common import Frozen

EPISODE_FORMAT = 1


class GripperInfo(Frozen):
    """The gripper an episode was recorded with (SI units)."""

    name: str
    stroke: float = Field(description="m")
    grip_force: float = Field(description="N")
    pad_friction: float
    arm_force: float = Field(description="N")


class EpisodeMeta(Frozen):
    """One recorded episode. ``states.parquet`` has ``steps + 1`` rows: the state before each control step with
    the action applied during it, then the final state (its action repeats the last one)."""

    format: int = EPISODE_FORMAT
    id: str
    variant: str
    base_unit: str
    handle: str
    handle_type: str
    preset: str
    front: str
    operator: str = Field(description="strategy, device or policy name")
    operator_kind: Literal["strategy", "device", "policy"]
    seed: int
    fps: int = Field(description="control and recording rate, Hz")
    timestep: float = Field(description="physics step, s")
    steps: int = Field(description="control steps taken")
    state_spec: str = "mjSTATE_INTEGRATION"
    state_size: int
    outcome: Literal["F", "P", "S"]
    final_opening: float = Field(description="fraction of the front's range")
    max_opening: float
    gripper: GripperInfo
    versions: dict[str, str]
    log: tuple[str, ...] = ()
    states_sha256: str
