"""The foreign generator (``rik.sysid.synthetic.foreign``): physics sanity of its own integrator (LuGre sticking with
presliding only, compliant end stops, a self-closing spring that shuts the front), its excitation, determinism,
trials that rik's preprocessing takes unchanged, a magnet law that is not rik's library law, and
``rik sysid simulate --generator foreign``."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rik.errors import RikError
from rik.schemas.joints import JointType, MagneticCatch
from rik.sysid.preprocess import preprocess
from rik.sysid.synthetic.foreign import (
    FOREIGN_KINDS,
    HINGE,
    SLIDE,
    ForeignTruth,
    Segment,
    effect_force,
    excitation,
    foreign_truth,
    run,
    simulate_foreign,
)
from rik.sysid.trials import load_trials

MM = 1e-3


def _truth(kind: str, joint: JointType = JointType.slide, seed: int = 0) -> ForeignTruth:
    return foreign_truth(kind, joint, np.random.default_rng(seed))


@pytest.mark.parametrize("joint", [JointType.slide, JointType.hinge])
@pytest.mark.parametrize("seed", [0, 1])
def test_a_front_released_inside_the_self_close_zone_ends_closed(joint: JointType, seed: int) -> None:
    truth = _truth("self_close", joint, seed)
    truth = dataclasses.replace(truth, coulomb=0.2 * truth.coulomb, static=0.2 * truth.static)
    zone = truth.params["zone"]
    sim = run(truth, [Segment("move", 0.6 * zone, speed=0.1 if joint is JointType.slide else 0.3),
                      Segment("hold", duration=0.8), Segment("release", duration=1.5)], start=0.8 * zone,
              duration_s=2.5)
    assert sim.released[-1] and sim.f[-1] == 0.0
    assert abs(sim.q[sim.released][0] - 0.6 * zone) < 0.05 * zone  # let go where it was held
    tolerance = 0.5 * MM if joint is JointType.slide else 0.5 * MM / 0.35
    assert abs(sim.q[-1]) < tolerance, (sim.q[-1], zone)  # pulled in, resting on the closed stop
    assert abs(sim.v[-1]) < 1e-3


def test_released_outside_the_zone_the_front_stays() -> None:
    truth = _truth("self_close")
    zone = truth.params["zone"]
    sim = run(truth, [Segment("hold", duration=0.2), Segment("release", duration=1.0)], start=zone + 0.02,
              duration_s=1.2)
    assert abs(sim.q[-1] - (zone + 0.02)) < 1 * MM


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lugre_front_at_rest_sticks_below_the_static_friction_and_slides_above(seed: int) -> None:
    truth = _truth("stiction", seed=seed)
    assert 1.4 <= truth.static / truth.coulomb <= 2.0
    start = 0.5 * truth.range[1]
    below = run(truth, [Segment("force", duration=1.5, force=0.85 * truth.static)], start=start, duration_s=1.5)
    shift = below.q - start
    assert shift.max() < 1 * MM  # presliding only
    assert shift[-1] > 1e-3 * MM  # ... but there is some: the bristles deflect
    assert abs(below.v[-1]) < 1e-4
    # above the static friction but below the sliding friction + what the damping takes, it breaks away
    above = run(truth, [Segment("force", duration=1.0, force=1.1 * truth.static)], start=start, duration_s=1.0)
    assert above.q[-1] - start > 20 * MM


def test_a_hinge_at_rest_sticks_below_the_static_friction() -> None:
    truth = _truth("stiction", JointType.hinge)
    sim = run(truth, [Segment("force", duration=1.0, force=-0.85 * truth.static)], start=1.0, duration_s=1.0)
    shift = sim.q - 1.0
    assert np.abs(shift).max() < 1 * MM / 0.35  # presliding only (1 mm at a 35 cm handle)
    assert shift[-1] < -1e-3 * MM / 0.35  # the bristles deflect, towards closed
    assert np.abs(sim.v[-2000:]).max() < 1e-5  # and the door is at rest, not chattering


@pytest.mark.parametrize(("joint", "lever"), [(JointType.slide, 1.0), (JointType.hinge, 0.35)])
def test_a_push_held_against_either_stop_sits_just_beyond_it(joint: JointType, lever: float) -> None:
    truth = _truth("none", joint)
    upper = truth.range[1]
    beyond = 0.015 / lever
    sim = run(truth, [Segment("move", -beyond, speed=0.3 / lever), Segment("hold", duration=1.0),
                      Segment("move", upper + beyond, speed=0.3 / lever), Segment("hold", duration=1.0)],
              start=0.3 * upper, duration_s=6.0)
    closed = (sim.q < 0.0) & (np.abs(sim.v) < 1e-3)
    opened = (sim.q > upper) & (np.abs(sim.v) < 1e-3)
    assert closed.sum() > 5000 and opened.sum() > 5000  # held at least 0.5 s against each
    assert np.median(sim.f[closed]) < -truth.coulomb and np.median(sim.f[opened]) > truth.coulomb  # pushing
    assert -1 * MM / lever < sim.q[closed].min() < 0.0 and sim.q[closed].max() < 0.1 * MM / lever
    assert upper < sim.q[opened].max() < upper + 1 * MM / lever and sim.q[opened].min() > upper - 0.1 * MM / lever


def test_the_excitation_holds_both_stops_creeps_releases_and_throws() -> None:
    truth = _truth("none")
    upper = truth.range[1]
    start, segments = excitation(truth.joint, upper, np.random.default_rng(4))
    kinds = [s.kind for s in segments]
    assert kinds.count("release") == 3 and kinds.count("throw") == 1 and kinds.count("creep") == 1
    creep = next(s for s in segments if s.kind == "creep")
    assert SLIDE.creep_speed[0] <= creep.speed <= SLIDE.creep_speed[1]
    goals = [s.goal for s in segments if s.kind == "move"]
    assert min(goals) <= -SLIDE.beyond[0] and max(goals) >= upper + SLIDE.beyond[0]
    sim = run(truth, segments, start=start, duration_s=12.0)
    assert np.all(sim.f[sim.released] == 0.0) and sim.released.mean() > 0.1
    assert np.abs(sim.f).max() <= SLIDE.hand_max
    assert sim.q.min() < 0.0 and sim.q.max() > upper  # pressed into both stops
    assert HINGE.hand_max < SLIDE.hand_max


def test_trials_are_deterministic_by_seed_and_pass_preprocessing() -> None:
    truth = _truth("magnetic_catch", seed=3)
    a = simulate_foreign(truth, n_trials=2, seed=5, duration_s=12.0)
    b = simulate_foreign(truth, n_trials=2, seed=5, duration_s=12.0)
    c = simulate_foreign(truth, n_trials=2, seed=6, duration_s=12.0)
    assert [t.name for t in a] == ["trial_1", "trial_2"]
    for x, y, z in zip(a, b, c, strict=True):
        assert np.array_equal(x.q, y.q) and np.array_equal(x.f, y.f) and np.array_equal(x.t, y.t)
        assert not np.array_equal(x.f, z.f)
        assert x.samples == 2401 and x.t[-1] == pytest.approx(12.0) and x.source == "foreign"
        prepared = preprocess(x)
        assert prepared.settings.rate_hz == 200.0
        assert abs(prepared.delay_s - 0.01) <= 0.0051  # the 10 ms force-to-position delay
    assert _truth("magnetic_catch", seed=3) == truth
    assert json.loads(json.dumps(truth.to_json()))["params"] == truth.params


def test_the_magnet_is_not_the_library_law() -> None:
    """The best fit of rik's library magnet (any pull, any decay) misses the foreign magnet by > 3 % RMS."""
    from rik.joints.laws import effect_force as library_force

    truth = _truth("magnetic_catch")
    decay = truth.params["decay"]
    q = np.linspace(0.0, 8 * decay, 400)
    v = np.zeros_like(q)
    mine = effect_force(truth, q, v)
    assert mine[0] == pytest.approx(-truth.params["force"])
    misfit = []
    for d in np.geomspace(decay / 20, decay * 20, 800):
        shape = library_force(MagneticCatch(force=1.0, decay=float(d)), q, v, JointType.slide)
        amplitude = float(mine @ shape / (shape @ shape))
        misfit.append(np.sqrt(np.mean((amplitude * shape - mine) ** 2) / np.mean(mine**2)))
    assert min(misfit) > 0.03


