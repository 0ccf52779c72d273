"""Turning raw entries into schema models, with pydantic's complaints rewritten as one-line catalog errors."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ValidationError

from rik.errors import CatalogError, RikError
from rik.registry.sources import MAX_CATALOG_BYTES, RawEntry, _safe_loader, check_yaml_shape, display_path, line_of
from rik.schemas import BaseUnit, Finish, Handle, HandleDesign, ResistancePreset
from rik.schemas.robots import Robot

if TYPE_CHECKING:
    from pydantic_core import ErrorDetails

CatalogModel = Finish | ResistancePreset | HandleDesign | Handle | BaseUnit | Robot
"""A catalog entry's model (each has an ``id``)."""

#: Schema model of each section.
SECTION_MODELS: dict[str, type[CatalogModel]] = {
    "finishes": Finish,
    "presets": ResistancePreset,
    "designs": HandleDesign,
    "handles": Handle,
    "base_units": BaseUnit,
    "robots": Robot,
}


def parse_entry(entry: RawEntry) -> CatalogModel:
    """Validate one raw entry against its section's model; raises :class:`rik.errors.CatalogError`."""
    model = SECTION_MODELS[entry.section]
    try:
        return model.model_validate(entry.data)
    except ValidationError as exc:
        errors = exc.errors(include_url=False)
        first = errors[0]
        field = ".".join(str(p) for p in error_loc(first))
        more = f" (and {len(errors) - 1} more problem{'s' if len(errors) > 2 else ''} in this entry)" \
            if len(errors) > 1 else ""
        raise entry.error(field or None, describe_error(model, first) + more) from None


def error_loc(error: ErrorDetails) -> tuple[int | str, ...]:
    """Where an error is: pydantic's location, extended by the field a model validator names
    (:class:`rik.schemas.common.FieldError`)."""
    from rik.schemas.common import FieldError

    cause = (error.get("ctx") or {}).get("error")
    return (*error["loc"], *(cause.loc if isinstance(cause, FieldError) else ()))


def describe_error(model: type[BaseModel], error: ErrorDetails) -> str:
    """A short, specific sentence for one pydantic error."""
    kind, msg = error["type"], error["msg"].removeprefix("Value error, ")
    if kind == "missing":
        return "required field is missing"
    if kind == "extra_forbidden":
        allowed = _fields_at(model, error["loc"][:-1])
        return "unknown field" + (f"; valid fields: {', '.join(allowed)}" if allowed else "")
    value = error.get("input")
    if isinstance(value, (str, int, float, bool)) and kind not in ("union_tag_invalid",):
        return f"{msg[0].lower()}{msg[1:]} (got {value!r})"
    return msg[0].lower() + msg[1:]


def _fields_at(model: type[BaseModel], loc: tuple[int | str, ...]) -> list[str]:
    """Field names of the (nested) model found at ``loc``, or [] when it cannot be followed."""
    current: Any = model
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(current, "model_fields", None)
        if fields is None or part not in fields:
            return []
        current = _model_of(fields[part].annotation)
        if current is None:
            return []
    return list(getattr(current, "model_fields", {}))


def _model_of(annotation: object) -> type[BaseModel] | None:
    """The BaseModel class inside an annotation such as ``X``, ``X | None`` or ``tuple[X, ...]``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = _model_of(arg)
        if found is not None:
            return found
    return None


def read_yaml_model[M: BaseModel](path: Path, model: type[M], what: str) -> M:
    """The YAML file at ``path`` validated as ``model``; a file that cannot be read, malformed YAML or a field
    that breaks the schema raises one :class:`rik.errors.RikError` line naming the file, line and field
    (``what`` names the file's role: "mapping file", "dataset spec")."""
    import yaml


    shown = display_path(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_CATALOG_BYTES + 1)
        if len(raw) > MAX_CATALOG_BYTES:
            raise RikError(f"{shown}: the {what} is larger than {MAX_CATALOG_BYTES // 2**20} MiB; nothing was read")
        text = raw.decode("utf-8")
        check_yaml_shape(text, shown, what)
        data = yaml.load(text, Loader=_safe_loader())
    except OSError as exc:
        raise RikError(f"{shown}: cannot read the {what} ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise RikError(f"{shown}: the {what} is not UTF-8 text") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise CatalogError(shown, None, None, f"malformed YAML: {getattr(exc, 'problem', exc)}",
                           mark.line + 1 if mark else None) from None
    if data is not None and not isinstance(data, dict):
        raise CatalogError(shown, None, None, f"the {what} must be a mapping of fields, not a "
                           f"{type(data).__name__}", 1)
    try:
        return model.model_validate(data if data is not None else {})
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        loc = error_loc(first)
        field = ".".join(str(p) for p in loc)
        raise CatalogError(shown, None, field or None, describe_error(model, first), line_of(path, loc)) from None
