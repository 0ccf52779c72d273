"""The app's page of recorded episodes and built datasets: ``GET /episodes`` (a static page) and ``GET
/api/episodes`` (JSON), read from the app's episodes folder (``rik serve --out``, where its stations save) and
datasets folder (``rik serve --datasets``: each subfolder a dataset built by ``rik dataset build``).

Each episode gives its variant, robot, operator, outcome (S, P, F: :mod:`rik.sim.outcome`), final and largest
opening, steps and simulated seconds, and the address of its station that replays it
(``/teleop/<variant>?robot=<robot>&replay=<episode id>``: the page starts nothing; its websocket, which needs the
app's Origin, loads the episode from this same folder). Each dataset gives its name, episodes, frames, robot and
outcomes. Both folders are untrusted: a ``meta.json`` that is missing, too large or damaged gives a row holding one
line that says so, never a failed page; at most :data:`MAX_ROWS` of each are read (the newest first), and the page
says how many there are. Hidden folders (drafts) are left out. Everything is read on request; nothing is written.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any
from urllib.parse import quote

from fastapi import APIRouter, Request
from fastapi.responses import FileResponse

from rik.errors import RikError
from rik.paths import read_meta_file
from rik.web.pages import STATIC

router = APIRouter()

MAX_ROWS = 500
"""Most episodes (and datasets) listed; the newest by their metadata's modification time."""
MAX_SCAN = 100_000
"""Most folder entries looked at in each folder (a larger folder is listed from its first ones)."""
OUTCOME_NAMES = {"S": "success", "P": "partial", "F": "fail"}
DATASET_META = "meta/rik_dataset.json"
"""A built dataset's record, relative to its folder (``rik.dataset.meta.DATASET_META`` in ``meta/``; rik.web sits
below rik.dataset, so it reads the file through :func:`rik.paths.read_meta_file` itself)."""


def _folders(root: Path, meta: str, *, required: bool = False) -> tuple[list[tuple[float, Path]], int]:
    """Up to :data:`MAX_ROWS` visible subfolders of ``root`` with their metadata file's time (newest first; a
    folder without one sorts last, or is left out when ``required``), and how many there are (of the first
    :data:`MAX_SCAN` entries)."""
    found: list[tuple[float, Path]] = []
    try:
        with os.scandir(root) as entries:
            for i, entry in enumerate(entries):
                if i >= MAX_SCAN:
                    break
                if entry.name.startswith(".") or not entry.is_dir(follow_symlinks=False):
                    continue
                try:
                    stamp = os.stat(Path(entry.path) / meta).st_mtime
                except OSError:
                    if required:
                        continue
                    stamp = 0.0
                found.append((stamp, Path(entry.path)))
    except OSError:
        return [], 0
    found.sort(key=lambda f: (-f[0], f[1].name))
    return found[:MAX_ROWS], len(found)


def episode_row(directory: Path) -> dict[str, Any]:
    """One episode for the page: its meta.json's numbers and the station address that replays it, or
    ``{"id", "error"}`` with one line when the meta is missing, damaged or edited."""
    from rik.episodes.episode import read_meta

    try:
        meta = read_meta(directory)  # bounded in size, validated, its seal checked
    except RikError as exc:
        return {"id": directory.name, "error": str(exc).splitlines()[0]}
    query = f"robot={quote(meta.robot)}&replay={quote(meta.id)}"
    return {"id": meta.id, "variant": meta.variant, "robot": meta.robot, "operator": meta.operator,
            "operator_kind": meta.operator_kind, "front": meta.front, "outcome": meta.outcome,
            "outcome_name": OUTCOME_NAMES[meta.outcome], "final_opening": meta.final_opening,
            "max_opening": meta.max_opening, "steps": meta.steps, "seconds": round(meta.steps / meta.fps, 3),
            "fps": meta.fps, "folder_matches": meta.id == directory.name,
            "replay": f"/teleop/{quote(meta.variant)}?{query}" if meta.id == directory.name else None}


def dataset_row(directory: Path) -> dict[str, Any] | None:
    """One dataset for the page (name, episodes, frames, robot, outcomes), ``{"name", "error"}`` with one line when
    its ``meta/rik_dataset.json`` is damaged, or None when the folder holds no built dataset."""
    from rik.schemas.dataset import DatasetRecord

    path = directory / DATASET_META
    if not path.is_file():
        return None
    try:
        meta = read_meta_file(path, DatasetRecord)  # bounded in size, checked as rik dataset list checks it
    except RikError as exc:
        return {"name": directory.name, "error": str(exc).splitlines()[0]}
    spec, counts = meta.get("spec", {}), meta.get("counts", {})
    return {"name": directory.name, "repo_id": spec.get("repo_id"), "robot": spec.get("robot", "hand-e"),
            "episodes": counts.get("episodes"), "frames": counts.get("frames"), "variants": counts.get("variants"),
            "outcomes": meta.get("outcomes", {}), "streams": spec.get("streams", [])}


def listing(episodes: Path, datasets: Path) -> dict[str, Any]:
    """The episodes and datasets of the two folders, as :func:`episode_row` and :func:`dataset_row` give them."""
    found, total = _folders(episodes, "meta.json")
    rows = [episode_row(d) for _, d in found]
    if (datasets / DATASET_META).is_file():  # --datasets names one dataset itself
        dfound, dtotal = [(0.0, datasets)], 1
    else:
        dfound, dtotal = _folders(datasets, DATASET_META, required=True)  # other folders are no datasets
    drows = [r for r in (dataset_row(d) for _, d in dfound) if r is not None]  # None: its meta went meanwhile
    return {"episodes_folder": str(episodes), "datasets_folder": str(datasets),
            "episodes": rows, "episodes_total": total, "datasets": drows, "datasets_total": dtotal,
            "max_rows": MAX_ROWS}


@router.get("/episodes", include_in_schema=False)
def episodes_page() -> FileResponse:
    return FileResponse(STATIC / "episodes.html", media_type="text/html", headers={"Cache-Control": "no-store"})


@router.get("/api/episodes")
def episodes_api(request: Request) -> dict[str, Any]:
    """Recorded episodes (``--out``) and built datasets (``--datasets``) of this app, newest first."""
    config = request.app.state.config
    return listing(Path(config.episodes), Path(config.datasets))
