"""The catalog in the web app: its JSON API (TestClient) and the page in a real Chromium (Playwright): every handle
listed with a loaded picture, filters by type, size and finish, one handle's dimensions, heatmap and mesh
statistics, and a pairing button linking to the teleop station of a valid variant with the robot picked."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from shared import BOW
from web_fixtures import app_client, browser, served, signed

from rik.registry.doc import csv_rows
from rik.registry.ids import parse_variant_id, variant_id
from rik.registry.index import build_index
from rik.registry.load import load_catalog
from rik.registry.stats import catalog_stats
from rik.web.app import AppConfig
from rik.web.catalog_view import REPO_ROOT

DEMO_HANDLE, DEMO_BASE = "two_point/bow-128", "drawer/chest-80"
OVERLAY_HANDLE = """\
handles:
  - id: knob/mushroom-40
    design: knob/mushroom
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


@pytest.fixture(scope="module")
def client(catalog):
    with app_client(AppConfig(catalog)) as c:
        yield c


def test_api_lists_handles_bases_presets_with_numbers(client, catalog) -> None:
    body = client.get("/api/catalog/handles").json()
    assert body["count"] == len(catalog.handles) == len(body["handles"])
    row = next(h for h in body["handles"] if h["id"] == DEMO_HANDLE)
    assert row["dimensions_mm"]["length"] == pytest.approx(catalog.handles[DEMO_HANDLE].geometry.length * 1000)
    assert row["type"] == "two_point" and row["finish"] == catalog.handles[DEMO_HANDLE].finish
    mesh = csv_rows(REPO_ROOT / "docs/catalog/mesh_stats.csv")[DEMO_HANDLE]
    assert row["mesh"]["vertices"] == int(mesh["vertices"]) and row["fidelity"]["hulls"] == int(mesh["hulls"])
    assert row["pictures"] == {"thumbnail": True, "fidelity": True}
    assert client.get("/api/catalog/bases").json()["count"] == len(catalog.base_units)
    assert [p["id"] for p in client.get("/api/catalog/presets").json()["presets"]] == list(catalog.presets)
    pairings = client.get(f"/api/catalog/handles/{DEMO_HANDLE}").json()["pairings"]
    chest = next(p for p in pairings if p["id"] == DEMO_BASE)
    assert chest["variants"]["normal"] == BOW
    for pairing in pairings:  # every offered pairing is a valid variant id of this catalog
        for vid in pairing["variants"].values():
            assert parse_variant_id(catalog, vid).handle == DEMO_HANDLE
    fitting = client.get(f"/api/catalog/bases/{DEMO_BASE}").json()["pairings"]
    assert sum(len(p["variants"]) for p in fitting) == len(fitting) * len(catalog.default_presets)  # measured: named
    picture = client.get(f"/catalog/img/{DEMO_HANDLE}/thumbnail.png")
    assert picture.status_code == 200 and picture.headers["content-type"] == "image/png"
    assert client.get(f"/catalog/img/{DEMO_BASE}/front.svg").headers["content-type"].startswith("image/svg+xml")


@pytest.mark.parametrize(("url", "message"), [
    ("/api/catalog/handles/two_point/bow-12", "no handle 'two_point/bow-12' in the catalog; did you mean "
                                              "'two_point/bow-128'"),
    ("/api/catalog/bases/drawer/chest-90", "no base unit 'drawer/chest-90' in the catalog"),
    ("/catalog/handle/knob/nope", "no handle 'knob/nope' in the catalog"),
    ("/catalog/img/knob/nope/thumbnail.png", "no handle 'knob/nope' in the catalog"),
    ("/catalog/img/knob/ball-25/mesh.png", "handle 'knob/ball-25' has no picture 'mesh.png'; valid: thumbnail.png"),
    ("/catalog/img/drawer/chest-80/thumbnail.png", "base unit 'drawer/chest-80' has no picture 'thumbnail.png'"),
])
def test_unknown_ids_are_a_404_with_one_line(client, url: str, message: str) -> None:
    response = client.get(url)
    assert response.status_code == 404
    detail = response.json()["detail"]
    assert detail.startswith(message) and "\n" not in detail


