"""The catalog's 3D view: the vendored three.js matches its SOURCE.txt, the GLB routes (a handle's mesh, a built
variant's visual geoms; unknown ids and unbuilt variants a 404 with one line that builds nothing; the token
required), and the view in a real Chromium: the canvas draws the model and a mouse drag turns it."""

from __future__ import annotations

import hashlib
import json
import shutil
import struct
from pathlib import Path
from typing import Any

import pytest
from shared import BOW
from web_fixtures import app_client, browser, served, signed

from rik.registry.load import load_catalog
from rik.web.app import AppConfig
from rik.web.pages import STATIC

HANDLE = "two_point/bow-128"
VENDOR = STATIC / "vendor" / "three"
needs_chromium = pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")


@pytest.fixture(scope="module")
def catalog():
    return load_catalog([])


def glb_json(data: bytes) -> dict[str, Any]:
    """The JSON chunk of a binary glTF (after checking its header)."""
    magic, version, length = struct.unpack("<4sII", data[:12])
    assert magic == b"glTF" and version == 2 and length == len(data)
    size, kind = struct.unpack("<I4s", data[12:20])
    assert kind == b"JSON"
    return json.loads(data[20:20 + size])


def test_vendored_three_matches_its_source_list() -> None:
    """Every file SOURCE.txt lists has the sha256 it records, and nothing else is vendored; the addons import three
    by relative path (no bare 'three' that would need an import map)."""
    lines = (VENDOR / "SOURCE.txt").read_text(encoding="utf-8").split("sha256 of each file, as vendored:\n")[1]
    listed = dict(reversed(line.split("  ", 1)) for line in lines.splitlines() if line.strip())
    assert len(listed) == 8 and "three.module.js" in listed and "LICENSE" in listed
    for name, digest in listed.items():
        assert hashlib.sha256((VENDOR / name).read_bytes()).hexdigest() == digest, name
    present = {str(p.relative_to(VENDOR)) for p in VENDOR.rglob("*") if p.is_file()}
    assert present == {*listed, "SOURCE.txt"}
    for addon in VENDOR.glob("addons/*/*.js"):
        assert "from 'three'" not in addon.read_text(encoding="utf-8"), addon


def test_glb_routes(catalog, bow_variants: Path, tmp_path: Path) -> None:
    """A handle's GLB: one mesh with its finish's metallic and roughness and a linear base colour; a built
    variant's: one node per drawn geom. Unknown ids and an unbuilt variant: a 404 with one line, nothing built;
    without the token's cookie: 403."""
    finish = catalog.finishes[catalog.handles[HANDLE].finish]
    with app_client(AppConfig(catalog, variants=bow_variants, episodes=tmp_path / "ep")) as client:
        answer = client.get(f"/catalog/model/{HANDLE}/visual.glb")
        assert answer.status_code == 200 and answer.headers["content-type"] == "model/gltf-binary"
        gltf = glb_json(answer.content)
        assert len(gltf["meshes"]) == 1 and gltf["meshes"][0]["primitives"][0]["attributes"].keys() >= {"NORMAL"}
        pbr = gltf["materials"][0]["pbrMetallicRoughness"]
        assert pbr["metallicFactor"] == finish.metallic and pbr["roughnessFactor"] == finish.roughness
        assert pbr["baseColorFactor"][0] < finish.base_color[0]  # sRGB made linear: darker
        assert client.get(f"/catalog/model/{HANDLE}/visual.glb").content == answer.content  # memoised

        variant = glb_json(client.get(f"/catalog/variant/{BOW}/visual.glb").content)
        assert len(variant["nodes"]) > 10 and {m["name"] for m in variant["materials"]} >= {finish.id}

        for url, words in [("/catalog/model/knob/nope/visual.glb", "no handle 'knob/nope'"),
                           ("/catalog/variant/nope/visual.glb", "nope")]:
            answer = client.get(url)
            assert answer.status_code == 404 and words in answer.json()["detail"], url
            assert "\n" not in answer.json()["detail"]
        client.cookies.clear()
        assert client.get(f"/catalog/model/{HANDLE}/visual.glb").status_code == 403
        assert client.get(f"/catalog/variant/{BOW}/visual.glb").status_code == 403

    fresh = tmp_path / "variants"
    with app_client(AppConfig(catalog, variants=fresh, episodes=tmp_path / "ep")) as client:
        answer = client.get(f"/catalog/variant/{BOW}/visual.glb")
        assert answer.status_code == 404
        assert answer.json()["detail"] == (f"variant {BOW} is not built in {fresh}: open its station (/teleop/{BOW}) "
                                           f"or run `rik variants build {BOW}`")
        assert not fresh.exists()


PIXELS = """sel => {
  const c = document.querySelector(sel + ' canvas');
  const t = document.createElement('canvas');
  t.width = c.width; t.height = c.height;
  const g = t.getContext('2d');
  g.drawImage(c, 0, 0);
  const d = g.getImageData(0, 0, t.width, t.height).data;
  const grey = [];
  for (let i = 0; i < d.length; i += 4) grey.push(Math.round((d[i] + d[i + 1] + d[i + 2]) / 3));
  return grey;
}"""


