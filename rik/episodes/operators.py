"""Operators: whatever produces the action of each control step. Scripted strategies with ground-truth handle
geometry (the paper's baselines and a closed-loop contact-rich strategy), learned policies, and teleop devices
all have the same shape, so the recorder and the benchmark treat them alike.

An action is 7 numbers: the target pose of the gripper's base (x, y, z in m, world; pitch, yaw, roll in rad) and
the gripper command (0 open, 0.5 closed without force, 1 closed with the full grip force).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from rik.errors import RikError
from rik.sim.grasp import PULL_SPEED, SWING_TILTS, GraspPlan, hook_plans, pinch_fits, pinch_plan, swing_plans
from rik.sim.outcome import SUCCESS_OPENING
from rik.sim.pose import base_for_tcp
from rik.sim.probe import APPROACH
from rik.sim.scene import SimScene

ACTION_NAMES = ("x", "y", "z", "pitch", "yaw", "roll", "gripper")
MOVE_SPEED = 0.25
"""Free-space speed of the gripper, m/s."""
APPROACH_SPEED = 0.08
"""Speed of the last few centimetres onto the handle, m/s."""
PULL_LEAD = 0.06
"""How far the commanded point may run ahead of the gripper in a pull, m (beyond the servo's force cap)."""
CLOSE_TIME = 0.6
"""Time given to the fingers to close and settle, s."""
SLIP_DISTANCE = 0.015
"""The handle moving this far relative to the pads means the grasp slipped, m."""
STALL_TIME = 1.5
"""A pull that gains less than :data:`STALL_PROGRESS` of the range in this time has stalled, s."""
STALL_PROGRESS = 0.01
DONE_OPENING = 0.97
"""A strategy stops pulling when the front is this far open (fraction of its range)."""
NOISE_TIME = 0.5
"""Correlation time of the action noise, s: an Ornstein-Uhlenbeck offset, so the gripper drifts off the path far
enough for the strategy's way back to be worth learning (white noise at 20 Hz averages out in the servos)."""
NOISE_ANGLE_PER_M = 5.0
"""Standard deviation of the angle noise per metre of position noise, rad/m (0.01 m: 0.05 rad, 2.9 degrees)."""
SAG_GAIN = 3.0
"""A swinging-jaw arm's sag correction: the rate at which the commanded pads' point is moved to cancel the gap
between where they were sent and where they are, 1/s (a time constant of 0.33 s)."""
SAG_DWELL = 1.0
"""How long a swinging-jaw arm pauses at the pre-grasp pose for its sag correction to settle, s."""
SAG_LIMIT = 0.04
"""The largest sag correction, m."""
REHEARSAL_PULL = 1.0
"""A swinging-jaw arm's scripted operator rehearses each grasp in the simulator up to this much pull, s
(:meth:`ScriptedGrasp.rehearse_plans`)."""
REHEARSAL_LIMIT = 10.0
"""The longest rehearsal of one grasp, simulated s (an approach that never ends counts as not holding)."""


class Operator(Protocol):
    """Produces one action per control step. ``done`` ends the episode early."""

    name: str
    done: bool

    def reset(self, scene: SimScene, rng: np.random.Generator) -> None: ...

    def act(self, scene: SimScene) -> np.ndarray: ...


# ---- the scripted operator ------------------------------------------------------------------------------------
@dataclass
class _Motion:
    """A straight move of the commanded pads' point and a blend of the angles."""

    start: np.ndarray
    end: np.ndarray
    a0: np.ndarray
    a1: np.ndarray
    speed: float
    t: float = 0.0
    dwell: float = 0.0
    """The least time the motion lasts, s (a pause at its end, for a still one)."""

    @property
    def duration(self) -> float:
        return max(float(np.linalg.norm(self.end - self.start)) / self.speed,
                   float(np.max(np.abs(self.a1 - self.a0))) / 1.5, 1e-9, self.dwell)


@dataclass
class ScriptedGrasp:
    """Grasp the operated handle by a plan, close, and pull the front open along its motion.

    ``closed_loop``: watch for slip (the handle moving relative to the pads) and stall (no progress while pulling),
    then let go, back off and re-grasp with the next plan, up to ``regrasps`` times.
    """

    name: str
    planner: Callable[[SimScene], list[GraspPlan]]
    closed_loop: bool = False
    regrasps: int = 3
    jitter: float = 0.0
    """Standard deviation of a random offset of the grasp point (m), drawn per episode."""
    action_noise: float = 0.0
    """Standard deviation of the noise on the executed target position, m (angles: :data:`NOISE_ANGLE_PER_M`
    times it, rad; the gripper command is never disturbed). DART-style: the episode records the strategy's own
    action while the robot runs the disturbed one, so the recorded actions lead back to the path from wherever
    the noise took the gripper. 0: none."""
    rehearse: bool = True
    """For a gripper with a fixed and a swinging jaw (the SO arms), try the planner's grasps in the simulator
    before each attempt and take the first that holds (:meth:`rehearse_plans`); off for strategies whose plans must not
    depend on the collision model (``planned``). Parallel jaws never rehearse."""
    turn_with_front: bool = True
    """While pulling a hinged front, turn the gripper with it (:meth:`_turn_with_the_front`)."""
    done: bool = False
    log: list[str] = field(default_factory=list)

    def reset(self, scene: SimScene, rng: np.random.Generator) -> None:
        self.done, self.log = False, []
        self._rng = rng
        self._offset = rng.normal(0.0, self.jitter, 3) if self.jitter > 0 else np.zeros(3)
        self._offset[1] = 0.0
        # the noise has a generator of its own, drawn last: without noise the episode is what it always was
        self._noise_rng = np.random.default_rng(int(rng.integers(2**63))) if self.action_noise > 0 else None
        self._noise = np.zeros(6)
        self._noise_decay = float(np.exp(-1.0 / (scene.control_fps * NOISE_TIME)))
        self._begin(scene, scene.tcp(), scene.pose()[3:].copy(), np.zeros(3))

    def _begin(self, scene: SimScene, cmd_tcp: np.ndarray, angles: np.ndarray, sag: np.ndarray) -> None:
        """Start the first attempt from the commanded pads' point ``cmd_tcp`` (m), ``angles`` (rad) and sag
        correction ``sag`` (m)."""
        self._tried: list[str] = []
        self._attempts = 0
        self._cmd_tcp, self._angles, self._sag = cmd_tcp, angles, sag
        self._grip = 0.0
        self._correct_sag = scene.gripper.fixed_jaw is not None
        self._start_plan(scene)

    # phases: approach (motions) -> close -> pull -> [release -> retreat -> approach ...]
    def _start_plan(self, scene: SimScene) -> None:
        plans = [p for p in self.planner(scene) if p.key not in self._tried]
        # a plan only the position-first reach check reaches after every other, in its order (the sort is stable)
        plans.sort(key=lambda p: p.position_first)
        if self.rehearse and self._correct_sag and len(plans) > 1:
            plans = self.rehearse_plans(scene, plans)
        if not plans:
            self.done = True
            self.log.append("no grasp found")
            return
        plan = plans[0]
        self._tried.append(plan.key)
        self._plan = plan
        target = plan.tcp + self._offset
        pre = target + plan.approach * APPROACH
        # leave the current spot along the old approach before turning, then come in along the new one
        self._motions = [_Motion(self._cmd_tcp, pre, self._angles.copy(), plan.angles, MOVE_SPEED),
                         _Motion(pre, target, plan.angles, plan.angles, APPROACH_SPEED)]
        if self._correct_sag:  # pause at the pre-grasp pose until the sag correction has settled there
            self._motions.insert(1, _Motion(pre, pre, plan.angles, plan.angles, MOVE_SPEED, dwell=SAG_DWELL))
        self._phase, self._clock = "approach", 0.0
        self.log.append(f"attempt {self._attempts + 1}: {plan.mode} {plan.detail}".strip())

    def rehearse_plans(self, scene: SimScene, plans: list[GraspPlan]) -> list[GraspPlan]:
        """``plans`` with the first that holds in a rehearsal put first, the others in their order: each is tried
        from this very moment in the simulator (approach, close, :data:`REHEARSAL_PULL` s of pull, watched for slip
        and stall as a closed-loop attempt is) and the scene is put back exactly as it was (every field of its
        data), so the episode goes on as if nothing had run. A swinging jaw's pinch on a lip or a knob's stem holds
        or slips in ways the handle's bounding box does not tell (docs/benchmark.md); the scripted demonstrator may
        use the simulator as its model of the world, as it uses the ground-truth geometry."""
        import copy

        import mujoco

        saved = copy.copy(scene.data)
        for i, plan in enumerate(plans):
            try:
                held = self._rehearsal_holds(scene, plan)
            finally:
                mujoco.mj_copyData(scene.data, scene.model, saved)
            if held:
                return [plan, *plans[:i], *plans[i + 1:]]
        return plans

    def _rehearsal_holds(self, scene: SimScene, plan: GraspPlan) -> bool:
        """Whether ``plan``, run from the scene's present state as this operator would run it, still holds the
        handle after :data:`REHEARSAL_PULL` s of pull (or opened the front). Changes the scene."""
        trial = ScriptedGrasp(self.name, lambda _scene: [plan], closed_loop=True, regrasps=0, rehearse=False)
        trial._offset = self._offset
        trial._begin(scene, self._cmd_tcp.copy(), self._angles.copy(), self._sag.copy())
        for _ in range(int(round(REHEARSAL_LIMIT * scene.control_fps))):
            scene.step(trial.act(scene))
            if trial.done:  # opened, stopped past a success, or let go (slip, stall, nothing planned)
                return scene.opening() >= SUCCESS_OPENING
            if trial._phase == "pull" and trial._clock >= REHEARSAL_PULL:
                return True
        return False

    def perturb(self, action: np.ndarray) -> np.ndarray | None:
        """The action the robot runs for the strategy's ``action`` (None: the same one): ``action`` plus this
        step's correlated noise on the target pose."""
        if self._noise_rng is None:
            return None
        sigma = self.action_noise * np.array([1.0, 1.0, 1.0, NOISE_ANGLE_PER_M, NOISE_ANGLE_PER_M,
                                              NOISE_ANGLE_PER_M])
        a = self._noise_decay
        self._noise = a * self._noise + np.sqrt(1.0 - a * a) * self._noise_rng.normal(0.0, 1.0, 6) * sigma
        executed = np.asarray(action, np.float64).copy()
        executed[:6] += self._noise
        return executed

    def _action(self, scene: SimScene) -> np.ndarray:
        return np.concatenate([base_for_tcp(scene.gripper, self._cmd_tcp + self._sag, self._angles), [self._grip]])

    def _track(self, scene: SimScene, dt: float) -> None:
        """A swinging-jaw arm (the SO arms) sags under its own weight by more than the millimetres its fixed jaw
        clears a handle by; while it moves in free space, integrate the gap between the commanded pads' point and
        the measured one into the command (up to :data:`SAG_LIMIT`), so the jaws arrive where the plan put them.
        The correction is held while closing and pulling. Parallel jaws (Hand-E, Panda) are never corrected."""
        if not self._correct_sag:
            return
        self._sag = self._sag + SAG_GAIN * dt * (self._cmd_tcp - scene.tcp())
        size = float(np.linalg.norm(self._sag))
        if size > SAG_LIMIT:
            self._sag *= SAG_LIMIT / size

    def act(self, scene: SimScene) -> np.ndarray:
        dt = 1.0 / scene.control_fps
        self._clock += dt
        if self.done:
            return self._action(scene)
        if self._phase in ("approach", "retreat"):
            self._track(scene, dt)
        if self._phase == "approach":
            if self._follow(dt):
                self._phase, self._clock, self._grip = "close", 0.0, 1.0
        elif self._phase == "close":
            if self._clock >= CLOSE_TIME:
                self._phase, self._clock = "pull", 0.0
                self._hold = scene.grasp_point() - scene.tcp()
                self._progress = [(0.0, scene.opening())]
                self._grasped = (scene.front_q()[0], self._angles.copy(), self._hold.copy())
        elif self._phase == "pull":
            self._pull(scene, dt)
        elif self._phase == "release":
            self._grip = 0.0
            if self._clock >= 0.4:
                back = self._plan.approach * 0.04 + np.array([0.0, 0.03, 0.0])
                self._motions = [_Motion(self._cmd_tcp, scene.tcp() + back, self._angles, self._angles, MOVE_SPEED)]
                self._phase, self._clock = "retreat", 0.0
        elif self._phase == "retreat":
            if self._follow(dt):
                self._start_plan(scene)
        return self._action(scene)

    def _follow(self, dt: float) -> bool:
        """Advance the commanded pose ``dt`` along the queued motions; True once the last one is done."""
        m = self._motions[0]
        m.t = min(m.t + dt, m.duration)
        s = m.t / m.duration
        self._cmd_tcp = m.start + s * (m.end - m.start)
        self._angles = m.a0 + s * (m.a1 - m.a0)
        if m.t >= m.duration:
            self._motions.pop(0)
        return not self._motions

    def _turn_with_the_front(self, scene: SimScene) -> None:
        """On a hinged front, turn the commanded gripper (and the hold offset the slip check compares with) about
        the hinge's axis by the angle the front turned since the grasp closed, as a hand turns with a door: held at
        its first orientation, a pinch faces a handle that turned up to 100 degrees away from it and slips off near
        the end of the swing (the benchmark's doors read P at 86-88 % open; docs/benchmark.md)."""
        if not scene.front.motion.endswith("hinge"):
            return
        from scipy.spatial.transform import Rotation

        from rik.sim.pose import angles_of, gripper_rotation, nearest_angles

        q0, angles0, hold0 = self._grasped
        turn = Rotation.from_rotvec(scene.data.xaxis[scene.front.joint] * (scene.front_q()[0] - q0))
        rotation = turn.as_matrix() @ gripper_rotation(angles0)
        self._angles = nearest_angles(angles_of(rotation), self._angles)
        self._hold = turn.apply(hold0)

    def _pull(self, scene: SimScene, dt: float) -> None:
        opening = scene.opening()
        if opening >= DONE_OPENING:
            self.done = True
            self.log.append(f"opened {opening:.0%}")
            return
        if self.turn_with_front:
            self._turn_with_the_front(scene)
        tcp = scene.tcp()
        direction = scene.pull_direction()
        cmd = self._cmd_tcp + PULL_SPEED * dt * direction
        lead = cmd - tcp
        if np.linalg.norm(lead) > PULL_LEAD:
            cmd = tcp + lead / np.linalg.norm(lead) * PULL_LEAD
        self._cmd_tcp = cmd
        self._progress.append((self._clock, opening))
        if not self.closed_loop:
            return
        slipped = np.linalg.norm(scene.grasp_point() - tcp - self._hold) > SLIP_DISTANCE
        old = [o for t, o in self._progress if t <= self._clock - STALL_TIME]
        stalled = bool(old) and opening - old[-1] < STALL_PROGRESS
        if slipped or stalled:
            event = f"{'slip' if slipped else 'stall'} at {opening:.0%} open"
            if opening >= SUCCESS_OPENING:  # a re-grasp's way in would push the front back below a success
                self.done = True
                self.log.append(f"{event}, past a success: stop")
                return
            self._attempts += 1
            self.log.append(event)
            if self._attempts > self.regrasps:
                self.done = True
                return
            self._phase, self._clock = "release", 0.0


VERTICAL_SIDES = ("below", "above")
HORIZONTAL_SIDES = ("left", "right")


SWING_CHOICES = 2 * len(SWING_TILTS)
"""Every swing plan of two sides: the pinch strategies run only their first plan, which a swinging-jaw arm's
rehearsal picks among them (:meth:`ScriptedGrasp.rehearse_plans`)."""


def _pinch_h(scene: SimScene) -> list[GraspPlan]:
    return [*swing_plans(scene, HORIZONTAL_SIDES, limit=SWING_CHOICES), pinch_plan(scene, vertical=False)]


def _pinch_v(scene: SimScene) -> list[GraspPlan]:
    return [*swing_plans(scene, VERTICAL_SIDES, limit=SWING_CHOICES), pinch_plan(scene, vertical=True)]


def _pinch_natural(scene: SimScene) -> list[GraspPlan]:
    vertical = pinch_fits(scene)
    return [*swing_plans(scene, VERTICAL_SIDES if vertical else HORIZONTAL_SIDES, limit=SWING_CHOICES),
            pinch_plan(scene, vertical=vertical)]


def _contact_rich(scene: SimScene, geometry: str = "collision", prefer: str | None = None) -> list[GraspPlan]:
    natural = pinch_fits(scene, geometry)
    sides = (*VERTICAL_SIDES, *HORIZONTAL_SIDES) if natural else (*HORIZONTAL_SIDES, *VERTICAL_SIDES)
    return [*swing_plans(scene, sides, limit=2, geometry=geometry),
            *hook_plans(scene, limit=2, geometry=geometry, prefer=prefer),
            pinch_plan(scene, vertical=natural, geometry=geometry),
            pinch_plan(scene, vertical=not natural, geometry=geometry)]


def _planned(scene: SimScene) -> list[GraspPlan]:
    return _contact_rich(scene, geometry="visual")


def _planned_above(scene: SimScene) -> list[GraspPlan]:
    return _contact_rich(scene, geometry="visual", prefer="above")


TYPED_HOOK_SIDES = {"two_point": "above", "finger_pull": "below"}
"""``planned_typed``'s hook side first, per handle type: the side ``planned`` itself picks most often by bite
(two-point handles 89 of 120 from above, finger pulls 76 of 113 from below, docs/policies.md); knobs, where forcing
one side cost grasps, keep ``planned``'s ranking by bite."""


def _planned_typed(scene: SimScene) -> list[GraspPlan]:
    return _contact_rich(scene, geometry="visual", prefer=TYPED_HOOK_SIDES.get(scene.info["handle_type"]))


@dataclass(frozen=True)
class Strategy:
    name: str
    summary: str
    make: Callable[[], ScriptedGrasp]


STRATEGIES: dict[str, Strategy] = {s.name: s for s in (
    Strategy("grasp_horizontal", "friction only: fingers towards the front, jaws horizontal, close on the handle's "
             "outer part and pull (the paper's 'normal way')",
             lambda: ScriptedGrasp("grasp_horizontal", _pinch_h, jitter=0.002)),
    Strategy("grasp_vertical", "friction only: as grasp_horizontal with the jaws vertical",
             lambda: ScriptedGrasp("grasp_vertical", _pinch_v, jitter=0.002)),
    Strategy("grasp_natural", "friction only: the pinch whose jaws close across the handle's narrower side",
             lambda: ScriptedGrasp("grasp_natural", _pinch_natural, jitter=0.002)),
    Strategy("contact_rich", "closed loop: a finger behind material (into a loop, under a lip, behind a knob's "
             "head) found by ray casts; on slip or stall let go and re-grasp with the next plan",
             lambda: ScriptedGrasp("contact_rich", _contact_rich, closed_loop=True, jitter=0.002)),
    Strategy("planned", "as contact_rich, but every grasp is planned on the catalog's visual meshes, not on the "
             "collision model: the same plan whichever collision a variant was built with (hull, CoACD)",
             lambda: ScriptedGrasp("planned", _planned, closed_loop=True, jitter=0.002, rehearse=False)),
    Strategy("planned_above", "as planned, but a hook from above first wherever one is found (planned ranks hooks "
             "by their bite, so the same handle is hooked from above in one drawer and from below in the next): "
             "one way to hold each handle, which a policy that cannot see the handle's shape can imitate",
             lambda: ScriptedGrasp("planned_above", _planned_above, closed_loop=True, jitter=0.002,
                                   rehearse=False)),
    Strategy("planned_typed", "as planned, with one hook side first per handle type: from above for two-point "
             "handles, from below for finger pulls (the sides planned picks most by bite), knobs by bite as planned",
             lambda: ScriptedGrasp("planned_typed", _planned_typed, closed_loop=True, jitter=0.002,
                                   rehearse=False)),
)}
PARAMS = ("jitter", "regrasps", "action_noise")
"""Parameters :func:`make_operator` sets on a strategy."""


def make_operator(name: str, params: Mapping[str, float | int] | None = None) -> ScriptedGrasp:
    """A fresh scripted operator by strategy name, with ``params`` (``jitter``, m; ``regrasps``; ``action_noise``,
    m) set on it."""
    try:
        operator = STRATEGIES[name].make()
    except KeyError:
        import difflib

        close = difflib.get_close_matches(name, STRATEGIES, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise RikError(f"unknown strategy '{name}' (strategies: {', '.join(STRATEGIES)}){hint}") from None
    for key, value in (params or {}).items():
        if key not in PARAMS:
            raise RikError(f"strategy {name}: unknown parameter '{key}' (parameters: {', '.join(PARAMS)})")
        setattr(operator, key, value)
    return operator


@dataclass
class PolicyOperator:
    """A learned (or any) policy as an operator: ``policy(observation) -> action`` where the action is the
    environment's (a target-pose delta and a gripper command, see :mod:`rik.envs.open_front`)."""

    policy: Callable[[dict[str, Any]], np.ndarray]
    name: str = "policy"
    done: bool = False

    def reset(self, scene: SimScene, rng: np.random.Generator) -> None:
        self.done = False
        self._target = scene.pose()

    def act(self, scene: SimScene) -> np.ndarray:
        from rik.sim.observation import delta_to_absolute, state_observation

        action = np.asarray(self.policy(state_observation(scene)), np.float64)
        absolute = delta_to_absolute(self._target, action)
        self._target = absolute[:6]
        return absolute


__all__ = ["ACTION_NAMES", "Operator", "PolicyOperator", "STRATEGIES", "make_operator"]
