"""Loading the catalog: rik's built-in data plus optional user overlays, validated, indexed and cached.

The validated catalog is cached (pickled) under :func:`rik.paths.cache_dir`, keyed by a hash of every source
file, the schema code and the library versions, so a warm ``rik catalog`` parses no YAML. Errors are never
cached: a broken file is read and reported every time.
"""

from __future__ import annotations

import hashlib
import os
import pickle
from collections.abc import Iterable, Sequence
from pathlib import Path

from pydantic import BaseModel

import rik
from rik.paths import cache_dir
from rik.registry import checks
from rik.registry.catalog import Catalog, Origin, sorted_by_id
from rik.registry.entries import SECTION_MODELS, parse_entry
from rik.registry.sources import BUILTIN_DIR, RawEntry, catalog_files, read_file

#: Separator of several overlay paths in ``RIK_CATALOG`` (``:`` on POSIX).
OVERLAY_SEPARATOR = os.pathsep


def overlay_paths_from_env() -> list[Path]:
    """Overlay paths named by ``RIK_CATALOG`` (several joined by ``:``)."""
    value = os.environ.get("RIK_CATALOG", "")
    return [Path(p).expanduser() for p in value.split(OVERLAY_SEPARATOR) if p.strip()]


def load_catalog(overlays: Iterable[Path] | None = None, use_cache: bool = True) -> Catalog:
    """The built-in catalog plus ``overlays`` (YAML files or directories; ``None``: those of ``RIK_CATALOG``).

    Raises :class:`rik.errors.CatalogError` naming the file, entry and field of the first problem found.
    """
    overlays = overlay_paths_from_env() if overlays is None else list(overlays)
    files = [(p, True) for p in catalog_files(BUILTIN_DIR)]
    for path in overlays:
        files += [(p, False) for p in catalog_files(Path(path))]
    key = _fingerprint(files)
    cache_file = cache_dir() / "catalog" / f"{key[:32]}.pickle"
    if use_cache:
        cached = _read_cache(cache_file, key)
        if cached is not None:
            return cached
    catalog = build_catalog([e for path, builtin in files for e in read_file(path, builtin)], key)
    if use_cache:
        _write_cache(cache_file, catalog)
    return catalog


def build_catalog(entries: Sequence[RawEntry], fingerprint: str = "") -> Catalog:
    """Validate raw entries (each against its schema, then the cross-entry checks) into a :class:`Catalog`."""
    parsed: dict[str, list[tuple[RawEntry, BaseModel]]] = {s: [] for s in SECTION_MODELS}
    for entry in entries:
        parsed[entry.section].append((entry, parse_entry(entry)))
    for section, items in parsed.items():
        checks.check_unique_ids(items, SECTION_MODELS[section][1])
    by_id = {s: {m.id: m for _, m in items} for s, items in parsed.items()}  # type: ignore[attr-defined]
    designs, finishes, presets = by_id["designs"], by_id["finishes"], by_id["presets"]
    for entry, handle in parsed["handles"]:
        checks.check_handle(entry, handle, designs, finishes)  # type: ignore[arg-type]
    used = [h.design for h in by_id["handles"].values()]  # type: ignore[attr-defined]
    for entry, design in parsed["designs"]:
        checks.check_design(entry, design, used.count(design.id))  # type: ignore[arg-type, attr-defined]
    for entry, base in parsed["base_units"]:
        checks.check_base_unit(entry, base, finishes, presets)  # type: ignore[arg-type]
    origins = {(s, m.id): Origin(str(e.file), e.builtin) for s, items in parsed.items() for e, m in items}  # type: ignore[attr-defined]
    return Catalog(**{s: sorted_by_id(ms.items()) for s, ms in by_id.items()}, origins=origins,  # type: ignore[arg-type]
                   fingerprint=fingerprint)


def _fingerprint(files: Sequence[tuple[Path, bool]]) -> str:
    """sha256 of the source files (path, role, bytes), the schema code and the versions that validate them."""
    import pydantic

    digest = hashlib.sha256()
    digest.update(f"rik {rik.__version__} schema {rik.CATALOG_SCHEMA} pydantic {pydantic.VERSION}\n".encode())
    code = sorted((Path(rik.__file__).parent / "schemas").glob("*.py")) + sorted(Path(__file__).parent.glob("*.py"))
    for path, builtin in [(p, True) for p in code] + list(files):
        digest.update(f"{path.resolve()}\0{builtin}\0".encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _read_cache(path: Path, key: str) -> Catalog | None:
    try:
        with path.open("rb") as fh:
            catalog = pickle.load(fh)
    except Exception:  # a missing, partial or stale cache file is simply rebuilt
        return None
    return catalog if isinstance(catalog, Catalog) and catalog.fingerprint == key else None


def _write_cache(path: Path, catalog: Catalog) -> None:
    """Write atomically; a cache that cannot be written (read-only home) is not an error."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(pickle.dumps(catalog, protocol=pickle.HIGHEST_PROTOCOL))
        os.replace(tmp, path)
    except OSError:
        pass
