"""Constants of the ground-truth generator: effect kinds, the truth's solver settings, the shapes' constants, the
hand, the sensors, the excitation, and the ranges random truths are drawn from."""

from __future__ import annotations

import math
from dataclasses import dataclass

from rik.joints.kinds import KINDS
from rik.schemas.joints import JointType

EFFECT_KINDS: tuple[str, ...] = (*KINDS, "spring")
"""Effect kinds :func:`random_truth` can draw: the library's (:data:`rik.joints.kinds.KINDS`) and ``spring``, its
closer :class:`Spring`."""
JOINT_KINDS = {JointType.slide: EFFECT_KINDS, JointType.hinge: EFFECT_KINDS}
"""Effect kinds valid per joint type (every kind has a drawer and a door form)."""
TRUTH_FILE = "truth.json"
"""Name of the ground-truth file :func:`write_trials` writes next to the trial CSVs."""
SOURCE = "simulated"
"""``TrialMeta.source`` of simulated trials."""

GRAVITY = 9.81
"""m/s²."""
SOLIMP_FRICTION = (0.9999, 0.9999, 0.001, 0.5, 2.0)
"""``solimpfriction`` of the truth's joint: nearly hard friction, so that a held joint does not creep."""
SOLREF_LIMIT = (0.005, 1.0)
"""``solreflimit``: a firm end stop (about 1.5 mm penetration at 0.3 m/s)."""

# Per-joint constants of the shapes, the hand and the sensors: slide (SI m, N), hinge (rad, N·m).
SOFT_CLOSE_VREF = {JointType.slide: 0.1, JointType.hinge: 0.25}
"""Speed at which the truth's soft-close force equals ``damping * v``: m/s or rad/s."""
SOFT_CLOSE_EXPONENT = 1.1
EDGE_FRACTION = 0.05
"""tanh half-width (soft-close) and softplus width (self-close) as a fraction of the zone."""
STRIBECK_EXPONENT = 1.5
DIRECTION_VEPS = {JointType.slide: 0.005, JointType.hinge: 0.0125}
"""Regularisation speed of the direction friction: m/s or rad/s."""
DIRECTION_FEPS = 0.01
"""Width of the direction friction's step in the hand force at rest, as a fraction of the total friction."""
CUBIC_VREF = {JointType.slide: 0.3, JointType.hinge: 1.0}
"""Speed at which the cubic damping term is 10 % of the quadratic one: m/s or rad/s."""
CUBIC_FRACTION = 0.1
LOAD_EXPONENT = 1.1

HAND_OMEGA = math.sqrt(400.0 / 6.0)
"""Natural frequency of the hand on the truth's inertia, rad/s (kp 400 N/m on 6 kg)."""
HAND_ZETA = 0.6
"""Damping ratio of the hand (kd 59 N·s/m on 6 kg): settled before a release from rest."""
HAND_DEADBAND = {JointType.slide: 0.01, JointType.hinge: 0.03}
"""kp is at least the static friction (Coulomb plus the effect's extra friction at rest) over this error, and
at least that friction plus the largest effect force at rest over the outer half of the range over twice this
error: m or rad."""
HAND_MAX = {JointType.slide: 60.0, JointType.hinge: 15.0}
"""Largest hand force, N or N·m."""
POSITION_NOISE = {JointType.slide: 2e-4, JointType.hinge: math.radians(0.2)}
"""Default position noise (standard deviation): m (0.2 mm) or rad (0.2°)."""
FORCE_NOISE = {JointType.slide: 0.3, JointType.hinge: 0.03}
"""Default force noise (standard deviation): N or N·m."""


@dataclass(frozen=True)
class _Excite:
    """Excitation constants of a joint type (m, m/s or rad, rad/s)."""

    speed: tuple[float, float]
    """Peak speeds of ordinary strokes."""
    block_speed: tuple[float, float]
    """Peak speeds of the strokes inside the required blocks (faster, to fit the trial)."""
    slow: tuple[float, float]
    """Speed of the slow constant-speed stroke."""
    throw: tuple[float, float]
    """Peak speed of the push towards closed that is let go."""
    near_closed: tuple[float, float]
    """Distance from closed at which that push is let go."""
    push: tuple[float, float]
    """How far beyond a stop the target goes when the front is pushed against it and held there (the hand
    presses with about kp times this)."""
    creep: tuple[float, float]
    """Speed of the creep from rest at closed (a slow constant-speed pull with a stiff hand, as a robot or a
    force gauge would make)."""
    creep_length: tuple[float, float]
    """Length of that creep."""


