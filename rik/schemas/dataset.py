"""A dataset spec (``rik dataset plan/build SPEC``): which variants, operators and episodes, and how they are
rendered and exported. Only the schema lives here; expanding it against the catalog is :mod:`rik.dataset.plan`."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictBool, field_validator, model_validator

from rik.schemas.common import CatalogId, Frozen, SimpleId

SPEC_FORMAT = 1
STRATEGY_PARAMS = ("jitter", "regrasps", "action_noise")
"""Parameters of a scripted strategy a spec may set (:func:`rik.episodes.operators.make_operator`)."""


class VariantSelection(Frozen):
    """Which variants: explicit ``ids``, or every base unit x handle x preset pairing the filters keep (an empty
    filter keeps all). Pairings whose variant fails its checks are left out and listed by ``rik dataset plan``."""

    ids: tuple[str, ...] = ()
    """Explicit variant ids (e.g. ``drawer-chest-60__two_point-bow-128__normal``); not combined with filters."""
    split: str = "all"
    """Catalog split of the handles: train, val, test, or all (``rik catalog splits``)."""
    kinds: tuple[SimpleId, ...] = ("drawer",)
    """Front kinds of the base units (drawer, door)."""
    base_units: tuple[CatalogId, ...] = ()
    handle_types: tuple[Literal["knob", "finger_pull", "two_point"], ...] = ()
    handles: tuple[CatalogId, ...] = ()
    presets: tuple[SimpleId, ...] = ()
    sample: int | None = Field(default=None, ge=1)
    """Keep this many of the selected variants, drawn with the spec's seed (None: all)."""
    draw: int | None = Field(default=None, ge=1, le=1_000_000)
    """Instead of every selected variant: this many episodes, each drawn from its seed (the spec's seed, then +1
    each) as the gym environment, ``rik eval`` and ``rik record --split`` draw them: the seed's handle type x preset
    cell in turn, a variant and front of the split's handles (:mod:`rik.episodes.draw`), so ``draw: 360`` records
    exactly ``rik record --split train --episodes 360``'s episodes. Takes ``split``, ``handle_types``, ``presets``
    and ``kinds`` (and ``joints``); each drawn episode runs once per operator."""
    joints: Literal["paper", "measured"] = "paper"
    """With ``draw``: the hinges of doors, the cell's preset (``paper``) or a real door of the split
    (``measured``, :data:`rik.episodes.draw.JOINTS`); drawers and flaps keep the paper's presets."""

    @model_validator(mode="after")
    def _ids_alone(self) -> VariantSelection:
        if self.ids and (self.base_units or self.handle_types or self.handles or self.presets or self.split != "all"):
            raise ValueError("give either explicit 'ids' or filters (split, base_units, handle_types, handles, "
                             "presets), not both")
        if self.draw is not None and (self.ids or self.base_units or self.handles or self.sample is not None):
            raise ValueError("'draw' takes split, handle_types, presets and kinds; drop ids, base_units, handles "
                             "and sample")
        if self.joints != "paper" and self.draw is None:
            raise ValueError("'joints' chooses the hinges of drawn episodes; give 'draw' too, or drop it")
        return self


class OperatorSpec(Frozen):
    """One operator that makes episodes: a scripted strategy with its parameters (policies later)."""

    strategy: str
    """A scripted strategy (``rik record --help`` lists them)."""
    name: Annotated[str, Field(pattern=r"^[a-z0-9][a-z0-9_\-]*$", max_length=60)] | None = None
    """Label of the operator in episode ids and the dataset (default: the strategy's name); needed when two
    operators run one strategy with different parameters."""
    jitter: float | None = Field(default=None, ge=0, le=0.02, allow_inf_nan=False)
    """Standard deviation of the random offset of the grasp point, m (None: the strategy's own)."""
    regrasps: int | None = Field(default=None, ge=0, le=20)
    """Re-grasps a closed-loop strategy may try (None: the strategy's own)."""
    action_noise: float | None = Field(default=None, ge=0, le=0.05, allow_inf_nan=False)
    """Standard deviation of the noise on the executed target position, m (DART-style: the episode records the
    strategy's own action; None: no noise)."""

    @property
    def label(self) -> str:
        return self.name or self.strategy

    @property
    def params(self) -> dict[str, float | int]:
        """The parameters set, by name."""
        return {k: v for k in STRATEGY_PARAMS if (v := getattr(self, k)) is not None}


class RenderSettings(Frozen):
    """The re-render's quality (Mitsuba; the ``rerendered`` stream only)."""

    spp: int = Field(default=16, ge=1, le=4096)
    """Samples per pixel."""
    denoise: bool = True
    variant: str = "auto"
    """Mitsuba variant; ``auto`` picks the fastest that works on the machine (``cuda_ad_rgb`` with a GPU)."""


