"""A spec expanded against the catalog: the variants it selects, its episodes, renders and shards, each a unit of
work with a deterministic key (the spec entry, the seed, the variant's content hash, code and library versions)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.dataset.spec import SPEC_FIELDS, library_versions, policy_io
from rik.dataset.spec import spec_hash as hash_of_spec
from rik.errors import RikError
from rik.paths import json_sha256
from rik.schemas.dataset import DatasetSpec, OperatorSpec

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.render.streams import StreamSpec

SAMPLE_STREAM = 0xDA7A_5E7
"""Second word of the seed sequence that draws ``variants.sample`` (apart from the episodes' own seeds)."""
LABELS = {"action_frame": "action frame '{}'", "handle_shape": "handle shape '{}'", "streams": "streams",
          "cameras": "cameras", "image_size": "resolution {}"}
"""How a problem of the spec's contract starts, after the field's name."""
MAX_EPISODES = 1_000_000
"""Most episodes one spec may make. A plan is held in memory (about 0.7 kB per episode with two streams, measured:
70 MB for 100,000 episodes) and a build keeps a record per unit beside it; a spec that selects more (counted on
the selected variants, before any is built or checked) is refused with one line: split it into several specs."""


@dataclass(frozen=True)
class EpisodeUnit:
    """One episode to record: an operator on a variant's front with a seed; ``key`` decides its output."""

    index: int
    variant: str
    front: str
    operator: OperatorSpec
    seed: int
    key: str
    robot: str = "hand-e"
    """The catalog robot that opens the front."""

    @property
    def episode_id(self) -> str:
        from rik.episodes.episode import episode_id

        return episode_id(self.variant, self.front, self.operator.label, self.seed, self.robot)


@dataclass(frozen=True)
class RenderUnit:
    """One image stream of one episode."""

    episode: EpisodeUnit
    stream: str
    key: str


@dataclass(frozen=True)
class ShardUnit:
    """A group of episodes written as one LeRobot dataset, merged with the others at the end."""

    index: int
    episodes: tuple[EpisodeUnit, ...]
    key: str


@dataclass
class Plan:
    """What a spec makes, in order."""

    spec: DatasetSpec
    spec_hash: str
    source: str
    """The spec's file, as messages name it."""
    variants: dict[str, str]
    """Variant id -> its content hash (the combinator's spec hash, with the collision and joint-friction modes)."""
    rejected: dict[str, str]
    """Selected pairings whose variant fails a check -> the reason; left out."""
    collision: str
    joint_friction: str
    episodes: list[EpisodeUnit] = field(default_factory=list)
    renders: list[RenderUnit] = field(default_factory=list)
    shards: list[ShardUnit] = field(default_factory=list)

    @property
    def streams(self) -> tuple[str, ...]:
        return self.spec.streams

    def stream_spec(self, stream: str) -> StreamSpec:
        from rik.render.streams import StreamSpec

        w, h = self.spec.size
        r = self.spec.render
        return StreamSpec(stream, w, h, spp=r.spp, denoise=r.denoise, variant=r.variant)  # type: ignore[arg-type]

    def episode_renders(self, episode: EpisodeUnit) -> list[RenderUnit]:
        """The render units of ``episode``, one per stream in the spec's order: the plan lays them out episode by
        episode, so they are a slice (O(streams), no search)."""
        n = len(self.spec.streams)
        return self.renders[episode.index * n:(episode.index + 1) * n]

    def summary(self) -> dict[str, Any]:
        """Counts, as ``rik dataset plan`` prints them and meta/rik_dataset.json keeps them."""
        return {"variants": len(self.variants), "rejected_variants": len(self.rejected),
                "operators": [o.label for o in self.spec.operators], "episodes": len(self.episodes),
                "renders": len(self.renders), "shards": len(self.shards)}


def _field_error(source: str, field_name: str, exc: RikError) -> RikError:
    return RikError(f"{source}, field '{field_name}': {exc}")


def select_variants(catalog: Catalog, spec: DatasetSpec, source: str) -> list[str]:
    """The variant ids the spec's ``variants`` selects, in catalog order (before any checks run)."""
    from rik.registry import ids as variant_ids

    sel = spec.variants
    if sel.ids:
        chosen = []
        for i, text in enumerate(sel.ids):
            try:
                chosen.append(variant_ids.parse_variant_id(catalog, text).id)
            except RikError as exc:
                raise _field_error(source, f"variants.ids.{i}", exc) from None
    else:
        split = None if sel.split == "all" else sel.split
        if split is not None:
            from rik.registry.splits import SPLITS

            if split not in SPLITS:
                import difflib

                close = difflib.get_close_matches(split, [*SPLITS, "all"], n=1, cutoff=0.6)
                hint = f"; did you mean '{close[0]}'?" if close else ""
                raise RikError(f"{source}, field 'variants.split': unknown split '{split}' (splits: "
                               f"{', '.join(SPLITS)}, or all for every handle){hint}")
        kinds = sorted({f.kind for u in catalog.base_units.values() for f in u.fronts})
        checks: list[tuple[str, Sequence[str], Any]] = [
            ("base_units", sel.base_units, catalog.base_unit), ("handles", sel.handles, catalog.handle),
            ("presets", sel.presets, catalog.preset)]
        for name, values, lookup in checks:
            for i, value in enumerate(values):
                try:
                    lookup(value)
                except RikError as exc:
                    raise _field_error(source, f"variants.{name}.{i}", exc) from None
        for i, kind in enumerate(sel.kinds):
            if kind not in kinds:
                raise RikError(f"{source}, field 'variants.kinds.{i}': unknown front kind '{kind}' (kinds: "
                               f"{', '.join(kinds)})")
        try:
            keys = variant_ids.select_variants(catalog, bases=sel.base_units, handle_types=sel.handle_types,
                                               handles=sel.handles, presets=sel.presets, split=split)
        except RikError as exc:
            raise _field_error(source, "variants.split", exc) from None
        chosen = [k.id for k in keys if catalog.base_units[k.base].fronts[0].kind in sel.kinds]
    chosen = list(dict.fromkeys(chosen))
    if sel.sample is not None and sel.sample < len(chosen):
        import numpy as np

        rng = np.random.default_rng([spec.seed, SAMPLE_STREAM])
        keep = sorted(rng.choice(len(chosen), size=sel.sample, replace=False).tolist())
        chosen = [chosen[i] for i in keep]
    if not chosen:
        raise RikError(f"{source}, field 'variants': the selection keeps no variant; widen its filters "
                       "(rik catalog list shows what the catalog holds)")
    return chosen


def check_operators(spec: DatasetSpec, source: str) -> None:
    """Every operator names a known strategy (with valid parameters)."""
    from rik.episodes.operators import make_operator

    for i, op in enumerate(spec.operators):
        try:
            make_operator(op.strategy, op.params)
        except RikError as exc:
            raise _field_error(source, f"operators.{i}.strategy", exc) from None


def check_contract(catalog: Catalog, spec: DatasetSpec, source: str) -> None:
    """The spec's contract with its policies (:func:`rik.dataset.spec.policy_io`) is valid: its robot is in the
    catalog, its action frame and handle shape are known, and the robot's action has that frame (only the Hand-E's
    pose action has a handle or a gripper frame); one line naming the spec's field."""
    from rik.lerobot.policy_io import ContractError

    try:
        catalog.robot(spec.robot)
    except RikError as exc:
        raise _field_error(source, "robot", exc) from None
    try:
        policy_io(spec).validate(catalog, LABELS)
    except ContractError as exc:
        raise _field_error(source, SPEC_FIELDS.get(exc.field, exc.field), exc) from None


def check_codec(spec: DatasetSpec, source: str) -> None:
    """The spec's image size is one its codec encodes (libsvtav1 crashes on frames under 25 px wide), checked
    before any work instead of when the first shard is encoded."""
    from rik.exporters.spec import least_width

    width, height = spec.size
    least = least_width(spec.codec, width, bool(spec.streams))
    if least is not None:
        raise RikError(f"{source}, field 'resolution': codec {spec.codec} encodes frames at least {least} pixels wide "
                       f"(narrower ones crash its encoder), got {width}x{height}; give a width of {least} or more, or "
                       "codec: h264")


def check_cameras(spec: DatasetSpec, source: str) -> None:
    """The spec's cameras exist in rik's scenes."""
    from rik.lerobot.features import CAMERAS

    for i, cam in enumerate(spec.cameras):
        if cam not in CAMERAS:
            raise RikError(f"{source}, field 'cameras.{i}': no camera '{cam}' in rik's scenes (cameras: "
                           f"{', '.join(CAMERAS)})")


def check_size(spec: DatasetSpec, variants: int, source: str) -> None:
    """A spec that would make more than :data:`MAX_EPISODES` episodes from ``variants`` selected variants is refused
    before anything is built (its plan would not fit in memory)."""
    total = variants * len(spec.operators) * spec.episodes_per_variant
    if total > MAX_EPISODES:
        raise RikError(f"{source}, field 'episodes_per_variant': {variants:,} selected variants x "
                       f"{len(spec.operators):,} operators x {spec.episodes_per_variant:,} episodes = {total:,} "
                       f"episodes, more than the {MAX_EPISODES:,} one spec may make (its plan is held in memory); "
                       "split it into several specs (by variants, operators or seed)")


def make_plan(catalog: Catalog, spec: DatasetSpec, *, source: str = "spec", variants_dir: Path = Path("variants"),
              workers: int = 1, overlays: Sequence[Path] = ()) -> Plan:
    """Expand ``spec``: select its variants, build the ones missing into ``variants_dir`` (their checks decide
    which can be simulated), and lay out its units. Bad input raises one line naming ``source`` and the field."""
    from rik.combinator.build import JOINT_FRICTION, rejected_variants, resolve_collision, spec_hash
    from rik.registry.ids import parse_variant_id

    check_cameras(spec, source)
    check_contract(catalog, spec, source)
    check_operators(spec, source)
    check_codec(spec, source)
    drawn = draw_episodes(catalog, spec, source)
    chosen = list(dict.fromkeys(v for v, _, _ in drawn)) if drawn else select_variants(catalog, spec, source)
    check_size(spec, len(drawn) if drawn else len(chosen), source)
    collision, joint_friction = resolve_collision(variants_dir), JOINT_FRICTION.resolve(variants_dir)
    rejected = {r.id: f"check {r.failed_check} failed: {r.reason}"
                for r in rejected_variants(catalog, chosen, variants_dir, workers=workers,
                                           overlays=overlays).values()}
    kept = [v for v in chosen if v not in rejected]
    if not kept:
        first = next(iter(rejected.items()))
        raise RikError(f"{source}, field 'variants': every selected variant fails its checks (the first, "
                       f"{first[0]}: {first[1]})")
    keys = {v: parse_variant_id(catalog, v) for v in kept}
    hashes = {v: spec_hash(catalog, k, collision, joint_friction) for v, k in keys.items()}
    plan = Plan(spec, hash_of_spec(spec), source, hashes, rejected, collision, joint_friction)
    if drawn:
        lay_out_units(plan, {}, [d for d in drawn if d[0] not in rejected])
    else:
        lay_out_units(plan, {v: catalog.base_units[k.base].fronts[0].id for v, k in keys.items()})
    return plan


def draw_episodes(catalog: Catalog, spec: DatasetSpec, source: str) -> list[tuple[str, str, int]]:
    """(variant, front, seed) of each episode of ``variants.draw`` (empty without it), drawn from its seed as the
    gym environment draws it."""
    sel = spec.variants
    if sel.draw is None:
        return []
    from rik.episodes.draw import DEFAULT_PRESETS, DEFAULT_TYPES, Draw

    draw = Draw(sel.split, tuple(sel.handle_types) or DEFAULT_TYPES, tuple(sel.presets) or DEFAULT_PRESETS,
                tuple(sel.kinds), sel.joints)
    try:
        draw.check(catalog)
    except RikError as exc:
        raise _field_error(source, "variants", exc) from None
    out = []
    for seed in range(spec.seed, spec.seed + sel.draw):
        episode = draw.episode(catalog, seed)
        out.append((episode.variant, episode.front, seed))
    return out


def lay_out_units(plan: Plan, fronts: dict[str, str], drawn: Sequence[tuple[str, str, int]] = ()) -> None:
    """Fill ``plan``'s episodes, renders and shards, with their keys, for its variants (``fronts``: variant id ->
    the front its episodes operate, in plan order; or ``drawn``: the (variant, front, seed) of each episode of
    ``variants.draw``). Linear in the episodes: each shard takes its renders by index
    (:meth:`Plan.episode_renders`), never by a search."""
    spec = plan.spec
    record_versions = library_versions("mujoco")
    if drawn:
        runs = [(v, front, op, seed) for v, front, seed in drawn for op in spec.operators]
    else:
        runs = [(v, front, op, spec.seed + k) for v, front in fronts.items() for op in spec.operators
                for k in range(spec.episodes_per_variant)]
    for v, front, op, seed in runs:
        key = json_sha256({"stage": "record", "variant": v, "variant_hash": plan.variants[v],
                           "front": front, "strategy": op.strategy, "params": op.params, "label": op.label,
                           "seed": seed, "max_seconds": spec.max_seconds, "gripper": spec.robot,
                           "versions": record_versions})  # the robot ("gripper" since the Hand-E's days)
        plan.episodes.append(EpisodeUnit(len(plan.episodes), v, front, op, seed, key, spec.robot))
    render_versions = library_versions("mujoco", "mitsuba")
    stream_keys = {s: plan.stream_spec(s).key for s in spec.streams}
    cameras = list(spec.cameras)
    for e in plan.episodes:
        for s in spec.streams:
            key = json_sha256({"stage": "render", "record": e.key, "stream": stream_keys[s],
                               "cameras": cameras, "versions": render_versions})
            plan.renders.append(RenderUnit(e, s, key))
    export_versions = library_versions("lerobot", "av")
    export = export_settings(spec)
    size = spec.shard_episodes
    for i in range(0, len(plan.episodes), size):
        chunk = tuple(plan.episodes[i:i + size])
        key = json_sha256({"stage": "shard", "episodes": [e.key for e in chunk],
                           "renders": [r.key for e in chunk for r in plan.episode_renders(e)],
                           "export": export, "versions": export_versions})
        plan.shards.append(ShardUnit(len(plan.shards), chunk, key))


def export_settings(spec: DatasetSpec) -> dict[str, Any]:
    """What decides the bytes of a shard besides its episodes and their frames."""
    w, h = spec.size
    return {"repo_id": spec.repo_id, "streams": list(spec.streams), "cameras": list(spec.cameras), "width": w,
            "height": h, "fps": spec.fps, "codec": spec.codec, "render": spec.render.model_dump(mode="json")}
