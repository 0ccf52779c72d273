"""An episode read once, for everything made from it (:class:`RecordedEpisode`): the renders of its image streams
and the export's frames share its meta, its decoded columns and its scene."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

from rik.episodes.episode import columns_of, read_episode, read_meta, states
from rik.episodes.replay import episode_scene

if TYPE_CHECKING:
    import numpy as np
    import pyarrow as pa

    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.scene import SimScene


class RecordedEpisode:
    """An episode read once, for everything made from it: its ``meta.json`` (given, or read at once) and, on first
    use, the columns of ``states.parquet`` it needs (:func:`rik.episodes.states.read_states`), the recorded states as
    an array and the scene it was recorded in (built once per catalog and variants folder). Every stream rendered
    from it (:func:`rik.render.episodes.render_episode`) and the export's frames of it share them; the states are
    read only if asked for."""

    def __init__(self, directory: Path, meta: EpisodeMeta | None = None, columns: Sequence[str] = ("state",)) -> None:
        self.directory = Path(directory)
        self.meta = meta if meta is not None else read_meta(self.directory)
        self.columns = tuple(c for c in columns if c in columns_of(self.meta))
        """Those of ``columns`` the episode has: what :attr:`table` decodes (a render needs ``state`` only)."""
        self._scene: tuple[Catalog, Path, SimScene] | None = None

    @cached_property
    def table(self) -> pa.Table:
        """:attr:`columns` of ``states.parquet``, bounded before decoding and checked against the meta's sha256 and
        layout (:func:`rik.episodes.states.read_states`; read on first use)."""
        return read_episode(self.directory, self.columns, self.meta)[1]

    @cached_property
    def states(self) -> np.ndarray:
        """The recorded integration states, one row per recorded step."""
        return states(self.table)

    def scene(self, catalog: Catalog, variants: Path) -> SimScene:
        """The scene the episode was recorded in (:func:`rik.episodes.replay.episode_scene`), built on the first call
        and on a call with another catalog or variants folder."""
        if self._scene is None or self._scene[0] is not catalog or self._scene[1] != Path(variants):
            self._scene = (catalog, Path(variants), episode_scene(catalog, self.directory, variants, self.meta))
        return self._scene[2]
