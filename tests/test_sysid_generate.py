"""The ground-truth generator (``rik.sysid.synthetic.generate``): determinism, CSV round trip, the excitation, the delay
convention, physics sanity, truth shapes that differ from the library laws but keep their parameters, parameter
ranges, and bad arguments."""

from __future__ import annotations

import dataclasses
import functools
import json
import math

import numpy as np
import pytest

from rik.errors import RikError
from rik.schemas.joints import (
    DirectionFriction,
    JointType,
    LoadFriction,
    MagneticCatch,
    QuadraticDamping,
    SelfClose,
    SoftClose,
    Spring,
    Stiction,
    Tilt,
)
from rik.sysid.preprocess import preprocess
from rik.sysid.synthetic import generate as gen
from rik.sysid.synthetic.generate import (
    BASE_RANGES,
    EFFECT_KINDS,
    EFFECT_RANGES,
    FORCE_NOISE,
    TRUTH_FILE,
    ExcitationPlan,
    GroundTruth,
    Segment,
    effect_laws,
    excitation_plan,
    ground_truth_force,
    measure,
    random_truth,
    read_truth,
    simulate,
    simulate_trials,
    truth_parameters,
    write_trials,
)
from rik.sysid.trials import load_trials

SLIDE, HINGE = JointType.slide, JointType.hinge
DRAWER = GroundTruth(SLIDE, mass=6.0, damping=4.0, frictionloss=3.0, range=(0.0, 0.4))
DOOR = GroundTruth(HINGE, mass=0.8, damping=0.2, frictionloss=0.4, range=(0.0, 1.6))


@functools.cache
def run(joint: JointType, kind: str | None, seed: int = 0) -> gen.Simulation:
    """A 12 s simulation of a random truth with effect ``kind``."""
    truth = random_truth(kind, joint, np.random.default_rng(seed))
    plan = excitation_plan(joint, truth.range[1], np.random.default_rng(seed + 100))
    return simulate(truth, plan, duration_s=12.0)


# ------------------------------------------------------------------------------------ determinism, files

def test_same_seed_same_trials_other_seed_other_trials() -> None:
    a = simulate_trials(DRAWER, n_trials=2, seed=5, duration_s=6.0)
    b = simulate_trials(DRAWER, n_trials=2, seed=5, duration_s=6.0)
    c = simulate_trials(DRAWER, n_trials=2, seed=6, duration_s=6.0)
    assert [t.name for t in a] == ["trial_1", "trial_2"]
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x.t, y.t) and np.array_equal(x.q, y.q) and np.array_equal(x.f, y.f)
    assert not np.array_equal(a[0].q, c[0].q)
    assert not np.array_equal(a[0].q, a[1].q[: len(a[0].q)])  # each trial its own excitation
    trial = a[0]
    assert trial.samples == 1201 and trial.meta.duration == pytest.approx(6.0)
    assert np.allclose(np.diff(trial.t), 1 / 200)
    assert trial.source == "simulated" and trial.meta.units.position == "m" and trial.meta.units.force == "N"
    assert trial.q.min() > -0.01 and trial.q.max() < 0.41


@pytest.mark.parametrize("truth", [DRAWER, DOOR], ids=["slide", "hinge"])
def test_csv_round_trip(tmp_path, truth: GroundTruth) -> None:
    truth = GroundTruth(truth.joint, truth.mass, truth.damping, truth.frictionloss, truth.range,
                        Spring(stiffness=1.0 if truth.joint is HINGE else 20.0, reference=-0.05))
    trials = simulate_trials(truth, n_trials=2, seed=1, duration_s=4.0)
    paths = write_trials(trials, tmp_path / "out", truth)
    assert [p.name for p in paths] == ["trial_1.csv", "trial_2.csv"]
    header = paths[0].read_text(encoding="utf-8").splitlines()[0]
    assert header == ("time [s],position [m],force [N]" if truth.joint is SLIDE
                      else "time [s],position [rad],torque [N·m]")
    back = load_trials(paths, truth.joint)
    for x, y in zip(trials, back, strict=True):
        assert y.name == x.name
        assert np.array_equal(x.t, y.t) and np.array_equal(x.q, y.q) and np.array_equal(x.f, y.f)
    assert read_truth(tmp_path / "out") == truth
    assert read_truth(tmp_path / "out" / TRUTH_FILE).effect == truth.effect
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".")]  # no temporaries left


