"""The simulator against a door's measured profile (rik.benchmark.real_doors): a door fitted from profiles, built
as a variant with its fitted preset and pulled through its handle, reproduces the fitted law at the handle, and
the comparison uses only the held-out openings. A synthetic door (a catch on a friction level, with noise), so the
test needs no data from outside the repository."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from shared import builtin_catalog

from rik.benchmark.real_doors import error_table, simulate_door
from rik.sysid.profile import Profile, ProfileGroup
from rik.sysid.real_presets import RealDoor, door_preset, fit_door, handle_force, split_openings

Q = np.radians(np.arange(36.0))
"""36 bins of 1°, as the real data, rad."""


def fridge(level: float = 2.0, catch: float = 20.0, decay_deg: float = 3.0, openings: int = 8) -> ProfileGroup:
    """Openings of a fridge-like door: force at the handle (N) = level + a catch's pull, plus 0.2 N of noise; the
    held-out openings (the last quarter) are 1 N stronger throughout, so that they differ from what was fitted."""
    rng = np.random.default_rng(11)
    law = level + catch / (1 + Q / math.radians(decay_deg)) ** 2
    shift = [1.0 if i >= openings - openings // 4 else 0.0 for i in range(openings)]
    return ProfileGroup("test_fridge", tuple(Profile(str(i), Q, law + shift[i] + rng.normal(0, 0.2, Q.size))
                                             for i in range(openings)))


def test_a_simulated_door_reproduces_its_fitted_preset_against_the_heldout_openings(tmp_path) -> None:
    group = fridge()
    fit = fit_door(group)
    catalog = builtin_catalog()
    preset = door_preset(group, "Fridge", catalog.presets, fit=fit)
    catalog = dataclasses.replace(catalog, presets={**catalog.presets, preset.id: preset})
    door = RealDoor(group, "Fridge", split_openings(group), fit, preset)

    result = simulate_door(catalog, door, tmp_path)

    assert result.heldout == ("6", "7")  # compared only with the openings the preset was not fitted on
    # the fitted law misses the held-out openings by their 1 N shift, and the simulator adds nothing of its own
    assert 0.9 < result.rms_law_n < 1.2
    assert abs(result.rms_fitted_n - result.rms_law_n) < 0.05
    # through the whole stroke, the simulated force at the catalog's lever arm follows the preset's law
    q, force = result.sim_q[preset.id], result.sim_force[preset.id]
    inside = (q > math.radians(0.5)) & (q < math.radians(35.0))
    expected = handle_force(preset.hinge, q[inside])
    assert np.max(np.abs(force[inside] - expected)) < 0.15  # N: damping at 5 °/s, the hook's small oscillations
    # the nearest paper preset (smooth: 5 N at the handle, no catch) misses the catch entirely
    assert result.paper_preset == "smooth" and result.rms_paper_n > 3 * result.rms_fitted_n
    table = error_table([result])
    assert "| test_fridge | Fridge | 2 | smooth |" in table and "median of 1 doors" in table
