"""rik's contract with LeRobot in one value: :class:`PolicyIO`, what a policy trained on a rik dataset reads and
writes (its robot's layout, the action's frame, the handle's shape in the front's state, its cameras, streams and
image size).

It is said once and carried, never guessed: ``rik export-lerobot`` (and ``rik dataset build``) write it into the
dataset as ``meta/rik_policy_io.json`` (:data:`POLICY_IO_FILE`), ``lerobot-train`` with rik's plugin copies it
beside each checkpoint (:mod:`rik.lerobot.train_hook`), and ``rik eval`` and ``--env.*=auto`` read it from the
policy's folder (:func:`read_policy`): its own file, else the file of the dataset its ``train_config.json`` names,
else, for a policy trained before rik wrote its contract, the old guess from its input widths and training
statistics, with a one-line note. The export's spec, ``rik eval``'s spec, a dataset spec, the environment and the
``--env.type=rik`` config all build one and let it check itself (:meth:`PolicyIO.validate`), naming the option at
fault in their own words (``labels``).

A policy folder is untrusted input: the file is read bounded (:data:`MAX_BYTES`), every field is checked (one line
naming the file and the field), and the contract is compared with the policy's own ``config.json``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.lerobot.features import (
    ACTION_FRAMES,
    CAMERAS,
    ENV_STATE_LAYOUTS,
    HANDLE_SHAPES,
    OBS_ENV_STATE,
    OBS_STATE,
    STREAMS,
    action_frame_of,
    dataset_features,
    image_name,
)
from rik.lerobot.policy_files import member, read_json
from rik.lerobot.policy_folder import image_feature, policy_config, policy_inputs, trained_action_frame
from rik.paths import json_object

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.sim.robots.layout import RobotLayout

POLICY_IO_FILE = "rik_policy_io.json"
"""The contract's file: in a dataset's ``meta/``, and beside a policy's ``config.json``."""
FORMAT = 1
"""Version of :data:`POLICY_IO_FILE`'s layout."""
MAX_BYTES = 64 * 2**10
"""Largest contract file read, bytes (one is about 200)."""
MAX_NAMES = 16
"""Most names in a list field (cameras, streams)."""
MAX_TEXT = 64
"""Longest text field, characters."""
MAX_FPS = 1000
"""Highest frame rate of a contract, Hz."""
DEFAULT_ROBOT = "hand-e"
AUTO = "auto"
"""An option's value that says: what the policy's contract says (``--env.action_frame=auto``)."""
TRAIN_CONFIG = "train_config.json"
"""What ``lerobot-train`` writes beside each checkpoint's policy: its ``dataset.repo_id`` and ``dataset.root``."""


