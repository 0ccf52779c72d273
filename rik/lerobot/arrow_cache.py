"""LeRobot reads a dataset's parquet tables through Hugging Face ``datasets``, which converts them to an Arrow copy
(and leaves a lock file) in ``~/.cache/huggingface/datasets`` at every load of files it has not seen, and never
removes either: each export rik checked, each build it verified and each card it wrote left a copy of the dataset's
tables there (a few hundred entries a day on a busy machine; the tables of an image dataset are large).
:func:`scratch_arrow_cache` gives rik's own loads a temporary folder for that cache instead, removed when they are
done; ``lerobot-train`` and a user's own ``LeRobotDataset`` keep ``datasets``' own cache (``HF_DATASETS_CACHE``)."""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def scratch_arrow_cache() -> Iterator[Path]:
    """Within it, ``datasets`` writes its Arrow copies into a new temporary folder (yielded), removed on the way out
    with everything in it; the cache it had is restored. Nests. Everything loaded within must be used within: its
    tables map files of that folder. Also a decorator (``@scratch_arrow_cache()``). Not for threads that load
    datasets at the same time (``datasets`` reads one module-wide setting)."""
    import datasets.config

    before = datasets.config.HF_DATASETS_CACHE
    with tempfile.TemporaryDirectory(prefix="rik-arrow-cache-") as folder:
        datasets.config.HF_DATASETS_CACHE = Path(folder)
        try:
            yield Path(folder)
        finally:
            datasets.config.HF_DATASETS_CACHE = before
