"""rik's own loads of a LeRobot dataset (the export's check and card, a build's merge and verification, the demo)
leave nothing in Hugging Face ``datasets``' cache: :func:`rik.lerobot.arrow_cache.scratch_arrow_cache`."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from rik.lerobot.arrow_cache import scratch_arrow_cache


def test_the_scratch_cache_is_used_within_removed_after_and_the_old_one_restored(tmp_path: Path,
                                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    import datasets.config

    monkeypatch.setattr(datasets.config, "HF_DATASETS_CACHE", tmp_path / "theirs")
    with scratch_arrow_cache() as outer:
        assert datasets.config.HF_DATASETS_CACHE == outer and outer.is_dir()
        (outer / "copy.arrow").write_bytes(b"x")
        with scratch_arrow_cache() as inner:
            assert datasets.config.HF_DATASETS_CACHE == inner != outer
        assert datasets.config.HF_DATASETS_CACHE == outer and not inner.exists()
    assert datasets.config.HF_DATASETS_CACHE == tmp_path / "theirs" and not outer.exists()
    with pytest.raises(ValueError), scratch_arrow_cache() as failed:
        raise ValueError("a load that fails")
    assert datasets.config.HF_DATASETS_CACHE == tmp_path / "theirs" and not failed.exists()


def test_an_export_and_its_checks_leave_nothing_in_the_datasets_cache(rik, knob_recording: Path, tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """``rik export-lerobot`` merges its shards, loads the result to check it and writes the card from its metadata:
    five loads, each of which left an Arrow copy of the dataset's tables and a lock file in ``datasets``' cache."""
    import datasets.config

    theirs = tmp_path / "hf-datasets"
    theirs.mkdir()
    monkeypatch.setattr(datasets.config, "HF_DATASETS_CACHE", theirs)
    shutil.copytree(knob_recording, tmp_path / "in")
    r = rik("export-lerobot", str(tmp_path / "in" / "episodes"), "--out", str(tmp_path / "ds"), "--repo-id",
            "local/arrow", "--streams", "none", "--variants", str(tmp_path / "in" / "variants"))
    assert r.code == 0, r
    assert sorted(p.name for p in theirs.iterdir()) == []
    assert datasets.config.HF_DATASETS_CACHE == theirs