def test_truth_json_round_trip_for_every_kind() -> None:
    for joint in (SLIDE, HINGE):
        for kind in (None, *EFFECT_KINDS):
            truth = random_truth(kind, joint, np.random.default_rng(3))
            assert truth.kind == kind
            assert GroundTruth.from_json(truth.to_json()) == truth


# ----------------------------------------------------------------------------------------- excitation

@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_excitation_has_holds_releases_slow_stroke_and_both_ends(joint: JointType) -> None:
    sim = run(joint, None)
    truth, dt = sim.truth, sim.timestep
    upper = truth.range[1]
    segs = [(k, a, b) for k, a, b in sim.segments if b <= 12.0 + 1e-9]
    kinds = [k for k, _, _ in segs]
    holds = [(a, b) for k, a, b in segs if k == "hold" and b - a >= 0.5 - 1e-9]
    assert len(holds) >= 3 and all(b - a <= 1.5 for a, b in holds)
    releases = [(int(round(a / dt)), int(round(b / dt))) for k, a, b in segs if k == "release"]
    assert len(releases) >= 2
    assert all(0.5 <= (j - i) * dt <= 1.0 + 1e-9 for i, j in releases)
    for i, j in releases:
        assert np.all(sim.f[i:j] == 0.0) and np.all(sim.released[i:j])
    # one let go near closed while moving (15-30 mm or 3-9°), one from rest at mid-range
    near = EXCITE_NEAR[joint]
    starts = [(sim.q[i], abs(sim.v[i])) for i, _ in releases]
    assert any(q <= near and v > 0.05 * MOVE_SCALE[joint] for q, v in starts)
    assert any(0.25 * upper <= q <= 0.75 * upper and v < 0.005 * MOVE_SCALE[joint] for q, v in starts)
    assert any(np.abs(sim.v[i:j]).max() > 0.05 * MOVE_SCALE[joint] for i, j in releases)  # moving, force 0
    # a slow stroke that moves, strokes up to fast, the closed end and the far stop reached
    slow = [s for s in sim.plan.segments if s.kind == "slow"]
    assert slow and slow[0].speed <= (0.02 if joint is SLIDE else 0.05)
    a, b = next((a, b) for k, a, b in segs if k == "slow")
    moved = sim.q[int(b / dt) - 1] - sim.q[int(a / dt)]
    assert abs(moved) > 0.3 * abs(slow[0].goal - sim.q[int(a / dt)])
    assert np.abs(sim.v).max() > 0.25 * MOVE_SCALE[joint]
    assert sim.q.min() <= 0.001 * MOVE_SCALE[joint]
    assert sim.q.max() >= 0.9 * upper
    assert "throw" in kinds
    # measured: the hand force is the recorded force, ~0 within noise while released
    trial = measure(sim, np.random.default_rng(0), duration_s=11.9, delay_s=0.0)
    rel = np.zeros(trial.samples, dtype=bool)
    for i, j in releases:
        rel |= (trial.t >= (i + 1) * dt) & (trial.t < (j - 1) * dt)
    assert rel.sum() > 150
    assert np.abs(trial.f[rel]).max() < 5 * FORCE_NOISE[joint]


EXCITE_NEAR = {SLIDE: 0.031, HINGE: 0.151}
MOVE_SCALE = {SLIDE: 1.0, HINGE: 4.0}  # m/s → rad/s, m → rad for thresholds


@pytest.mark.parametrize("delay", [0.01, 0.025, -0.015])
@pytest.mark.parametrize("truth", [DRAWER, DOOR], ids=["slide", "hinge"])
def test_delay_is_recovered_by_preprocess(truth: GroundTruth, delay: float) -> None:
    """The delay convention agrees with preprocess (positive: position recorded later). Position noise is off:
    preprocess's delay search is thrown off by the default 0.2° on a door (its noisy acceleration)."""
    trial = simulate_trials(truth, n_trials=1, seed=2, delay_s=delay, duration_s=8.0, position_noise=0.0)[0]
    prepared = preprocess(trial)
    assert abs(prepared.settings.delay_s - delay) <= 1 / 200 + 1e-9


def test_delay_is_recovered_with_default_noise_on_most_drawer_trials() -> None:
    trials = simulate_trials(DRAWER, n_trials=3, seed=1, delay_s=0.02)
    found = [preprocess(t).settings.delay_s for t in trials]
    assert sum(abs(d - 0.02) <= 1 / 200 + 1e-9 for d in found) >= 2, found