@dataclass(frozen=True)
class PolicyIO:
    """What a policy reads and writes in rik's environment: the features of the dataset it was trained on."""

    robot: str = DEFAULT_ROBOT
    """The robot (rik catalog id) whose ``observation.state`` and ``action`` layout it uses
    (:mod:`rik.sim.robots.layout`)."""
    action_frame: str = "world"
    """Where a pose action's position is measured from: ``world``, ``handle`` (the grasp point) or ``gripper`` (the
    gripper base, which also adds the grasp point from the gripper to the front's state); an arm's: ``world``."""
    handle_shape: str = "none"
    """What of the handle's shape ends ``observation.environment_state``: ``none``, ``kind`` or ``full``."""
    cameras: tuple[str, ...] = ()
    """Cameras of its images (none: a state-only policy)."""
    streams: tuple[str, ...] = ()
    """Image streams of those cameras: ``sim`` (MuJoCo), ``rerendered`` (Mitsuba)."""
    image_size: tuple[int, int] = (96, 128)
    """(height, width) of its images, px."""
    fps: int = 20
    """The rate it acts at, Hz: its dataset's frame rate (rik records at 20 Hz; ``--fps`` resamples)."""
    environment_state: bool = True
    """Whether it reads ``observation.environment_state``, the simulator's state of the front and its handle (a real
    robot has none: a policy without it reads its own state and its cameras only)."""

    @property
    def height(self) -> int:
        return self.image_size[0]

    @property
    def width(self) -> int:
        return self.image_size[1]

    @property
    def images(self) -> tuple[str, ...]:
        """The image of each camera and stream (``front``, ``front_rerendered``); none without streams."""
        return tuple(image_name(c, s) for c in self.cameras for s in self.streams)

    def layout(self, catalog: Catalog | None = None) -> RobotLayout:
        """The robot's layout, its pose action in :attr:`action_frame` (``catalog``: where the robot is; default
        the built-in one)."""
        from rik.sim.robots.layout import robot_layout

        if catalog is None:
            from rik.registry.load import load_catalog

            catalog = load_catalog()
        return robot_layout(catalog.robot(self.robot).as_arm, self.action_frame)

    def features(self, layout: RobotLayout | None = None) -> dict[str, dict[str, Any]]:
        """The LeRobot features of a dataset of this contract (``layout``: the robot's, when already at hand)."""
        return dataset_features(layout or self.layout(), self.handle_shape, self.cameras, self.streams,
                                self.image_size, environment_state=self.environment_state)

    # ---- checks -----------------------------------------------------------------------------------------------
    def validate(self, catalog: Catalog | None = None, labels: Mapping[str, str] | None = None) -> PolicyIO:
        """This contract, checked: known frame, handle shape, cameras and streams, an image size rik renders (where
        there are images), and with ``catalog`` a robot it holds whose action has that frame. A problem is one
        :class:`ContractError` naming the field as the caller names it (``labels``: field -> its option, ``{}``
        standing for the value, e.g. ``{"action_frame": "--action-frame {}"}``)."""
        for name, check in CHECKS.items():
            problem = check(self, getattr(self, name))
            if problem:
                raise ContractError(name, f"{label(name, getattr(self, name), labels)}: {problem}")
        if catalog is not None:
            from rik.sim.robots.layout import robot_layout

            robot = catalog.robot(self.robot)  # an unknown robot: one line with suggestions
            if self.action_frame != "world" and not robot_layout(robot.as_arm).is_pose:
                raise ContractError("action_frame", f"{label('action_frame', self.action_frame, labels)}: robot "
                                    f"{robot.id} acts with joint targets, which have no {self.action_frame} frame "
                                    "(it is the Hand-E's pose action's)")
        return self

    def with_options(self, options: Mapping[str, Any], labels: Mapping[str, str] | None = None, *,
                     auto: bool = False) -> PolicyIO:
        """This contract with ``options`` (field -> value; None or a field left out keeps this contract's, and so
        does :data:`AUTO` where ``auto``), each parsed as its field's type (a list field also from a
        comma-separated string); any other key is refused."""
        changes = {}
        for name, value in options.items():
            if name not in FIELD_TYPES:
                raise RikError(f"{name}: not a field of rik's policy contract ({', '.join(FIELD_TYPES)})")
            if value is None or (auto and isinstance(value, str) and value == AUTO):
                continue
            changes[name] = PARSERS[FIELD_TYPES[name]](value, label(name, value, labels), True)
        return replace(self, **changes)

    # ---- the file ---------------------------------------------------------------------------------------------
    def to_json(self) -> str:
        """The contract as :data:`POLICY_IO_FILE` holds it (its format, then every field)."""
        data: dict[str, Any] = {"format": FORMAT}
        for f in fields(self):
            value = getattr(self, f.name)
            data[f.name] = list(value) if isinstance(value, tuple) else value
        return json.dumps(data, indent=1) + "\n"

    @classmethod
    def from_json(cls, data: Any, where: str) -> PolicyIO:
        """The contract in ``data`` (a file's JSON), every field checked: ``where`` (the file) starts a problem's
        line. A field missing takes its default (a file written before the field existed)."""
        if not isinstance(data, dict):
            raise RikError(f"{where}: not a JSON object (rik's policy contract)")
        if data.get("format") != FORMAT:
            raise RikError(f"{where}: field 'format': {data.get('format')!r} is not {FORMAT} (a file of another "
                           "rik; export the dataset again with this one)")
        unknown = [k for k in data if k != "format" and k not in FIELD_TYPES]
        if unknown:
            raise RikError(f"{where}: field {unknown[0]!r}: not a field of rik's policy contract "
                           f"({', '.join(FIELD_TYPES)})")
        io = cls(**{name: PARSERS[FIELD_TYPES[name]](data[name], f"{where}: field '{name}'", False)
                    for name in FIELD_TYPES if name in data})
        return io.validate(labels={name: f"{where}: field '{name}' {{}}" for name in FIELD_TYPES})

    @classmethod
    def read(cls, file: Path) -> PolicyIO:
        """The contract in ``file``, read only when it is a regular file of at most :data:`MAX_BYTES`."""
        from rik import paths

        file = Path(file)
        try:
            if not file.is_file():
                raise RikError(f"{file}: missing or not a regular file")
            if file.stat().st_size > MAX_BYTES:
                raise RikError(f"{file}: larger than {MAX_BYTES // 1024} KiB; rik's policy contract is a few "
                               "hundred bytes")
            data = paths.read_json(file, MAX_BYTES)
        except OSError as e:
            raise RikError(f"{file}: not readable ({e.strerror or e})") from None
        except ValueError as e:
            raise RikError(f"{file}: not readable JSON ({str(e).splitlines()[0] if str(e) else 'empty'})") from None
        return cls.from_json(data, str(file))

    # ---- where a contract comes from --------------------------------------------------------------------------
    @classmethod
    def from_dataset(cls, root: Path, robot: str | None = None) -> PolicyIO:
        """The contract of the dataset at ``root``: its ``meta/rik_policy_io.json``, or for a dataset exported
        before rik wrote one, what its ``meta/info.json`` names (:func:`io_of_info`)."""
        file = Path(root) / "meta" / POLICY_IO_FILE
        if file.is_file() or file.is_symlink():
            return cls.read(file)
        return io_of_info(Path(root), robot)

    @classmethod
    def from_policy(cls, folder: Path, *, robot: str = DEFAULT_ROBOT, allow_rerendered: bool = False) -> PolicyIO:
        """The contract of the saved policy in ``folder`` run with ``robot`` (:func:`read_policy`)."""
        return read_policy(folder, robot=robot, allow_rerendered=allow_rerendered).io