EXCITE = {
    JointType.slide: _Excite(speed=(0.05, 0.5), block_speed=(0.1, 0.5), slow=(0.01, 0.02), throw=(0.12, 0.3),
                             near_closed=(0.015, 0.03), push=(0.01, 0.025), creep=(0.004, 0.006),
                             creep_length=(0.006, 0.01)),
    JointType.hinge: _Excite(speed=(0.2, 2.0), block_speed=(0.4, 2.0), slow=(0.025, 0.05), throw=(0.5, 1.2),
                             near_closed=(0.05, 0.15), push=(math.radians(3.0), math.radians(8.0)),
                             creep=(0.02, 0.03), creep_length=(0.025, 0.04)),
}
CREEP_STIFFNESS = 10.0
"""The hand's stiffness during a creep, as a multiple of its usual kp (its damping scales with the square root):
the force builds at about 10·kp·speed until the front breaks away."""
MOVE_TIME = (0.25, 2.0)
"""Shortest and longest minimum-jerk stroke, s (the peak speed is raised where a stroke would take longer)."""
BLOCK_MOVE_TIME = 1.2
"""Longest stroke inside a required block, s."""
SLOW_RAMP = 0.2
"""Acceleration time of the slow stroke, s."""


Range = tuple[float, float]
BASE_RANGES: dict[JointType, dict[str, Range]] = {
    JointType.slide: {"mass": (2.0, 15.0), "damping": (1.0, 10.0), "frictionloss": (1.0, 8.0),
                      "upper": (0.35, 0.5)},
    JointType.hinge: {"mass": (0.2, 2.0), "damping": (0.05, 0.5), "frictionloss": (0.1, 1.0),
                      "upper": (1.5, 1.9)},
}
"""Ranges of :func:`random_truth`'s base parameters: mass kg or kg·m², damping N·s/m or N·m·s/rad, frictionloss
N or N·m, upper (the range's upper end; the lower is 0) m or rad. ``mass=`` may be given outside them."""

EFFECT_RANGES: dict[JointType, dict[str, dict[str, Range]]] = {
    JointType.slide: {
        "stiction": {"frictionloss": (3.0, 8.0), "ratio": (1.4, 2.0), "breakaway": (1.2, 8.0),
                     "stribeck_velocity": (0.01, 0.03)},
        "soft_close": {"zone": (0.03, 0.06), "damping": (50.0, 150.0)},
        "self_close": {"zone": (0.02, 0.04), "pull": (5.0, 15.0)},
        "magnetic_catch": {"force": (5.0, 30.0), "decay": (0.002, 0.008)},
        "tilt": {"abs_force": (2.0, 7.8), "angle_deg": (1.0, 6.0), "over_friction": (1.2, 2.5)},
        "direction_friction": {"extra": (1.5, 4.0)},
        "quadratic_damping": {"coefficient": (15.0, 40.0)},
        "load_friction": {"per_extension": (8.0, 25.0)},
        "spring": {"stiffness": (10.0, 40.0), "reference": (-0.1, 0.0)},
    },
    JointType.hinge: {
        "stiction": {"frictionloss": (0.3, 1.0), "ratio": (1.4, 2.0), "breakaway": (0.12, 1.0),
                     "stribeck_velocity": (0.03, 0.08)},
        "soft_close": {"zone": (math.radians(10), math.radians(25)), "damping": (1.0, 3.0)},
        "self_close": {"zone": (math.radians(20), math.radians(30)), "pull": (0.5, 2.0)},
        "magnetic_catch": {"force": (1.5, 6.0), "decay": (0.005, 0.02)},
        "tilt": {"amplitude": (0.4, 1.5), "abs_force": (0.12, 1.5), "abs_sine": (0.12, 1.5),
                 "over_friction": (1.2, 2.5)},
        "direction_friction": {"extra": (0.15, 0.5)},
        "quadratic_damping": {"coefficient": (0.2, 0.6)},
        "load_friction": {"per_extension": (0.2, 0.6)},
        "spring": {"stiffness": (0.5, 2.0), "reference": (-0.3, 0.0)},
    },
}
"""Ranges of the effect parameters :func:`random_truth` draws, per joint and kind (library units). Derived
quantities (see :func:`truth_parameters`): stiction ``ratio`` = static / kinetic friction and its own
``frictionloss`` range; self-close ``pull`` = stiffness * zone; tilt ``abs_force`` = |force|, ``angle_deg`` the
runner's tilt (slide), ``amplitude`` = hypot(force, sine) (hinge, with |force| and |sine| each at least 30 % of
it) and ``over_friction`` = the largest tilt force over the range / frictionloss (> 1: a released front drifts,
which tells tilt from direction friction)."""
