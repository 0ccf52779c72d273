"""``variants.draw`` in a dataset spec: episodes drawn from their seeds as the gym environment, ``rik eval`` and
``rik record --split`` draw them, so a spec rebuilds exactly the demonstrations a ``rik record --split`` made (the
policy experiment's data, examples/policies/)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

from rik.dataset.spec import load_spec, spec_hash
from rik.schemas.dataset import DatasetSpec

SPEC = """repo_id: local/rik-drawn
variants:
  split: train
  kinds: [drawer]
  handle_types: [knob]
  presets: [smooth, high]
  draw: 3
operators:
  - strategy: planned
seed: 5
max_seconds: 0.3
streams: []
"""


@pytest.mark.slow
def test_a_drawn_spec_records_rik_record_splits_episodes_bit_for_bit(rik, tmp_path: Path) -> None:
    from rik.episodes.draw import Draw
    from rik.episodes.record import record_split
    from rik.registry import load_catalog

    variants = tmp_path / "variants"
    metas = record_split(load_catalog(), Draw.parse("train", "knob", "smooth,high"), "planned", episodes=3, seed=5,
                         out=tmp_path / "recorded", variants=variants, max_seconds=0.3)
    spec = tmp_path / "drawn.yaml"
    spec.write_text(SPEC)
    r = rik("dataset", "build", str(spec), "--out", str(tmp_path / "ds"), "-j", "1", "--variants", str(variants),
            "--work", str(tmp_path / "work"))
    assert r.code == 0, r
    built = {p.parent.name: json.loads(p.read_text(encoding="utf-8"))["states_sha256"]
             for p in (tmp_path / "work" / "episodes").glob("*/meta.json")}
    assert built == {m.id: m.states_sha256 for m in metas}
    assert [m.preset for m in metas] == ["high", "smooth", "high"]  # seed mod 2 picks the cell


def test_draw_takes_only_the_filters_it_can_draw_from() -> None:
    base = yaml.safe_load(SPEC)
    for extra, message in (({"sample": 2}, "'draw' takes split, handle_types, presets and kinds"),
                           ({"handles": ["knob/mushroom-30"]}, "drop ids, base_units, handles and sample")):
        data = {**base, "variants": {**base["variants"], **extra}}
        with pytest.raises(ValidationError, match=message):
            DatasetSpec.model_validate(data)
    with pytest.raises(ValidationError, match="each drawn episode runs once per operator; drop 'episodes_per_variant'"):
        DatasetSpec.model_validate({**base, "episodes_per_variant": 2})


def test_specs_without_draw_keep_their_hash_and_the_examples_load() -> None:
    example = Path(__file__).parents[1] / "examples" / "dataset-drawers.yaml"
    assert spec_hash(load_spec(example)) == "ac4fc7fcddaee1f45a48277a3404af7e7f41d87865c923f00b8247ccd32d0509"
    for spec in sorted((Path(__file__).parents[1] / "examples" / "policies").glob("*.yaml")):
        loaded = load_spec(spec)
        # the drawer experiments draw 360 (40 per cell); the joints ablation's arms 540 over every front kind
        assert loaded.variants.draw == (540 if spec.name.startswith("joints-") else 360), spec
        assert loaded.outcomes == ("S",), spec
    paper, measured = (load_spec(Path(__file__).parents[1] / "examples" / "policies" / f"joints-{j}.yaml")
                       for j in ("paper", "measured"))
    assert (paper.variants.joints, measured.variants.joints) == ("paper", "measured")
    assert paper.model_dump(exclude={"repo_id", "description", "variants"}) == measured.model_dump(
        exclude={"repo_id", "description", "variants"})
    assert paper.variants.model_dump(exclude={"joints"}) == measured.variants.model_dump(exclude={"joints"})