def test_position_lags_force_by_the_delay() -> None:
    sim = run(SLIDE, None)
    rng = np.random.default_rng(0)
    a = measure(sim, rng, duration_s=10.0, delay_s=0.0, position_noise=0.0, force_noise=0.0)
    b = measure(sim, rng, duration_s=10.0, delay_s=0.02, position_noise=0.0, force_noise=0.0)
    assert np.allclose(b.f[:-4], a.f[4:])  # the same force is recorded at t and...
    assert np.allclose(b.q[4:-4], a.q[4:-4])  # ...the position at t is the true position 20 ms before the force's
    q = measure(sim, rng, duration_s=10.0, quantum=1e-3).q
    assert np.allclose(q / 1e-3, np.round(q / 1e-3))


# -------------------------------------------------------------------------------------------- physics

def _release_drift(truth: GroundTruth, start: float) -> float:
    plan = ExcitationPlan(start, (Segment("hold", duration=0.5), Segment("release", duration=1.0)))
    sim = simulate(truth, plan, duration_s=1.5)
    released = np.flatnonzero(sim.released)
    assert len(released) == 2000 and np.all(sim.f[released] == 0.0)
    return float(sim.q[released[-1] + 1] - sim.q[released[0]])


@pytest.mark.parametrize("force", [5.0, -5.0, 2.0, -2.9])
def test_tilted_drawer_drifts_on_release_only_above_friction(force: float) -> None:
    truth = GroundTruth(SLIDE, 6.0, 4.0, 3.0, (0.0, 0.4), Tilt(force=force))
    drift = _release_drift(truth, 0.2)
    if abs(force) > truth.frictionloss:
        assert drift * force > 0 and abs(drift) > 0.02
    else:
        assert abs(drift) < 1e-5  # friction holds: no creep


@pytest.mark.parametrize(("force", "sine", "moves"), [(0.2, 0.6, True), (0.1, 0.2, False)])
def test_tilted_door_drifts_on_release_only_above_friction(force: float, sine: float, moves: bool) -> None:
    truth = GroundTruth(HINGE, 0.8, 0.2, 0.4, (0.0, 1.6), Tilt(force=force, sine=sine))
    drift = _release_drift(truth, 0.8)
    assert (abs(drift) > 0.02) if moves else (abs(drift) < 1e-5)


@pytest.mark.parametrize(("effect", "at", "static"), [
    (Stiction(breakaway=2.0, stribeck_velocity=0.02), 0.2, {1: 5.0, -1: 5.0}),
    (DirectionFriction(extra=2.0, direction="closing"), 0.2, {1: 3.0, -1: 5.0}),
    (DirectionFriction(extra=2.0, direction="opening"), 0.2, {1: 5.0, -1: 3.0}),
    (LoadFriction(per_extension=10.0), 0.3, {1: 3.0 + 10.0 * 0.2 * 1.5**1.1, -1: 3.0 + 10.0 * 0.2 * 1.5**1.1}),
], ids=["stiction", "direction-closing", "direction-opening", "load"])
def test_friction_effects_hold_below_their_static_level_without_creep(effect, at: float, static: dict) -> None:
    """The hand's push ramps slowly (2 s) to 90 % or 110 % of the static friction in each direction."""
    truth = _truth(effect)
    kp, _ = gen.hand_gains(truth)
    for direction in (1, -1):
        for share, moves in ((0.9, False), (1.1, True)):
            goal = at + direction * share * static[direction] / kp
            plan = ExcitationPlan(at, (Segment("move", goal, 1e-3, 2.0), Segment("hold", duration=0.5)))
            sim = simulate(truth, plan, duration_s=2.5)
            drift = sim.q[-1] - at
            if moves:
                assert drift * direction > 3e-4, (direction, share, drift)  # breaks away
            else:
                assert abs(drift) < 1e-5, (direction, share, drift)


