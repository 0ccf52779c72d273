"""Look at variants: re-validate one (from its files or in memory) and render a picture of it."""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.combinator.build import (
    DEFAULT_OUT,
    JOINT_FRICTION,
    assemble_variant,
    check_collision,
    check_variant,
    is_current,
    make_report,
    materialise,
    resolve_collision,
    spec_hash,
)
from rik.combinator.checks import CheckResult, ModelContext, run_model_checks
from rik.errors import RikError
from rik.outputs import RECORDED, check_destination, write_png
from rik.registry.ids import VariantKey, parse_variant_id

if TYPE_CHECKING:
    import mujoco

    from rik.registry.catalog import Catalog


@dataclass
class Validation:
    """The checks of one variant and where they ran."""

    key: VariantKey
    checks: list[CheckResult]
    source: str
    """``files`` (the written model.xml, loaded as MuJoCo loads it) or ``memory`` (assembled, nothing written)."""
    notes: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


def _model_file(target: str) -> Path | None:
    path = Path(target)
    if path.is_dir() and (path / "model.xml").is_file():
        return path / "model.xml"
    if path.is_file() and path.suffix == ".xml":
        return path
    return None


def _variant_text(model: mujoco.MjModel, file: Path) -> dict[str, Any]:
    import mujoco

    tid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, "rik.variant")
    if tid < 0:
        raise RikError(f"{file}: not a rik variant (it has no text element 'rik.variant')")
    adr = model.text_adr[tid]
    raw = bytes(model.text_data[adr: adr + model.text_size[tid] - 1]).decode()
    return json.loads(raw)


def validate_variant(catalog: Catalog, target: str, out: Path = DEFAULT_OUT) -> Validation:
    """Validate a variant directory (or its ``model.xml``), or a variant id: from ``out/<id>`` when built there,
    else assembled in memory."""
    import mujoco

    file = _model_file(target)
    if file is None:
        key = parse_variant_id(catalog, target)
        if (out / key.id / "model.xml").is_file():
            file = out / key.id / "model.xml"
        else:
            checked = check_variant(catalog, key, stop_at_failure=False, collision=resolve_collision(out),
                                    joint_friction=JOINT_FRICTION.resolve(out))
            return Validation(key, checked.checks, "memory", [f"{out / key.id} does not exist: checked in memory"])
    try:
        model = mujoco.MjModel.from_xml_path(str(file))
    except ValueError as exc:
        raise RikError(f"{file}: MuJoCo cannot load it: {str(exc).splitlines()[0]}") from None
    info = _variant_text(model, file)
    key = parse_variant_id(catalog, info["id"])
    directory = file.parent
    notes = []
    collision = check_collision(info.get("collision", "coacd"), f"{file}: rik.variant field collision")
    joint_friction = JOINT_FRICTION.check(info.get("joint_friction", JOINT_FRICTION.default),
                                          f"{file}: rik.variant field joint_friction")
    if not is_current(directory, spec_hash(catalog, key, collision, joint_friction)):
        notes.append(f"{directory} is stale or damaged: its report's spec hash or file hashes differ from what the "
                     "catalog builds now (rik variants build rebuilds it)")
    # the layout and the geometry checks
    assembled = assemble_variant(catalog, key, stop_at_failure=False, collision=collision,
                                 joint_friction=joint_friction)
    loaded = CheckResult("compiles", True, f"{file.name} loads with mujoco.MjModel.from_xml_path")
    ctx = ModelContext(assembled.variant, assembled.variant.unit, model, mujoco.MjData(model))
    return Validation(key, [*assembled.checks, loaded, *run_model_checks(ctx, stop_at_failure=False)], "files",
                      notes)


def render_variant(catalog: Catalog, key: VariantKey, png: Path, *, out: Path = DEFAULT_OUT,
                   open_fraction: float = 0.5, width: int = 960, height: int = 720) -> Path:
    """Render ``scene.xml`` of a variant through its front camera, with every front opened to ``open_fraction``
    of its range, into ``png``. Uses ``out/<id>`` when built there; otherwise the variant (even a rejected one)
    is written to a temporary directory first."""
    if not 0.0 <= open_fraction <= 1.0:
        raise RikError(f"--open must be between 0 and 1 (a fraction of each joint's range), got {open_fraction}")
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco


    check_destination(png, RECORDED, "--png")
    directory = out / key.id
    with tempfile.TemporaryDirectory(prefix="rik-show-") as tmp:
        if not (directory / "scene.xml").is_file():
            collision, joint_friction = resolve_collision(out), JOINT_FRICTION.resolve(out)
            checked = check_variant(catalog, key, stop_at_failure=False, collision=collision,
                                    joint_friction=joint_friction)
            directory = Path(tmp) / key.id
            digest = spec_hash(catalog, key, collision, joint_friction)
            materialise(checked, directory, make_report(catalog, checked, digest, 0.0), Path(tmp))
        model = mujoco.MjModel.from_xml_path(str(directory / "scene.xml"))
        model.vis.global_.offwidth, model.vis.global_.offheight = max(width, 64), max(height, 64)
        data = mujoco.MjData(model)
        for j in range(model.njnt):
            data.qpos[model.jnt_qposadr[j]] = open_fraction * model.jnt_range[j][1]
        mujoco.mj_forward(model, data)
        with mujoco.Renderer(model, height, width) as renderer:
            renderer.update_scene(data, camera="front")
            pixels = renderer.render()
    return write_png(png, pixels, RECORDED)
