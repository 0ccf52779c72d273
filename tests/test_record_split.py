"""``rik record --split``: each episode's variant and front drawn from its seed (:mod:`rik.episodes.draw`), recorded in
worker processes exactly as ``rik record VARIANT --front F --seed S`` records it; bad combinations get one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from shared import BOW, builtin_catalog

CAT = builtin_catalog()
DRAW_ARGS = ("--types", "knob", "--presets", "smooth")


@pytest.mark.slow  # a build, recording or render end to end: out of the everyday tier
def test_record_split_draws_each_episode_and_writes_it_as_plain_record(rik, tmp_path: Path) -> None:
    from rik.episodes.draw import Draw
    from rik.episodes.episode import find_episodes, read_meta

    out, variants = tmp_path / "drawn", tmp_path / "variants"
    res = rik("record", "--split", "all", *DRAW_ARGS, "--episodes", "2", "--seed", "3", "-s", "grasp_vertical",
              "--workers", "2", "--out", str(out), "--variants", str(variants))
    assert res.code == 0, res.err
    draws = [Draw(split=None, handle_types=("knob",), presets=("smooth",)).episode(CAT, s) for s in (3, 4)]
    metas = {read_meta(d).seed: read_meta(d) for d in find_episodes([out])}
    assert sorted(metas) == [3, 4]
    for d in draws:
        meta = metas[d.seed]
        assert (meta.variant, meta.front, meta.operator) == (d.variant, d.front, "grasp_vertical")
        assert meta.id == f"{d.variant}__{d.front}__grasp_vertical__s{d.seed:04d}" and meta.id in res.out
    plain = tmp_path / "plain"
    first = draws[0]
    res = rik("record", first.variant, "--front", first.front, "--seed", "3", "-s", "grasp_vertical", "--out",
              str(plain), "--variants", str(variants))
    assert res.code == 0, res.err
    (episode,) = find_episodes([plain])
    drawn = out / episode.name
    files = sorted(p.name for p in episode.iterdir())
    assert files == sorted(p.name for p in drawn.iterdir())
    assert all((episode / f).read_bytes() == (drawn / f).read_bytes() for f in files)


def test_record_split_bad_combinations(rik, tmp_path: Path) -> None:
    bow = BOW

    def err(*args: str) -> str:
        res = rik("record", *args, "-s", "grasp_vertical", "--out", str(tmp_path / "e"), "--variants",
                  str(tmp_path / "v"))
        assert res.code == 2 and "Traceback" not in res.err, res.err
        assert not (tmp_path / "e").exists()
        return res.err.strip()

    assert err(bow, "--split", "all") == (f"rik: error: give a VARIANT or --split, not both (got {bow} and --split "
                                          "all)")
    assert err() == ("rik: error: give a VARIANT to record, or --split SPLIT (train, val, test or all) to draw each "
                     "episode's variant from its seed")
    assert err(bow, *DRAW_ARGS) == ("rik: error: --types, --presets, --kinds and --joints choose the variants of "
                                    "--split; give --split too, or drop them")
    assert err("--split", "all", "--front", "drawer") == ("rik: error: --front drawer: with --split each episode's "
                                                          "front is drawn from its seed; drop --front")
    assert err("--split", "all", "--types", "lever") == ("rik: error: unknown handle type 'lever' (types: "
                                                         "finger_pull, knob, two_point)")
