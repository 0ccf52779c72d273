"""Reading catalog YAML files into raw entries, with errors that name the file, line, entry and field."""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik import CATALOG_SCHEMA
from rik.errors import CatalogError, RikError

if TYPE_CHECKING:
    import yaml

#: Top-level sections a catalog file may hold, each a list of entries.
SECTIONS = ("finishes", "presets", "designs", "handles", "base_units", "robots")
#: Top-level key of a catalog file that assigns designs to the named splits (:mod:`rik.registry.splits`); its
#: value is one mapping (``version``, ``train``, ``val``, ``test``), read as a single raw entry of this name.
SPLITS_KEY = "splits"
#: How messages name one entry of each section.
NOUNS = {"finishes": "finish", "presets": "preset", "designs": "design", "handles": "handle",
         "base_units": "base unit", "robots": "robot"}

BUILTIN_DIR = Path(__file__).parent / "data"

def _safe_loader() -> type[yaml.CSafeLoader | yaml.SafeLoader]:
    """PyYAML's fastest safe loader (libyaml's, which PyYAML's wheels ship)."""
    import yaml

    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)


@dataclass(frozen=True)
class RawEntry:
    """One entry of a section, as read, with where it came from."""

    section: str
    index: int
    data: Any
    file: Path
    builtin: bool

    @property
    def label(self) -> str:
        """``handles[3] 'knob/mushroom-30'``: how messages name the entry."""
        ident = self.data.get("id") if isinstance(self.data, dict) else None
        return f"{self.section}[{self.index}]" + (f" '{ident}'" if isinstance(ident, str) else "")

    def error(self, field: str | None, problem: str) -> CatalogError:
        """A :class:`CatalogError` for this entry; ``field`` is a dotted path (``fronts.0.joint.range``)."""
        loc = tuple(int(p) if p.isdigit() else p for p in field.split(".")) if field else ()
        return CatalogError(display_path(self.file), self.label, field, problem,
                            line_of(self.file, (self.section, self.index, *loc)))


def display_path(path: Path) -> str:
    """The path as a user would type it: relative to the working directory when below it."""
    try:
        return os.path.relpath(path) if Path(path).resolve().is_relative_to(Path.cwd()) else str(path)
    except ValueError:  # pragma: no cover - another drive on Windows
        return str(path)


MAX_CATALOG_FILES = 1000
"""Most YAML files one catalog folder may hold (:func:`catalog_files`)."""
MAX_CATALOG_DEPTH = 8
"""Deepest level of folders below a catalog folder that is searched for YAML files."""
MAX_CATALOG_ENTRIES = 100_000
"""Most entries (files and folders) looked at below a catalog folder: ``--catalog /`` stops here, not at the end of
the file system."""
MAX_CATALOG_BYTES = 16 * 2**20
"""Largest catalog YAML file read (rik's built-in catalog is a few hundred kB in all)."""


def catalog_files(path: Path) -> list[Path]:
    """The YAML files of a catalog: the file itself, or every ``*.yaml``/``*.yml`` below a directory, sorted
    (hidden files and directories, such as an import in progress, are skipped; so are symbolic links to folders,
    which are never followed). The walk is bounded (:data:`MAX_CATALOG_FILES` files, :data:`MAX_CATALOG_DEPTH`
    levels, :data:`MAX_CATALOG_ENTRIES` entries looked at) and so is each file (:data:`MAX_CATALOG_BYTES`): past a
    bound, one :class:`CatalogError` naming the folder or file, before any file is read."""
    if path.is_dir():
        files = _walk_catalog(path)
    elif path.is_file():
        files = [path]
    else:
        raise CatalogError(display_path(path), None, None, "no such catalog file or directory")
    for file in files:
        _check_size(file)
    return files


