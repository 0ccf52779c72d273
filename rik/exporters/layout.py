"""The layout of a LeRobot v3.0 dataset as rik writes it, and how rik tells its own datasets and the ones it is
merging from a folder of the user's (:mod:`rik.outputs`)."""

from __future__ import annotations

import re
from pathlib import Path

from rik.outputs import MadeFolder, Replaces, holds_only

DATASET_NAMES = frozenset({"meta", "data", "videos", "images", "README.md"})
"""What the top of a LeRobot v3.0 dataset holds."""
DATASET_FILE = re.compile(r"README\.md|meta/(info\.json|stats\.json|tasks\.parquet|rik_\w+\.json"
                          r"|episodes/chunk-\d+/file-\d+\.parquet)|data/chunk-\d+/file-\d+\.parquet"
                          r"|videos/[^/]+/chunk-\d+/file-\d+\.mp4|images/[^/]+/episode-\d+/[^/]+\.png")
"""Every file of a LeRobot v3.0 dataset rik exported, by its path in the dataset (lerobot's layout)."""
MERGING = MadeFolder("a dataset rik was merging", lambda d: holds_only(d, DATASET_NAMES), "delete it yourself")
"""The folder shards are aggregated into before a dataset is published."""
MERGED_FILE = Replaces("a file of a dataset rik is merging", lambda p: MERGING.made(Path(p).parent.parent))
"""A file in ``meta/`` of a dataset being merged (:data:`MERGING`): lerobot's ``stats.json``, rik's card."""
