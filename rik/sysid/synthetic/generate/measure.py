"""Measured trials from simulations: sampling, noise, delay, quantisation; writing them with the truth."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.schemas.trajectory import TrialColumns, TrialMeta, TrialUnits
from rik.sysid.synthetic.draws import joint_type as _joint
from rik.sysid.synthetic.generate.common import _non_negative, _positive
from rik.sysid.synthetic.generate.constants import FORCE_NOISE, POSITION_NOISE, SOURCE
from rik.sysid.synthetic.generate.excitation import excitation_plan
from rik.sysid.synthetic.generate.simulation import Simulation, simulate
from rik.sysid.synthetic.generate.truth import GroundTruth
from rik.sysid.trials import Trial, si_columns, write_simulated


def trial_units(joint: JointType) -> tuple[TrialUnits, TrialColumns]:
    """The SI units and CSV headers of a simulated trial of ``joint`` (:func:`rik.sysid.trials.si_columns`)."""
    return si_columns(_joint(joint))


def measure(sim: Simulation, rng: np.random.Generator, *, name: str = "trial_1", duration_s: float | None = None,
            rate_hz: float = 200.0, position_noise: float | None = None, force_noise: float | None = None,
            delay_s: float = 0.01, quantum: float | None = None) -> Trial:
    """Sample ``sim`` at ``rate_hz`` Hz for ``duration_s`` s (default: as long as it lasts), times from 0: force
    (zero-order hold) + N(0, ``force_noise``), position (interpolated) at ``delay_s`` s earlier +
    N(0, ``position_noise``), then rounded to multiples of ``quantum`` (m or rad) if given. Noise defaults per joint:
    :data:`POSITION_NOISE`, :data:`FORCE_NOISE`. The simulation must cover ``duration_s + |delay_s|``."""
    joint = sim.truth.joint
    position_noise = POSITION_NOISE[joint] if position_noise is None else position_noise
    force_noise = FORCE_NOISE[joint] if force_noise is None else force_noise
    _positive(rate_hz=rate_hz)
    _non_negative(position_noise=position_noise, force_noise=force_noise)
    if quantum is not None:
        _positive(quantum=quantum)
    if not (isinstance(delay_s, (int, float)) and math.isfinite(delay_s)):
        raise RikError(f"delay_s must be a finite number, got {delay_s!r}")
    span = float(sim.t[-1])
    available = span - abs(delay_s)
    duration = available if duration_s is None else float(duration_s)
    if duration_s is not None:
        _positive(duration_s=duration_s)
    if duration > available + 1e-9:
        raise RikError(f"duration_s {duration:g} s plus |delay_s| {abs(delay_s):g} s exceeds the simulation "
                       f"({span:g} s)")
    samples = int(math.floor(duration * rate_hz + 1e-9)) + 1
    t = np.arange(samples) / rate_hz
    offset = max(delay_s, 0.0)
    force_index = np.minimum(np.floor((t + offset) / sim.timestep + 1e-6).astype(np.int64), len(sim.f) - 1)
    f = sim.f[force_index] + rng.normal(0.0, force_noise, samples)
    q = np.interp(t + offset - delay_s, sim.t, sim.q) + rng.normal(0.0, position_noise, samples)
    if quantum is not None:
        q = np.round(q / quantum) * quantum
    si_units, columns = trial_units(joint)
    meta = TrialMeta(name=name, source=SOURCE, joint=joint, units=si_units, columns=columns, samples=samples,
                     duration=float(t[-1]))
    return Trial(meta, t, q, f)


def simulate_trials(truth: GroundTruth, *, n_trials: int = 4, seed: int = 0, duration_s: float = 12.0,
                    rate_hz: float = 200.0, timestep: float = 0.0005, position_noise: float | None = None,
                    force_noise: float | None = None, delay_s: float = 0.01,
                    quantum: float | None = None) -> list[Trial]:
    """``n_trials`` measured trials ``trial_1`` … of ``truth``, each with its own excitation plan, deterministic
    for ``seed``: ``duration_s`` s at ``rate_hz`` Hz simulated at ``timestep`` s; noise, delay (s, position later
    than force) and quantum as in :func:`measure`."""
    if not isinstance(truth, GroundTruth):
        raise RikError(f"truth must be a GroundTruth, got {type(truth).__name__}")
    if not isinstance(n_trials, int) or isinstance(n_trials, bool) or n_trials < 1:
        raise RikError(f"n_trials must be an integer ≥ 1, got {n_trials!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise RikError(f"seed must be an integer ≥ 0, got {seed!r}")
    _positive(duration_s=duration_s, rate_hz=rate_hz, timestep=timestep)
    if timestep > 0.5 / rate_hz:
        raise RikError(f"timestep {timestep:g} s must be at most half the sample interval ({0.5 / rate_hz:g} s)")
    _non_negative(position_noise=position_noise, force_noise=force_noise)
    if quantum is not None:
        _positive(quantum=quantum)
    if not (isinstance(delay_s, (int, float)) and math.isfinite(delay_s) and abs(delay_s) < duration_s):
        raise RikError(f"delay_s must be a finite number smaller than duration_s in size, got {delay_s!r}")
    trials = []
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n_trials)):
        plan_rng, noise_rng = (np.random.default_rng(s) for s in child.spawn(2))
        start = 0.0 if i == 0 else None
        plan = excitation_plan(truth.joint, truth.range[1], plan_rng, duration_s=duration_s, start=start)
        sim = simulate(truth, plan, duration_s=duration_s + abs(delay_s) + timestep, timestep=timestep)
        trials.append(measure(sim, noise_rng, name=f"trial_{i + 1}", duration_s=duration_s, rate_hz=rate_hz,
                              position_noise=position_noise, force_noise=force_noise, delay_s=delay_s,
                              quantum=quantum))
    return trials


def write_trials(trials: Sequence[Trial], directory: str | Path, truth: GroundTruth) -> list[Path]:
    """Write each trial to ``directory/<name>.csv`` (headers ``time [s]``, ``position [m|rad]``,
    ``force [N]`` or ``torque [N·m]``, values printed to round-trip exactly) and the truth to
    ``directory/truth.json``, the folder whole (:func:`rik.sysid.trials.write_simulated`: an existing folder is
    replaced only if it holds simulated trials); returns the CSV paths (for :func:`rik.sysid.trials.load_trials`)."""
    if not isinstance(truth, GroundTruth):
        raise RikError(f"truth must be a GroundTruth, got {type(truth).__name__}")
    return write_simulated(trials, directory, truth.joint, truth.to_json())
