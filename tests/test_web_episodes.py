"""The app's page of recorded episodes and built datasets: real episodes listed with their numbers and a replay link
that replays the episode in its station (Chromium), damaged metadata a row with one line (never a 500), hostile
names shown as text (no HTML injection), the station refusing an episode of another variant, and the API
behind the token."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from conftest import SHORT_KNOB
from web_fixtures import WAIT_MS, app_client, browser, served, signed

from rik.episodes.episode import meta_digest
from rik.registry.load import load_catalog
from rik.web.app import AppConfig

HOSTILE = "<img src=x onerror=window.pwned=1>"
needs_chromium = pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")


@pytest.fixture(scope="module")
def catalog():
    return load_catalog([])


def folders(knob_recording: Path, tmp_path: Path) -> tuple[Path, Path, Path, str, str]:
    """An episodes folder with the session's real episode, a resealed copy whose operator is an HTML tag, a meta that
    is not JSON and a folder named by an HTML tag; a datasets folder with one dataset's metadata and a damaged one;
    a copy of the variants. Returns (episodes, datasets, variants, real id, copy id)."""
    episodes, datasets = tmp_path / "episodes", tmp_path / "datasets"
    shutil.copytree(knob_recording / "episodes", episodes)
    variants = shutil.copytree(knob_recording / "variants", tmp_path / "variants")
    real = next(p.name for p in episodes.iterdir() if not p.name.startswith("."))
    data = json.loads((episodes / real / "meta.json").read_text())
    copy = real.replace("__s", "__x")
    data.update(id=copy, operator="<img src=x onerror=window.pwned=2>")
    data["meta_sha256"] = meta_digest(data)
    shutil.copytree(episodes / real, episodes / copy)
    (episodes / copy / "meta.json").write_text(json.dumps(data))
    (episodes / "bad-episode").mkdir()
    (episodes / "bad-episode" / "meta.json").write_text("{not json")
    (episodes / HOSTILE).mkdir()
    (episodes / HOSTILE / "meta.json").write_text(json.dumps({"id": HOSTILE, "variant": HOSTILE}))
    good = datasets / "knob-demo" / "meta"
    good.mkdir(parents=True)
    (good / "rik_dataset.json").write_text(json.dumps({
        "spec_hash": "0" * 64, "spec": {"repo_id": "local/knob-demo", "robot": "hand-e", "streams": ["front"]},
        "counts": {"episodes": 2, "frames": 14, "variants": 1}, "outcomes": {"F": 2}, "files": {}}))
    (datasets / "broken" / "meta").mkdir(parents=True)
    (datasets / "broken" / "meta" / "rik_dataset.json").write_text("[1, 2")
    (datasets / "not-a-dataset").mkdir()
    return episodes, datasets, variants, real, copy


def test_api_lists_episodes_and_datasets_and_says_what_is_damaged(catalog, knob_recording: Path,
                                                                 tmp_path: Path) -> None:
    episodes, datasets, variants, real, copy = folders(knob_recording, tmp_path)
    meta = json.loads((episodes / real / "meta.json").read_text())
    with app_client(AppConfig(catalog, variants=variants, episodes=episodes, datasets=datasets)) as client:
        answer = client.get("/api/episodes")
        assert answer.status_code == 200
        body = answer.json()
        rows = {r["id"]: r for r in body["episodes"]}
        assert body["episodes_total"] == 4 == len(rows)
        row = rows[real]
        assert (row["variant"], row["robot"], row["outcome"], row["steps"]) == (SHORT_KNOB, "hand-e", meta["outcome"],
                                                                               meta["steps"])
        assert row["seconds"] == pytest.approx(meta["steps"] / meta["fps"])
        assert row["final_opening"] == meta["final_opening"]
        assert row["replay"] == f"/teleop/{SHORT_KNOB}?robot=hand-e&replay={real}"
        assert rows[copy]["operator"] == "<img src=x onerror=window.pwned=2>"
        assert rows["bad-episode"]["error"].endswith("meta.json: not valid JSON (line 1): Expecting property name "
                                                     "enclosed in double quotes")
        assert rows[HOSTILE]["error"] == (f"{episodes / HOSTILE / 'meta.json'}: field 'id': Value error, '{HOSTILE}' "
                                          "is not a safe folder name (letters, digits, '_', '.', '-'; not starting "
                                          "with '.'; no '/')")
        assert all("\n" not in r.get("error", "") for r in rows.values())
        sets = {d["name"]: d for d in body["datasets"]}
        assert sets.keys() == {"knob-demo", "broken"} and body["datasets_total"] == 2  # not-a-dataset: not one
        assert (sets["knob-demo"]["episodes"], sets["knob-demo"]["frames"], sets["knob-demo"]["robot"]) == (2, 14,
                                                                                                         "hand-e")
        assert "rik_dataset.json: damaged: not the JSON rik wrote" in sets["broken"]["error"]
        client.cookies.clear()
        assert client.get("/api/episodes").status_code == 403
        assert client.get("/episodes").status_code == 403
    missing = tmp_path / "nothing"
    with app_client(AppConfig(catalog, variants=variants, episodes=missing, datasets=missing)) as client:
        body = client.get("/api/episodes").json()
        assert body["episodes"] == [] and body["datasets"] == [] and not missing.exists()


def banner(page: Any, words: str) -> str:
    page.wait_for_function("w => document.querySelector('#banner').textContent.includes(w)", arg=words,
                           timeout=WAIT_MS, polling=200)
    return page.text_content("#banner")


@pytest.mark.browser
@needs_chromium
def test_episodes_page_in_chromium_lists_escapes_and_replays(catalog, knob_recording: Path, tmp_path: Path) -> None:
    """The page lists the four episodes and two datasets, damaged ones with their one line; the hostile names are
    text (no <img> made, no script run); the real episode's replay link opens its station, which replays it."""
    episodes, datasets, variants, real, copy = folders(knob_recording, tmp_path)
    config = AppConfig(catalog, variants=variants, episodes=episodes, datasets=datasets)
    with served(config) as url, browser() as chromium:
        page = chromium.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(signed(f"{url}/episodes"))
        page.wait_for_selector("body[data-ready='1']")
        assert page.locator("#episodes tbody tr").count() == 4
        assert page.locator("#datasets tbody tr").count() == 2
        assert page.locator("main img").count() == 0
        assert page.evaluate("() => window.pwned") is None
        assert HOSTILE in page.text_content("#episodes") and "window.pwned=2" in page.text_content("#episodes")
        assert "not valid JSON" in page.text_content("#episodes tr[data-id='bad-episode']")
        assert "damaged" in page.text_content("#datasets tr[data-name='broken']")
        assert "local/knob-demo" in page.text_content("#datasets tr[data-name='knob-demo']")
        assert "4 episodes in" in page.text_content("#episodes-note")

        page.click(f"#episodes tr[data-id='{real}'] a.replay")
        page.wait_for_url(f"{url}/teleop/{SHORT_KNOB}?robot=hand-e&replay={real}")
        assert banner(page, "replayed") == f"replayed {real}; back to live"

        page.goto(f"{url}/teleop/drawer-chest-80__two_point-bow-128__normal?replay={real}")  # another variant's
        text = banner(page, "replay failed")
        assert text == (f"replay failed: episode {real} is of variant {SHORT_KNOB} with robot hand-e, not this "
                        "station's (drawer-chest-80__two_point-bow-128__normal with hand-e): open its own replay link")
        assert errors == []
