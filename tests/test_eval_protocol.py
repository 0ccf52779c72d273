"""``rik eval --protocol FILE``: a committed, frozen set of episodes run exactly; every option, catalog, variants
folder or policy that would change them refused in one line before anything runs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rik.errors import RikError
from rik.evaluation.evaluate import EvalSpec
from rik.evaluation.protocol import read_protocol

ROOT = Path(__file__).resolve().parents[1]
TINY = """protocol: 1
name: tiny-v1
split: test
kinds: [drawer]
handle_types: [knob]
presets: [smooth]
episodes_per_cell: 1
seed: 1000
episode_length: 40
success_opening: 0.9
"""


def test_the_committed_protocols_are_the_documented_draws() -> None:
    drawers = read_protocol(ROOT / "protocols/drawers-test-v1.yaml")
    spec = EvalSpec("strategy:planned")  # rik eval's defaults: the drawer benchmark's test episodes
    assert (drawers.split, drawers.kinds, drawers.joints, drawers.handle_types, drawers.presets,
            drawers.episodes_per_cell, drawers.seed, drawers.episode_length) == (
        spec.split, spec.kinds, spec.joints, spec.handle_types, spec.presets, spec.episodes_per_cell, spec.seed,
        spec.episode_length)
    measured = read_protocol(ROOT / "protocols/fronts-measured-test-v1.yaml")
    paper = read_protocol(ROOT / "protocols/fronts-paper-test-v1.yaml")
    assert measured.model_dump(exclude={"name", "description", "joints"}) == paper.model_dump(
        exclude={"name", "description", "joints"})
    assert (measured.joints, paper.joints, measured.kinds, measured.episodes) == (
        "measured", "paper", ("drawer", "door", "flap"), 90)


@pytest.mark.slow
def test_a_protocol_runs_its_episodes_and_says_so(rik, tmp_path: Path) -> None:
    (tmp_path / "tiny.yaml").write_text(TINY)
    r = rik("eval", "strategy:grasp_vertical", "--protocol", str(tmp_path / "tiny.yaml"), "--out",
            str(tmp_path / "eval"), "--variants", str(tmp_path / "variants"), "--videos", "0", "--workers", "1")
    assert r.code == 0, r.err
    spec = json.loads((tmp_path / "eval/eval_info.json").read_text())["rik"]["spec"]
    assert spec["protocol"] == "tiny-v1" and spec["seed"] == 1000 and spec["episode_length"] == 40
    assert spec["handle_types"] == ["knob"] and spec["presets"] == ["smooth"]


@pytest.mark.slow
@pytest.mark.parametrize(("extra", "clash"), [
    (["--split", "val"], "--split"), (["--seed", "1000"], "--seed"), (["-n", "3"], "--episodes-per-cell"),
    (["--kinds", "door", "--joints", "measured"], "--kinds, --joints"), (["--episode-length", "40"],
                                                                          "--episode-length"),
    (["--catalog", "mine.yaml"], "--catalog"),
])
def test_options_that_change_the_episodes_are_refused(rik, tmp_path: Path, monkeypatch, extra: list[str],
                                                      clash: str) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.yaml").write_text(TINY)
    (tmp_path / "mine.yaml").write_text("schema: 1\n")
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "tiny.yaml"), *extra, "--out",
            str(tmp_path / "eval"))
    assert r.code == 2 and r.out == ""
    assert r.err == (f"rik: error: --protocol {tmp_path / 'tiny.yaml'} fixes the episodes; drop {clash} (the "
                     "protocol's own: split, kinds, joints, handle types, presets, episodes per cell, seed, episode "
                     "length, the built-in catalog)\n")
    assert not (tmp_path / "eval").exists()


@pytest.mark.slow
def test_a_user_catalog_from_the_environment_is_refused(rik, tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "tiny.yaml").write_text(TINY)
    (tmp_path / "mine.yaml").write_text("schema: 1\n")
    monkeypatch.setenv("RIK_CATALOG", str(tmp_path / "mine.yaml"))
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "tiny.yaml"), "--out", str(tmp_path / "e"))
    assert r.code == 2 and "drop --catalog" in r.err and not (tmp_path / "e").exists()


@pytest.mark.slow
def test_another_robot_or_collision_model_is_refused(rik, tmp_path: Path) -> None:
    (tmp_path / "tiny.yaml").write_text(TINY)
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "tiny.yaml"), "--robot", "so100", "--out",
            str(tmp_path / "e"))
    assert r.code == 2 and r.err == (f"rik: error: --protocol {tmp_path / 'tiny.yaml'}: strategy:planned runs robot "
                                     "so100; the protocol's episodes are hand-e's\n")
    hull = tmp_path / "hull"
    hull.mkdir()
    (hull / "collision.json").write_text('{"collision": "hull"}\n')
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "tiny.yaml"), "--variants", str(hull), "--out",
            str(tmp_path / "e"))
    assert r.code == 2 and r.err == (f"rik: error: --protocol {tmp_path / 'tiny.yaml'}: --variants {hull} holds "
                                     "collision 'hull' variants; the protocol's episodes run in 'coacd' ones "
                                     "(another --variants folder)\n")
    assert not (tmp_path / "e").exists()


@pytest.mark.parametrize(("text", "message"), [
    ("protocol: 1\nname: [x\n", "not a YAML protocol (line 3): while parsing a flow sequence"),
    ("- 1\n- 2\n", "a protocol is a mapping of protocol, name, split, kinds"),
    (TINY + "speed: 2\n", "field 'speed': Extra inputs are not permitted"),
    (TINY.replace("episodes_per_cell: 1", "episodes_per_cell: '10'"), "field 'episodes_per_cell': Input should be a "
     "valid integer"),
    (TINY.replace("episodes_per_cell: 1", "episodes_per_cell: 1000000000"), "field 'episodes_per_cell': Input "
     "should be less than or equal to 1000"),
    (TINY.replace("episode_length: 40", "episode_length: .inf"), "field 'episode_length': Input should be a valid "
     "integer"),
    (TINY.replace("success_opening: 0.9", "success_opening: .nan"), "field 'success_opening': Input should be a "
     "finite number"),
    (TINY.replace("success_opening: 0.9", "success_opening: 0.8"), "field 'success_opening': 0.8 is not rik's "
     "success rule (0.9 of the front's range)"),
    (TINY.replace("name: tiny-v1", "name: \"tiny\\0\""), "field 'name': String should match pattern"),
    (TINY.replace("name: tiny-v1", "name: türen-v1"), "field 'name': String should match pattern"),
    (TINY.replace("kinds: [drawer]", "kinds: [shelf]"), "field 'kinds.0': Input should be 'drawer', 'door' or "
     "'flap'"),
    (TINY.replace("protocol: 1", "protocol: 2"), "field 'protocol': Input should be 1"),
    ("#" * 70_000, "over 64 KiB; a protocol is a few lines of YAML"),
])
def test_bad_protocols_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(RikError) as caught:
        read_protocol(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)


@pytest.mark.slow
def test_a_bad_protocol_stops_rik_eval_in_one_line(rik, tmp_path: Path) -> None:
    """The library's refusal reaches the command as one line, exit 2, nothing written (every case above)."""
    path = tmp_path / "p.yaml"
    for text in (TINY + "speed: 2\n", TINY.replace("episode_length: 40", "episode_length: .inf"), "#" * 70_000):
        path.write_text(text, encoding="utf-8")
        with pytest.raises(RikError) as caught:
            read_protocol(path)
        r = rik("eval", "strategy:planned", "--protocol", str(path), "--out", str(tmp_path / "e"))
        assert r.code == 2 and r.err == f"rik: error: {caught.value}\n" and not (tmp_path / "e").exists()


@pytest.mark.slow
def test_an_unreadable_protocol_is_one_line(rik, tmp_path: Path) -> None:
    import os

    os.mkfifo(tmp_path / "fifo.yaml")  # would block a plain read for ever
    for special in (tmp_path / "fifo.yaml", tmp_path):
        r = rik("eval", "strategy:planned", "--protocol", str(special))
        assert r.code == 2 and r.err == (f"rik: error: {special}: not a file; a protocol is a YAML file "
                                         "(protocols/*.yaml)\n")
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "none.yaml"))
    assert r.code == 2 and r.err.startswith(f"rik: error: {tmp_path / 'none.yaml'}: cannot read the protocol")
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00")
    r = rik("eval", "strategy:planned", "--protocol", str(tmp_path / "bin.yaml"))
    assert r.code == 2 and "not a YAML protocol" in r.err and r.err.count("\n") == 1
