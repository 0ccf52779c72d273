"""Build variants: assemble, check, and write ``<out>/<id>/{model.xml, scene.xml, meshes/, report.json}``.

A variant is written only when every check passes, through a staging directory renamed into place, so a
directory under ``<out>`` is always a whole, valid variant. Mesh files are stored once per content under
``<out>/.meshes/`` and hard-linked into each variant (copied where links are not possible), so a thousand
variants of 83 handles take the disk of 83. ``<out>/manifest.json`` lists every variant asked for and its
status. A variant whose report matches its current spec hash and whose files match their recorded sha256 is
skipped (resumable builds).

A folder holds variants of one collision mode (:data:`rik.combinator.mjcf.COLLISION_MODES`): ``coacd`` (the
handle collides as its CoACD hulls, the default) or ``hull`` (as its single convex hull). The mode is part of a
variant's spec hash and its report, and ``<out>/collision.json`` names the folder's mode, so anything that
builds into the folder later (``rik record --variants``, ``rik bench`` ...) rebuilds with that mode. A folder
without the marker is a ``coacd`` folder (every folder written before modes existed). Likewise a folder holds one
joint-friction mode (:data:`rik.joints.mjcf.JOINT_FRICTION_MODES`): ``held`` (the default) or ``creeping``
(MuJoCo's default friction impedance, the other side of the fidelity ablation), named by
``<out>/joint_friction.json``. Both are :class:`FolderMode` s.
"""

from __future__ import annotations

import functools
import json
import os
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.combinator.checks import GEOMETRY_CHECKS, CheckResult, ModelContext, run_model_checks
from rik.combinator.scene import scene_xml
from rik.errors import RikError
from rik.outputs import (
    NEW,
    PRIVATE,
    MadeFolder,
    Replaces,
    check_replaceable,
    link_or_copy,
    make_stage,
    remove_empty_folder,
    remove_stage,
    replace_directory,
    tree_holds_only,
    write_bytes,
    write_text,
)
from rik.paths import check_folder, inside, json_object
from rik.registry.ids import VariantKey

if TYPE_CHECKING:
    from rik.assets.build import Asset
    from rik.assets.cache import AssetCache
    from rik.combinator.mjcf import VariantModel
    from rik.registry.catalog import Catalog

REPORT_FORMAT = 1
DEFAULT_OUT = Path("variants")
MESH_STORE = ".meshes"
STAGING = ".staging"
MANIFEST = "manifest.json"
VARIANT_FILES = frozenset({"model.xml", "scene.xml", "meshes", "report.json"})
"""What :func:`materialise` writes at the top of a variant's folder."""


def is_variant(directory: Path) -> bool:
    """Whether ``directory`` is a variant rik built: its ``report.json``, and nothing else at any depth but the files
    the report lists (``model.xml``, ``scene.xml``, ``meshes/*``; a report without a list: those names)."""
    report = json_object(Path(directory) / "report.json")
    if report is None:
        return False
    files = report.get("files")
    if isinstance(files, dict):
        return tree_holds_only(directory, {"report.json", *files})
    return tree_holds_only(directory, lambda rel: rel in VARIANT_FILES or (rel.startswith("meshes/")
                                                                           and rel.count("/") == 1))


VARIANT_FOLDER = MadeFolder("a variant rik built", is_variant, "choose another --out")
"""A variant's folder: rebuilt, it is replaced, and only if it is a variant (:func:`is_variant`)."""
COMBINATOR_DIR = Path(__file__).parent
JOINTS_DIR = COMBINATOR_DIR.parent / "joints"
"""rik.joints: the joint model's MJCF mapping and laws, part of what decides a variant's files."""


class VariantRejected(RikError):
    """A variant failed a check; the message names the check and why."""

    def __init__(self, variant: str, check: CheckResult):
        self.variant, self.check = variant, check
        super().__init__(f"variant {variant} rejected by check {check.name}: {check.reason}")


@dataclass(frozen=True)
class VariantResult:
    """What building one variant did (small and picklable: it comes back from worker processes)."""

    id: str
    status: str
    """``built``, ``skipped`` (already valid on disk) or ``rejected``."""
    spec_hash: str
    seconds: float
    failed_check: str | None = None
    reason: str = ""
    hulls: int = 0
    collision_vertices: int = 0
    compile_seconds: float | None = None


@dataclass
class CheckedVariant:
    """A variant assembled and checked in memory."""

    variant: VariantModel
    checks: list[CheckResult]
    model: Any = None
    compile_seconds: float | None = None
    metrics: dict[str, Any] | None = None

    @property
    def failed(self) -> CheckResult | None:
        return next((c for c in self.checks if not c.passed), None)


