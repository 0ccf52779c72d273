"""Run a function over catalog ids in worker processes, each of which loads the catalog once."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

_CATALOG: Catalog | None = None
"""The catalog of this worker process."""


def _load(overlays: list[Path]) -> None:
    global _CATALOG
    from rik.registry.load import load_catalog

    _CATALOG = load_catalog(overlays)


def _call(fn: Callable[[Catalog, str], Any], item: str) -> tuple[str, Any]:
    assert _CATALOG is not None
    return item, fn(_CATALOG, item)


def map_ids(fn: Callable[[Catalog, str], Any], catalog: Catalog, ids: Sequence[str], *, workers: int = 1,
            overlays: Sequence[Path] = ()) -> Iterator[tuple[str, Any]]:
    """``(id, fn(catalog, id))`` for every id, as each finishes. With ``workers`` > 1 and more than one id the
    calls run in that many spawned processes (``fn`` must be picklable: a module-level function, or a
    ``functools.partial`` of one), which load the catalog from ``overlays`` themselves; otherwise here, in order."""
    if workers > 1 and len(ids) > 1:
        from concurrent.futures import ProcessPoolExecutor, as_completed
        from multiprocessing import get_context

        with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn"), initializer=_load,
                                 initargs=(list(overlays),)) as pool:
            for future in as_completed([pool.submit(_call, fn, i) for i in ids]):
                yield future.result()
    else:
        for i in ids:
            yield i, fn(catalog, i)
