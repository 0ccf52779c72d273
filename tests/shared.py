"""What many test files share: the built-in catalog, loaded once per test process, and the ids of the demo's
variant. Session fixtures that build from them live in ``conftest.py``."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rik.episodes.operators import ScriptedGrasp
    from rik.registry.catalog import Catalog
    from rik.sim.scene import SimScene

BOW = "drawer-chest-80__two_point-bow-128__normal"
"""The demo's first variant: the 80 cm chest of drawers with the 128 mm bow handle, normal resistance."""
BOW_HANDLE, DEMO_BASE = "two_point/bow-128", "drawer/chest-80"


@functools.cache
def builtin_catalog() -> Catalog:
    """The built-in catalog (no overlays), loaded once per process; treat it as read-only."""
    from rik.registry.load import load_catalog

    return load_catalog([])


def grasp_until_pull(scene: SimScene, max_steps: int, strategy: str = "grasp_vertical") -> ScriptedGrasp:
    """Run ``strategy`` (seed 0, start randomised as a recording does) on ``scene`` until its jaws have closed and
    it starts to pull, or for ``max_steps`` control steps; the operator, for the caller to check its phase."""
    import numpy as np

    from rik.episodes.operators import make_operator
    from rik.episodes.record import randomise_start

    rng = np.random.default_rng(0)
    randomise_start(scene, rng)
    op = make_operator(strategy)
    op.reset(scene, rng)
    for _ in range(max_steps):
        if op._phase == "pull":
            break
        scene.step(op.act(scene))
    return op