# ---- identity ---------------------------------------------------------------------------------------------------
@functools.cache
def _versions() -> dict[str, str]:
    """Library versions that shape a variant (read once: importlib.metadata is slow)."""
    from importlib.metadata import version

    from rik.assets.cache import library_versions

    return {**library_versions(), "mujoco": version("mujoco")}


@functools.cache
def _code_digest() -> str:
    from rik.assets.cache import source_digest

    return source_digest(sorted(COMBINATOR_DIR.glob("*.py")) + sorted(JOINTS_DIR.glob("*.py")))


def spec_identity(catalog: Catalog, key: VariantKey, collision: str = "coacd",
                  joint_friction: str = "held") -> dict[str, object]:
    """Everything that decides a variant's files: the catalog entries, the asset keys, the collision and
    joint-friction modes, the combinator's code and the library versions."""
    from rik.assets.build import asset_key

    unit, handle = catalog.base_unit(key.base), catalog.handle(key.handle)
    finishes = sorted({unit.carcass.finish, handle.finish, *(f.finish for f in unit.fronts)})
    return {"report_format": REPORT_FORMAT, "variant": key.id,
            "base_unit": unit.model_dump(mode="json"), "handle": handle.model_dump(mode="json"),
            "design": catalog.designs[handle.design].model_dump(mode="json"),
            "preset": catalog.preset(key.preset).model_dump(mode="json"),
            "finishes": [catalog.finishes[f].model_dump(mode="json") for f in finishes],
            "assets": [asset_key(catalog, key.handle), asset_key(catalog, key.base)], "collision": collision,
            "joint_friction": joint_friction,
            "code": _code_digest(), "versions": _versions()}


def spec_hash(catalog: Catalog, key: VariantKey, collision: str = "coacd", joint_friction: str = "held") -> str:
    from rik.assets.cache import content_key

    return content_key(spec_identity(catalog, key, collision, joint_friction))


def folder_spec_hash(catalog: Catalog, key: VariantKey, out: Path) -> str:
    """The spec hash a variant built into the folder ``out`` has (in the folder's modes)."""
    return spec_hash(catalog, key, resolve_collision(out), JOINT_FRICTION.resolve(out))


# ---- modes of a folder ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FolderMode:
    """A build mode every variant of a folder shares, named by a marker file ``<out>/<marker>``
    (``{"<field>": "<mode>"}``), so that anything building into the folder later builds in its mode."""

    marker: str
    field: str
    modes: tuple[str, ...]
    default: str
    option: str
    """The command-line option that chooses it (for messages)."""
    always_mark: bool = False
    """Write the marker for the default mode too (collision: every folder built since modes exist has one)."""

    def check(self, mode: str, what: str | None = None) -> str:
        """``mode`` when it is one of :attr:`modes`, else a :class:`RikError` naming the valid ones."""
        if mode not in self.modes:
            raise RikError(f"{what or self.option} {mode!r}: not a {self.field.replace('_', '-')} mode; valid modes "
                           f"are {', '.join(self.modes)}")
        return mode

    def of_folder(self, out: Path) -> str | None:
        """The mode the folder's marker names; without it the default when the folder holds variants (written
        before the mode existed), None when it holds none."""
        marker = out / self.marker
        if not marker.exists():
            return self.default if next(out.glob("*/report.json"), None) is not None else None
        try:
            mode = json.loads(marker.read_text(encoding="utf-8"))[self.field]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise RikError(f"{marker}: unreadable {self.field.replace('_', ' ')} marker ({type(exc).__name__}); it "
                           f"must hold " + " or ".join(f'{{"{self.field}": "{m}"}}' for m in self.modes)) from None
        return self.check(mode, f"{marker}: field {self.field}")

    def resolve(self, out: Path, mode: str | None = None) -> str:
        """The mode to build into ``out`` with: ``mode`` when given (it must match the folder's marker, if any),
        else the folder's (the default for a folder without a marker)."""
        marked = self.of_folder(out)
        if mode is None:
            return marked or self.default
        self.check(mode)
        if marked is not None and marked != mode:
            raise RikError(f"{out}: this folder holds {marked} {self.field.replace('_', ' ')} variants, not {mode} "
                           f"(its {self.marker}); build {self.option} {mode} variants into another --out folder")
        return mode

    def mark(self, out: Path, mode: str) -> None:
        """Write the marker naming the folder's mode where the folder does not say it yet (a mode that is not
        always marked needs no marker for its default)."""
        said = self.of_folder(out) if self.always_mark or (out / self.marker).exists() else self.default
        if said != mode:
            out.mkdir(parents=True, exist_ok=True)
            ours = Replaces.when(f"rik's {self.marker} (an object with {self.field!r})",
                                 lambda p: self.field in (json_object(p) or {}))
            write_text(out / self.marker, json.dumps({self.field: mode}) + "\n", ours)


