"""Schema behaviour that the rest of rik relies on."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from rik.schemas import JointSpec


def test_axis_is_normalised_and_models_are_frozen() -> None:
    joint = JointSpec(type="slide", axis=(0, 2, 0), anchor=(0, 0, 0), range=(0, 0.4))
    assert joint.axis == (0.0, 1.0, 0.0)
    with pytest.raises(ValidationError):
        joint.range = (0, 1)  # type: ignore[misc]


def test_range_must_contain_the_closed_position() -> None:
    with pytest.raises(ValidationError, match="must contain 0"):
        JointSpec(type="slide", axis=(0, 1, 0), anchor=(0, 0, 0), range=(0.1, 0.4))


def test_hinge_range_at_most_a_turn() -> None:
    with pytest.raises(ValidationError, match="at most 2π"):
        JointSpec(type="hinge", axis=(0, 0, 1), anchor=(0, 0, 0), range=(0, 7.0))
