"""Named, versioned splits of the catalog: whole designs held out, all three handle types in each split."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from rik.errors import RikError
from rik.registry import load_catalog
from rik.registry.ids import select_variants
from rik.registry.splits import SPLITS, SPLITS_VERSION, split_designs, split_handles, split_of, splits_version

#: An overlay design of its own with one handle, for the overlay cases.
OVERLAY = """\
designs:
  - id: knob/mine
    type: knob
    subtype: mushroom
    name: My knob
    generator: {name: knob_lathe, profile: mushroom, neck_ratio: 0.45, head_ratio: 0.45}
    provenance: {origin: parametric, reference: test}
handles:
  - id: knob/mine-40
    design: knob/mine
    size: "40"
    finish: metal/brushed-steel
    geometry: {length: 0.04, width: 0.04, projection: 0.032, grip_diameter: 0.04, clearance: {depth: 0.017, width: 0.04}}
    mount: {kind: single_screw, screw: M4}
    mass: 0.07
    licence: CC-BY-4.0
"""


@pytest.fixture(scope="module")
def catalog():
    return load_catalog([])


def test_designs_are_disjoint_and_cover_the_catalog(catalog) -> None:
    per_split = {name: split_designs(catalog, name) for name in SPLITS}
    listed = [d for designs in per_split.values() for d in designs]
    assert len(listed) == len(set(listed)) == len(catalog.designs) == 47
    assert set(listed) == set(catalog.designs)


def test_each_split_has_all_three_types_in_about_70_15_15(catalog) -> None:
    for name in SPLITS:
        types = {catalog.designs[d].type.value for d in split_designs(catalog, name)}
        assert types == {"knob", "two_point", "finger_pull"}, name
    assert [len(split_designs(catalog, n)) for n in SPLITS] == [31, 8, 8]


def test_whole_designs_are_held_out(catalog) -> None:
    for design in catalog.designs:
        assert {split_of(catalog, h.id) for h in catalog.handles_of(design)} == {catalog.splits[design]}


def test_split_handles_counts_and_order(catalog) -> None:
    counts = {name: len(split_handles(catalog, name)) for name in SPLITS}
    assert counts == {"train": 58, "val": 11, "test": 14}
    assert sum(counts.values()) == len(catalog.handles)
    test = split_handles(catalog, "test")
    assert list(test) == [h for h in catalog.handles if h in set(test)]
    assert "two_point/d-pull-96" in test and split_of(catalog, "two_point/bow-128") == "train"


def test_version(catalog) -> None:
    assert splits_version(catalog) == SPLITS_VERSION == 1


def test_unknown_split_in_the_api(catalog) -> None:
    with pytest.raises(RikError, match=r"^unknown split 'tset' \(splits: train, val, test\); did you mean 'test'\?$"):
        split_handles(catalog, "tset")


def test_select_variants_filters_by_split(catalog) -> None:
    everything = select_variants(catalog)
    test = select_variants(catalog, split="test")
    assert {k.handle for k in test} == set(split_handles(catalog, "test"))
    presets = catalog.default_presets  # measured presets are built only when named
    assert {k.base for k in test} == set(catalog.base_units) and {k.preset for k in test} == set(presets)
    assert len(test) == len(catalog.base_units) * 14 * len(presets) < len(everything)
    knobs = select_variants(catalog, handle_types=["knob"], presets=["normal"], split="val")
    assert {k.handle for k in knobs} == {"knob/dome-30", "knob/dome-36", "knob/octagon-30", "knob/button-38"}
    with pytest.raises(RikError, match=r"^unknown split 'nope' \(splits: train, val, test\)$"):
        select_variants(catalog, split="nope")


def test_cli_list_by_split(rik) -> None:
    handles = json.loads(rik("catalog", "list", "--split", "test", "-f", "json").out)
    assert len(handles) == 14 and {h["split"] for h in handles} == {"test"}
    designs = json.loads(rik("catalog", "list", "--kind", "designs", "--split", "val", "-f", "json").out)
    assert len(designs) == 8 and {d["type"] for d in designs} == {"knob", "two_point", "finger_pull"}


def test_cli_unknown_split_is_one_line(rik) -> None:
    result = rik("catalog", "list", "--split", "nope")
    assert result.code == 2 and result.out == ""
    assert result.err == "rik: error: unknown split 'nope' (splits: train, val, test)\n"


def test_cli_split_does_not_filter_bases(rik) -> None:
    result = rik("catalog", "list", "--kind", "bases", "--split", "test")
    assert result.code == 2 and result.err == "rik: error: --split filters handles and designs, not bases\n"


def test_cli_show_and_splits_table(rik) -> None:
    assert "split: test" in rik("catalog", "show", "knob/bell-28").out
    assert "split: val" in rik("catalog", "show", "knob/dome").out
    table = rik("catalog", "splits")
    assert table.code == 0 and "splits v1" in table.out
    assert [line.split()[:1] + line.split()[-2:] for line in table.out.splitlines()[2:5]] == \
        [["train", "31", "58"], ["val", "8", "11"], ["test", "8", "14"]]
    numbers = json.loads(rik("catalog", "splits", "-f", "json").out)
    assert numbers["version"] == 1 and numbers["splits"]["test"]["by_type"]["knob"] == {"designs": 3, "handles": 4}


def _overlay(tmp_path: Path, splits: str) -> Path:
    path = tmp_path / "mine.yaml"
    path.write_text(OVERLAY + textwrap.dedent(splits))
    return path


def test_overlay_designs_default_to_train_or_their_own_split(rik, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    plain = load_catalog([_overlay(tmp_path, "")])
    assert split_of(plain, "knob/mine-40") == "train"
    placed = load_catalog([_overlay(tmp_path, "splits:\n  test: [knob/mine]\n")])
    assert split_of(placed, "knob/mine-40") == "test" and len(split_handles(placed, "test")) == 15
    shown = json.loads(rik("catalog", "show", "knob/mine-40", "--catalog", "mine.yaml", "-f", "json").out)
    assert shown["split"] == "test"


@pytest.mark.parametrize(("splits", "message"), [
    ("splits:\n  train: [knob/mine]\n  test: [knob/mine]\n",
     "mine.yaml:19, field 'splits.test': design 'knob/mine' is already in split 'train' (mine.yaml:18); "
     "a design is in exactly one split"),
    ("splits:\n  val: [knob/mien]\n",
     "mine.yaml:18, field 'splits.val': no design 'knob/mien' in the catalog; did you mean 'knob/mine'?"),
    ("splits:\n  test: [knob/bell]\n",
     "mine.yaml:18, field 'splits.test': design 'knob/bell' is built in and has its split in rik's own "
     "splits.yaml; an overlay may place only its own designs"),
    ("splits:\n  holdout: [knob/mine]\n",
     "mine.yaml:18, field 'splits.holdout': unknown split; valid fields: version, train, val, test, presets"),
    ("splits:\n  version: 2\n",
     "mine.yaml:18, field 'splits.version': must be 1, the splits version this rik reads (got 2)"),
    ("splits: [knob/mine]\n",
     "mine.yaml:17, field 'splits': must be a mapping of version, train, val, test"),
    ("splits:\n  test: knob/mine\n",
     "mine.yaml:18, field 'splits.test': must be a list of design ids"),
])
def test_bad_overlay_splits(rik, tmp_path, monkeypatch, splits: str, message: str) -> None:
    monkeypatch.chdir(tmp_path)
    _overlay(tmp_path, splits)
    result = rik("catalog", "list", "--catalog", "mine.yaml")
    assert result.code == 2 and result.out == ""
    assert result.err == f"rik: error: {message}\n"


def test_builtin_design_in_no_split(tmp_path, monkeypatch) -> None:
    """A catalog whose splits file leaves out a built-in design is an error naming the file and the design."""
    from rik.registry.load import build_catalog
    from rik.registry.sources import BUILTIN_DIR, catalog_files, read_file

    monkeypatch.chdir(tmp_path)
    splits = tmp_path / "splits.yaml"
    text = (BUILTIN_DIR / "splits.yaml").read_text().replace("    - knob/hexagon\n", "")
    splits.write_text(text)
    files = [p for p in catalog_files(BUILTIN_DIR) if p.name != "splits.yaml"]
    entries = [e for p in files for e in read_file(p, True)] + read_file(splits, True)
    with pytest.raises(RikError) as err:
        build_catalog(entries)
    assert str(err.value) == ("splits.yaml:6, field 'splits': design 'knob/hexagon' is in no split; add it to one of "
                              "train, val, test")
