"""Differential inverse kinematics for an arm, with mink (quadratic programs on MuJoCo's kinematics).

One IK step per control step turns the target pose of rik's gripper frame into the arm's joint targets, as
:mod:`rik.sim.robots.arm` servos them: a frame task on the gripper frame (for an arm of fewer than six joints with its
orientation weighed less, :data:`FEW_JOINTS_ORIENTATION_COST`, and in the grasp planner's fallback reach check
less again where the position would miss: :meth:`ArmIK.step`), a light posture task towards the mount's home
posture (it settles the redundant joints of a 7-joint arm), and three limits: the joints' ranges, their speeds
(over the control step) and a distance to the floor for every link (mink's collision-avoidance limit).

The IK works on the arm's own kinematic model (no furniture, no gripper linkage), placed at its mount, so a step
costs a fraction of a millisecond and reads nothing but the joint positions it is given: a replay re-simulates
exactly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rik.sim.robots.arm import ROBOT_PREFIX, TCP_SITE, Placement, robot_spec
from rik.sim.robots.reach import REACH_TOLERANCE

if TYPE_CHECKING:
    from rik.schemas.robots import Robot

SOLVER = "daqp"
DAMPING = 1e-3
"""Levenberg-Marquardt damping of the IK step (keeps it calm near singular postures)."""
POSTURE_COST = 1e-3
"""Weight of the home posture against the gripper frame's pose (per rad, against per m)."""
STILL = 1e-5
"""A solve has converged when no joint moves more than this in a step, rad (an arm of fewer than six joints meets
a full pose only in the least-squares sense)."""
FLOOR_CLEARANCE = 0.02
"""Closest a link may come to the floor, m."""
FULL_POSE_JOINTS = 6
"""Joints an arm needs to meet any pose of its gripper frame (within its workspace)."""
FEW_JOINTS_ORIENTATION_COST = 0.2
"""Weight of the gripper frame's orientation (per rad, against its position's 1 per m) for an arm of fewer than
:data:`FULL_POSE_JOINTS` joints, which meets a pose only in the least-squares sense. An arm of more joints weighs
both alike (1)."""
POSITION_FIRST_ORIENTATION_COST = 0.05
"""The orientation's weight of a position-first step of an arm of fewer than :data:`FULL_POSE_JOINTS` joints (the
grasp planner's fallback reach check for plans its usual one drops, :func:`rik.sim.grasp.swing_plans`), taken
instead of the usual one where that would leave the gripper frame further from its target's position than the
reach tolerance (:data:`rik.sim.robots.reach.REACH_TOLERANCE`): the position first, the orientation kept within the
tolerance, as the scripted operator's sag correction meets the position in an episode (at
:data:`FEW_JOINTS_ORIENTATION_COST` alone the SO-100 ended 5.2 mm and 0.02 rad from a grasp it meets within 1 mm
and 0.05 rad at this weight)."""


