"""The gripper frame's maths: its rotation from pitch, yaw and roll (the Hand-E's base chain, which every robot's
target pose uses), the inverse, and the base pose that puts the pads' centre at a point. Angles in rad, lengths
in m."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rik.sim.robots.gripper import GripperSpec

GRIPPER_BASE_QUAT = [0.7071067811865476, 0.0, 0.0, 0.7071067811865476]
"""The gripper frame's rotation at zero pitch, yaw and roll (x, y, z, w: a quarter turn about world x), which
:func:`gripper_rotation` composes with the angles and :func:`angles_of` takes back out."""



def base_for_tcp(gripper: GripperSpec, tcp: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """The base pose (x, y, z, pitch, yaw, roll) that puts the pads' centre at ``tcp`` with ``angles``."""
    rot = gripper_rotation(angles)
    return np.concatenate([np.asarray(tcp) - rot[:, 2] * gripper.tcp_offset, angles])


def gripper_rotation(angles: np.ndarray) -> np.ndarray:
    """World rotation of the gripper frame for pitch, yaw, roll (the base chain's composition)."""
    from scipy.spatial.transform import Rotation

    base = Rotation.from_quat(GRIPPER_BASE_QUAT, scalar_first=False)
    pitch, yaw, roll = angles
    # joints are applied in the base frame, in chain order: about x, then the (pitched) y, then the approach z
    chain = Rotation.from_euler("XYZ", [pitch, yaw, roll])
    return (base * chain).as_matrix()


def angles_of(rotation: np.ndarray) -> np.ndarray:
    """Pitch, yaw, roll (rad) of a gripper frame's world rotation: the inverse of
    :func:`gripper_rotation` (yaw in [-pi/2, pi/2], the others in (-pi, pi])."""
    from scipy.spatial.transform import Rotation

    base = Rotation.from_quat(GRIPPER_BASE_QUAT, scalar_first=False)
    return (base.inv() * Rotation.from_matrix(rotation)).as_euler("XYZ")


def nearest_angles(angles: np.ndarray, near: np.ndarray) -> np.ndarray:
    """The pitch, yaw, roll (rad) of the same gripper rotation as ``angles`` that lie nearest ``near``.

    An arm's pose gives its angles as principal Euler angles (:func:`angles_of`: roll wraps at
    +-pi, and past a yaw of +-pi/2 pitch and roll flip by pi), while a held key moves the target's angles on
    without a wrap: compared as they are, a roll past pi would read as a lead of -2 pi. Every triple
    ``(p, y, r) + 2 pi k`` and ``(p + pi, pi - y, r + pi) + 2 pi k`` is the same rotation
    (:func:`gripper_rotation`); this picks the one nearest ``near``. The Hand-E's pose is its
    joints' values, which lie within the lead of its target: they come back unchanged."""
    a = np.asarray(angles, np.float64)
    ref = np.asarray(near, np.float64)
    best = a
    for c in (a, a + np.array([np.pi, np.pi - 2 * a[1], np.pi])):
        c = ref + (c - ref + np.pi) % (2 * np.pi) - np.pi
        if np.abs(c - ref).max() < np.abs(best - ref).max() - 1e-9:
            best = c
    return best