@pytest.mark.parametrize("kind", EFFECT_KINDS)
@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_simulation_applies_the_truth_law_and_it_is_identifiable(joint: JointType, kind: str) -> None:
    """Equation of motion on sliding samples away from the stops: f = m a + b v + (Fc + extra) sign v − applied;
    and the effect's RMS force where active is at least 3× the force noise."""
    sim = run(joint, kind)
    truth, dt = sim.truth, sim.timestep
    q, v, f = sim.q[:-1], sim.v[:-1], sim.f[:-1]
    a = np.diff(sim.v) / dt
    applied, extra = effect_laws(truth, q, v, f)
    # MuJoCo's friction constraint, though nearly hard, is regularised while a front decelerates to a stop: the
    # law holds exactly from about 25 mm/s (0.06 rad/s) up
    slide_ = (np.abs(v) > 0.03 * MOVE_SCALE[joint]) & (np.sign(v) == np.sign(sim.v[1:]))
    inside = (q > 0.01 * MOVE_SCALE[joint]) & (q < truth.range[1] - 0.01 * MOVE_SCALE[joint])
    keep = slide_ & inside
    # implicitfast treats the joint damping implicitly: (m + dt b) a = ...
    model = (truth.mass + dt * truth.damping) * a + truth.damping * v + (truth.frictionloss + extra) * np.sign(v) \
        - applied
    scale = float(np.abs(ground_truth_force(truth, q, v, f)).max())
    assert keep.sum() > 2000
    assert np.abs(f - model)[keep].max() < 1e-6 * (1.0 + scale)  # exact: the law is what the simulation applies
    g = ground_truth_force(truth, sim.q, sim.v)
    active = np.abs(g) > 0.05 * np.abs(g).max()
    assert math.sqrt(np.mean(g[active] ** 2)) >= 3 * FORCE_NOISE[joint]


@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_step_loop_laws_match_the_vectorised_laws(joint: JointType) -> None:
    rng = np.random.default_rng(1)
    qq = rng.uniform(-0.01, 0.5 if joint is SLIDE else 1.8, 500)
    vv = np.concatenate([rng.uniform(-0.5, 0.5, 250), rng.uniform(-0.01, 0.01, 250)]) * MOVE_SCALE[joint]
    ff = rng.uniform(-5.0, 5.0, 500) * (1.0 if joint is SLIDE else 0.1)
    for kind in EFFECT_KINDS:
        truth = random_truth(kind, joint, np.random.default_rng(7))
        applied, friction = gen.laws._scalar_laws(truth)
        va, vf = effect_laws(truth, qq, vv, ff)
        got_a = np.zeros(500) if applied is None else np.array([applied(*x) for x in zip(qq, vv, strict=True)])
        got_f = np.zeros(500) if friction is None else np.array([friction(*x) for x in zip(qq, vv, ff, strict=True)])
        assert np.allclose(got_a, va, rtol=1e-9, atol=1e-12), kind
        assert np.allclose(got_f, vf, rtol=1e-9, atol=1e-12), kind


# ------------------------------------------------------------------------------------ shapes vs library

def _truth(effect, joint: JointType = SLIDE) -> GroundTruth:
    base = DRAWER if joint is SLIDE else DOOR
    return GroundTruth(joint, base.mass, base.damping, base.frictionloss, base.range, effect)


def _force(truth: GroundTruth, q: float, v: float) -> float:
    return float(ground_truth_force(truth, np.array([q]), np.array([v]))[0])


def test_soft_close_keeps_its_damping_but_not_its_shape() -> None:
    e = SoftClose(zone=0.05, damping=100.0)
    t = _truth(e)
    assert _force(t, 0.025, -0.1) == pytest.approx(100.0 * 0.1, rel=0.05)  # = damping · 0.1 m/s in the zone
    assert _force(t, 0.025, +0.1) == 0.0  # closing only
    assert _force(t, 0.2, -0.1) == pytest.approx(0.0, abs=1e-6)  # outside the zone
    assert abs(_force(t, 0.025, -0.4) - 100.0 * 0.4) > 0.05 * 40.0  # |v|^1.1, not linear
    assert _force(t, 0.0515, -0.1) > 0.1 * 10.0  # a smooth edge: still acting just past the zone
    assert _force(t, 0.05, -0.1) == pytest.approx(5.0, rel=1e-6)  # half at the edge
    hinge = _truth(SoftClose(zone=0.3, damping=2.0), HINGE)
    assert _force(hinge, 0.15, -0.25) == pytest.approx(2.0 * 0.25, rel=0.05)


def test_self_close_keeps_its_pull_but_not_its_shape() -> None:
    e = SelfClose(zone=0.03, stiffness=400.0)
    t = _truth(e)
    assert _force(t, 0.0, 0.0) == pytest.approx(-12.0, rel=0.01)  # stiffness · zone at closed
    assert _force(t, 0.015, 0.0) == pytest.approx(-6.0, rel=0.01)
    assert _force(t, 0.03, 0.0) < -0.2  # rounded edge (library: 0)
    assert _force(t, 0.05, 0.0) == pytest.approx(0.0, abs=1e-3)
    assert _force(t, 0.015, 0.3) == _force(t, 0.015, -0.3)  # conservative