def _collision_mode() -> FolderMode:
    from rik.combinator.mjcf import COLLISION_MODES, DEFAULT_COLLISION

    return FolderMode("collision.json", "collision", COLLISION_MODES, DEFAULT_COLLISION, "--collision",
                      always_mark=True)


def _joint_friction_mode() -> FolderMode:
    from rik.joints.mjcf import DEFAULT_JOINT_FRICTION, JOINT_FRICTION_MODES

    return FolderMode("joint_friction.json", "joint_friction", tuple(JOINT_FRICTION_MODES), DEFAULT_JOINT_FRICTION,
                      "--joint-friction")


COLLISION = _collision_mode()
"""``<out>/collision.json``: the handles' collision mode of every variant in ``<out>``."""
JOINT_FRICTION = _joint_friction_mode()
"""``<out>/joint_friction.json``: how the fronts' joint friction holds in every variant of ``<out>``."""
COLLISION_MARKER = COLLISION.marker


def check_collision(mode: str, what: str = "--collision") -> str:
    """``mode`` when it is a collision mode, else a :class:`RikError` naming the valid ones."""
    return COLLISION.check(mode, what)


def folder_collision(out: Path) -> str | None:
    """The collision mode recorded in ``<out>/collision.json`` (:meth:`FolderMode.of_folder`)."""
    return COLLISION.of_folder(out)


def resolve_collision(out: Path, collision: str | None = None) -> str:
    """The collision mode to build into ``out`` with (:meth:`FolderMode.resolve`)."""
    return COLLISION.resolve(out, collision)


def mark_collision(out: Path, collision: str) -> None:
    """Write ``<out>/collision.json`` naming the folder's mode (only when absent or different)."""
    COLLISION.mark(out, collision)


# ---- assemble and check -----------------------------------------------------------------------------------------
_ASSETS: dict[tuple[str, str], Asset] = {}
"""Assets loaded in this process, by (cache root, id): a handle is used by every base unit."""


def _asset(catalog: Catalog, asset_id: str, cache: AssetCache) -> Asset:
    from rik.assets.build import asset_key, build_asset

    memo = (str(cache.root), asset_key(catalog, asset_id))
    if memo not in _ASSETS:
        if len(_ASSETS) > 16:  # builds run handle by handle, so a few suffice
            _ASSETS.pop(next(iter(_ASSETS)))
        _ASSETS[memo] = build_asset(catalog, asset_id, cache=cache)[0]
    return _ASSETS[memo]


def assemble_variant(catalog: Catalog, key: VariantKey, cache: AssetCache | None = None,
                     stop_at_failure: bool = True, collision: str = "coacd",
                     joint_friction: str = "held") -> CheckedVariant:
    """Assemble a variant's spec in memory (handles colliding as ``collision`` says, joint friction holding as
    ``joint_friction`` says) and run the checks of its geometry (nothing compiled yet)."""
    from rik.assets.cache import AssetCache
    from rik.combinator.mjcf import variant_spec

    cache = cache or AssetCache()
    variant = variant_spec(catalog, key, _asset(catalog, key.handle, cache), _asset(catalog, key.base, cache),
                           collision, joint_friction)
    checks: list[CheckResult] = []
    for check in GEOMETRY_CHECKS:
        checks.append(check(catalog, variant))
        if stop_at_failure and not checks[-1].passed:
            break
    return CheckedVariant(variant, checks)


