"""The validated catalog: every entry by id, where it came from, and queries over it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from rik.errors import UnknownIdError
from rik.schemas import BaseUnit, Finish, Handle, HandleDesign, HandleType, JointType, ResistancePreset
from rik.schemas.robots import Robot


@dataclass(frozen=True)
class Origin:
    """Where an entry was defined."""

    file: str
    """Path as shown in messages."""
    builtin: bool
    """True for rik's own data, False for a user overlay."""


@dataclass(frozen=True)
class Catalog:
    """Handles, designs, base units, presets and finishes, each keyed by id, in definition order
    (built-in files in path order, then overlays)."""

    designs: Mapping[str, HandleDesign]
    handles: Mapping[str, Handle]
    base_units: Mapping[str, BaseUnit]
    presets: Mapping[str, ResistancePreset]
    finishes: Mapping[str, Finish]
    origins: Mapping[tuple[str, str], Origin] = field(default_factory=dict)
    """(section, id) -> where the entry was defined."""
    splits: Mapping[str, str] = field(default_factory=dict)
    """Design id -> its split (train, val or test; :mod:`rik.registry.splits`)."""
    splits_version: int = 0
    """Version of the split assignment (:data:`rik.registry.splits.SPLITS_VERSION`)."""
    robots: Mapping[str, Robot] = field(default_factory=dict)
    """Robots that open the fronts (``hand-e``, the default, and arms)."""
    preset_splits: Mapping[str, str] = field(default_factory=dict)
    """Measured preset id -> its split (real doors held out whole; the paper's presets are in every split)."""

    # ---- lookups with suggestions -------------------------------------------------------------------------
    def handle(self, handle_id: str) -> Handle:
        """The handle with this id; :class:`UnknownIdError` suggests close ids."""
        return _get(self.handles, handle_id, "handle")

    def design(self, design_id: str) -> HandleDesign:
        return _get(self.designs, design_id, "design")

    def base_unit(self, base_id: str) -> BaseUnit:
        return _get(self.base_units, base_id, "base unit")

    def preset(self, preset_id: str) -> ResistancePreset:
        return _get(self.presets, preset_id, "preset")

    def finish(self, finish_id: str) -> Finish:
        return _get(self.finishes, finish_id, "finish")

    def robot(self, robot_id: str) -> Robot:
        """The robot with this id; :class:`UnknownIdError` suggests close ids."""
        return _get(self.robots, robot_id, "robot")

    # ---- derived facts --------------------------------------------------------------------------------------
    @property
    def default_presets(self) -> list[str]:
        """Ids of the presets variants are built with when none is named (``rik variants build --all``, datasets,
        :func:`rik.registry.ids.select_variants`), in catalog order: every preset but the measured ones
        (:attr:`rik.schemas.joints.ResistancePreset.in_default_set`), which are built when named."""
        return [p.id for p in self.presets.values() if p.in_default_set]

    def handle_type(self, handle: Handle) -> HandleType:
        """The type of a handle, from its design."""
        return self.designs[handle.design].type

    def handles_of(self, design_id: str) -> list[Handle]:
        return [h for h in self.handles.values() if h.design == design_id]

    def joint_types(self, base: BaseUnit) -> list[JointType]:
        """Distinct joint types of a base unit's fronts, in front order."""
        return list(dict.fromkeys(front.joint.type for front in base.fronts))


def _get[T](entries: Mapping[str, T], wanted: str, kind: str) -> T:
    try:
        return entries[wanted]
    except KeyError:
        raise UnknownIdError(kind, wanted, entries) from None