def test_magnet_keeps_its_pull_and_impulse_but_not_its_shape() -> None:
    e = MagneticCatch(force=15.0, decay=0.004)
    t = _truth(e)
    q = np.linspace(0.0, 0.4, 400001)
    truth_f = ground_truth_force(t, q, np.zeros_like(q))
    library = -15.0 / (1 + q / 0.004) ** 2
    assert truth_f[0] == pytest.approx(-15.0)
    assert np.trapezoid(truth_f, q) == pytest.approx(np.trapezoid(library, q), rel=1e-3)
    i = int(0.004 / 0.4 * 400000)
    assert abs(truth_f[i] - library[i]) > 0.1 * abs(library[i])


def test_friction_effects_keep_their_levels_but_not_their_shapes() -> None:
    stiction = _truth(Stiction(breakaway=2.0, stribeck_velocity=0.02))
    _, level = effect_laws(stiction, np.zeros(3), np.array([0.0, 0.02, 0.04]))
    assert level[0] == pytest.approx(2.0) and level[1] == pytest.approx(2.0 / math.e)
    assert level[2] > 2.0 * 2.0 * math.exp(-4.0)  # exponent 1.5: slower fade than the library's 2
    for direction, sign in (("closing", -1.0), ("opening", 1.0)):
        t = _truth(DirectionFriction(extra=2.0, direction=direction))
        _, level = effect_laws(t, np.zeros(3), np.array([sign * 0.1, 0.0, -sign * 0.1]))
        assert level == pytest.approx([2.0, 1.0, 0.0], abs=1e-6)
    load = _truth(LoadFriction(per_extension=20.0))
    _, level = effect_laws(load, np.array([0.0, 0.2, 0.4]), np.zeros(3))
    assert level[0] == 0.0 and level[1] == pytest.approx(20.0 * 0.2)  # equal at mid-range
    assert level[2] == pytest.approx(20.0 * 0.4 * 2**0.1) and level[2] != pytest.approx(8.0, rel=0.05)
    assert _force(load, 0.2, 0.1) == pytest.approx(-4.0) and _force(load, 0.2, 0.0) == 0.0


def test_damping_tilt_and_spring() -> None:
    quad = _truth(QuadraticDamping(coefficient=25.0))
    assert _force(quad, 0.1, 0.01) == pytest.approx(-25.0 * 1e-4, rel=0.01)
    assert _force(quad, 0.1, -0.3) == pytest.approx(25.0 * 0.09 * 1.1)  # + 10 % cubic at 0.3 m/s
    tilt = _truth(Tilt(force=0.5, sine=-0.3), HINGE)
    assert _force(tilt, 0.7, 0.3) == pytest.approx(0.5 * math.cos(0.7) - 0.3 * math.sin(0.7))  # exact
    assert _force(_truth(Tilt(force=-3.0)), 0.3, 0.0) == -3.0
    spring = _truth(Spring(stiffness=30.0, reference=-0.05))
    assert _force(spring, 0.2, 0.1) == pytest.approx(-30.0 * 0.25)  # exact


# ----------------------------------------------------------------------------------------- random truths

@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_random_truths_stay_in_their_declared_ranges(joint: JointType) -> None:
    types = {"stiction": Stiction, "soft_close": SoftClose, "self_close": SelfClose, "magnetic_catch": MagneticCatch,
             "tilt": Tilt, "direction_friction": DirectionFriction, "quadratic_damping": QuadraticDamping,
             "load_friction": LoadFriction, "spring": Spring}
    for kind in (None, *EFFECT_KINDS):
        for seed in range(8):
            truth = random_truth(kind, joint, np.random.default_rng(seed))
            assert truth.joint is joint and truth.range[0] == 0.0
            if kind is None:
                assert truth.effect is None
            else:
                assert isinstance(truth.effect, types[kind])
            params = truth_parameters(truth)
            for name, (lo, hi) in BASE_RANGES[joint].items():
                if not (kind == "stiction" and name == "frictionloss"):
                    assert lo - 1e-9 <= params[name] <= hi + 1e-9, (kind, name, params[name], (lo, hi))
            for name, (lo, hi) in EFFECT_RANGES[joint].get(kind or "", {}).items():
                value = params.get(f"effect.{name}", params.get(name))
                assert value is not None, (kind, name)
                assert lo - 1e-9 <= value <= hi + 1e-9, (kind, name, value, (lo, hi))
            if kind == "tilt" and joint is HINGE:
                assert truth.effect.force != 0.0 and truth.effect.sine != 0.0
            if kind == "tilt" and joint is SLIDE:
                assert truth.effect.sine == 0.0
    assert random_truth("spring", joint, np.random.default_rng(0), mass=3.0).mass == 3.0