def check_variant(catalog: Catalog, key: VariantKey, cache: AssetCache | None = None,
                  stop_at_failure: bool = True, collision: str = "coacd",
                  joint_friction: str = "held") -> CheckedVariant:
    """Assemble a variant in memory and run its checks (geometry first, then the compiled model's)."""
    import mujoco

    assembled = assemble_variant(catalog, key, cache, stop_at_failure, collision, joint_friction)
    variant, checks = assembled.variant, assembled.checks
    if assembled.failed is not None and stop_at_failure:
        return assembled
    for name, data in variant.mesh_files.items():
        variant.spec.assets[name] = data
    t0 = time.perf_counter()
    try:
        model = variant.spec.compile()
    except ValueError as exc:
        checks.append(CheckResult("compiles", False, f"MuJoCo could not compile the model: {exc}"))
        return CheckedVariant(variant, checks)
    compile_seconds = time.perf_counter() - t0
    checks.append(CheckResult("compiles", True, f"MuJoCo compiled it in {compile_seconds * 1000:.0f} ms"))
    ctx = ModelContext(variant, variant.unit, model, mujoco.MjData(model))
    checks += run_model_checks(ctx, stop_at_failure)
    return CheckedVariant(variant, checks, model, compile_seconds, ctx.metrics)


# ---- writing ----------------------------------------------------------------------------------------------------
def _sha256(data: bytes) -> str:
    import hashlib

    return hashlib.sha256(data).hexdigest()


def _intact(path: Path, data: bytes) -> bool:
    """True when the file at ``path`` holds exactly ``data``."""
    try:
        return path.stat().st_size == len(data) and path.read_bytes() == data
    except OSError:
        return False


def _store_mesh(out: Path, data: bytes) -> Path:
    """The content-addressed copy of a mesh file under ``<out>/.meshes``, written when absent or when its
    content no longer matches its name (a variant's hard link to it was written to). The rewrite replaces the
    file with a new inode: variants still linked to the damaged one fail :func:`is_current` and are rebuilt."""
    store = out / MESH_STORE / f"{_sha256(data)}.stl"
    if not _intact(store, data):
        write_bytes(store, data, PRIVATE)
    return store


def materialise(checked: CheckedVariant, directory: Path, report: dict[str, Any], out: Path | None = None) -> None:
    """Write ``model.xml``, ``scene.xml``, ``meshes/`` and ``report.json`` into ``directory`` (replaced
    whole, through a staging directory beside it under ``out``)."""
    variant = checked.variant
    out = out or directory.parent
    stage = make_stage(out / STAGING / directory.name)  # a name of its own: builders side by side never share it
    try:
        (stage / "meshes").mkdir()
        files: dict[str, str] = {}
        for name, data in sorted(variant.mesh_files.items()):
            link_or_copy(_store_mesh(out, data), stage / "meshes" / name)
            files[f"meshes/{name}"] = _sha256(data)
        model_xml = variant.spec.to_xml()
        scene = scene_xml(variant.key.id, variant.unit)
        for name, text in (("model.xml", model_xml), ("scene.xml", scene)):
            write_text(stage / name, text, NEW)
            files[name] = _sha256(text.encode())
        write_text(stage / "report.json", json.dumps({**report, "files": files}, indent=2) + "\n", NEW)
        replace_directory(stage, directory, VARIANT_FOLDER)
    except BaseException:
        remove_stage(stage)
        raise
    finally:
        remove_empty_folder(out / STAGING)  # when no other builder stages a variant in it


def make_report(catalog: Catalog, checked: CheckedVariant, digest: str, build_seconds: float) -> dict[str, Any]:
    """The ``report.json`` of a checked variant (without its file list)."""
    from rik import __version__

    variant = checked.variant
    model = checked.model
    pull = (checked.metrics or {}).get("pull", {})
    fronts = [{"id": f.id, "kind": f.kind, "motion": f.motion, "joint_range": list(f.joint_range),
               "placement": {"rule": f.placement.rule, "u_m": round(f.placement.u, 6), "v_m": round(f.placement.v, 6),
                             "rotation_deg": f.placement.rotation, "edge": f.placement.edge,
                             "pos_m": [round(c, 6) for c in f.placement.pos]},
               **({"runtime_effects": list(f.runtime_effects)} if f.runtime_effects else {}),
               **pull.get(f.id, {})} for f in variant.fronts]
    failed = checked.failed
    return {
        **variant.info(), "status": "valid" if failed is None else "rejected", "spec_hash": digest,
        "rik_version": __version__, "mujoco_version": _versions()["mujoco"],
        "checks": [c.as_dict() for c in checked.checks],
        "fronts": fronts,
        "hulls": variant.hulls, "collision_vertices": _collision_vertices(variant),
        "bodies": int(model.nbody) if model is not None else None,
        "geoms": int(model.ngeom) if model is not None else None,
        "compile_seconds": round(checked.compile_seconds, 5) if checked.compile_seconds else None,
        "step_seconds": round((checked.metrics or {}).get("step_seconds", 0.0), 8) or None,
        "build_seconds": round(build_seconds, 4),
    }


