"""Trials out: CSV files with rik's SI headers (:func:`write_csv_trials`), and the folder of simulated trials with
their ground truth (:func:`write_simulated`) that the generators of :mod:`rik.sysid.synthetic` write."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.outputs import NEW, MadeFolder, holds_only, recorded, staged_directory, write_text
from rik.paths import json_object
from rik.schemas.joints import JointType
from rik.schemas.trajectory import TrialColumns, TrialUnits
from rik.sysid.trials.load import Trial

if TYPE_CHECKING:
    from rik.outputs import MadeFolder


def si_columns(joint: JointType) -> tuple[TrialUnits, TrialColumns]:
    """The SI units and CSV headers of a trial of ``joint`` as rik writes it: ``time [s]``, ``position [m|rad]``,
    ``force [N]`` or ``torque [N·m]``."""
    position, force = ("m", "N") if joint is JointType.slide else ("rad", "N·m")
    word = "force" if joint is JointType.slide else "torque"
    return (TrialUnits(time="s", position=position, force=force),
            TrialColumns(time="time [s]", position=f"position [{position}]", force=f"{word} [{force}]"))


def _check_writable(trials: Sequence[Trial], joint: JointType) -> None:
    """Refuse an empty list, repeated names, a name that is no file name and a trial of another joint type."""
    if not trials:
        raise RikError("trials is empty; nothing to write")
    names = [t.name for t in trials]
    if len(set(names)) != len(names):
        raise RikError(f"trials have repeated names ({', '.join(sorted({n for n in names if names.count(n) > 1}))})")
    for trial in trials:
        if trial.joint is not joint:
            raise RikError(f"trials: '{trial.name}' is a {trial.joint.value} trial but the truth is a {joint.value}")
        if "/" in trial.name or "\\" in trial.name or trial.name.startswith("."):
            raise RikError(f"trials: name '{trial.name}' cannot be a file name")


def _csv_header(joint: JointType) -> str:
    """The header line rik writes into a trial CSV of ``joint``."""
    _, columns = si_columns(joint)
    return f"{columns.time},{columns.position},{columns.force}\n"


def write_csv_trials(trials: Sequence[Trial], directory: str | Path, joint: JointType) -> list[Path]:
    """Write each trial of ``joint`` to ``directory/<name>.csv`` (:func:`si_columns`' headers, values printed to
    round-trip exactly), each atomically; returns the paths (what :func:`load_trials` reads back). Refuses an empty
    list, repeated names, a name that is no file name and a trial of another joint type, each in one line."""

    _check_writable(trials, joint)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    header = _csv_header(joint)
    paths = []
    for trial in trials:
        rows = zip(trial.t.tolist(), trial.q.tolist(), trial.f.tolist(), strict=True)
        path = directory / f"{trial.name}.csv"
        write_text(path, header + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows), NEW)
        paths.append(path)
    return paths


TRUTH_FILE = "truth.json"
"""The ground truth beside simulated trials (the generators' ``TRUTH_FILE``)."""


def is_simulated(folder: Path) -> bool:
    """Whether ``folder`` holds trials a generator wrote (:func:`write_simulated`): a ``truth.json`` object naming
    the joint, and nothing else but CSV files that start with rik's header line and that rik recorded writing there
    (:func:`rik.outputs.recorded`): rik's header is also the documented format of measured trials, so a measured
    CSV copied beside simulated ones has it too."""

    truth = json_object(folder / TRUTH_FILE)
    if truth is None or truth.get("joint") not in {j.value for j in JointType}:
        return False
    headers = {_csv_header(j) for j in JointType}

    def rik_file(name: str) -> bool:
        if name == TRUTH_FILE:
            return True
        try:
            with (folder / name).open(encoding="utf-8") as handle:
                return name.endswith(".csv") and handle.readline() in headers and recorded(folder / name)
        except (OSError, UnicodeDecodeError):
            return False

    return holds_only(folder, rik_file)


def simulated_folder() -> MadeFolder:
    """The folder ``rik sysid simulate --out`` writes: replaced whole, and only if :func:`is_simulated`."""

    return MadeFolder("a folder of trials rik sysid simulate wrote", is_simulated, "choose another --out")


def write_simulated(trials: Sequence[Trial], directory: str | Path, joint: JointType,
                    truth: dict[str, Any]) -> list[Path]:
    """Write simulated ``trials`` (:func:`write_csv_trials`) and their ``truth`` (JSON) to ``directory`` as a whole:
    into a hidden sibling first, then renamed into place, replacing an earlier folder of simulated trials only (any
    other folder that is not empty is refused, before anything is written). Returns the CSV paths."""


    _check_writable(trials, joint)
    directory = Path(directory)
    with staged_directory(directory, simulated_folder(), record_files=True) as stage:
        written = write_csv_trials(trials, stage, joint)
        write_text(stage / TRUTH_FILE, json.dumps(truth, indent=2) + "\n", NEW)
    return [directory / p.name for p in written]
