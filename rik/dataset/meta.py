"""The metadata rik writes into a built dataset's ``meta/`` folder and reads back: names, and a checked reader that
turns a damaged file into one line naming the file and the field."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError

if TYPE_CHECKING:
    from pydantic import BaseModel

DATASET_META = "rik_dataset.json"
"""``meta/rik_dataset.json``: the spec, its hash, versions, variant hashes, counts, outcomes and file checksums;
identical for identical builds."""
BUILD_META = "rik_build.json"
"""``meta/rik_build.json``: the build's statistics (engine, seconds per stage, units run and reused, failures);
these vary from one build to the next."""


def read_dataset_meta(root: Path) -> dict[str, Any] | None:
    """``meta/rik_dataset.json`` of a built dataset, or None when ``root`` holds none. One that is there but
    damaged (not JSON, not an object, a field rik reads missing or of the wrong type) raises one line naming the
    file and the field (:func:`read_meta_file`)."""
    from rik.schemas.dataset import DatasetRecord

    path = Path(root) / "meta" / DATASET_META
    if not path.is_file():
        return None
    return read_meta_file(path, DatasetRecord)


def read_meta_file(path: Path, model: type[BaseModel]) -> dict[str, Any]:
    """The JSON object in ``path``, checked against ``model`` (which says what rik reads of it); a file that cannot
    be read or is damaged raises a :class:`RikError` line naming the file and the field."""
    from pydantic import ValidationError

    from rik.paths import read_json

    try:
        data = read_json(path)
    except OSError as exc:
        raise RikError(f"{path}: cannot read it ({exc.strerror})") from None
    except ValueError as exc:  # too large, not UTF-8, not JSON, nested too deeply
        raise RikError(f"{path}: damaged: not the JSON rik wrote ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise RikError(f"{path}: damaged: holds a JSON {type(data).__name__}, not the object rik wrote")
    try:
        model.model_validate(data)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        where = ".".join(str(p) for p in first["loc"])
        raise RikError(f"{path}, field '{where}': damaged: {first['msg'][0].lower()}{first['msg'][1:]}") from None
    return data
