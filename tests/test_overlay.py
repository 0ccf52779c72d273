"""User catalogs: added through --catalog or RIK_CATALOG, validated the same way, cache follows content."""

from __future__ import annotations

import json

from test_bad_input import GOOD_HANDLE

from rik.registry import load_catalog


def test_overlay_adds_a_handle(rik, tmp_path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD_HANDLE)
    handles = json.loads(rik("catalog", "list", "--catalog", str(path), "-f", "json").out)
    assert len(handles) == 84
    mine = next(h for h in handles if h["id"] == "knob/mushroom-40")
    assert mine["origin"] == "overlay" and mine["type"] == "knob"
    assert load_catalog([path]).handle("knob/mushroom-40").geometry.projection == 0.032


def test_overlay_from_environment_and_directory(rik, tmp_path, monkeypatch) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "mine.yml").write_text(GOOD_HANDLE)
    monkeypatch.setenv("RIK_CATALOG", str(tmp_path))
    assert len(json.loads(rik("catalog", "list", "-f", "json").out)) == 84
    assert "knob/mushroom-40" in load_catalog().handles


def test_index_cache_follows_file_content(rik, tmp_path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD_HANDLE)
    assert json.loads(rik("catalog", "show", "knob/mushroom-40", "--catalog", str(path), "-f", "json").out)["mass"] == 0.07
    path.write_text(GOOD_HANDLE.replace("mass: 0.07", "mass: 0.08"))
    assert json.loads(rik("catalog", "show", "knob/mushroom-40", "--catalog", str(path), "-f", "json").out)["mass"] == 0.08