class DatasetSpec(Frozen):
    """A dataset as a reproducible spec. Every field has a default but ``repo_id`` and ``operators``."""

    format: int = Field(default=SPEC_FORMAT, ge=1, le=SPEC_FORMAT)
    repo_id: Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.\-]*/[A-Za-z0-9][A-Za-z0-9_.\-]*$")]
    """LeRobot repo id, OWNER/NAME (e.g. ``local/rik-drawers``)."""
    description: str = ""
    variants: VariantSelection = VariantSelection()
    operators: tuple[OperatorSpec, ...] = Field(min_length=1)
    robot: SimpleId = "hand-e"
    """The catalog robot that opens the fronts (``rik catalog list --kind robots``): ``hand-e`` (rik's floating
    gripper), or an arm such as ``so100``, ``so101`` or ``panda-2f85``; the dataset is exported in its layout."""
    episodes_per_variant: int = Field(default=1, ge=1, le=100_000)
    """Episodes of each operator on each variant."""
    seed: int = Field(default=0, ge=0, le=2**62)
    """Seed of the first episode of each variant and operator (then +1 each); also draws ``variants.sample``."""
    max_seconds: float = Field(default=30.0, gt=0, le=600, allow_inf_nan=False)
    """Longest episode, simulated s."""
    streams: tuple[Literal["sim", "rerendered"], ...] = ("sim",)
    """Image streams: ``sim`` (MuJoCo), ``rerendered`` (Mitsuba); empty: a state-only dataset."""
    cameras: tuple[str, ...] = ()
    """Cameras of the scene to export (empty: all)."""
    resolution: int | tuple[int, int] = 128
    """Image size, px: one number (square) or [width, height]."""
    render: RenderSettings = RenderSettings()
    fps: int | None = Field(default=None, ge=1, le=1000)
    """Dataset frame rate, Hz (None: the recording's, 20 Hz)."""
    codec: Literal["libsvtav1", "h264", "hevc"] = "libsvtav1"
    shard_episodes: int = Field(default=16, ge=1, le=10_000)
    """Episodes per shard: each shard is a LeRobot dataset of its own, merged at the end."""
    outcomes: tuple[Literal["F", "P", "S"], ...] = Field(default=("F", "P", "S"), min_length=1)
    """Outcomes of the episodes exported into the dataset: ``[S]`` keeps the successful demonstrations only (every
    episode is recorded, and counted in the build's outcomes, either way)."""
    action_frame: str = "world"
    """The Hand-E's exported ``action`` position: ``world``, ``handle`` (from the handle's grasp point) or
    ``gripper`` (from the gripper base); arms' joint actions: world. A field of the dataset's contract with its
    policies (``robot``, ``action_frame``, ``handle_shape``, ``cameras``, ``streams``, ``resolution``: one
    :class:`rik.lerobot.policy_io.PolicyIO`, :func:`rik.dataset.spec.policy_io`), which checks it when the spec is
    planned."""
    handle_shape: str = "none"
    """What of the handle's shape ends ``observation.environment_state``: ``none``, ``kind`` (its type and mount
    flags) or ``full`` (and the catalog's grasp dimensions); a field of the contract, as ``action_frame``."""
    environment_state: StrictBool = True
    """Whether the dataset holds ``observation.environment_state`` (the simulator's state of the front); false: the
    robot's own state and the images only, as a real robot has them (needs ``streams``); a field of the contract."""

    @field_validator("resolution")
    @classmethod
    def _size(cls, v: int | tuple[int, int]) -> int | tuple[int, int]:
        for n in (v,) if isinstance(v, int) else v:
            if not 16 <= n <= 4096:
                raise ValueError(f"image sides must lie in 16 .. 4096 px, got {n}")
        return v

    @model_validator(mode="after")
    def _labels_unique(self) -> DatasetSpec:
        from collections import Counter

        labels = [o.label for o in self.operators]
        counts = Counter(labels)  # not list.count per label: a spec may list thousands of operators
        for label in labels:
            if counts[label] > 1:
                raise ValueError(f"two operators are labelled '{label}'; give each a distinct 'name'")
        if not self.streams and self.cameras:
            raise ValueError("a state-only dataset (streams: []) has no cameras; drop 'cameras'")
        if self.variants.draw is not None and self.episodes_per_variant != 1:
            raise ValueError("with variants.draw each drawn episode runs once per operator; drop "
                             "'episodes_per_variant'")
        return self

    @property
    def size(self) -> tuple[int, int]:
        """(width, height), px."""
        return (self.resolution, self.resolution) if isinstance(self.resolution, int) else self.resolution


class RecordedSpec(BaseModel):
    """The spec as ``meta/rik_dataset.json`` records it: the fields rik reads back (the others are kept)."""

    model_config = ConfigDict(extra="allow")
    repo_id: str
    streams: list[str] = []


class RecordedCounts(BaseModel):
    """The counts a built dataset records (episodes, frames, variants; the others are kept)."""

    model_config = ConfigDict(extra="allow")
    episodes: int = Field(ge=0)
    frames: int = Field(ge=0)
    variants: int = Field(default=0, ge=0)


class DatasetRecord(BaseModel):
    """``meta/rik_dataset.json`` of a built dataset, as ``rik dataset show|list|verify`` and a rebuild read it: a
    file that breaks this is damaged (refused with one line naming the field)."""

    model_config = ConfigDict(extra="allow")
    spec_hash: str
    source: str | None = None
    spec: RecordedSpec
    counts: RecordedCounts
    outcomes: dict[str, int] = {}
    versions: dict[str, str] = {}
    files: dict[str, str]
    """sha256 of every file of the dataset but rik's two metadata files, by relative path."""


class BuildRecord(BaseModel):
    """``meta/rik_build.json``: the statistics of the build, as ``rik dataset show`` prints them."""

    model_config = ConfigDict(extra="allow")
    engine: str | None = None
    workers: int | None = None
    wall_seconds: float | None = None
    seconds: dict[str, float] = {}