# ---------------------------------------------------------------------------------------------- two effects

SOFT_CLOSE_RUNNER = GroundTruth(SLIDE, 6.0, 4.0, 3.0, (0.0, 0.4), SoftClose(zone=0.05, damping=100.0),
                                SelfClose(zone=0.03, stiffness=400.0))


def _singles(truth: GroundTruth) -> tuple[GroundTruth, GroundTruth]:
    """The two one-effect truths of a two-effect ``truth``."""
    return dataclasses.replace(truth, second=None), dataclasses.replace(truth, effect=truth.second, second=None)


def test_two_effect_truth_round_trips_and_old_files_load(tmp_path) -> None:
    truth = SOFT_CLOSE_RUNNER
    assert truth.kind == "soft_close" and truth.kinds == ("soft_close", "self_close")
    assert truth.effects == (truth.effect, truth.second)
    data = truth.to_json()
    assert data["second"] == {"kind": "self_close", "zone": 0.03, "stiffness": 400.0}
    assert GroundTruth.from_json(data) == truth
    spring = dataclasses.replace(truth, second=Spring(stiffness=20.0, reference=-0.05))
    assert spring.kinds == ("soft_close", "spring") and GroundTruth.from_json(spring.to_json()) == spring
    # a one-effect truth is written as before (no "second") and a file without "second" loads
    single = dataclasses.replace(truth, second=None)
    assert "second" not in single.to_json() and single.kinds == ("soft_close",) and DRAWER.kinds == ()
    old = {k: v for k, v in data.items() if k != "second"}
    (tmp_path / TRUTH_FILE).write_text(json.dumps(old), encoding="utf-8")
    loaded = read_truth(tmp_path)
    assert loaded == single and loaded.second is None
    for joint in (SLIDE, HINGE):
        for kind, second in (("soft_close", "self_close"), ("self_close", "soft_close"), ("stiction", "spring"),
                             ("tilt", "direction_friction"), ("magnetic_catch", "tilt")):
            drawn = random_truth(kind, joint, np.random.default_rng(4), second=second)
            assert drawn.kinds == (kind, second)
            assert GroundTruth.from_json(json.loads(json.dumps(drawn.to_json()))) == drawn


def test_two_effect_truths_are_refused_when_inconsistent() -> None:
    base = (SLIDE, 6.0, 4.0, 3.0, (0.0, 0.4))
    rng = np.random.default_rng(0)
    cases = [
        (lambda: GroundTruth(*base, SoftClose(zone=0.05, damping=1.0), SoftClose(zone=0.03, damping=2.0)),
         "GroundTruth second is a soft_close, the same kind as effect; the two effects must be of different "
         "kinds"),
        (lambda: GroundTruth(*base, Spring(stiffness=1.0), Spring(stiffness=2.0)),
         "GroundTruth second is a spring, the same kind as effect"),
        (lambda: GroundTruth(*base, None, SelfClose(zone=0.03, stiffness=400.0)),
         "GroundTruth second (self_close) needs a first effect: give it as effect"),
        (lambda: GroundTruth(*base, Spring(stiffness=1.0), "wobble"),
         "GroundTruth second must be a JointEffect, a Spring or None, got str"),
        (lambda: GroundTruth(*base, Spring(stiffness=1.0), SelfClose(zone=0.5, stiffness=1.0)),
         "GroundTruth second zone 0.5 must be inside the range"),
        (lambda: GroundTruth(*base, Spring(stiffness=1.0), Tilt(force=1.0, sine=0.5)),
         "GroundTruth second: a slide's tilt has no sine term"),
        (lambda: GroundTruth.from_json({**SOFT_CLOSE_RUNNER.to_json(), "second": {"kind": "warp"}}),
         "ground truth second is malformed"),
        (lambda: random_truth("soft_close", SLIDE, rng, second="soft_close"),
         "second 'soft_close' is the same kind as kind; the two effects must differ"),
        (lambda: random_truth(None, SLIDE, rng, second="self_close"),
         "second 'self_close' needs a first effect kind; give kind"),
        (lambda: random_truth("soft_close", SLIDE, rng, second="wobble"), "second 'wobble' is not an effect kind"),
        (lambda: random_truth("tilt", HINGE, rng, second="stiction"),
         "kind 'tilt' and second 'stiction' cannot be drawn together: both set the Coulomb friction"),
        (lambda: random_truth("stiction", SLIDE, rng, second="tilt"),
         "kind 'stiction' and second 'tilt' cannot be drawn together"),
    ]
    for call, words in cases:
        with pytest.raises(RikError) as exc:
            call()
        assert words in _one_line(exc)


