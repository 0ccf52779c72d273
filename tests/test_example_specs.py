"""Every data-set spec committed under examples/ loads as `rik dataset build` reads it, so a documented command
never starts with a spec error."""

from __future__ import annotations

from pathlib import Path

import pytest

from rik.dataset.spec import load_spec
from rik.registry import load_catalog

ROOT = Path(__file__).parents[1]
SPECS = sorted((ROOT / "examples").rglob("*.yaml"))


def test_examples_hold_specs() -> None:
    assert len(SPECS) >= 5


@pytest.mark.parametrize("path", SPECS, ids=lambda p: str(p.relative_to(ROOT)))
def test_each_example_spec_loads_and_draws_from_the_catalog(path: Path) -> None:
    from rik.dataset.plan import draw_episodes, select_variants

    spec = load_spec(path)
    catalog = load_catalog()
    if spec.variants.draw is not None:
        drawn = draw_episodes(catalog, spec, str(path))
        assert len(drawn) == spec.variants.draw
        assert len({seed for _, _, seed in drawn}) == spec.variants.draw  # one episode per seed
    else:
        assert select_variants(catalog, spec, str(path))
