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
    assert "](docs/catalog/knob__ball-25/thumbnail.png)" in (tmp_path / "CATALOG.md").read_text()