@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_random_two_effect_truths_keep_the_first_draws_and_their_ranges(joint: JointType) -> None:
    for kind in EFFECT_KINDS:
        for second in EFFECT_KINDS:
            if second == kind or {kind, second} == {"tilt", "stiction"}:
                continue
            for seed in range(3):
                one = random_truth(kind, joint, np.random.default_rng(seed))
                two = random_truth(kind, joint, np.random.default_rng(seed), second=second)
                assert two.kinds == (kind, second) and two.kind == kind
                assert two.effect == one.effect and two.damping == one.damping and two.range == one.range
                if second not in ("tilt", "stiction"):  # these set the friction (tilt on a slide: the mass too)
                    assert two.mass == one.mass and two.frictionloss == one.frictionloss
                params = truth_parameters(two)
                for name, (lo, hi) in EFFECT_RANGES[joint][second].items():
                    value = params.get(f"second.{name}", params.get(name))  # stiction's frictionloss: base
                    assert value is not None, (second, name)
                    assert lo - 1e-9 <= value <= hi + 1e-9, (kind, second, name, value, (lo, hi))
                for name, (lo, hi) in EFFECT_RANGES[joint][kind].items():
                    if name in ("frictionloss", "over_friction", "ratio") and second in ("tilt", "stiction"):
                        continue  # the second redrew the friction the first's ratio refers to
                    value = params.get(f"effect.{name}", params.get(name))
                    assert lo - 1e-9 <= value <= hi + 1e-9, (kind, second, name, value, (lo, hi))


@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_two_effect_laws_are_the_sums_of_the_single_laws(joint: JointType) -> None:
    rng = np.random.default_rng(2)
    q = rng.uniform(-0.01, 0.5 if joint is SLIDE else 1.8, 400)
    v = np.concatenate([rng.uniform(-0.5, 0.5, 200), rng.uniform(-0.01, 0.01, 200)]) * MOVE_SCALE[joint]
    load = rng.uniform(-5.0, 5.0, 400) * (1.0 if joint is SLIDE else 0.1)
    pairs = [("soft_close", "self_close"), ("self_close", "soft_close"), ("stiction", "direction_friction"),
             ("load_friction", "quadratic_damping"), ("tilt", "spring"), ("magnetic_catch", "stiction")]
    for kind, second in pairs:
        truth = random_truth(kind, joint, np.random.default_rng(5), second=second)
        first, other = _singles(truth)
        applied, friction = effect_laws(truth, q, v, load)
        a1, f1 = effect_laws(first, q, v, load)
        a2, f2 = effect_laws(other, q, v, load)
        assert np.array_equal(applied, a1 + a2) and np.array_equal(friction, f1 + f2), (kind, second)
        assert np.array_equal(ground_truth_force(truth, q, v, load),
                              ground_truth_force(first, q, v, load) + ground_truth_force(other, q, v, load))
        # the step loop's closures sum the same
        step_a, step_f = gen.laws._scalar_laws(truth)
        got_a = np.zeros(400) if step_a is None else np.array([step_a(*x) for x in zip(q, v, strict=True)])
        got_f = np.zeros(400) if step_f is None else np.array([step_f(*x) for x in zip(q, v, load, strict=True)])
        assert np.allclose(got_a, applied, rtol=1e-9, atol=1e-12), (kind, second)
        assert np.allclose(got_f, friction, rtol=1e-9, atol=1e-12), (kind, second)
    # the soft-close runner: damper and pull-in spring both act inside their zones
    damper, spring = _singles(SOFT_CLOSE_RUNNER)
    assert _force(SOFT_CLOSE_RUNNER, 0.015, -0.1) == pytest.approx(_force(damper, 0.015, -0.1)
                                                                   + _force(spring, 0.015, 0.0))
    assert _force(SOFT_CLOSE_RUNNER, 0.0, 0.0) == pytest.approx(-12.0, rel=0.01)
    assert gen.hand_gains(SOFT_CLOSE_RUNNER)[0] >= max(gen.hand_gains(damper)[0], gen.hand_gains(spring)[0])


