"""Frozen evaluation protocols: the episodes a headline figure is measured on (split, front kinds, joints, handle
types, presets, seeds, episodes per cell, episode length and the success rule), in a committed YAML file that
``rik eval --protocol FILE`` runs exactly.

A protocol is the test side of a pre-registered comparison (docs/policies.md): nothing that would change its
episodes may be given beside it (a draw option, a user catalog, a variants folder of another collision model or
joint friction, a policy for another robot), and each of those is refused in one line before anything runs. The
files rik ships live in ``protocols/`` at the repository's root.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, StrictStr, ValidationError

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.evaluation.evaluate import EvalSpec

PROTOCOL_FORMAT = 1
MAX_PROTOCOL_BYTES = 64 * 1024
"""A protocol file is a few hundred bytes; a larger one is refused before it is parsed."""
DRAW_OPTIONS = {"split": "--split", "kinds": "--kinds", "joints": "--joints", "types": "--types",
                "presets": "--presets", "per_cell": "--episodes-per-cell", "seed": "--seed",
                "episode_length": "--episode-length", "catalog": "--catalog"}
"""``rik eval``'s options that would change a protocol's episodes, by the command's parameter name."""


class Protocol(BaseModel):
    """One frozen set of evaluation episodes (see the module docstring). Units: control steps at 20 Hz."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    protocol: Literal[1]
    """The file format (:data:`PROTOCOL_FORMAT`)."""
    name: StrictStr = Field(min_length=1, max_length=80, pattern=r"^[a-z0-9][a-z0-9._-]*$")
    description: StrictStr = Field(default="", max_length=2000)
    split: Literal["train", "val", "test"]
    kinds: tuple[Literal["drawer", "door", "flap"], ...] = Field(min_length=1, max_length=3)
    joints: Literal["paper", "measured"] = "paper"
    handle_types: tuple[Literal["knob", "finger_pull", "two_point"], ...] = Field(min_length=1, max_length=3)
    presets: tuple[StrictStr, ...] = Field(min_length=1, max_length=32)
    episodes_per_cell: StrictInt = Field(ge=1, le=1000)
    seed: StrictInt = Field(ge=0, le=2**31 - 1)
    episode_length: StrictInt = Field(ge=1, le=100_000)
    success_opening: float = Field(ge=0.0, le=1.0, allow_inf_nan=False)
    """The success rule: S when the front ends at least this fraction of its range open (rik's own: 0.9)."""
    robot: StrictStr = "hand-e"
    collision: Literal["coacd"] = "coacd"
    joint_friction: Literal["held"] = "held"

    @property
    def episodes(self) -> int:
        return len(self.handle_types) * len(self.presets) * self.episodes_per_cell


def read_protocol(path: Path) -> Protocol:
    """The protocol in ``path``; a missing, oversized, malformed or invalid file is one :class:`RikError` naming
    the file and the field."""
    import yaml

    from rik.sim.outcome import SUCCESS_OPENING

    path = Path(path)
    if path.exists() and not path.is_file():  # a folder, a FIFO (which would block the read), a device
        raise RikError(f"{path}: not a file; a protocol is a YAML file (protocols/*.yaml)")
    try:
        with path.open("rb") as handle:
            raw = handle.read(MAX_PROTOCOL_BYTES + 1)
    except OSError as exc:
        raise RikError(f"{path}: cannot read the protocol ({exc.strerror or exc})") from None
    if len(raw) > MAX_PROTOCOL_BYTES:
        raise RikError(f"{path}: over {MAX_PROTOCOL_BYTES // 1024} KiB; a protocol is a few lines of YAML")
    try:
        data = yaml.safe_load(raw.decode("utf-8"))
    except (UnicodeDecodeError, yaml.YAMLError) as exc:
        where = getattr(exc, "problem_mark", None)
        at = f" (line {where.line + 1})" if where is not None else ""
        raise RikError(f"{path}: not a YAML protocol{at}: {str(exc).splitlines()[0]}") from None
    if not isinstance(data, dict):
        raise RikError(f"{path}: a protocol is a mapping of protocol, name, split, kinds, ...")
    try:
        protocol = Protocol.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"]) or "protocol"
        message = first["msg"].replace("\n", " ").replace("\x00", "\\x00")
        raise RikError(f"{path}, field '{field}': {message}") from None
    if protocol.success_opening != SUCCESS_OPENING:
        raise RikError(f"{path}, field 'success_opening': {protocol.success_opening} is not rik's success rule "
                       f"({SUCCESS_OPENING} of the front's range); this rik cannot run the protocol's episodes")
    return protocol


def check_options(path: Path, given: list[str]) -> None:
    """Refuse, in one line, ``rik eval`` options given beside a protocol that would change its episodes."""
    clash = [o for o in DRAW_OPTIONS.values() if o in given]
    if clash:
        raise RikError(f"--protocol {path} fixes the episodes; drop {', '.join(clash)} (the protocol's own: "
                       "split, kinds, joints, handle types, presets, episodes per cell, seed, episode length, "
                       "the built-in catalog)")


def check_variants(path: Path, variants: Path) -> None:
    """Refuse a variants folder whose collision model or joint friction is not the protocol's."""
    from rik.combinator.build import COLLISION, JOINT_FRICTION

    for mode, field in ((COLLISION, "collision"), (JOINT_FRICTION, "joint_friction")):
        found = mode.of_folder(Path(variants))
        if found is not None and found != mode.default:
            raise RikError(f"--protocol {path}: --variants {variants} holds {field} '{found}' variants; the "
                           f"protocol's episodes run in '{mode.default}' ones (another --variants folder)")


def check_policy(path: Path, protocol: Protocol, spec: EvalSpec) -> None:
    """Refuse a prepared evaluation whose episodes would differ from the protocol's (another robot)."""
    if spec.robot != protocol.robot:
        raise RikError(f"--protocol {path}: {spec.operator} runs robot {spec.robot}; the protocol's episodes are "
                       f"{protocol.robot}'s")
