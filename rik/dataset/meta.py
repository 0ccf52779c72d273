"""The metadata rik writes into a built dataset's ``meta/`` folder and reads back: names, and a checked reader that
turns a damaged file into one line naming the file and the field."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rik.paths import read_meta_file

__all__ = ["BUILD_META", "DATASET_META", "read_dataset_meta", "read_meta_file"]

DATASET_META = "rik_dataset.json"
"""``meta/rik_dataset.json``: the spec, its hash, versions, variant hashes, counts, outcomes and file checksums;
identical for identical builds."""
BUILD_META = "rik_build.json"
"""``meta/rik_build.json``: the build's statistics (engine, seconds per stage, units run and reused, failures);
these vary from one build to the next."""


def read_dataset_meta(root: Path) -> dict[str, Any] | None:
    """``meta/rik_dataset.json`` of a built dataset, or None when ``root`` holds none. One that is there but
    damaged (not JSON, not an object, a field rik reads missing or of the wrong type) raises one line naming the
    file and the field (:func:`read_meta_file`)."""
    from rik.schemas.dataset import DatasetRecord

    path = Path(root) / "meta" / DATASET_META
    if not path.is_file():
        return None
    return read_meta_file(path, DatasetRecord)
