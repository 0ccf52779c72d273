"""Writing a fitted joint model into a user catalog as a resistance preset, so variants can be built with it.

The preset holds the measured resistance on its joint type's side (provenance ``measured``) and a base preset's
values on the other side, in ``<catalog_dir>/preset-<name>.yaml``. Use it with ``--catalog <catalog_dir>`` (or
``RIK_CATALOG``): ``rik variants build --preset <name> --catalog <catalog_dir> ...``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.outputs import NEW, make_stage, remove_stage, write_text
from rik.paths import read_json

if TYPE_CHECKING:
    from rik.schemas.joints import JointResistance, JointType, ResistancePreset

NAME = re.compile(r"^[a-z0-9](?:[a-z0-9_.\-]*[a-z0-9.\-])?$")
"""A preset id usable in variant ids: lower case letters, digits, ``_ . -``, no ``/``, no ``__``."""


def preset_file(catalog_dir: Path, name: str) -> Path:
    """Where :func:`write_preset` puts preset ``name``."""
    return Path(catalog_dir) / f"preset-{name}.yaml"


def _entry(resistance: JointResistance, joint_type: JointType, name: str, base_preset: ResistancePreset,
           description: str) -> dict[str, object]:
    from rik.schemas.common import Provenance
    from rik.schemas.joints import JointType as JT

    measured = resistance.model_copy(update={"provenance": Provenance.measured})
    jtype = JT(getattr(joint_type, "value", joint_type))
    other = JT.hinge if jtype is JT.slide else JT.slide
    sides = {jtype.value: measured, other.value: base_preset.for_joint(other)}
    return {"id": name, "name": name, "description": description,
            **{side: sides[side].model_dump(mode="json", exclude_none=True) for side in ("slide", "hinge")}}


def write_preset(resistance: JointResistance, joint_type: JointType, name: str, catalog_dir: Path, *,
                 base_preset: ResistancePreset, description: str) -> Path:
    """Write a new resistance preset ``name`` into the user catalog ``catalog_dir`` (created if needed): its
    ``joint_type`` side is ``resistance`` (provenance ``measured``), its other side ``base_preset``'s. Returns the
    file written (``preset-<name>.yaml``, atomically, validated with the rest of ``catalog_dir`` first).

    Refuses (:class:`RikError`) a name that is not a simple id, a preset id of rik's built-in catalog, and one
    already in ``catalog_dir``."""
    import yaml

    from rik import CATALOG_SCHEMA
    from rik.registry import load_catalog
    from rik.registry.sources import BUILTIN_DIR, catalog_files, display_path

    catalog_dir = Path(catalog_dir)
    file = preset_file(catalog_dir, name)
    shown = display_path(file)
    if not NAME.match(name) or "__" in name:
        raise RikError(f"{shown}: preset id '{name}' is not valid: use lower case letters, digits, '_', '.' and "
                       "'-' (no '/' and no '__', since it goes into variant ids)")
    if catalog_dir.exists() and not catalog_dir.is_dir():
        raise RikError(f"{display_path(catalog_dir)}: not a directory; give the user catalog's directory")
    builtin = load_catalog([])
    if name in builtin.presets:
        where = builtin.origins.get(("presets", name))
        raise RikError(f"{shown}: preset '{name}' is a built-in preset "
                       f"({display_path(Path(where.file) if where else BUILTIN_DIR)}); choose another name")
    if catalog_dir.is_dir() and catalog_files(catalog_dir):
        existing = load_catalog([catalog_dir])
        origin = existing.origins.get(("presets", name))
        if origin is not None:
            raise RikError(f"{shown}: preset '{name}' is already in the user catalog "
                           f"({display_path(Path(origin.file))}); choose another name or remove it there")
    if file.exists():
        raise RikError(f"{shown}: the file already exists; preset '{name}' would overwrite it")
    entry = _entry(resistance, joint_type, name, base_preset, description)
    text = (f"# Resistance preset '{name}' fitted to measured data (rik sysid); units: rik/schemas/joints.py\n"
            + yaml.safe_dump({"schema": CATALOG_SCHEMA, "presets": [entry]}, sort_keys=False, allow_unicode=True))
    catalog_dir.mkdir(parents=True, exist_ok=True)
    stage = make_stage(file)  # a new hidden folder (never one of the user's): a catalog scan skips it
    try:
        staged = write_text(stage / file.name, text, NEW)
        load_catalog([catalog_dir, staged])  # the whole user catalog must still validate with the new preset
    finally:
        remove_stage(stage)
    return write_text(file, text, NEW)


def read_summary(path: Path) -> dict[str, Any]:
    """The ``summary.json`` of a ``rik sysid fit`` report (``path``: the report directory or the file), checked
    to hold what a preset needs: one line naming the file and field when it does not."""
    from pydantic import ValidationError

    from rik.schemas.joints import JointResistance, JointType

    path = Path(path)
    file = path / "summary.json" if path.is_dir() else path
    if not file.is_file():
        raise RikError(f"{file}: no such report summary; pass the directory `rik sysid fit --report` wrote")
    try:
        data = read_json(file)
    except ValueError as exc:  # not JSON, not UTF-8, too large or nested too deeply
        raise RikError(f"{file}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != 1:
        raise RikError(f"{file}: field 'format' must be 1 (a rik sysid report summary), got "
                       f"{data.get('format') if isinstance(data, dict) else type(data).__name__!r}")
    if not isinstance(data.get("joint"), str) or data["joint"] not in {j.value for j in JointType}:
        raise RikError(f"{file}: field 'joint' must be slide or hinge, got {data.get('joint')!r}")
    try:
        data["resistance"] = JointResistance.model_validate(data.get("resistance"))
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"])
        raise RikError(f"{file}: field 'resistance{'.' + where if where else ''}': {err['msg']}") from None
    return data


def apply_report(report: Path, name: str, catalog_dir: Path, *, base: str = "normal",
                 overlays: list[Path] | None = None) -> Path:
    """Write the joint fitted in ``report`` (directory or ``summary.json``) as preset ``name`` into the user catalog
    ``catalog_dir``; its other joint type takes preset ``base``'s values. Returns the preset file."""
    from rik.registry import load_catalog
    from rik.schemas.joints import JointType

    data = read_summary(report)
    catalog = load_catalog(list(overlays or []))
    if base not in catalog.presets:
        raise RikError(f"--base: no preset '{base}'; choose one of {', '.join(sorted(catalog.presets))}")
    return write_preset(data["resistance"], JointType(data["joint"]), name, catalog_dir,
                        base_preset=catalog.presets[base], description=f"Fitted by rik sysid: {data.get('cause', '')}")