def drawn_and_turned(page: Any, selector: str) -> tuple[int, int]:
    """Wait for the view in ``selector`` to draw; count its pixels unlike the background; drag across it; count the
    pixels that changed. Also checks the camera's azimuth moved."""
    page.wait_for_selector(f"{selector}[data-ready='1'] canvas", timeout=60_000)
    before = page.evaluate(PIXELS, selector)
    background = before[0]  # a corner: the clear colour
    drawn = sum(abs(p - background) > 12 for p in before)
    angles = page.evaluate(f"() => document.querySelector({selector!r}).angles()")
    page.locator(f"{selector} canvas").scroll_into_view_if_needed()
    box = page.locator(f"{selector} canvas").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    for step in range(1, 9):
        page.mouse.move(x + 5 * step, y + 2 * step)
    page.mouse.up()
    after = page.evaluate(PIXELS, selector)
    turned = page.evaluate(f"() => document.querySelector({selector!r}).angles()")
    assert turned["azimuth"] != pytest.approx(angles["azimuth"], abs=0.05), (angles, turned)
    return drawn, sum(abs(a - b) > 12 for a, b in zip(before, after, strict=True))


@pytest.mark.browser
@needs_chromium
def test_3d_view_of_a_handle_and_a_built_variant_in_chromium(catalog, tmp_path: Path) -> None:
    """A handle's panel draws its model (at least 2 % of the canvas unlike the background) and a drag turns it
    (at least 1 % of the pixels change); the same for a variant built in tmp_path, picked in the pairing picker.
    An unbuilt variant's view shows the server's one line."""
    from rik.combinator.build import ensure_variant

    variants = tmp_path / "variants"
    ensure_variant(catalog, BOW, variants)
    with served(AppConfig(catalog, variants=variants, episodes=tmp_path / "ep")) as url, browser() as chromium:
        page = chromium.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(signed(f"{url}/catalog/handle/{HANDLE}"))
        drawn, changed = drawn_and_turned(page, "#viewer-handle")
        pixels = len(page.evaluate(PIXELS, "#viewer-handle"))
        print(f"handle: {drawn} of {pixels} pixels drawn, {changed} changed by the drag")
        assert drawn > 0.02 * pixels and changed > 0.01 * pixels

        page.select_option("#pair-other", value=str(next(
            i for i, b in enumerate(page.evaluate("() => [...document.querySelectorAll('#pair-other option')]"
                                                  ".map(o => o.textContent)")) if b.startswith("drawer/chest-80 "))))
        page.select_option("#pair-preset", "normal")
        assert page.text_content("#variant-id") == BOW
        page.click("#variant-3d")
        drawn, changed = drawn_and_turned(page, "#viewer-variant")
        pixels = len(page.evaluate(PIXELS, "#viewer-variant"))
        print(f"variant: {drawn} of {pixels} pixels drawn, {changed} changed by the drag")
        assert drawn > 0.02 * pixels and changed > 0.01 * pixels

        page.select_option("#pair-preset", "high")  # not built: the view says so in one line
        page.wait_for_selector("#viewer-variant[data-ready='error']", timeout=30_000)
        assert "is not built" in page.text_content("#viewer-variant .viewer3d-error")
        assert errors == []


def test_a_user_mesh_handle_is_served_and_a_changed_file_is_one_line(tmp_path: Path) -> None:
    """A user catalog's imported handle: its mesh file (checked against its recorded sha256) as GLB; a file changed
    since it was registered: a 404 with one line, not a traceback."""
    import trimesh

    from rik.assets.importer import mesh_sha256

    (tmp_path / "meshes").mkdir()
    for name in ("box", "changed"):
        trimesh.creation.box(extents=(0.03, 0.03, 0.025)).export(tmp_path / "meshes" / f"{name}.stl")
    digest = mesh_sha256(tmp_path / "meshes" / "box.stl")
    designs = "".join(
        f"  - id: knob/{name}\n    type: knob\n    subtype: imported\n    name: {name}\n"
        f"    generator: {{name: user_mesh, file: meshes/{name}.stl, sha256: '{digest}'}}\n"
        "    provenance: {origin: user_mesh, reference: test}\n" for name in ("box", "changed"))
    handles = "".join(
        f"  - id: knob/{name}-30\n    design: knob/{name}\n    size: '30'\n    finish: metal/stainless\n"
        "    geometry: {length: 0.03, width: 0.03, projection: 0.025, grip_diameter: 0.03}\n"
        "    mount: {kind: single_screw}\n    mass: 0.03\n    licence: MIT\n" for name in ("box", "changed"))
    overlay = tmp_path / "mine.yaml"
    overlay.write_text(f"designs:\n{designs}handles:\n{handles}")
    catalog = load_catalog([overlay])
    trimesh.creation.box(extents=(0.04, 0.03, 0.025)).export(tmp_path / "meshes" / "changed.stl")
    with app_client(AppConfig(catalog, variants=tmp_path / "v", episodes=tmp_path / "ep")) as client:
        gltf = glb_json(client.get("/catalog/model/knob/box-30/visual.glb").content)
        assert gltf["accessors"][gltf["meshes"][0]["primitives"][0]["indices"]]["count"] == 36  # the box's 12 faces
        answer = client.get("/catalog/model/knob/changed-30/visual.glb")
        assert answer.status_code == 404
        detail = answer.json()["detail"]
        assert "changed.stl" in detail and "sha256" in detail and "\n" not in detail, detail
