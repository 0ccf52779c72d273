"""What the robot checks report: a named check's verdict with the numbers it decided on, and one point of a robot's
reach profile. Plain data, so that every module of the robots can name them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class CheckResult:
    name: str
    passed: bool
    reason: str
    values: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ReachPoint:
    opening: float
    position_error: float
    """m"""
    orientation_error: float
    """rad"""
    joints: tuple[float, ...]
    torque_use: float
    """Largest share of a joint's torque the held pull and gravity need (1: all of it)."""
    limiting_joint: str
