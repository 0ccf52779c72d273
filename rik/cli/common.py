"""Pieces every command group shares: the ``--catalog`` option and output helpers."""

from __future__ import annotations

import os
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    from collections.abc import Callable

    from rich.console import Console
    from rich.progress import Progress, TaskID

CatalogOption = Annotated[
    list[Path] | None,
    typer.Option("--catalog", envvar="RIK_CATALOG", show_envvar=True,
                 help="A user catalog (YAML file or directory) to add to the built-in one; repeatable. "
                      "RIK_CATALOG takes several paths joined by ':'."),
]


RobotOpt = Annotated[str, typer.Option("--robot", help="Robot that opens the front: hand-e (the floating Robotiq "
                                      "Hand-E), panda-2f85, so100 or so101 (rik catalog list --kind robots).")]
DEFAULT_ROBOT = "hand-e"


def robot_entry(catalog: object, robot: str) -> object | None:
    """The catalog entry of an arm given as ``--robot`` (None for the floating Hand-E, rik's own gripper); an
    unknown id, or an arm whose model's package is not installed, is a one-line error."""
    from rik.registry.robots import usable_robot

    entry = usable_robot(catalog, robot)  # type: ignore[arg-type]
    return entry.as_arm


DEFAULT_WORKERS = max(1, min(8, os.cpu_count() or 1))
"""One process per core, at most eight."""


def _check_workers(workers: int) -> int:
    """``--workers``, refused (one line) below 1 or above what the machine can hold, before the command does any
    work. (Not typer's ``min=1``: that prints a usage box of many lines.)"""
    from rik.assets.workers import check_workers

    return check_workers(workers)


def check_at_least_one_worker(workers: int) -> int:
    """``--workers`` of a command whose workers may run elsewhere (a Ray cluster): refused (one line) below 1 only."""
    from rik.errors import RikError

    if workers < 1:
        raise RikError(f"--workers {workers}: give 1 or more worker processes")
    return workers


WorkersOpt = Annotated[int, typer.Option("--workers", "-j", callback=_check_workers, help="Parallel processes.")]


class OutputFormat(StrEnum):
    table = "table"
    json = "json"
    csv = "csv"


class HandleTypeOpt(StrEnum):
    """The three handle types, as a command-line choice."""

    knob = "knob"
    two_point = "two_point"
    finger_pull = "finger_pull"


def overlays(paths: list[Path] | None) -> list[Path]:
    """The overlay paths a command was given (``--catalog`` or ``RIK_CATALOG``)."""
    return list(paths or [])


def print_json(data: object) -> None:
    """JSON to stdout: indented, keys in schema order, UTF-8 (stable for scripts)."""
    import json
    import sys

    sys.stdout.write(json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def console() -> Console:
    """A rich console for data: no automatic highlighting or emoji codes (cells are data, and the regex
    highlighter costs more than the rest of a listing); when output is not a terminal, wide enough that tables
    are not folded."""
    import sys

    from rich.console import Console

    width = None if sys.stdout.isatty() else 240
    return Console(highlight=False, emoji=False, width=width)


def progress_bar() -> Progress:
    """A rich progress bar for batch work: description, bar, done/total, elapsed time and the last item. It draws on
    stderr, so that what a command prints on stdout (a table, JSON, CSV) stays whole for scripts; and it is wiped
    when the work stops with an error, so that the error is the one line left on stderr."""
    from types import TracebackType

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    class WipedOnError(Progress):
        def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                     tb: TracebackType | None) -> None:
            if exc_type is not None:
                self.live.transient = True
                if not self.console.is_terminal:  # rich would still end a piped bar with a line of its own
                    import io

                    self.console.file = io.StringIO()
            super().__exit__(exc_type, exc, tb)

    return WipedOnError(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                        TextColumn("{task.fields[last]}"), console=Console(stderr=True, highlight=False, emoji=False),
                        transient=False)


def quiet_writers() -> None:
    """Silence what lerobot's stack prints per episode (tqdm bars of datasets and aggregation; FFmpeg and SVT-AV1
    are quieted by the writer itself): rik shows its own progress. Read when tqdm is first imported."""
    os.environ.setdefault("TQDM_DISABLE", "1")


def stage_progress(bar: Progress) -> Callable[[str, int, int], None]:
    """A ``progress(stage, done, total)`` callback that keeps one task of ``bar`` per stage."""
    tasks: dict[str, TaskID] = {}

    def report(stage: str, done: int, total: int) -> None:
        if stage not in tasks:
            tasks[stage] = bar.add_task(stage, total=total, last="")
        bar.update(tasks[stage], completed=done, total=total)

    return report