def test_user_handle_without_pictures_gets_a_placeholder(tmp_path: Path) -> None:

    overlay = tmp_path / "mine.yaml"
    overlay.write_text(textwrap.dedent(OVERLAY_HANDLE))
    with app_client(AppConfig(load_catalog([overlay]))) as client:
        row = client.get("/api/catalog/handles/knob/mushroom-40").json()
        assert row["origin"] == "overlay" and row["pictures"] == {"thumbnail": False, "fidelity": False}
        assert row["mesh"] is None and row["fidelity"] is None
        for name in ("thumbnail", "fidelity"):
            response = client.get(f"/catalog/img/knob/mushroom-40/{name}.png")
            assert response.status_code == 200 and response.headers["x-rik-placeholder"] == "1"
            assert response.headers["content-type"].startswith("image/svg+xml") and f"no {name} picture" in \
                response.text


@pytest.mark.browser
def test_catalog_page_in_chromium(catalog, tmp_path: Path) -> None:
    index = build_index(catalog)
    total = len(catalog.handles)
    knobs = catalog_stats(index)["by_type"]["knob"]["handles"]
    large = len(index.select("handles", min_length=0.150))
    finish = catalog.handles[DEMO_HANDLE].finish
    same_finish = sum(h.finish == finish for h in catalog.handles.values())
    vertices = csv_rows(REPO_ROOT / "docs/catalog/mesh_stats.csv")[DEMO_HANDLE]["vertices"]

    def count_is(page, n: int) -> None:
        page.wait_for_function("t => document.querySelector('#count').textContent === t", arg=f"{n} of {total} handles",
                               timeout=10_000, polling=100)
        assert page.locator("#handle-grid .card:visible").count() == n

    with served(AppConfig(catalog)) as url, browser() as chromium:
        page = chromium.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(signed(f"{url}/catalog"))
        count_is(page, total)
        assert page.locator("#handle-grid .card img").count() == total
        page.wait_for_function("() => [...document.querySelectorAll('#handle-grid img')]"
                               ".every(i => i.complete && i.naturalWidth > 0)", timeout=20_000, polling=100)
        page.select_option("#f-type", "knob")
        count_is(page, knobs)
        assert {page.locator("#handle-grid .card:visible").nth(i).get_attribute("data-id").split("/")[0]
                for i in range(knobs)} == {"knob"}
        page.click("#f-reset")
        page.select_option("#f-size", "150-")
        count_is(page, large)
        page.fill("#f-min", "")
        page.fill("#f-max", "")
        page.select_option("#f-finish", finish)
        count_is(page, same_finish)
        page.fill("#f-text", "bow-128")
        count_is(page, 1)

        page.click(f"#handle-grid .card[data-id='{DEMO_HANDLE}']")
        page.wait_for_selector("#detail-title", state="visible")
        assert page.text_content("#detail-title") == DEMO_HANDLE
        assert page.url.endswith(f"/catalog/handle/{DEMO_HANDLE}?finish={finish.replace('/', '%2F')}&q=bow-128")
        dimensions = page.text_content("#dimensions")
        assert "length mm140" in dimensions and "clearance mm (depth x width)20 x 116" in dimensions
        page.wait_for_function("() => document.querySelector('#fidelity-img').naturalWidth > 0", timeout=10_000, polling=100)
        assert "CoACD (3 hulls)" in page.text_content("#fidelity")
        assert f"vertices{vertices}" in page.text_content("#mesh-stats")
        page.select_option("#pair-other", label=f"{DEMO_BASE} ({catalog.base_units[DEMO_BASE].name})")
        page.select_option("#pair-preset", "normal")
        href = page.get_attribute("#teleop-link", "href")
        assert href == "/teleop/" + variant_id(DEMO_BASE, DEMO_HANDLE, "normal")
        assert parse_variant_id(catalog, href.removeprefix("/teleop/")).base == DEMO_BASE
        assert page.input_value("#pair-robot") == "hand-e"  # the server's robot: the link names none
        page.select_option("#pair-robot", "panda-2f85")  # another robot: its own station
        assert page.get_attribute("#teleop-link", "href") == href + "?robot=panda-2f85"
        page.click("#f-reset")
        count_is(page, total)
        page.screenshot(path=str(tmp_path / "catalog.png"))

        page.click("#tabs button[data-tab=bases]")
        assert page.locator("#base-grid .card:visible").count() == len(catalog.base_units)
        page.wait_for_function("() => [...document.querySelectorAll('#base-grid img')]"
                               ".every(i => i.complete && i.naturalWidth > 0)", timeout=10_000, polling=100)
        page.click(f"#base-grid .card[data-id='{DEMO_BASE}']")
        page.wait_for_selector("#pair-other optgroup", state="attached")
        assert page.get_attribute("#teleop-link", "href").startswith("/teleop/drawer-chest-80__")

        page.goto(f"{url}/catalog/handle/knob/ball-25")  # an entry's own address opens its panel
        page.wait_for_function("() => document.querySelector('#detail-title')?.textContent === 'knob/ball-25'",
                               timeout=10_000, polling=100)
        assert errors == []