def _collision_vertices(variant: VariantModel) -> int:
    """Vertices of every collision mesh geom plus 8 per box."""
    total = 0
    for g in variant.spec.geoms:
        if g.classname.name == "collision":
            total += variant.mesh_vertices[g.meshname] if g.meshname else 8
    return total


# ---- one variant ------------------------------------------------------------------------------------------------
def is_current(directory: Path, digest: str) -> bool:
    """True when ``directory`` holds a valid variant built from this spec hash, with every file intact."""
    try:
        report = json.loads((directory / "report.json").read_text(encoding="utf-8"))
        if report.get("spec_hash") != digest or report.get("status") != "valid":
            return False
        return all(_sha256(inside(directory, *name.split("/"), what="file").read_bytes()) == sha
                   for name, sha in report["files"].items())
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RikError):  # a name leading elsewhere too
        return False


def build_variant(catalog: Catalog, key: VariantKey, out: Path = DEFAULT_OUT, cache: AssetCache | None = None,
                  force: bool = False, collision: str | None = None,
                  joint_friction: str | None = None) -> VariantResult:
    """Build one variant into ``out/<id>`` unless it is already there and current; a variant that fails a check
    is not written (the result says which check and why). ``collision`` and ``joint_friction``: the folder's
    modes by default (:data:`COLLISION`, :data:`JOINT_FRICTION`)."""
    t0 = time.perf_counter()
    collision = resolve_collision(out, collision)
    joint_friction = JOINT_FRICTION.resolve(out, joint_friction)
    digest = spec_hash(catalog, key, collision, joint_friction)
    directory = out / key.id
    if not force and is_current(directory, digest):
        return VariantResult(key.id, "skipped", digest, time.perf_counter() - t0)
    from rik.locks import exclusive

    # two processes that need the same variant (evaluations side by side) build it once: the second waits, then
    # finds it current; without the lock it would replace the folder under the first one's compiling model
    with exclusive(directory, "rik variants build", wait=True):
        if not force and is_current(directory, digest):
            return VariantResult(key.id, "skipped", digest, time.perf_counter() - t0)
        check_replaceable(directory, VARIANT_FOLDER)  # before any work: a folder there that is no variant stays
        mark_collision(out, collision)
        JOINT_FRICTION.mark(out, joint_friction)
        checked = check_variant(catalog, key, cache, collision=collision, joint_friction=joint_friction)
        failed = checked.failed
        if failed is not None:
            return VariantResult(key.id, "rejected", digest, time.perf_counter() - t0, failed.name, failed.reason)
        report = make_report(catalog, checked, digest, time.perf_counter() - t0)
        materialise(checked, directory, report, out)
    return VariantResult(key.id, "built", digest, time.perf_counter() - t0, hulls=report["hulls"],
                         collision_vertices=report["collision_vertices"], compile_seconds=checked.compile_seconds)


# ---- many variants ----------------------------------------------------------------------------------------------
def _build_one(catalog: Catalog, variant: str, out: Path, cache_root: Path, force: bool,
               collision: str, joint_friction: str) -> VariantResult:
    from rik.assets.cache import AssetCache
    from rik.registry.ids import parse_variant_id

    return build_variant(catalog, parse_variant_id(catalog, variant), out, AssetCache(cache_root), force, collision,
                         joint_friction)


def check_manifest(out: Path) -> None:
    """Refuse an ``--out`` whose ``manifest.json`` is not one rik wrote (an object with ``variants``): a build
    would write over it."""
    file = out / MANIFEST
    if os.path.lexists(file) and not isinstance((json_object(file) or {}).get("variants"), dict):
        raise RikError(f"{file}: exists and is not the manifest of rik variants build (an object with 'variants'), "
                       "so nothing was written: choose another --out, or move it away yourself")


def read_manifest(out: Path) -> dict[str, Any]:
    """``<out>/manifest.json`` (empty when absent or unreadable)."""
    try:
        data = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
        return data if isinstance(data.get("variants"), dict) else {"variants": {}}
    except (OSError, ValueError, AttributeError):
        return {"variants": {}}


