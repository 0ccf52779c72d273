"""The hidden truth: :class:`GroundTruth` and its JSON form (``truth.json``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rik.errors import RikError
from rik.joints.kinds import SCHEMAS
from rik.paths import read_json
from rik.schemas.joints import JointEffect, JointType, Spring, Tilt
from rik.sysid.synthetic.draws import joint_type as _joint
from rik.sysid.synthetic.generate.constants import TRUTH_FILE

Effect = JointEffect | Spring


@dataclass(frozen=True)
class GroundTruth:
    """The hidden joint behind simulated trials; SI units of the joint (see the module docstring)."""

    joint: JointType
    mass: float
    """Total moving inertia: kg (slide) or kg·m² (hinge)."""
    damping: float
    """Viscous damping, N·s/m or N·m·s/rad."""
    frictionloss: float
    """Coulomb friction, N or N·m."""
    range: tuple[float, float]
    """(lower, upper) joint limits, m or rad; lower ≤ 0 < upper."""
    effect: Effect | None = None
    """The (first) effect beyond the baseline, in library form (the simulated shape differs slightly)."""
    second: Effect | None = None
    """A second effect acting together with ``effect``, e.g. the pull-in spring of a soft-close runner; of
    another kind than ``effect``, and only with one."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint", _joint(self.joint))
        for name, low in (("mass", None), ("damping", 0.0), ("frictionloss", 0.0)):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 if low is None else
                                                                                value >= low)
            if not ok:
                raise RikError(f"GroundTruth {name} must be a finite number {'> 0' if low is None else '≥ 0'}, "
                               f"got {value!r}")
            object.__setattr__(self, name, float(value))
        try:
            lower, upper = (float(x) for x in self.range)
        except (TypeError, ValueError):
            raise RikError(f"GroundTruth range must be (lower, upper), got {self.range!r}") from None
        if not (math.isfinite(lower) and math.isfinite(upper) and lower <= 0.0 < upper):
            raise RikError(f"GroundTruth range must be (lower, upper) with lower ≤ 0 < upper, got {self.range!r}")
        object.__setattr__(self, "range", (lower, upper))
        _check_effect("effect", self.effect, self.joint, upper)
        _check_effect("second", self.second, self.joint, upper)
        if self.second is not None:
            if self.effect is None:
                raise RikError(f"GroundTruth second ({_kind(self.second)}) needs a first effect: give it as effect "
                               "(second only acts together with effect)")
            if _kind(self.second) == _kind(self.effect):
                raise RikError(f"GroundTruth second is a {_kind(self.second)}, the same kind as effect; the two "
                               "effects must be of different kinds")

    @property
    def kind(self) -> str | None:
        """The (first) effect's kind (``spring`` for a :class:`Spring`), or None."""
        return _kind(self.effect)

    @property
    def effects(self) -> tuple[Effect, ...]:
        """The effects present, in order (``effect``, then ``second``)."""
        return tuple(e for e in (self.effect, self.second) if e is not None)

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds of the effects present, in order (empty for none)."""
        return tuple(_kind(e) or "" for e in self.effects)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict; each effect carries its ``kind`` (``spring`` for a Spring). ``second`` is written
        only when there is one (so a one-effect truth's file is as before)."""
        out = {"joint": self.joint.value, "mass": self.mass, "damping": self.damping,
               "frictionloss": self.frictionloss, "range": list(self.range), "effect": _effect_json(self.effect)}
        if self.second is not None:
            out["second"] = _effect_json(self.second)
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> GroundTruth:
        """The inverse of :meth:`to_json`; ``effect`` and ``second`` may be absent (None; files written before
        ``second`` existed load). A malformed dict is a :class:`RikError`."""
        if not isinstance(data, dict):
            raise RikError(f"ground truth must be a JSON object, got {type(data).__name__}")
        keys = {"joint", "mass", "damping", "frictionloss", "range", "effect", "second"}
        if missing := sorted(keys - {"effect", "second"} - set(data)):
            raise RikError(f"ground truth lacks {', '.join(missing)}")
        if extra := sorted(set(data) - keys):
            raise RikError(f"ground truth has unknown field(s) {', '.join(extra)}")
        return cls(joint=data["joint"], mass=data["mass"], damping=data["damping"],
                   frictionloss=data["frictionloss"], range=data["range"],
                   effect=_effect_from_json("effect", data.get("effect")),
                   second=_effect_from_json("second", data.get("second")))


_EFFECT_TYPES: tuple[type, ...] = (Spring, *SCHEMAS)


def _check_effect(name: str, effect: object, joint: JointType, upper: float) -> None:
    """Refuse an effect (field ``name`` of a :class:`GroundTruth`) that is not one or does not fit the joint."""
    if effect is None:
        return
    if not isinstance(effect, _EFFECT_TYPES):
        raise RikError(f"GroundTruth {name} must be a JointEffect, a Spring or None, got {type(effect).__name__}")
    if isinstance(effect, Tilt) and joint is JointType.slide and effect.sine != 0.0:
        raise RikError(f"GroundTruth {name}: a slide's tilt has no sine term (got sine={effect.sine}); "
                       "sine is for hinges")
    zone = getattr(effect, "zone", None)
    if zone is not None and zone >= upper:
        raise RikError(f"GroundTruth {name} zone {zone:g} must be inside the range (upper {upper:g})")


def _effect_json(effect: Effect | None) -> dict[str, Any] | None:
    if effect is None:
        return None
    out = effect.model_dump(mode="json")
    out.setdefault("kind", "spring")
    return out


def _effect_from_json(name: str, raw: object) -> Effect | None:
    from pydantic import TypeAdapter, ValidationError

    if raw is None:
        return None
    try:
        if isinstance(raw, dict) and raw.get("kind") == "spring":
            return Spring(**{k: v for k, v in raw.items() if k != "kind"})
        return TypeAdapter(JointEffect).validate_python(raw)
    except (ValidationError, TypeError) as exc:
        first = str(exc).splitlines()
        raise RikError(f"ground truth {name} is malformed: {' '.join(first[:3])}") from None


def _kind(effect: Effect | None) -> str | None:
    if effect is None:
        return None
    return "spring" if isinstance(effect, Spring) else effect.kind


def read_truth(path: str | Path) -> GroundTruth:
    """The :class:`GroundTruth` in ``path``: a ``truth.json`` file or a folder holding one."""
    path = Path(path)
    if path.is_dir():
        path = path / TRUTH_FILE
    try:
        data = read_json(path)
    except (OSError, ValueError) as exc:  # not JSON, not UTF-8, too large or nested too deeply
        raise RikError(f"{path}: cannot read the ground truth ({str(exc).splitlines()[0]})") from None
    try:
        return GroundTruth.from_json(data)
    except RikError as exc:
        raise RikError(f"{path}: {exc}") from None