class ContractError(RikError):
    """A field of a :class:`PolicyIO` that is not valid; ``field`` names it (the caller may name it otherwise)."""

    def __init__(self, field: str, message: str):
        self.field = field
        super().__init__(message)


# ---- fields: types, parsing, checks -------------------------------------------------------------------------------
def _text(value: Any, where: str, options: bool) -> str:
    if not isinstance(value, str) or not value or len(value) > MAX_TEXT:
        raise RikError(f"{where}: {_shown(value)} is not a name (a string of 1 to {MAX_TEXT} characters)")
    return value


def _names(value: Any, where: str, options: bool) -> tuple[str, ...]:
    if options and isinstance(value, str):
        value = [v.strip() for v in value.split(",") if v.strip()]
    if not isinstance(value, list | tuple) or len(value) > MAX_NAMES:
        raise RikError(f"{where}: {_shown(value)} is not a list of at most {MAX_NAMES} names")
    return tuple(_text(v, where, options) for v in value)


def _pair(value: Any, where: str, options: bool) -> tuple[int, int]:
    if not isinstance(value, list | tuple) or len(value) != 2 or not all(
            isinstance(v, int) and not isinstance(v, bool) for v in value):
        raise RikError(f"{where}: give (height, width), two whole numbers of pixels")
    return (value[0], value[1])  # their range: CHECKS (also of a contract built in Python)


