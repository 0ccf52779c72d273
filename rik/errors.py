"""The errors rik raises on bad input. The CLI prints them as one line and exits with code 2."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class RikError(Exception):
    """Base of every error caused by a user's input; its message is one line that says what to fix."""


class CatalogError(RikError):
    """A catalog file is malformed or an entry breaks a rule.

    The message names the file (with line when known), the entry and the field at fault.
    """

    def __init__(self, file: str, entry: str | None, field: str | None, problem: str, line: int | None = None):
        self.file, self.entry, self.field, self.problem, self.line = file, entry, field, problem, line
        where = f"{file}:{line}" if line else file
        parts = [where]
        if entry:
            parts.append(f"entry {entry}")
        if field:
            parts.append(f"field '{field}'")
        super().__init__(", ".join(parts) + f": {problem}")


LISTED_KINDS = frozenset({"robot"})
"""Kinds of entry a catalog holds a handful of: a miss names them all, not only the closest."""


class UnknownIdError(RikError, LookupError):
    """An id asked for is not in the catalog; the message suggests the closest ids (and, for a kind of
    :data:`LISTED_KINDS`, names every one)."""

    def __init__(self, kind: str, wanted: str, known: Iterable[str]):
        self.kind, self.wanted = kind, wanted
        known = list(known)
        close = difflib.get_close_matches(wanted, known, n=3, cutoff=0.8)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        if kind in LISTED_KINDS and known:
            hint += f" (the catalog's {kind}s: {', '.join(known)})"
        super().__init__(f"no {kind} '{wanted}' in the catalog{hint}")


def os_error_text(exc: OSError, longest_name: int = 200) -> str:
    """An OSError in a few words, for one line: ``episodes/x/states.parquet: No space left on device (ENOSPC)`` (the
    file's name cut at ``longest_name`` characters; none when the error names no file)."""
    import errno

    code = errno.errorcode.get(exc.errno or 0, "")
    name = "" if exc.filename is None else str(exc.filename)
    name = name if len(name) <= longest_name else name[:longest_name] + "..."
    return f"{name + ': ' if name else ''}{exc.strerror or exc}{f' ({code})' if code else ''}"
