"""The measured presets (real doors) split into train, val and test by the committed rule; draws with
``joints="measured"`` give a door a real door of the split and every other choice of the paper draw."""

from __future__ import annotations

import csv
import hashlib
import json
from pathlib import Path

import pytest
from shared import builtin_catalog

from rik.episodes.draw import Draw
from rik.errors import RikError
from rik.registry.ids import parse_variant_id
from rik.registry.load import load_catalog
from rik.registry.splits import SPLITS, split_presets
from rik.schemas.joints import MECHANISMS

KINDS = ("drawer", "door", "flap")


def test_every_real_door_is_in_one_split_and_every_mechanism_in_every_split() -> None:
    catalog = builtin_catalog()
    measured = [p for p, v in catalog.presets.items() if not v.in_default_set]
    assert len(measured) == 16 and set(catalog.preset_splits) == set(measured)
    by_split = {s: split_presets(catalog, s) for s in SPLITS}
    assert sorted(p for ids in by_split.values() for p in ids) == sorted(measured)  # each door once
    for split, ids in by_split.items():
        assert {catalog.presets[p].hinge.mechanism() for p in ids} == set(MECHANISMS), split
    assert not set(split_presets(catalog, "train")) & set(split_presets(catalog, "test"))


def test_the_committed_assignment_is_the_documented_rule() -> None:
    """Per mechanism, in sha256 order of the preset id: the first to test, the second to val, the rest to train
    (splits.yaml's comment): the split was not picked by hand."""
    catalog = builtin_catalog()
    for mechanism in MECHANISMS:
        doors = sorted((p for p in catalog.preset_splits if catalog.presets[p].hinge.mechanism() == mechanism),
                       key=lambda p: hashlib.sha256(p.encode()).hexdigest())
        assert [catalog.preset_splits[p] for p in doors] == ["test", "val"] + ["train"] * (len(doors) - 2)


def test_mechanism_classes() -> None:
    catalog = builtin_catalog()
    mech = {p: catalog.presets[p].hinge.mechanism() for p in catalog.preset_splits}
    assert mech["real-hai-refrigerator"] == "catch"  # a catch and a tilt: the catch decides
    assert mech["real-lab-fridge-cody-robot"] == "self-closing"
    assert mech["real-kitchen-cabinet-pr2-robot"] == "tilted"
    assert mech["real-hai-kitchen-cabinet-lower-left"] == "plain"  # a tilt of 0.42 N·m: below 1 N·m
    assert catalog.presets["normal"].hinge.mechanism() == "plain"
    assert [list(mech.values()).count(m) for m in MECHANISMS] == [4, 3, 5, 4]


@pytest.mark.parametrize("split", ["train", "val", "test", None])
def test_a_measured_draw_is_the_paper_draw_with_real_hinges(split: str | None) -> None:
    """The same seed gives the same base unit, handle and front with both joints; a door's preset is a real door
    of the split, a drawer's and a flap's the cell's; the draw is the same every time."""
    catalog = builtin_catalog()
    paper = Draw(split, kinds=KINDS)
    measured = Draw(split, kinds=KINDS, joints="measured")
    measured.check(catalog)
    doors = set(split_presets(catalog, split)) if split else set(catalog.preset_splits)
    seen: set[str] = set()
    for seed in range(60):
        a, b = paper.episode(catalog, seed), measured.episode(catalog, seed)
        assert b == measured.episode(catalog, seed)
        assert (a.front, a.handle_type) == (b.front, b.handle_type)
        assert a.variant.rsplit("__", 1)[0] == b.variant.rsplit("__", 1)[0]
        base = catalog.base_units[parse_variant_id(catalog, b.variant).base]
        if next(f for f in base.fronts if f.id == b.front).kind == "door":
            assert b.preset in doors and b.variant.endswith("__" + b.preset)
            seen.add(b.preset)
        else:
            assert b.preset == a.preset in ("smooth", "normal", "high")
    assert seen and seen <= doors


def test_measured_joints_need_doors_and_known_names() -> None:
    catalog = builtin_catalog()
    for kinds in (("drawer",), ("drawer", "flap")):
        with pytest.raises(RikError, match=r"^joints 'measured': real doors' presets go on doors; the kinds "
                           f"{', '.join(kinds)} "
                           r"have none \(drawers and flaps keep the paper's presets: no real drawer or flap was "
                           r"measured\)$"):
            Draw("test", kinds=kinds, joints="measured").check(catalog)
    with pytest.raises(RikError, match=r"^unknown joints 'real' \(joints: paper, measured\)$"):
        Draw("test", kinds=KINDS, joints="real").check(catalog)