def _flag(value: Any, where: str, options: bool) -> bool:
    if options and isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    if not isinstance(value, bool):
        raise RikError(f"{where}: {_shown(value)} is not true or false")
    return value


def _count(value: Any, where: str, options: bool) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise RikError(f"{where}: {_shown(value)} is not a whole number")
    return value


PARSERS: dict[str, Callable[[Any, str, bool], Any]] = {"str": _text, "tuple[str, ...]": _names,
                                                       "tuple[int, int]": _pair, "int": _count,
                                                       "bool": _flag}
"""A field's declared type -> its parser (value, where, from options): a new field of one of these types needs no
code here."""
FIELD_TYPES = {f.name: str(f.type) for f in fields(PolicyIO)}
""":class:`PolicyIO`'s fields and their types, in order."""


def _choice(choices: tuple[str, ...]) -> Callable[[PolicyIO, Any], str | None]:
    return lambda io, value: None if value in choices else f"use one of {', '.join(choices)}"


def _items(what: str, choices: tuple[str, ...], problem: str) -> Callable[[PolicyIO, Any], str | None]:
    def check(io: PolicyIO, value: Any) -> str | None:
        bad = next((v for v in value if v not in choices), None)
        return None if bad is None else problem.format(what, repr(bad), ", ".join(choices))
    return check


def _size(io: PolicyIO, value: Any) -> str | None:
    from rik.render.streams import MAX_SIDE, MIN_SIDE

    if not io.streams:
        return None  # no images: no size to render
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        return "give (height, width), two whole numbers of pixels"
    if not all(MIN_SIDE <= v <= MAX_SIDE for v in value):
        return f"give (height, width), {MIN_SIDE} to {MAX_SIDE} pixels each"
    return None


def _state_or_images(io: PolicyIO, value: Any) -> str | None:
    if value:
        return None
    if not io.streams:
        return "a policy without the front's state reads the robot's state and images: give it streams (sim)"
    if io.handle_shape != "none" or io.action_frame == "gripper":
        return ("the handle's shape and the gripper frame's grasp point are part of the front's state: use "
                "handle_shape none and the world or handle frame")
    return None


def _rate(io: PolicyIO, value: Any) -> str | None:
    whole = isinstance(value, int) and not isinstance(value, bool)
    return None if whole and 1 <= value <= MAX_FPS else f"give 1 to {MAX_FPS} frames per second"


CHECKS: dict[str, Callable[[PolicyIO, Any], str | None]] = {
    "action_frame": _choice(ACTION_FRAMES),
    "handle_shape": _choice(tuple(HANDLE_SHAPES)),
    "streams": _items("stream", STREAMS, "unknown {} {} (streams: {})"),
    "cameras": _items("camera", CAMERAS, "no {} {} in the scene (cameras: {})"),
    "image_size": _size,
    "fps": _rate,
    "environment_state": _state_or_images,
}
"""Field -> the check of its value (None: fine; else the problem, after the field's label)."""
LABELS = {"robot": "robot '{}'", "action_frame": "action frame '{}'", "handle_shape": "handle_shape {}",
          "cameras": "cameras", "streams": "streams", "image_size": "image_size {}",
          "environment_state": "environment_state {}"}
"""How a problem names each field by default (the environment's keyword arguments); ``{}``: the value."""


def _shown(value: Any) -> str:
    text = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
    return text if len(text) <= 60 else text[:60] + "..."


def label(name: str, value: Any, labels: Mapping[str, str] | None = None) -> str:
    """How a problem of field ``name`` with ``value`` starts (``labels``, else :data:`LABELS`)."""
    template = (labels or {}).get(name) or LABELS.get(name, f"{name} {{}}")
    if isinstance(value, tuple | list) and all(isinstance(v, str) for v in value):
        shown = ",".join(value)
    else:
        shown = str(value)
    return template.replace("{}", shown) if "{}" in template else template