class ArmIK:
    """The IK of one arm at one placement (see the module docstring)."""

    def __init__(self, robot: Robot, where: Placement) -> None:
        """The frame task weighs orientation at 1 per rad against 1 per m of position, or at
        :data:`FEW_JOINTS_ORIENTATION_COST` (with position-first steps, :data:`POSITION_FIRST_ORIENTATION_COST`) for
        an arm of fewer than :data:`FULL_POSE_JOINTS` joints."""
        import mink
        import mujoco

        assert robot.joints is not None and robot.mount is not None
        arm = robot_spec(robot, kinematic=True)
        world = mujoco.MjSpec()
        world.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05])
        frame = world.worldbody.add_frame(pos=where.pos.tolist(), quat=where.quat())
        frame.attach_body(arm.body(robot.model.root_body), ROBOT_PREFIX, "")
        self.model = world.compile()
        self.joints = [ROBOT_PREFIX + n for n in robot.joint_names]
        self.qpos_adr = np.array([self.model.joint(n).qposadr[0] for n in self.joints])
        if self.model.nq != len(self.joints):  # pragma: no cover - robot_spec removes every other joint
            raise AssertionError(f"the IK model of {robot.id} has {self.model.nq} coordinates")
        few = len(self.joints) < FULL_POSE_JOINTS
        self.orientation_cost = FEW_JOINTS_ORIENTATION_COST if few else 1.0
        self.position_first_cost: float | None = POSITION_FIRST_ORIENTATION_COST if few else None
        """The orientation's weight of a position-first step (:meth:`step`); None: none."""
        self.configuration = mink.Configuration(self.model)
        self._fk = mujoco.MjData(self.model)
        self._site = self.model.site(ROBOT_PREFIX + TCP_SITE).id
        self.frame_task = mink.FrameTask(ROBOT_PREFIX + TCP_SITE, "site", position_cost=1.0,
                                         orientation_cost=self.orientation_cost, lm_damping=1e-6)
        self.posture = mink.PostureTask(self.model, cost=POSTURE_COST)
        self.home = np.array(robot.mount.home, float)
        self.posture.set_target(self.home)
        speeds = {ROBOT_PREFIX + j.name: j.speed for j in robot.joints.joints}
        root = self.model.body(ROBOT_PREFIX + str(robot.model.root_body)).id
        links = [g for g in range(self.model.ngeom) if self.model.geom_bodyid[g] != root
                 and self.model.geom_bodyid[g] != 0 and self.model.geom_contype[g] | self.model.geom_conaffinity[g]]
        self.limits = [mink.ConfigurationLimit(self.model), mink.VelocityLimit(self.model, speeds),
                       mink.CollisionAvoidanceLimit(self.model, [(links, ["floor"])],
                                                    minimum_distance_from_collisions=FLOOR_CLEARANCE,
                                                    collision_detection_distance=0.1)]

    def _target(self, position: np.ndarray, rotation: np.ndarray):  # noqa: ANN202 - mink.SE3
        import mink

        return mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(np.asarray(rotation, float)),
                                                      np.asarray(position, float))

    def step(self, q: np.ndarray, position: np.ndarray, rotation: np.ndarray, dt: float,
             floor: bool = True, position_first: bool = False) -> np.ndarray:
        """Joint positions (rad) one IK step of ``dt`` s from ``q`` towards the gripper frame at ``position``
        (world, m) with ``rotation`` (world rotation matrix); ``floor``: with the floor's limit (it costs a third
        of a step). ``position_first``: where the step would end further from ``position`` than the reach tolerance,
        an arm with :attr:`position_first_cost` takes the step at that orientation weight instead when it ends
        nearer and within the tolerance's orientation error."""
        q_next = self._step(q, position, rotation, dt, floor)
        if not position_first or self.position_first_cost is None:
            return q_next
        dp, _ = self.error(q_next, position, rotation)
        if dp <= REACH_TOLERANCE[0]:
            return q_next
        self.frame_task.set_orientation_cost(self.position_first_cost)
        try:
            q_first = self._step(q, position, rotation, dt, floor)
        finally:
            self.frame_task.set_orientation_cost(self.orientation_cost)
        dp_first, da_first = self.error(q_first, position, rotation)
        return q_first if dp_first < dp and da_first <= REACH_TOLERANCE[1] else q_next

    def _step(self, q: np.ndarray, position: np.ndarray, rotation: np.ndarray, dt: float,
              floor: bool) -> np.ndarray:
        """One IK step at the frame task's weights (see :meth:`step`)."""
        import mink
        import qpsolvers

        self.configuration.update(np.asarray(q, float))
        self.frame_task.set_target(self._target(position, rotation))
        # mink.solve_ik without its check_limits (a Python loop over the joints that only warns: a quarter of a
        # step's cost); the same quadratic program and solver
        problem = mink.build_ik(self.configuration, [self.frame_task, self.posture], dt, DAMPING,
                                self.limits if floor else self.limits[:2])
        result = qpsolvers.solve_problem(problem, solver=SOLVER)
        if not result.found or result.x is None:  # a start outside the limits the QP cannot leave at once: hold
            return np.asarray(q, float).copy()
        return self.configuration.integrate(result.x / dt, dt)

    def solve(self, position: np.ndarray, rotation: np.ndarray, q0: np.ndarray | None = None,
              iterations: int = 200, tolerance: float = 1e-4, floor: bool = True,
              position_first: bool = False) -> tuple[np.ndarray, float, float]:
        """Joint positions that put the gripper frame at the pose, stepped from ``q0`` (default: home) under the
        limits (``floor``: the floor's too), as the arm would move there, with position-first steps where
        ``position_first`` (:meth:`step`); (q, position error m, orientation error rad) at the end."""
        q = (self.home if q0 is None else np.asarray(q0, float)).copy()
        for _ in range(iterations):
            q_next = self.step(q, position, rotation, 0.05, floor, position_first)
            err = self.error(q_next, position, rotation)
            if err[0] < tolerance and err[1] < 10 * tolerance or np.max(np.abs(q_next - q)) < STILL:
                return (q_next, *err)
            q = q_next
        return (q, *self.error(q, position, rotation))

    def frame(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position (m) and rotation matrix of the gripper frame at joint positions ``q`` (kinematics alone,
        in a data of its own: the IK's configuration is left as it was)."""
        import mujoco

        self._fk.qpos[:] = q
        mujoco.mj_kinematics(self.model, self._fk)
        return self._fk.site_xpos[self._site].copy(), self._fk.site_xmat[self._site].reshape(3, 3).copy()

    def error(self, q: np.ndarray, position: np.ndarray, rotation: np.ndarray) -> tuple[float, float]:
        """(position error m, orientation error rad) of the gripper frame at ``q`` from the pose."""
        self.configuration.update(np.asarray(q, float))
        site = self.configuration.data.site(ROBOT_PREFIX + TCP_SITE)
        dp = float(np.linalg.norm(site.xpos - np.asarray(position, float)))
        r = site.xmat.reshape(3, 3).T @ np.asarray(rotation, float)
        angle = float(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))
        return dp, angle
