"""The finger test on every catalogued two-point handle: a 10 mm finger passes through the loop of rik's CoACD
collision, and the single convex hull of prior data sets blocks it. This is why the decomposition matters.

Each handle is decomposed with the real CoACD parameters (about 1 to 3 s each), so this file is the slowest of the
suite; the assets are cached for the rest of the session."""

from __future__ import annotations

import pytest
from shared import builtin_catalog

from rik.assets.build import build_asset
from rik.assets.finger import FINGER_RADIUS, finger_test

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CATALOG = builtin_catalog()
TWO_POINT = [h.id for h in CATALOG.handles.values() if CATALOG.handle_type(h).value == "two_point"]


def test_every_two_point_handle_is_covered():
    assert len(TWO_POINT) == 34


@pytest.mark.parametrize("handle_id", TWO_POINT)
def test_finger_passes_coacd_and_is_blocked_by_the_hull(handle_id):
    asset, _ = build_asset(CATALOG, handle_id)
    part = asset.part("handle")
    geometry = CATALOG.handles[handle_id].geometry
    free = finger_test(part.hulls, geometry)
    blocked = finger_test(part.baseline, geometry)
    assert free.passes, f"{handle_id}: the finger touches the CoACD collision ({free.min_distance * 1e3:.2f} mm)"
    assert not blocked.passes, f"{handle_id}: the convex hull left the loop open"
    # the collision is really there: the grip above the finger is nearer than the handle's top
    assert free.min_distance < geometry.projection - geometry.clearance.depth / 2 - FINGER_RADIUS
