"""Pieces every command group shares: the ``--catalog`` option and output helpers."""

from __future__ import annotations

import math
import os
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from typer._click import types as click_types

from rik.errors import RikError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rich.console import Console
    from rich.progress import Progress, TaskID
    from typer._click import Command, Context, Parameter
    from typer._click.exceptions import ClickException

CatalogOption = Annotated[
    list[Path] | None,
    typer.Option("--catalog", envvar="RIK_CATALOG", show_envvar=True,
                 help="A user catalog (YAML file or directory) to add to the built-in one; repeatable. "
                      "RIK_CATALOG takes several paths joined by ':'."),
]


RobotOpt = Annotated[str, typer.Option("--robot", help="Robot that opens the front: hand-e (the floating Robotiq "
                                      "Hand-E), panda-2f85, so100 or so101 (rik catalog list --kind robots).")]
DEFAULT_ROBOT = "hand-e"

JointsOpt = Annotated[str, typer.Option("--joints", help="The hinges of doors: paper (the preset of the "
                                       "episode's cell, as the paper's Table 3) or measured (a real door of the "
                                       "split, rik catalog splits); drawers and flaps keep the paper's presets.")]


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
    from rik.workers import check_workers

    return check_workers(workers)


def check_at_least_one_worker(workers: int) -> int:
    """``--workers`` of a command whose workers may run elsewhere (a Ray cluster): refused (one line) below 1 only."""

    if workers < 1:
        raise RikError(f"--workers {workers}: give 1 or more worker processes")
    return workers


WorkersOpt = Annotated[int, typer.Option("--workers", "-j", callback=_check_workers, help="Parallel processes.")]


class FiniteFloat(click_types.FloatParamType):
    """A float option's type that refuses ``inf`` and ``nan``, which Python's ``float()`` (click's ``FLOAT``)
    accepts: a time limit of ``inf``, a speed of ``nan``."""

    def convert(self, value: object, param: Parameter | None, ctx: Context | None) -> float:
        _check_finite(value, self, param, ctx)
        number: float = super().convert(value, param, ctx)
        return number


class FiniteFloatRange(click_types.FloatRange):
    """``FiniteFloat`` within typer's ``min=``/``max=`` (``nan`` passes click's range checks: every comparison is
    false); a value that is not finite is said to be so before any range."""

    def convert(self, value: object, param: Parameter | None, ctx: Context | None) -> float:
        _check_finite(value, self, param, ctx)
        number: float = super().convert(value, param, ctx)
        return number


def _check_finite(value: object, kind: click_types.ParamType, param: Parameter | None, ctx: Context | None) -> None:
    """Click's parameter error (one line from :func:`usage_line`) when ``value`` is a number that is not finite."""
    if not math.isfinite(click_types.FLOAT.convert(value, param, ctx)):
        kind.fail(f"{value} is not a finite number; give a finite one", param, ctx)


def _finite_type(kind: click_types.ParamType) -> click_types.ParamType:
    """``kind`` with every float in it (a ``FLOAT``, a ``FloatRange``, the floats of a tuple) finite."""
    if isinstance(kind, click_types.FloatRange):
        return FiniteFloatRange(kind.min, kind.max, kind.min_open, kind.max_open, kind.clamp)
    if isinstance(kind, click_types.FloatParamType):
        return FiniteFloat()
    if isinstance(kind, click_types.Tuple):
        kind.types = [_finite_type(t) for t in kind.types]
    return kind


def finite_floats(command: Command) -> Command:
    """``command`` (and each of its subcommands) with every float parameter refusing ``inf`` and ``nan``: a float
    on rik's command line is a time, a size, a speed or a mass, always finite. Set on the click command typer builds,
    so that no option can be declared without it."""
    for param in command.params:
        param.type = _finite_type(param.type)
    for sub in getattr(command, "commands", {}).values():
        finite_floats(sub)
    return command


def usage_line(exc: ClickException) -> str:
    """A click usage or parameter error (an option out of its range, a missing argument, an unknown command) as
    rik's one line: the parameter at fault, what is wrong, and where its help is."""
    from typer._click.exceptions import BadParameter, MissingParameter, UsageError

    text = exc.format_message()
    if isinstance(exc, BadParameter) and not isinstance(exc, MissingParameter) and exc.param is not None:
        text = f"{'/'.join(exc.param.opts) or exc.param.human_readable_name}: {exc.message}"
    text = " ".join(text.split()).rstrip(".")
    if isinstance(exc, UsageError) and exc.ctx is not None:
        text += f" (see {exc.ctx.command_path} --help)"
    return text


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
