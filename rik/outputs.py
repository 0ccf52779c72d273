"""The one way rik writes: every file and folder a command writes, replaces or removes goes through this module.

The contract, in four rules (docs/reliability.md, section 3b):

1. **Exclusive names.** A name that two writers could share is created exclusively: staging folders get a fresh
   random name (:func:`make_stage`), a new file is published with a hard link that fails when the name is taken
   (:data:`NEW`), a folder with :func:`publish_new_directory` (the episode a second station saves under the same
   id goes to the next free one), locks live in :mod:`rik.locks`.
2. **Only what rik made is replaced or removed.** Each write says what may already be at its destination
   (:class:`Replaces`): nothing (:data:`NEW`), a file rik wrote there and recorded (:data:`RECORDED`: rik's record
   of the files it writes at paths a person names, kept in its cache, by path and sha256), a file of a folder rik
   recognises as its own (:meth:`Replaces.in_folder`), or rik's private files (:data:`PRIVATE`: its cache and
   hidden staging folders). Folders are recognised by :class:`MadeFolder` over their whole tree, not their top.
3. **No way out through a link.** A symbolic link where a file or folder is written or removed is refused.
4. **Destinations are checked before the work** (:func:`check_destination`, :func:`check_replaceable`), and
   written through a temporary and a rename, so nothing is half-written.

``tests/test_output_contract.py`` scans rik's source and fails on a write, rename or removal outside this module
(and :mod:`rik.locks`).
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import shutil
from collections.abc import Callable, Collection, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.paths import cache_dir, read_json

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.figure import Figure


# ---- recognising what rik made ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MadeFolder:
    """A kind of folder that rik makes whole (a report, a stream, simulated trials), and how to tell one from a
    folder of the user's: rik replaces or removes a folder only when it is absent, empty, or ``made`` recognises it.

    ``made(folder)`` reads the file rik writes into every such folder (its marker: a report's ``summary.json``, a
    stream's ``stream.json``, ...) and checks that nothing else is anywhere in it but the files rik writes
    (:func:`tree_holds_only`), so a folder an older rik made is recognised as well, and a user's file added to it,
    at any depth, stops the replacement. ``what`` names the kind in messages ("a report of rik sysid fit"),
    ``advice`` says where else to write ("choose another --report")."""

    what: str
    made: Callable[[Path], bool]
    advice: str = "choose another folder"


TEMPORARY = re.compile(r"\.[^/]+\.\d+(\.[0-9a-f]{8})?\.tmp(\.[A-Za-z0-9]{1,8})?")
"""The name of a temporary of :func:`writing` (``.<file>.<pid>.<random>.tmp``, or ``...tmp.mp4`` keeping the
file's suffix; older rik: ``.<file>.<pid>.tmp``)."""


def is_temporary(name: str) -> bool:
    """Whether ``name`` is a temporary of :func:`writing`, which a killed write leaves."""
    return TEMPORARY.fullmatch(name) is not None


def holds_only(folder: Path, names: Callable[[str], bool] | Collection[str]) -> bool:
    """Whether every entry at the top of ``folder`` is one of ``names`` (a set, or a test of a name) or a temporary
    of :func:`writing`. For a folder rik may replace, use :func:`tree_holds_only`: it looks inside subfolders."""
    allowed = names if callable(names) else names.__contains__
    try:
        return all(allowed(e.name) or is_temporary(e.name) for e in os.scandir(folder))
    except OSError:
        return False


def tree_holds_only(folder: Path, allowed: Callable[[str], bool] | Collection[str], *,
                    limit: int = 1_000_000) -> bool:
    """Whether every file anywhere under ``folder`` is a regular file whose path relative to it (``a/b.png``) is
    ``allowed`` (a set of such paths, or a test of one), or a temporary of :func:`writing`; no symbolic link, no
    other kind of file, at most ``limit`` entries. Folders count only through the files in them (an empty one is
    fine)."""
    test = allowed if callable(allowed) else allowed.__contains__
    count = 0
    stack = [(Path(folder), "")]
    try:
        while stack:
            directory, prefix = stack.pop()
            for entry in os.scandir(directory):
                count += 1
                if count > limit or entry.is_symlink():
                    return False
                rel = f"{prefix}{entry.name}"
                if entry.is_dir(follow_symlinks=False):
                    stack.append((Path(entry.path), f"{rel}/"))
                elif not entry.is_file(follow_symlinks=False) or not (test(rel) or is_temporary(entry.name)):
                    return False
    except OSError:
        return False
    return True


# ---- rik's record of the files it wrote where a person said ------------------------------------------------------
def _record_path(path: Path) -> Path:
    """Where rik's record of the file at ``path`` lives: one small JSON per path in ``<cache>/written/``."""
    key = hashlib.sha256(str(_absolute(path)).encode("utf-8", "surrogateescape")).hexdigest()
    return cache_dir() / "written" / key[:2] / f"{key}.json"


def _absolute(path: Path) -> Path:
    """``path`` absolute, its folder resolved (its own name not: a link there is not followed)."""
    path = Path(path)
    return path.parent.resolve() / path.name


def file_sha256(path: Path) -> str:
    """sha256 of the file at ``path`` (read in 1 MiB blocks)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while block := handle.read(2**20):
            digest.update(block)
    return digest.hexdigest()


def recorded(path: Path) -> bool:
    """Whether the file at ``path`` is one rik wrote there and recorded (:data:`RECORDED`), unchanged since: its
    path and sha256 match rik's record. False for anything else (a person's file, one they edited, a link)."""
    path = Path(path)
    if path.is_symlink() or not path.is_file():
        return False
    try:
        record = read_json(_record_path(path), 4096)
        return (isinstance(record, dict) and record.get("path") == str(_absolute(path))
                and record.get("sha256") == file_sha256(path))
    except (OSError, ValueError):
        return False


def record(path: Path) -> None:
    """Note in rik's record that the file now at ``path`` is one rik wrote (:func:`recorded`)."""
    import json

    path = Path(path)
    entry = _record_path(path)
    entry.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps({"path": str(_absolute(path)), "sha256": file_sha256(path)}) + "\n"
    _publish_text(entry, text)


def record_tree(folder: Path) -> None:
    """:func:`record` every file under ``folder`` (a folder rik just published whole)."""
    for path in sorted(Path(folder).rglob("*")):
        if path.is_file() and not path.is_symlink():
            _record_quietly(path)


# ---- what a write may replace -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Replaces:
    """What may already be at a destination for rik to write over it: ``test(path)`` says whether the thing there is
    rik's own; ``what`` describes it for the message when it is not ("a file rik wrote there"). With ``record``,
    each file written is noted in rik's record (:func:`record`), so that a later run recognises it."""

    what: str
    test: Callable[[Path], bool]
    record: bool = False

    @staticmethod
    def in_folder(kind: MadeFolder) -> Replaces:
        """A file of a folder that ``kind`` recognises as rik's (a rerun writes over its own results)."""
        return Replaces(kind.what, lambda path: kind.made(Path(path).parent))

    @staticmethod
    def when(what: str, test: Callable[[Path], bool]) -> Replaces:
        """A file that ``test`` recognises as rik's (``what`` names it), or one rik recorded writing there."""
        return Replaces(what, lambda path: test(path) or recorded(path), record=True)

    @staticmethod
    def marked(what: str, marker: str, head: int = 4096) -> Replaces:
        """A text file that holds ``marker`` (the line rik writes into every such file) in its first ``head``
        bytes, or one rik recorded writing there."""
        def test(path: Path) -> bool:
            try:
                with open(path, "rb") as handle:
                    return marker.encode() in handle.read(head)
            except OSError:
                return False

        return Replaces.when(what, test)


def _private(path: Path) -> bool:
    """Whether ``path`` is in one of rik's private places: its cache, or a hidden staging folder (a name of
    :func:`make_stage`, ``.staging``, ``*.partial``, ``.meshes``) that only rik writes into."""
    path = _absolute(path)
    cache = cache_dir().resolve()
    if path.is_relative_to(cache):
        return True
    return any(part == ".staging" or part == ".meshes" or (part.endswith(".partial")) or STAGE.fullmatch(part)
               for part in path.parent.parts)


NEW = Replaces("nothing: rik writes only new files there", lambda path: False)
"""A new file: published only when nothing has that name (two writers never share it)."""
RECORDED = Replaces("a file rik wrote there before (rik keeps a record of the files it writes where you say)",
                    recorded, record=True)
"""A file at a path a person named (``--csv``, ``--png``, ``--out FILE``): replaced only when it is rik's own
earlier output there, unchanged (:func:`recorded`)."""
PRIVATE = Replaces("a file in rik's cache or staging folders", _private)
"""A file in rik's own cache or in a hidden staging folder of its own: rik's by construction."""
REGENERATED = Replaces("a file the repository's scripts regenerate", lambda path: True)
"""For rik's developer scripts (``scripts/``) only: a table or figure of the repository's docs that the script
writes again from its data; git keeps what it replaces. Never for a command's output."""
CACHED = Replaces("an entry of a content-addressed cache", lambda path: True)
"""An entry of a cache whose file names are the hashes of what they hold (the same name, the same content): only
for files under a cache root (``cache_dir()``, or a root a caller made for its cache)."""


def _refuse(path: Path, replaces: Replaces, advice: str = "choose another path, or move it away yourself") -> None:
    raise RikError(f"{path}: exists and is not {replaces.what}, so nothing was written: {advice}")


def check_destination(path: Path, replaces: Replaces, option: str = "output") -> Path:
    """Check, before the work, that ``path`` can take a file: no folder or link there, the nearest existing folder
    above it a folder, and whatever file is there ``replaces``'s to replace. Raises :class:`RikError` naming
    ``option`` and the path."""
    path = Path(path)
    if path.is_symlink():
        raise RikError(f"{option} {path}: is a symbolic link; rik writes only plain files, never through a link")
    if path.is_dir():
        raise RikError(f"{option} {path}: is a folder, where a file is expected")
    for parent in path.parents:
        if parent.is_dir():
            break
        if os.path.lexists(parent):
            raise RikError(f"{option} {path}: {parent} is not a folder")
    if path.exists() and not replaces.test(path):
        _refuse(path, replaces)
    return path


# ---- writing files -------------------------------------------------------------------------------------------------
def _temporary(path: Path, keep_suffix: bool = False) -> Path:
    """A fresh name beside ``path`` for its temporary (ending in ``path``'s suffix too, with ``keep_suffix``)."""
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp{path.suffix if keep_suffix else ''}")


def _publish(tmp: Path, path: Path, replaces: Replaces) -> None:
    """Move the finished temporary ``tmp`` to ``path``: exclusively when nothing is there (a hard link fails when
    another writer took the name meanwhile), else over the file there only when ``replaces`` says it is rik's."""
    if path.is_symlink() or path.is_dir():
        _refuse(path, replaces)
    try:
        os.link(tmp, path)
    except FileExistsError:
        if not replaces.test(path):
            _refuse(path, replaces)
        os.replace(tmp, path)
    except OSError:  # a file system without hard links: the check and the rename are two steps there
        if os.path.lexists(path) and not replaces.test(path):
            _refuse(path, replaces)
        os.replace(tmp, path)
    else:
        os.unlink(tmp)
    if replaces.record:
        _record_quietly(path)


def _record_quietly(path: Path) -> None:
    """:func:`record`, where a cache that cannot be written (a read-only home, a full disk) only costs the record:
    the output is written, and a later run refuses to replace it (it cannot tell it from a person's)."""
    try:
        record(path)
    except OSError:
        pass


def _publish_text(path: Path, text: str) -> None:
    tmp = _temporary(path)
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def writing(path: Path, replaces: Replaces, *, keep_suffix: bool = False) -> Iterator[Path]:
    """A temporary path beside ``path`` (its folder made first) for a library to write a file to
    (``pq.write_table``, ``np.savez``, an encoder; with ``keep_suffix`` it ends in ``path``'s suffix, for a writer
    that picks its format by it); published onto ``path`` when the block ends without an error (:class:`Replaces`
    says what may be there), removed when it raises: a full disk or a kill leaves no half-written file and no
    ``*.tmp``. Two writers never share a temporary."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(path, keep_suffix)
    try:
        yield tmp
        _publish(tmp, path, replaces)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_bytes(path: Path, data: bytes, replaces: Replaces) -> Path:
    """Write ``data`` to ``path`` through a temporary and a rename (:func:`writing`); returns ``path``."""
    with writing(path, replaces) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: Path, text: str, replaces: Replaces) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through a temporary and a rename (:func:`writing`); returns ``path``."""
    return write_bytes(path, text.encode("utf-8"), replaces)


def write_png(path: Path, pixels: np.ndarray, replaces: Replaces, compress_level: int = 6) -> Path:
    """Write an (H, W, 3) uint8 image as PNG (:func:`writing`)."""
    import numpy as np
    from PIL import Image

    with writing(path, replaces) as tmp:
        Image.fromarray(np.ascontiguousarray(pixels, np.uint8)).save(tmp, format="PNG", compress_level=compress_level)
    return Path(path)


def save_figure(fig: Figure, path: Path, replaces: Replaces, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG (no timestamp metadata, so reruns are byte-identical) through
    :func:`writing`, its folder made first, and close it."""
    from rik.paths import pyplot

    path = Path(path)
    try:
        with writing(path, replaces) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png", metadata={"Software": None})
    finally:
        pyplot().close(fig)
    return path


def move_new(source: Path, destination: Path) -> None:
    """Move the file ``source`` (a file rik staged) to ``destination``, which must not exist: exclusively, so a
    file that appeared there meanwhile is never replaced (:class:`RikError` naming it)."""
    try:
        os.link(source, destination)
    except FileExistsError:
        raise RikError(f"{destination}: already exists; rik writes only new files there, so nothing was moved "
                       "there: move or remove it yourself") from None
    os.unlink(source)


def link_or_copy(source: Path, destination: Path) -> None:
    """A hard link at ``destination`` (which must not exist) to the file ``source``, or a copy where the file system
    has no hard links: a variant's meshes share the content-addressed store's files."""
    try:
        os.link(source, destination)
    except FileExistsError:
        raise RikError(f"{destination}: already exists; rik writes only new files there") from None
    except OSError:
        with writing(destination, NEW) as tmp:
            shutil.copyfile(source, tmp)


def remove_empty_folder(folder: Path) -> None:
    """Remove ``folder`` if it is an empty folder (rik's staging parent once no writer uses it); else leave it."""
    try:
        os.rmdir(folder)
    except OSError:
        pass


def remove_file(path: Path, replaces: Replaces) -> None:
    """Remove the file at ``path`` if it is there and ``replaces`` recognises it as rik's; a link or anything else
    is refused (:class:`RikError`)."""
    path = Path(path)
    if not os.path.lexists(path):
        return
    if path.is_symlink() or not path.is_file() or not replaces.test(path):
        _refuse(path, replaces, "move or remove it yourself")
    path.unlink(missing_ok=True)


# ---- folders -------------------------------------------------------------------------------------------------------
STAGE = re.compile(r"\..+\.[0-9a-f]{12}\.partial")
"""The name of a staging folder of :func:`make_stage` (``.<final>.<random>.partial``)."""


def make_stage(final: Path) -> Path:
    """A new, empty hidden sibling of ``final`` (``.<name>.<random>.partial``) to write a whole folder into, made
    exclusively: no other writer, in this process or another, ever gets the same one."""
    final = Path(final)
    while True:
        stage = final.with_name(f".{final.name}.{secrets.token_hex(6)}.partial")
        try:
            stage.mkdir()
            return stage
        except FileExistsError:
            continue
        except FileNotFoundError:  # its folder is not there (yet, or again: removed empty by another writer)
            final.parent.mkdir(parents=True, exist_ok=True)


def remove_stage(stage: Path) -> None:
    """Remove a staging folder of rik's own (:func:`make_stage`, or one in a private place): a path that is not one
    is refused, so this never removes a person's folder."""
    stage = Path(stage)
    if not os.path.lexists(stage):
        return
    if stage.is_symlink() or not (STAGE.fullmatch(stage.name) or _private(stage / "x")):
        raise RikError(f"{stage}: not a staging folder of rik's; it was not removed")
    shutil.rmtree(stage, ignore_errors=True)


def check_replaceable(folder: Path, kind: MadeFolder) -> None:
    """Refuse (:class:`rik.errors.RikError`, one line naming ``folder``) to replace or remove ``folder`` unless
    nothing is there, it is an empty folder, or it is a ``kind`` folder rik made (:class:`MadeFolder`)."""
    folder = Path(folder)
    advice = f"{kind.advice}, or move or remove it yourself"
    if folder.name in ("", ".", "..") or Path.cwd().is_relative_to(folder.resolve()):
        raise RikError(f"{folder}: is the current folder or holds it, and rik writes {kind.what} as a folder of "
                       f"its own: name a new folder inside it")
    if not os.path.lexists(folder):
        return
    if folder.is_symlink() or not folder.is_dir():
        what = "a symbolic link" if folder.is_symlink() else "a file"
        raise RikError(f"{folder}: is {what}, not {kind.what}; rik replaces only folders it made: {advice}")
    try:
        names = sorted(e.name for e in os.scandir(folder))
    except OSError as exc:
        raise RikError(f"{folder}: cannot read this folder ({exc.strerror}); {advice}") from None
    if not names or kind.made(folder):
        return
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    raise RikError(f"{folder}: exists and is not {kind.what} (it holds {shown}); rik "
                   f"replaces only folders it made, so nothing was written: {advice}")


def check_own_files(folder: Path, names: Collection[str], made: Callable[[Path], bool], tool: str,
                    mark: str) -> None:
    """Refuse (:class:`rik.errors.RikError`, one line) to write the files ``names`` into ``folder`` when one of them
    is there and ``made(folder)`` does not recognise the folder as ``tool``'s earlier output (by ``mark``, the file
    it writes there): a rerun may write over its own results, never a user's file."""
    taken = [name for name in names if os.path.lexists(Path(folder) / name)]
    if taken and not made(Path(folder)):
        raise RikError(f"{Path(folder) / taken[0]}: exists and was not written by {tool} (no {mark} of its own beside "
                       "it), so nothing was run: choose another --out, or move it away yourself")


def remove_directory(folder: Path, kind: MadeFolder) -> None:
    """Remove ``folder`` (rik's own earlier output) if it is there: only after :func:`check_replaceable`."""
    check_replaceable(folder, kind)
    if os.path.lexists(folder):
        shutil.rmtree(folder)


def replace_directory(stage: Path, final: Path, kind: MadeFolder) -> None:
    """Move the finished directory ``stage`` onto ``final``, replacing what is there if rik made it (a ``kind``
    folder, :func:`check_replaceable`; anything else is refused and ``stage`` left for the caller): the old one is
    renamed aside first (to a name of its own) and removed after, so ``final`` is at every moment the old directory
    or the new one, whole."""
    check_replaceable(final, kind)
    if os.path.lexists(final):
        old = make_stage(final)
        os.replace(final, old)
        os.replace(stage, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(stage, final)


class NameTaken(RikError):
    """Another writer published a folder under the name first (:func:`publish_new_directory`)."""


def publish_new_directory(stage: Path, final: Path) -> None:
    """Move the finished directory ``stage`` to ``final``, which must not exist: the name is taken with an exclusive
    ``mkdir`` and the stage renamed onto that empty folder, so of two writers of one name exactly one succeeds; the
    other gets :class:`NameTaken` and keeps its stage."""
    try:
        os.mkdir(final)
    except FileExistsError:
        raise NameTaken(f"{final}: already exists") from None
    try:
        os.replace(stage, final)
    except BaseException:
        os.rmdir(final)
        raise


def publish_cache_entry(stage: Path, final: Path) -> None:
    """Move the finished cache entry ``stage`` to ``final`` (a content-addressed name); when another writer
    published it first, theirs is kept (the same content) and ``stage`` removed."""
    try:
        os.rename(stage, final)
    except OSError:
        shutil.rmtree(stage, ignore_errors=True)


def remove_cache_entry(entry: Path) -> None:
    """Remove an entry of a content-addressed cache (damaged, or a stage of one): only under a cache root."""
    shutil.rmtree(entry, ignore_errors=True)


@contextmanager
def staged_directory(final: Path, kind: MadeFolder, *, record_files: bool = False) -> Iterator[Path]:
    """A fresh hidden sibling of ``final`` (:func:`make_stage`, never shared) to write a whole directory into; moved
    onto ``final`` when the block ends without an error (:func:`replace_directory`), removed when it raises:
    ``final`` is never half-written. A ``final`` that rik did not make (``kind``) is refused before anything is
    written. With ``record_files``, every file published is noted in rik's record (:func:`record_tree`), for a
    ``kind`` that recognises its files by it."""
    check_replaceable(final, kind)
    stage = make_stage(final)
    try:
        yield stage
        replace_directory(stage, final, kind)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    if record_files:
        record_tree(final)


def rewrite_in_place(path: Path, data: bytes) -> None:
    """Write ``data`` over the file at ``path`` that rik is building in a private place (:data:`PRIVATE`), through
    a temporary and a rename."""
    write_bytes(path, data, PRIVATE)


def json_text(data: Any, indent: int | None = 2) -> str:
    """``data`` as JSON text with a final newline (rik's own files)."""
    import json

    return json.dumps(data, indent=indent) + "\n"