@pytest.mark.browser
def test_split_base_scale_presets_and_filters_in_the_address_in_chromium(catalog) -> None:
    """The split and fits-base filters show exactly the handles the server says; the filters go into the address
    and come back on reload and on back after opening a handle; common scale draws thumbnails in proportion to the
    handles' largest dimensions; the presets tab and the pairing picker show each preset's joint numbers with units."""
    from rik.web.catalog_view import build_view

    view = build_view(catalog)
    total = len(view.handles)
    val = {h for h, row in view.handles.items() if row["split"] == "val"}
    fits = {h for h, bases in view.fits.items() if DEMO_BASE in bases}
    small_base = min(view.bases, key=lambda b: view.bases[b]["fits"])
    both = {h for h in val if small_base in view.fits[h]}
    extents = {h: row["extent_mm"] for h, row in view.handles.items()}

    def shown(page) -> set[str]:
        page.wait_for_function("() => !document.querySelector('#count').textContent.startsWith('loading')",
                               timeout=10_000, polling=100)
        cards = page.locator("#handle-grid .card:visible")
        return {cards.nth(i).get_attribute("data-id") for i in range(cards.count())}

    with served(AppConfig(catalog)) as url, browser() as chromium:
        page = chromium.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(signed(f"{url}/catalog"))
        page.wait_for_selector("body[data-ready='1']")
        assert len(shown(page)) == total
        page.select_option("#f-split", "val")
        assert shown(page) == val and 0 < len(val) < total
        assert page.url == f"{url}/catalog?split=val"
        page.select_option("#f-split", "")
        page.select_option("#f-base", DEMO_BASE)
        assert shown(page) == fits
        page.select_option("#f-base", small_base)
        page.select_option("#f-split", "val")
        assert shown(page) == both
        page.check("#f-scale")
        address = page.url
        assert "split=val" in address and f"base={small_base.replace('/', '%2F')}" in address and "scale=common" in address

        page.reload()  # the address restores every filter
        page.wait_for_selector("body[data-ready='1']")
        assert shown(page) == both and page.input_value("#f-split") == "val" and page.is_checked("#f-scale")
        page.uncheck("#f-scale")
        page.select_option("#f-base", "")
        page.click(f"#handle-grid .card[data-id='{sorted(val)[0]}']")
        page.wait_for_selector("#detail-title", state="visible")
        assert page.url.endswith("?split=val")
        page.go_back()  # back to the grid, its filters kept
        page.wait_for_function("() => document.querySelector('#detail').hidden", timeout=10_000, polling=100)
        assert shown(page) == val and page.url == f"{url}/catalog?split=val"
        page.go_forward()  # the handle again, the filters still in its address
        page.wait_for_selector("#detail-title", state="visible")
        assert page.url.endswith("?split=val") and shown(page) == val

        page.goto(f"{url}/catalog?scale=common")  # common scale: widths in proportion to the largest dimensions
        page.wait_for_selector("body[data-ready='1']")
        widths = page.evaluate("() => Object.fromEntries([...document.querySelectorAll('#handle-grid .card')]"
                               ".map(c => [c.dataset.id, c.querySelector('img').getBoundingClientRect().width]))")
        largest = max(extents.values())
        for handle, width in widths.items():
            assert width == pytest.approx(max(120 * extents[handle] / largest, 4), abs=0.6), handle
        assert min(widths.values()) < 40 and max(widths.values()) == pytest.approx(120, abs=0.6)
        assert "mm per pixel" in page.text_content("#scale-note")

        page.click("#tabs button[data-tab=presets]")
        normal = catalog.presets["normal"]
        row = page.text_content("#presets tr[data-id='normal']")
        assert f"damping {normal.slide.damping:g} N·s/m" in row and f"friction {normal.slide.frictionloss:g} N" in row
        assert f"damping {float(f'{normal.hinge.damping:.3g}'):g} N·m·s/rad" in row
        assert page.locator("#presets tbody tr").count() == len(catalog.presets)
        page.goto(f"{url}/catalog/handle/{DEMO_HANDLE}")
        page.wait_for_selector("#preset-numbers")
        page.select_option("#pair-preset", "normal")
        assert page.text_content("#preset-numbers").startswith(f"normal: slide damping {normal.slide.damping:g} N·s/m")
        assert errors == []
