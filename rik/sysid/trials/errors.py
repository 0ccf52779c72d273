"""The error of measured data: :class:`TrialError`, one line naming the file, trial and column at fault."""

from __future__ import annotations

from pathlib import Path

from rik.errors import RikError


class TrialError(RikError):
    """Measured data is unreadable or unusable. The message names the file, the trial and the column at
    fault (those known) and what would be valid."""

    def __init__(self, file: str | Path, trial: str | None, column: str | None, problem: str):
        self.file, self.trial, self.column, self.problem = str(file), trial, column, problem
        parts = [str(file)]
        if trial is not None:
            parts.append(f"trial '{trial}'")
        if column is not None:
            parts.append(f"column '{column}'")
        super().__init__(", ".join(parts) + f": {problem}")