def write_manifest(out: Path, results: Sequence[VariantResult]) -> Path:
    """Merge ``results`` into ``<out>/manifest.json`` (atomically)."""
    manifest = read_manifest(out)
    variants = manifest["variants"]
    for r in results:
        variants[r.id] = {"status": "valid" if r.status in ("built", "skipped") else "rejected",
                          "spec_hash": r.spec_hash, "failed_check": r.failed_check, "reason": r.reason}
    manifest = {"format": REPORT_FORMAT, "variants": dict(sorted(variants.items()))}
    out.mkdir(parents=True, exist_ok=True)
    ours = Replaces.when("the manifest of rik variants build (an object with 'variants')",
                         lambda p: isinstance((json_object(p) or {}).get("variants"), dict))
    write_text(out / MANIFEST, json.dumps(manifest, indent=1) + "\n", ours)
    return out / MANIFEST


def rejected_variants(catalog: Catalog, variant_ids: Iterable[str], out: Path = DEFAULT_OUT, *, workers: int = 1,
                      overlays: Sequence[Path] = ()) -> dict[str, VariantResult]:
    """Build the variants ``variant_ids`` name into ``out`` where missing or stale (in the folder's collision mode);
    the ones that fail a check, by id in id order. Callers decide whether a rejection stops them."""
    from rik.registry.ids import parse_variant_id

    keys = [parse_variant_id(catalog, v) for v in sorted(set(variant_ids))]
    return {r.id: r for r in build_variants(catalog, keys, out, workers=workers, overlays=overlays)
            if r.status == "rejected"}


def require_variants(catalog: Catalog, variant_ids: Iterable[str], out: Path = DEFAULT_OUT, *, workers: int = 1,
                     overlays: Sequence[Path] = ()) -> None:
    """:func:`rejected_variants`, where any rejection is an error naming the first variant and its check."""
    for r in rejected_variants(catalog, variant_ids, out, workers=workers, overlays=overlays).values():
        raise RikError(f"variant {r.id} rejected by check {r.failed_check}: {r.reason}")


def build_variants(catalog: Catalog, keys: Sequence[VariantKey], out: Path = DEFAULT_OUT, *, workers: int = 1,
                   overlays: Sequence[Path] = (), cache: AssetCache | None = None, force: bool = False,
                   on_result: Callable[[VariantResult], None] | None = None,
                   on_assets: Callable[[int], None] | None = None,
                   collision: str | None = None, joint_friction: str | None = None) -> list[VariantResult]:
    """Build many variants (in ``workers`` processes), then record them in the manifest. Their assets are
    built first (once each, also in parallel). ``on_result`` is called as each variant finishes. ``collision`` and
    ``joint_friction``: the folder's modes by default (:data:`COLLISION`, :data:`JOINT_FRICTION`)."""
    from rik.assets.build import build_assets
    from rik.assets.cache import AssetCache
    from rik.workers import map_ids

    collision = resolve_collision(out, collision)
    joint_friction = JOINT_FRICTION.resolve(out, joint_friction)
    check_manifest(out)
    cache = cache or AssetCache()
    needed = list(dict.fromkeys([k.handle for k in keys] + [k.base for k in keys]))
    assets = build_assets(catalog, needed, overlays=overlays, workers=workers, cache=cache)
    if on_assets:
        on_assets(sum(r.status != "cached" for r in assets))
    mark_collision(out, collision)
    JOINT_FRICTION.mark(out, joint_friction)
    fn = functools.partial(_build_one, out=out.resolve(), cache_root=cache.root, force=force, collision=collision,
                           joint_friction=joint_friction)
    done: dict[str, VariantResult] = {}
    pending: list[VariantResult] = []
    order = sorted(keys, key=lambda k: (k.handle, k.base, k.preset))  # handle by handle: each loads once
    try:
        for _, result in map_ids(fn, catalog, [k.id for k in order], workers=workers, overlays=overlays):
            done[result.id] = result
            pending.append(result)
            if on_result:
                on_result(result)
            if len(pending) >= 100:
                write_manifest(out, pending)
                pending = []
    finally:
        if pending:
            write_manifest(out, pending)
    return [done[k.id] for k in keys]


def ensure_variant(catalog: Catalog, variant: str, variants: Path) -> Path:
    """The folder of the built variant ``variant`` (an id) in ``variants``, building it (with its checks, in the
    folder's collision mode: :func:`resolve_collision`) first when it is missing or stale; a rejected variant is a
    :class:`RikError` naming its check."""
    from rik.registry.ids import parse_variant_id

    key = parse_variant_id(catalog, variant)
    check_folder(variants, "--variants")
    directory = inside(variants, key.id, what="variant id")
    result = build_variant(catalog, key, variants)
    if result.status == "rejected":
        raise RikError(f"variant {key.id} cannot be simulated: check {result.failed_check} failed: {result.reason}")
    return directory