# ---- a dataset's contract from its info.json (exports made before the file) ----------------------------------------
def io_of_info(root: Path, robot: str | None = None, catalog: Catalog | None = None) -> PolicyIO:
    """The contract the LeRobot dataset at ``root`` holds, as its ``meta/info.json`` names it: the robot whose
    layout has its ``robot_type`` and state names (``robot`` where several of ``catalog``'s do, else the first), the
    frame its action's names are in, the handle's shape its front's state's names end with, the cameras, streams and
    size of its video features. What the export writes (from the dataset it wrote, so that the two cannot differ),
    and what a dataset exported before the contract existed is read as."""
    from rik.registry.load import load_catalog
    from rik.sim.robots.layout import robot_layout

    info_file = Path(root) / "meta" / "info.json"
    info = json_object(info_file) or {}
    feats = info.get("features")
    if not isinstance(feats, dict):
        raise RikError(f"{info_file}: not a LeRobot dataset's info.json (no features)")

    def names(key: str) -> tuple[str, ...]:
        entry = feats.get(key)
        return tuple(entry.get("names") or ()) if isinstance(entry, dict) else ()

    catalog = catalog or load_catalog()
    state = names(OBS_STATE)
    robots = [r for r in catalog.robots.values()
              if robot_layout(r.as_arm).robot_type == info.get("robot_type")
              and robot_layout(r.as_arm).state_names == state]
    if not robots:
        raise RikError(f"{info_file}: robot_type {info.get('robot_type')!r} with observation.state "
                       f"{', '.join(state) or '(none)'} is no robot of rik's catalog")
    chosen = next((r for r in robots if r.id == robot), robots[0])
    has_env_state = OBS_ENV_STATE in feats
    env = next((key for key, known in ENV_STATE_LAYOUTS.items() if known == names(OBS_ENV_STATE)),
               None) if has_env_state else ("none", False)
    if env is None:
        raise RikError(f"{info_file}: observation.environment_state holds {', '.join(names(OBS_ENV_STATE))}, none "
                       "of rik's layouts")
    frame = action_frame_of(names("action")) or "world"
    images = [(image_feature(k), f) for k, f in feats.items() if isinstance(f, dict) and f.get("dtype") == "video"]
    cameras = tuple(dict.fromkeys(c for (c, _), _ in images if c is not None))
    streams = tuple(dict.fromkeys(s for (c, s), _ in images if c is not None))
    size = tuple(images[0][1].get("shape", (96, 128))[:2]) if images else (96, 128)
    return PolicyIO(chosen.id, frame, env[0], cameras, streams, (int(size[0]), int(size[1])),
                    _count(info.get("fps"), f"{info_file}: field 'fps'", False), has_env_state)


# ---- a policy's contract -----------------------------------------------------------------------------------------
FALLBACK_NOTE = ("{folder}: no {file} beside the policy or its training data (a policy trained before rik wrote its "
                 "contract): its action frame and handle shape are guessed from its input widths and training "
                 "statistics")
"""The one line said where a policy's contract is guessed."""


@dataclass(frozen=True)
class PolicyContract:
    """A saved policy's contract (narrowed to the images it reads), its type, and where the contract was read."""

    io: PolicyIO
    policy_type: str
    source: Path | None
    """The contract file it came from; None: guessed (a policy trained before rik wrote its contract)."""
    folder: Path

    @property
    def note(self) -> str | None:
        """One line where the contract was guessed (:data:`FALLBACK_NOTE`), else None."""
        return None if self.source is not None else FALLBACK_NOTE.format(folder=self.folder, file=POLICY_IO_FILE)


