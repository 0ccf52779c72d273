"""CATALOG.md is generated from the registry and must not go stale."""

from __future__ import annotations

from conftest import REPO


def test_committed_catalog_md_is_up_to_date(rik, monkeypatch) -> None:
    monkeypatch.chdir(REPO)
    result = rik("catalog", "doc", "--check")
    assert result.code == 0, result.err


def test_check_fails_on_a_stale_page_and_doc_rewrites_it(rik, tmp_path) -> None:
    page = tmp_path / "CATALOG.md"
    page.write_text("# old\n")
    stale = rik("catalog", "doc", "--check", "--out", str(page))
    assert stale.code == 1 and "out of date" in stale.err
    assert rik("catalog", "doc", "--out", str(page)).code == 0
    text = page.read_text()
    assert "**83 handles** in **47 designs**" in text and "two_point/bow-128" in text
    assert rik("catalog", "doc", "--check", "--out", str(page)).code == 0
    assert [p.name for p in tmp_path.iterdir()] == ["CATALOG.md"], "no temporary file left behind"


def test_pictures_are_linked_when_present(rik, tmp_path) -> None:
    pictures = tmp_path / "docs" / "catalog" / "knob__ball-25"
    pictures.mkdir(parents=True)
    (pictures / "thumbnail.png").write_bytes(b"\x89PNG")
    rik("catalog", "doc", "--out", str(tmp_path / "CATALOG.md"))
    text = (tmp_path / "CATALOG.md").read_text()
    assert '<img src="docs/catalog/knob__ball-25/thumbnail.png" width="96" alt="thumbnail of knob/ball-25">' in text
    assert "docs/catalog/knob__ball-32/" not in text  # absent pictures are a dash


def test_fidelity_and_mesh_statistics_are_shown_when_present(rik, tmp_path) -> None:
    from rik.assets.report import FIDELITY_COLUMNS, STATS_COLUMNS, write_csv

    catalog_dir = tmp_path / "docs" / "catalog"
    fid = dict.fromkeys(FIDELITY_COLUMNS, 0.0) | {"id": "knob/ball-25", "type": "knob", "hulls": 3,
                                                 "eqp_mean_mm": 0.25, "hull_eqp_mean_mm": 1.0, "hull_over_coacd": 4.0}
    write_csv([fid], FIDELITY_COLUMNS, catalog_dir / "fidelity.csv")
    stats = {"id": "knob/ball-25", "type": "knob", "vertices": 1200, "faces": 2396, "mean_edge_mm": 0.61,
             "mean_face_area_mm2": 0.162, "watertight": True, "hulls": 3, "collision_vertices": 192}
    write_csv([stats], STATS_COLUMNS, catalog_dir / "mesh_stats.csv")
    rik("catalog", "doc", "--out", str(tmp_path / "CATALOG.md"))
    text = (tmp_path / "CATALOG.md").read_text()
    assert "CoACD 0.25 (3 hulls), hull 1.00 (4.0x)" in text
    assert "1200 / 2396 / 0.61 / 0.162" in text
    assert "| Knobs | 1 | 0.25 |" in text  # the summary table of the fidelity section