def _walk_catalog(root: Path) -> list[Path]:
    shown = display_path(root)
    advice = "give --catalog the folder (or file) of the catalog itself"
    found: list[Path] = []
    seen = 0
    todo = [(root, 0)]
    while todo:
        folder, depth = todo.pop()
        try:
            entries = list(os.scandir(folder))
        except OSError as exc:
            raise CatalogError(display_path(folder), None, None, f"cannot read this catalog folder "
                               f"({exc.strerror})") from None
        seen += len(entries)
        if seen > MAX_CATALOG_ENTRIES:
            raise CatalogError(shown, None, None, f"holds more than {MAX_CATALOG_ENTRIES:,} files and folders, too "
                               f"many for a catalog; {advice}")
        for e in entries:
            if e.name.startswith("."):
                continue
            if e.is_dir(follow_symlinks=False):
                if depth + 1 > MAX_CATALOG_DEPTH:
                    raise CatalogError(shown, None, None, f"has folders more than {MAX_CATALOG_DEPTH} levels deep "
                                       f"({display_path(Path(e.path))}), too deep for a catalog; {advice}")
                todo.append((Path(e.path), depth + 1))
            elif e.name.endswith((".yaml", ".yml")) and e.is_file():
                found.append(Path(e.path))
                if len(found) > MAX_CATALOG_FILES:
                    raise CatalogError(shown, None, None, f"holds more than {MAX_CATALOG_FILES:,} YAML files, too "
                                       f"many for a catalog; {advice}")
    return sorted(found)


def _check_size(file: Path) -> None:
    try:
        size = file.stat().st_size
    except OSError as exc:
        raise CatalogError(display_path(file), None, None, f"cannot read the file ({exc.strerror})") from None
    if size > MAX_CATALOG_BYTES:
        raise CatalogError(display_path(file), None, None, f"{size / 2**20:,.0f} MiB, larger than the "
                           f"{MAX_CATALOG_BYTES // 2**20} MiB a catalog file may have; nothing was read")


MAX_YAML_DEPTH = 16
"""Deepest nesting of lists and mappings in a YAML file rik reads from a user (a catalog entry nests 5 deep, a dataset
spec 3): libyaml's composer recurses in C, and a deeper document crashes the process (a segmentation fault at about
10^5 levels)."""
MAX_YAML_NODES = 1_000_000
"""Most values a YAML file may hold with its aliases and merge keys expanded: an alias bomb ("billion laughs") is
refused before it is expanded."""


def check_yaml_shape(text: str, shown: str, what: str, max_depth: int = MAX_YAML_DEPTH,
                     max_nodes: int = MAX_YAML_NODES) -> None:
    """Refuse, with one :class:`RikError` line naming the file (``shown``) and line, YAML ``text`` nested deeper than
    ``max_depth`` or whose aliases expand past ``max_nodes`` values, from libyaml's event stream (which neither
    recurses nor expands aliases). ``what`` names the file's role ("dataset spec", "catalog file"). Malformed YAML is
    left to the reader, which names its line."""
    import yaml


    sizes: dict[str, int] = {}
    """Expanded node count of each anchor, once its node is closed."""
    stack: list[tuple[str | None, int]] = [(None, 0)]
    """Open collections: their anchor and node count so far (the document at the bottom)."""
    try:
        for event in yaml.parse(text, Loader=_safe_loader()):
            line = event.start_mark.line + 1 if event.start_mark is not None else 0
            if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
                stack.append((event.anchor, 1))
                if len(stack) - 1 > max_depth:
                    raise RikError(f"{shown}:{line}: the {what} nests lists and mappings more than {max_depth} deep")
                continue
            if isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
                anchor, n = stack.pop()
                if anchor is not None:
                    sizes[anchor] = n
            elif isinstance(event, yaml.ScalarEvent):
                n = 1
                if event.anchor is not None:
                    sizes[event.anchor] = 1
            elif isinstance(event, yaml.AliasEvent):
                if event.anchor not in sizes:  # an alias inside its own anchor: a structure that contains itself
                    raise RikError(f"{shown}:{line}: the {what} has an alias (*{event.anchor}) inside its own "
                                   "anchor; it must be a tree")
                n = sizes[event.anchor]
            else:
                continue
            anchor, total = stack[-1]
            stack[-1] = (anchor, total + n)
            if total + n > max_nodes:
                raise RikError(f"{shown}:{line}: the {what} expands to more than {max_nodes:,} values through its "
                               "aliases (*name); write it without them, or with fewer")
    except yaml.YAMLError:
        return  # malformed: the reader names the line


