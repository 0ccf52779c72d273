"""Exclusive locks on output folders, so two runs never write one folder at once.

A lock is an advisory ``flock`` on a small file beside the folder it guards (``<folder>.lock``), holding the
holder's pid for the message the second run prints. The kernel releases it when the holder exits, however it
ends (a ``kill -9`` too), so a stale file left behind by a killed run never blocks the next one; a run that ends
normally removes it.
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


def lock_file(folder: Path) -> Path:
    """The lock file that guards ``folder``: ``<folder>.lock`` beside it."""
    folder = Path(folder)
    return folder.with_name(f"{folder.name}.lock")


@contextmanager
def exclusive(folder: Path, command: str, *, wait: bool = False) -> Iterator[Path]:
    """Hold the lock of ``folder`` for the block. When another process holds it: with ``wait``, wait for it;
    else raise :class:`LockedError` at once (``command`` names the holder in the message: ``rik export-lerobot``)."""
    path = lock_file(folder)
    made = [d for d in (path.parent, *path.parent.parents) if not d.exists()]  # removed again if still empty
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise LockedError(f"{folder}: another {command} (pid {holder}) is writing it now; wait for it to "
                              "finish, or choose another --out") from None
        try:  # the file may have been removed by the previous holder between our open and our lock: lock anew
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield path
    finally:
        path.unlink(missing_ok=True)  # before the unlock: a waiter that opened the old file sees it is gone
        os.close(fd)
        for d in made:  # deepest first
            try:
                d.rmdir()
            except OSError:
                break
