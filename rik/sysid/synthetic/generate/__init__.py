"""Ground-truth generator for ``rik sysid``: "measured" trials of a furniture joint simulated from a hidden truth.

A :class:`GroundTruth` is a 1-DOF joint (slide: m, N, kg; hinge: rad, N·m, kg·m²) with inertia, viscous damping,
Coulomb friction, a range and up to two effects beyond them (each a :data:`~rik.schemas.joints.JointEffect` or a
closer :class:`~rik.schemas.joints.Spring`, of different kinds; two act together, their forces and extra frictions
add up, e.g. the damper and the pull-in spring of a soft-close runner). Its parameters are in the library's form,
so a fit can be compared with them, but the force the simulation applies has a slightly different shape from the
library law (no "inverse crime"):

==================  ========================================================================================
effect              truth's force law (library parameters keep their meaning)
==================  ========================================================================================
stiction            extra friction ``breakaway * exp(-(|v|/stribeck_velocity)^1.5)`` (library: exponent 2)
soft_close          ``-damping * g(q) * v_ref * (|v|/v_ref)^1.1 * sign(v)`` (only while closing), g a tanh
                    edge at ``zone`` about 10 % of the zone wide; equals ``-damping * v`` at ``|v| = v_ref``
                    (0.1 m/s or 0.25 rad/s) inside the zone
self_close          ``-stiffness * s * softplus((zone - q) / s)``, s = 5 % of the zone: the ramp, rounded at
                    its edge; the pull at closed is ``stiffness * zone``
magnetic_catch      ``-force * exp(-q / (decay * k))``, k so that its impulse over [0, upper] equals the
                    library law's ``-force / (1 + q/decay)^2``; same pull at contact
tilt, spring        exact
direction_friction  extra friction ``extra * (1 + tanh(±v / v_eps)) / 2`` (v_eps 5 mm/s or 0.0125 rad/s);
                    at rest the direction the hand pushes in (see :func:`direction_share`)
quadratic_damping   ``-coefficient * (v|v| + 0.1 v^3 / v_ref)`` (v_ref 0.3 m/s or 1 rad/s)
load_friction       extra friction ``per_extension * q_mid * (q / q_mid)^1.1``, q_mid = upper / 2
==================  ========================================================================================

Friction-type forces (Coulomb, stiction, direction and load friction) stay a MuJoCo constraint: the Coulomb part
is the joint's ``frictionloss`` and the extra friction is written into ``model.dof_frictionloss`` every step, with
``solimpfriction`` d0 = 0.9999 so that a sub-threshold load does not creep (< 0.01 mm/s). The other effects are
``data.qfrc_applied``. Effects are evaluated at ``max(q, 0)``.

The joint is driven by a human-like impedance "hand", ``kp (target - q) + kd (target_vel - v)`` clipped to
60 N or 15 N·m, tracking an :class:`ExcitationPlan`: strokes of varied speed (minimum-jerk), a slow
constant-speed stroke, holds, a stroke into the closed end, one near the far stop, a push towards closed let go
at 15-30 mm (3-9°) from closed and a release from rest at mid-range (hand force exactly 0). The hand force is the
measured force. :func:`measure` samples it with noise, optional quantisation and a delay: the position sample at
time t is the true position at t - ``delay_s``, i.e. the position is recorded ``delay_s`` later than the force
(positive delay in :mod:`rik.sysid.preprocess`).

One module per job (everything public is re-exported here, so ``from rik.sysid.synthetic.generate import X``
works):

- :mod:`~rik.sysid.synthetic.generate.constants`: effect kinds, the truth's solver settings, the constants of the
  shapes, the hand, the sensors and the excitation, and the ranges of random truths;
- :mod:`~rik.sysid.synthetic.generate.common`: argument checks and random draws the modules share;
- :mod:`~rik.sysid.synthetic.generate.truth`: :class:`GroundTruth` and its ``truth.json``;
- :mod:`~rik.sysid.synthetic.generate.draw`: :func:`random_truth` and :func:`truth_parameters`;
- :mod:`~rik.sysid.synthetic.generate.laws`: the truth's force laws, each written once for floats and arrays;
- :mod:`~rik.sysid.synthetic.generate.excitation`: :class:`ExcitationPlan`, :func:`excitation_plan` and the hand's
  profiles;
- :mod:`~rik.sysid.synthetic.generate.simulation`: :func:`simulate` (MuJoCo) and :func:`hand_gains`;
- :mod:`~rik.sysid.synthetic.generate.measure`: :func:`measure`, :func:`simulate_trials` and :func:`write_trials`.
"""

from __future__ import annotations

from rik.sysid.synthetic.generate.constants import (
    BASE_RANGES,
    BLOCK_MOVE_TIME,
    CREEP_STIFFNESS,
    CUBIC_FRACTION,
    CUBIC_VREF,
    DIRECTION_FEPS,
    DIRECTION_VEPS,
    EDGE_FRACTION,
    EFFECT_KINDS,
    EFFECT_RANGES,
    EXCITE,
    FORCE_NOISE,
    GRAVITY,
    HAND_DEADBAND,
    HAND_MAX,
    HAND_OMEGA,
    HAND_ZETA,
    JOINT_KINDS,
    LOAD_EXPONENT,
    MOVE_TIME,
    POSITION_NOISE,
    SLOW_RAMP,
    SOFT_CLOSE_EXPONENT,
    SOFT_CLOSE_VREF,
    SOLIMP_FRICTION,
    SOLREF_LIMIT,
    SOURCE,
    STRIBECK_EXPONENT,
    TRUTH_FILE,
    Range,
)
from rik.sysid.synthetic.generate.draw import SECOND_CONFLICTS, random_truth, truth_parameters
from rik.sysid.synthetic.generate.excitation import ExcitationPlan, Segment, SegmentKind, excitation_plan
from rik.sysid.synthetic.generate.laws import (
    FrictionLaw,
    Law,
    direction_share,
    effect_laws,
    ground_truth_force,
    magnet_scale,
)
from rik.sysid.synthetic.generate.measure import measure, simulate_trials, trial_units, write_trials
from rik.sysid.synthetic.generate.simulation import Simulation, hand_gains, simulate
from rik.sysid.synthetic.generate.truth import Effect, GroundTruth, read_truth

__all__ = [
    "BASE_RANGES", "BLOCK_MOVE_TIME", "CREEP_STIFFNESS", "CUBIC_FRACTION", "CUBIC_VREF", "DIRECTION_FEPS",
    "DIRECTION_VEPS", "EDGE_FRACTION", "EFFECT_KINDS", "EFFECT_RANGES", "EXCITE", "Effect", "ExcitationPlan",
    "FORCE_NOISE", "FrictionLaw", "GRAVITY", "GroundTruth", "HAND_DEADBAND", "HAND_MAX", "HAND_OMEGA", "HAND_ZETA",
    "JOINT_KINDS", "LOAD_EXPONENT", "Law", "MOVE_TIME", "POSITION_NOISE", "Range", "SECOND_CONFLICTS", "SLOW_RAMP",
    "SOFT_CLOSE_EXPONENT", "SOFT_CLOSE_VREF", "SOLIMP_FRICTION", "SOLREF_LIMIT", "SOURCE", "STRIBECK_EXPONENT",
    "Segment", "SegmentKind", "Simulation", "TRUTH_FILE", "direction_share", "effect_laws", "excitation_plan",
    "ground_truth_force", "hand_gains", "magnet_scale", "measure", "random_truth", "read_truth", "simulate",
    "simulate_trials", "trial_units", "truth_parameters", "write_trials",
]