@pytest.mark.parametrize("joint", [SLIDE, HINGE])
def test_two_effect_simulation_applies_the_summed_law_and_its_trials_load_back(tmp_path, joint: JointType) -> None:
    truth = random_truth("soft_close", joint, np.random.default_rng(0), second="self_close")
    plan = excitation_plan(joint, truth.range[1], np.random.default_rng(100))
    sim = simulate(truth, plan, duration_s=12.0)
    dt = sim.timestep
    q, v, f = sim.q[:-1], sim.v[:-1], sim.f[:-1]
    a = np.diff(sim.v) / dt
    applied, extra = effect_laws(truth, q, v, f)
    first, other = _singles(truth)
    assert np.array_equal(applied, effect_laws(first, q, v, f)[0] + effect_laws(other, q, v, f)[0])
    keep = (np.abs(v) > 0.02 * MOVE_SCALE[joint]) & (np.sign(v) == np.sign(sim.v[1:])) \
        & (q > 0.001 * MOVE_SCALE[joint]) & (q < truth.range[1] - 0.01 * MOVE_SCALE[joint])
    model = (truth.mass + dt * truth.damping) * a + truth.damping * v + (truth.frictionloss + extra) * np.sign(v) \
        - applied
    both = keep & (np.abs(effect_laws(first, q, v)[0]) > 0.1) & (np.abs(effect_laws(other, q, v)[0]) > 0.1)
    assert keep.sum() > 2000 and both.sum() > 20  # both effects act together on some samples
    assert np.abs(f - model)[keep].max() < 1e-6 * (1.0 + float(np.abs(applied).max()))
    trials = simulate_trials(truth, n_trials=2, seed=3, duration_s=4.0)
    paths = write_trials(trials, tmp_path / "out", truth)
    back = load_trials(paths, joint)
    for x, y in zip(trials, back, strict=True):
        assert y.name == x.name
        assert np.array_equal(x.t, y.t) and np.array_equal(x.q, y.q) and np.array_equal(x.f, y.f)
    loaded = read_truth(tmp_path / "out")
    assert loaded == truth and loaded.kinds == ("soft_close", "self_close")


# ---------------------------------------------------------------------------------------------- bad input

def _one_line(exc: pytest.ExceptionInfo) -> str:
    message = str(exc.value)
    assert "\n" not in message
    return message


def test_bad_arguments_are_one_line_rik_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(0)
    cases = [
        (lambda: random_truth("wobble", SLIDE, rng), "kind 'wobble'"),
        (lambda: random_truth("tilt", "ball", rng), "joint 'ball'"),
        (lambda: random_truth(None, SLIDE, rng, mass=-1.0), "mass"),
        (lambda: simulate_trials(DRAWER, n_trials=0), "n_trials"),
        (lambda: simulate_trials(DRAWER, rate_hz=0.0), "rate_hz"),
        (lambda: simulate_trials(DRAWER, duration_s=-1.0), "duration_s"),
        (lambda: simulate_trials(DRAWER, timestep=0.01), "timestep"),
        (lambda: simulate_trials(DRAWER, position_noise=-0.1), "position_noise"),
        (lambda: simulate_trials(DRAWER, delay_s=math.nan), "delay_s"),
        (lambda: GroundTruth(SLIDE, 6.0, 4.0, 3.0, (0.0, 0.4), Tilt(force=1.0, sine=0.5)), "sine"),
        (lambda: GroundTruth(SLIDE, 0.0, 4.0, 3.0, (0.0, 0.4)), "mass"),
        (lambda: GroundTruth(SLIDE, 6.0, 4.0, 3.0, (0.1, 0.4)), "range"),
        (lambda: GroundTruth(SLIDE, 6.0, 4.0, 3.0, (0.0, 0.4), SoftClose(zone=0.5, damping=1.0)), "zone"),
        (lambda: GroundTruth.from_json({"joint": "slide"}), "lacks"),
        (lambda: GroundTruth.from_json({**DRAWER.to_json(), "effect": {"kind": "warp"}}), "effect"),
        (lambda: write_trials([], "/nonexistent", DRAWER), "trials"),
    ]
    for call, word in cases:
        with pytest.raises(RikError) as exc:
            call()
        assert word in _one_line(exc)
    monkeypatch.setitem(gen.JOINT_KINDS, HINGE, ("spring",))
    with pytest.raises(RikError) as exc:
        random_truth("magnetic_catch", HINGE, rng)
    assert "kind 'magnetic_catch' is not valid for a hinge joint" in _one_line(exc)