def test_every_kind_simulates_within_the_stops() -> None:
    for kind in FOREIGN_KINDS:
        truth = _truth(kind, seed=1)
        trial = simulate_foreign(truth, n_trials=1, seed=1, duration_s=12.0)[0]
        assert np.all(np.isfinite(trial.q)) and np.all(np.isfinite(trial.f))
        assert -3 * MM < trial.q.min() and trial.q.max() < truth.range[1] + 3 * MM, kind


def test_bad_kind_and_joint_are_refused() -> None:
    with pytest.raises(RikError, match=r"kind 'spring' is not a foreign effect kind; use one of none, stiction"):
        foreign_truth("spring", "slide", np.random.default_rng(0))
    with pytest.raises(RikError, match=r"joint 'ball' is not a joint type; use 'slide' or 'hinge'"):
        foreign_truth("none", "ball", np.random.default_rng(0))


def test_cli_simulate_foreign_writes_loadable_trials(rik, tmp_path) -> None:
    out = tmp_path / "data"
    result = rik("sysid", "simulate", "--generator", "foreign", "--effect", "self_close", "--trials", "2",
                 "--duration", "3", "--out", str(out))
    assert result.code == 0, result.err
    truth = json.loads((out / "truth.json").read_text())
    assert truth["generator"] == "foreign" and truth["kind"] == "self_close"
    trials = load_trials(sorted(out.glob("*.csv")), "slide")
    assert [t.samples for t in trials] == [601, 601]


def test_cli_simulate_foreign_refuses_what_it_cannot_draw(rik, tmp_path) -> None:
    result = rik("sysid", "simulate", "--generator", "foreign", "--effect", "spring", "--out", str(tmp_path / "d"))
    assert result.code == 2
    assert "rik: error: --effect 'spring' is not an effect of the foreign generator; use one of none" in result.err
    result = rik("sysid", "simulate", "--generator", "foreign", "--effect", "tilt", "--mass", "3", "--out",
                 str(tmp_path / "d"))
    assert result.code == 2 and "--second and --mass work with --generator rik only" in result.err


def test_the_foreign_laws_import_nothing_of_riks_effect_laws() -> None:
    import ast
    import inspect

    import rik.sysid.synthetic.foreign as foreign

    imported = set()
    for node in ast.walk(ast.parse(inspect.getsource(foreign))):
        if isinstance(node, ast.Import):
            imported.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module or "")
    forbidden = ("rik.sim", "rik.sysid.effects", "rik.combinator", "rik.sysid.synthetic.generate", "rik.sysid.fit",
                 "rik.joints")
    assert not [m for m in imported if m.startswith(forbidden)], imported