@pytest.mark.slow
def test_record_split_draws_measured_joints_as_the_draw_says(rik, tmp_path: Path) -> None:
    """``rik record --split val --kinds door --joints measured`` records the draw's variant (a real door of val)."""
    seed = next(s for s in range(20) if Draw("val", kinds=("door",), joints="measured")
                .episode(builtin_catalog(), s).handle_type == "knob")
    want = Draw("val", kinds=("door",), joints="measured").episode(builtin_catalog(), seed)
    r = rik("record", "--split", "val", "--kinds", "door", "--joints", "measured", "--seed", str(seed),
            "--strategy", "grasp_vertical", "--out", str(tmp_path / "eps"),
            "--variants", str(tmp_path / "variants"))
    assert r.code == 0, r.err
    (episode,) = (tmp_path / "eps").iterdir()
    meta = json.loads((episode / "meta.json").read_text())
    assert meta["variant"] == want.variant and want.preset in split_presets(builtin_catalog(), "val")
    r = rik("record", "--split", "val", "--joints", "measured", "--strategy", "planned", "--out", str(tmp_path / "no"))
    assert r.code == 2 and r.err.startswith("rik: error: joints 'measured': real doors' presets go on doors")
    assert not (tmp_path / "no").exists()


OVERLAY_DOOR = """schema: 1
presets:
- id: real-my-door
  name: my door
  slide: {damping: 5.0, frictionloss: 15.0, provenance: assumed}
  hinge: {damping: 0.3, frictionloss: 1.2, provenance: measured}
  source: {kind: measured, reference: my pulls, data: my.csv}
"""


@pytest.mark.slow
@pytest.mark.parametrize(("splits", "message"), [
    ("splits:\n  presets:\n    test: [smooth]\n",
     "field 'splits.presets.test': 'smooth' is not a measured preset (only measured presets are split; the paper's "
     "are in every split)"),
    ("splits:\n  presets:\n    test: [real-hai-freezer]\n",
     "field 'splits.presets.test': preset 'real-hai-freezer' is built in and has its split in rik's own "
     "splits.yaml; an overlay may place only its own presets"),
    ("splits:\n  presets:\n    test: [real-my-door]\n    val: [real-my-door]\n",
     "field 'splits.presets.val': preset 'real-my-door' is already in split 'test' (mine.yaml:"),
    ("splits:\n  presets:\n    holdout: [real-my-door]\n",
     "field 'splits.presets.holdout': unknown split; valid fields: train, val, test"),
    ("splits:\n  presets: [real-my-door]\n",
     "field 'splits.presets': must be a mapping of train, val, test to measured preset ids"),
])
def test_bad_preset_splits_are_one_line(rik, tmp_path: Path, monkeypatch, splits: str, message: str) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.yaml").write_text(OVERLAY_DOOR + splits)
    r = rik("catalog", "splits", "--catalog", "mine.yaml")
    assert r.code == 2 and r.out == "" and r.err.count("\n") == 1
    assert r.err.startswith("rik: error: mine.yaml:") and message in r.err


def test_a_users_door_is_train_unless_placed(tmp_path: Path) -> None:
    (tmp_path / "mine.yaml").write_text(OVERLAY_DOOR)
    assert load_catalog([tmp_path / "mine.yaml"]).preset_splits["real-my-door"] == "train"
    (tmp_path / "mine.yaml").write_text(OVERLAY_DOOR + "splits:\n  presets:\n    test: [real-my-door]\n")
    catalog = load_catalog([tmp_path / "mine.yaml"])
    assert "real-my-door" in split_presets(catalog, "test") and len(split_presets(catalog, "test")) == 5


@pytest.mark.slow
def test_rik_eval_on_real_doors_tables_them_in_a_measured_column(rik, tmp_path: Path) -> None:
    """Every episode is in the table: a door drawn with a real door's hinge counts in the ``measured`` column."""
    r = rik("eval", "strategy:grasp_vertical", "--split", "test", "--kinds", "door", "--joints", "measured",
            "--types", "knob", "--presets", "smooth", "-n", "1", "--episode-length", "40", "--videos", "0",
            "--workers", "1", "--out", str(tmp_path / "eval"), "--variants", str(tmp_path / "variants"))
    assert r.code == 0, r.err
    table = (tmp_path / "eval/table.md").read_text()
    assert "| strategy | measured F | measured P | measured S | n |" in table and table.rstrip().endswith("| 1 |")
    (row,) = list(csv.DictReader((tmp_path / "eval/episodes.csv").open()))
    assert row["preset"] in split_presets(builtin_catalog(), "test")
    spec = json.loads((tmp_path / "eval/eval_info.json").read_text())["rik"]["spec"]
    assert spec["joints"] == "measured" and spec["kinds"] == ["door"]