def read_file(path: Path, builtin: bool) -> list[RawEntry]:
    """Parse one catalog file into raw entries; raises :class:`CatalogError` on malformed YAML or layout."""
    import yaml

    loader = _safe_loader()
    shown = display_path(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_CATALOG_BYTES + 1)
        if len(raw) > MAX_CATALOG_BYTES:  # grown since catalog_files checked it
            _check_size(path)
            raise CatalogError(shown, None, None, f"larger than the {MAX_CATALOG_BYTES // 2**20} MiB a catalog "
                               "file may have")
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CatalogError(shown, None, None, f"cannot read the file ({exc.__class__.__name__}: {exc})") from None
    if not builtin:
        check_yaml_shape(text, shown, "catalog file")
    try:
        doc = yaml.load(text, Loader=loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        line = mark.line + 1 if mark is not None else None
        where = f" (column {mark.column + 1})" if mark is not None else ""
        raise CatalogError(shown, None, None, f"malformed YAML: {problem}{where}", line) from None
    if doc is None:
        return []
    if not isinstance(doc, dict):
        raise CatalogError(shown, None, None, f"a catalog file must be a mapping of sections {', '.join(SECTIONS)}")
    schema = doc.get("schema", CATALOG_SCHEMA)
    if schema != CATALOG_SCHEMA:
        raise CatalogError(shown, None, "schema", f"catalog schema {schema!r} is not supported; this rik reads "
                           f"schema {CATALOG_SCHEMA}", line_of(path, ("schema",)))
    entries: list[RawEntry] = []
    for section, items in doc.items():
        if section == "schema":
            continue
        if section == SPLITS_KEY:
            if items is not None:
                entries.append(RawEntry(SPLITS_KEY, 0, items, path, builtin))
            continue
        if section not in SECTIONS:
            raise CatalogError(shown, None, str(section), "unknown section; valid sections: "
                               f"{', '.join((*SECTIONS, SPLITS_KEY))}", line_of(path, (section,)))
        if items is None:
            continue
        if not isinstance(items, list):
            raise CatalogError(shown, None, section, "a section must be a list of entries", line_of(path, (section,)))
        for index, item in enumerate(items):
            entry = RawEntry(section, index, item, path, builtin)
            if not isinstance(item, dict):
                raise entry.error(None, "an entry must be a mapping of fields")
            entries.append(entry)
    return entries


def line_of(path: Path, loc: tuple[int | str, ...]) -> int | None:
    """1-based line of the deepest node along ``loc`` (section, index, field, ...) in a YAML file.

    Only called when reporting an error, so the file is parsed again here rather than on every load.
    """
    import yaml

    loader = _safe_loader()
    try:
        node = yaml.compose(path.read_text(encoding="utf-8"), Loader=loader)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    if node is None:
        return None
    line = node.start_mark.line + 1
    for key in loc:
        child = None
        if isinstance(node, yaml.MappingNode):
            child = next((v for k, v in node.value if getattr(k, "value", None) == str(key)), None)
            if child is None and not isinstance(key, int):
                key_node = next((k for k, _ in node.value if getattr(k, "value", None) == str(key)), None)
                child = key_node
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and 0 <= key < len(node.value):
            child = node.value[key]
        if child is None:
            break
        node, line = child, child.start_mark.line + 1
    return line


#: Separator of several overlay paths in ``RIK_CATALOG`` (``:`` on POSIX).
OVERLAY_SEPARATOR = os.pathsep


def overlay_paths_from_env() -> list[Path]:
    """Overlay paths named by ``RIK_CATALOG`` (several joined by ``:``)."""
    value = os.environ.get("RIK_CATALOG", "")
    return [Path(p).expanduser() for p in value.split(OVERLAY_SEPARATOR) if p.strip()]


def catalog_sources(overlays: Iterable[Path] | None = None) -> list[tuple[Path, bool]]:
    """Every catalog file as (path, builtin): rik's data, then ``overlays`` (``None``: from ``RIK_CATALOG``)."""
    overlays = overlay_paths_from_env() if overlays is None else list(overlays)
    files = [(p, True) for p in catalog_files(BUILTIN_DIR)]
    for path in overlays:
        files += [(p, False) for p in catalog_files(Path(path))]
    return files
