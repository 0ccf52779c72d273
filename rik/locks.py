"""Exclusive locks on output folders, so two runs never write one folder at once.

A lock is an advisory ``flock`` on a small hidden file beside the folder it guards (``.<folder>.rik-lock``),
holding ``rik-lock <pid>`` for the message the second run prints. The kernel releases it when the holder exits,
however it ends (a ``kill -9`` too), so a stale file left behind by a killed run never blocks the next one; a run
that ends normally removes it. A file of that name that is not a rik lock (a person's) is never locked, written or
removed: the command stops with one line instead.

This module and :mod:`rik.outputs` are the only ones that create, write or remove files (tests/test_output_contract.py).
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rik.errors import RikError


class LockedError(RikError):
    """Another process holds the lock of the folder a command would write."""


LOCK_TAG = b"rik-lock"
"""How a lock file's content starts (then the holder's pid): what tells rik's lock files from a person's."""


def lock_file(folder: Path) -> Path:
    """The lock file that guards ``folder``: ``.<folder>.rik-lock`` beside it."""
    folder = Path(folder)
    return folder.with_name(f".{folder.name}.rik-lock")


def _is_lock(fd: int) -> bool:
    """Whether the open file ``fd`` is a rik lock: empty (just made) or ``rik-lock <pid>``."""
    head = os.pread(fd, 64, 0)
    return not head or (head.startswith(LOCK_TAG) and len(head) < 64)


@contextmanager
def exclusive(folder: Path, command: str, *, wait: bool = False) -> Iterator[Path]:
    """Hold the lock of ``folder`` for the block. When another process holds it: with ``wait``, wait for it;
    else raise :class:`LockedError` at once (``command`` names the holder in the message: ``rik export-lerobot``)."""
    path = lock_file(folder)
    made = [d for d in (path.parent, *path.parent.parents) if not d.exists()]  # removed again if still empty
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd = _lock(path, folder, command, wait)
    except BaseException:
        _remove_empty(made)
        raise
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, LOCK_TAG + f" {os.getpid()}\n".encode(), 0)
        yield path
    finally:
        path.unlink(missing_ok=True)  # before the unlock: a waiter that opened the old file sees it is gone
        os.close(fd)
        _remove_empty(made)


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) that the lock made, while they are empty."""
    for d in folders:
        try:
            d.rmdir()
        except OSError:
            break


def _lock(path: Path, folder: Path, command: str, wait: bool) -> int:
    """Open and lock the lock file ``path`` of ``folder``; its file descriptor."""
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        except OSError as exc:  # a link or a folder of that name: not rik's
            raise RikError(f"{path}: is not a lock file of rik's ({exc.strerror}); move it away, or choose another "
                           "--out") from None
        if not _is_lock(fd):
            os.close(fd)
            raise RikError(f"{path}: exists and is not a lock file of rik's; rik locks {folder} with a file of this "
                           "name, and writes over nothing it did not make: move it away, or choose another --out")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            text = os.pread(fd, 64, 0).decode(errors="replace")
            holder = text.removeprefix(LOCK_TAG.decode()).strip() or "unknown"
            os.close(fd)
            raise LockedError(f"{folder}: another {command} (pid {holder}) is writing it now; wait for it to "
                              "finish, or choose another --out") from None
        try:  # the file may have been removed by the previous holder between our open and our lock: lock anew
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return fd
        os.close(fd)