def contract_file(folder: Path) -> Path | None:
    """Where a policy's contract is: :data:`POLICY_IO_FILE` beside its ``config.json`` (copied there at training),
    else the one of the dataset its ``train_config.json`` names (``dataset.root``, or LeRobot's cache folder of
    ``dataset.repo_id``), where that dataset still is; None: neither."""
    own = Path(folder) / POLICY_IO_FILE
    if own.exists() or own.is_symlink():
        return member(Path(folder), POLICY_IO_FILE, str(own))  # inside the folder, a regular file
    root = training_dataset(Path(folder))
    if root is None:
        return None
    file = root / "meta" / POLICY_IO_FILE
    return file if file.is_file() else None


def training_dataset(folder: Path) -> Path | None:
    """The root of the dataset the policy in ``folder`` was trained on, as its ``train_config.json`` says (None: no
    such file, or it names no dataset). Read bounded; the path is the folder's own claim, read from, never written."""
    if not (Path(folder) / TRAIN_CONFIG).is_file():
        return None
    data = read_json(Path(folder), TRAIN_CONFIG)
    dataset = data.get("dataset") if isinstance(data, dict) else None
    if not isinstance(dataset, dict):
        return None
    root, repo_id = dataset.get("root"), dataset.get("repo_id")
    if isinstance(root, str) and 0 < len(root) <= 4096 and "\x00" not in root:
        return Path(root)
    if root is None and isinstance(repo_id, str) and repo_id.count("/") == 1 and ".." not in repo_id:
        from lerobot.utils.constants import HF_LEROBOT_HOME

        return Path(HF_LEROBOT_HOME) / repo_id
    return None


def read_policy(folder: Path, *, robot: str = DEFAULT_ROBOT, allow_rerendered: bool = False) -> PolicyContract:
    """The contract of the saved policy in ``folder`` run with ``robot``: its contract file (:func:`contract_file`)
    checked against its ``config.json`` (the robot, the front's state's width; the images narrowed to those the
    policy reads, at its size), or, where there is none, guessed from its input widths and training statistics
    (:attr:`PolicyContract.note` says so)."""
    from rik.registry.load import load_catalog
    from rik.sim.robots.layout import robot_layout

    folder = Path(folder)
    config = policy_config(folder)
    catalog = load_catalog()
    entry = catalog.robot(robot)  # an unknown robot: one line with suggestions
    file = contract_file(folder)
    if file is not None:
        said = PolicyIO.read(file)
        if said.robot != entry.id:  # its config.json's shapes name the difference first, where they differ
            policy_inputs(folder, config, robot_layout(entry.as_arm), None, allow_rerendered=allow_rerendered)
            raise RikError(f"{file}: the policy was trained for robot {said.robot}; run it with --robot "
                           f"{said.robot} (rik eval) or --env.robot={said.robot} (lerobot-eval)")
        layout = said.validate(catalog, {"action_frame": f"{file}: field 'action_frame' {{}}"}).layout(catalog)
        inputs = policy_inputs(folder, config, layout, (said.handle_shape, said.action_frame == "gripper"),
                               allow_rerendered=allow_rerendered, said=str(file))
        if not said.environment_state and OBS_ENV_STATE in (config.get("input_features") or {}):
            raise RikError(f"{file}: field 'environment_state' is false, but the policy reads "
                           f"{OBS_ENV_STATE}: the policy was not trained on that dataset")
        io = replace(said, cameras=inputs.cameras, streams=inputs.streams, image_size=inputs.image_size)
        return PolicyContract(io, inputs.policy_type, file, folder)
    layout = robot_layout(entry.as_arm)
    inputs = policy_inputs(folder, config, layout, None, allow_rerendered=allow_rerendered)
    shape, from_gripper = inputs.env_layout
    frame = ("gripper" if from_gripper else trained_action_frame(folder)) if layout.is_pose else "world"
    io = PolicyIO(entry.id, frame, shape, inputs.cameras, inputs.streams, inputs.image_size)
    return PolicyContract(io, inputs.policy_type, None, folder)


