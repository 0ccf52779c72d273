"""Where rendered image streams live, and how they are written so that an interrupted render resumes.

A stream of one episode is a folder ``<renders>/<episode id>/<key>/`` holding ``<camera>/<frame:06d>.png`` for
every camera and every recorded state, plus ``stream.json`` (what was rendered, how, from which states). The
key names the stream and its settings, e.g. ``sim-256x256-shadow1024-msaa4`` or ``rerendered-256x256-16spp-oidn``,
so streams at other settings sit beside it (and a stream rendered with other settings is another stream, not a
silent change). Frames are written into ``.<key>.partial/`` (each PNG through a temporary
file and a rename) and the folder is renamed into place when every frame is there: a finished stream is never
redone, an interrupted one resumes at its first missing frame (frames are deterministic, seeded by their
index), and a stream of an episode recorded again (another states sha256) is rendered again.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rik.errors import RikError
from rik.outputs import (
    PRIVATE,
    MadeFolder,
    check_replaceable,
    remove_file,
    remove_stage,
    replace_directory,
    tree_holds_only,
    write_png,
    write_text,
)
from rik.paths import inside, json_object

DEFAULT_RENDERS = Path("renders")
MANIFEST = "stream.json"
StreamKind = Literal["sim", "rerendered"]


MIN_SIDE, MAX_SIDE = 8, 4096
"""Smallest and largest side of a rendered image, px."""
MAX_SPP = 4096
"""Most samples per pixel of the re-render (as ``rik rerender --spp`` allows)."""


MULTISAMPLES = 4
"""Multisamples per pixel of MuJoCo's frames (on llvmpipe 2 render the same frames as 4; docs/benchmarks.md)."""
SHADOW_TEXELS_PER_PIXEL = 4
"""Shadow map texels per image pixel on the image's longer side (:func:`sim_settings`)."""
SHADOW_SIZES = (512, 1024, 2048)
"""The shadow map sizes a sim stream is rendered with, px a side: the smallest that holds
:data:`SHADOW_TEXELS_PER_PIXEL` per image pixel, 2048 (rik's scenes' own) above."""


@dataclass(frozen=True)
class SimSettings:
    """How MuJoCo renders a sim stream's frames: what decides its cost and picture, recorded in its key and
    ``stream.json``."""

    shadow_size: int
    """Each shadow-casting light's shadow map, px a side (rik's scenes are compiled with 2048)."""
    multisamples: int = MULTISAMPLES

    @property
    def tag(self) -> str:
        return f"shadow{self.shadow_size}-msaa{self.multisamples}"


def sim_settings(width: int, height: int) -> SimSettings:
    """The settings of a ``width`` x ``height`` sim frame: a shadow map of :data:`SHADOW_TEXELS_PER_PIXEL` texels per
    pixel of the longer side, rounded up to one of :data:`SHADOW_SIZES` (512 px up to 128 px images, 1024 up to 256,
    2048 above). Chosen by ``benchmarks/render_settings.py`` (docs/rendering.md): at 64 and 128 px a 512 px map
    renders 1.6-1.7 times faster than 2048 with the same picture in the front camera (PSNR 36-37 dB median); on the
    wrist camera's close-ups shadow edges are coarser (the worst frames, 22 dB: docs/rendering.md)."""
    need = SHADOW_TEXELS_PER_PIXEL * max(width, height)
    return SimSettings(next((s for s in SHADOW_SIZES if s >= need), SHADOW_SIZES[-1]))


@dataclass(frozen=True)
class StreamSpec:
    """What a stream is: which renderer, at what size and, for the re-render, quality."""

    kind: StreamKind
    width: int
    height: int
    spp: int = 16
    """Samples per pixel (re-render only)."""
    denoise: bool = True
    """Intel Open Image Denoise with albedo and normal guides (re-render only)."""
    variant: str = "auto"
    """Mitsuba variant (re-render only); ``auto`` picks the fastest that works here. Not part of the key:
    variants render the same image up to Monte Carlo noise."""

    def __post_init__(self) -> None:
        """Sizes and samples within what a renderer can hold, checked before any frame is rendered."""
        if not all(MIN_SIDE <= side <= MAX_SIDE for side in (self.width, self.height)):
            raise RikError(f"image size {self.width}x{self.height}: give {MIN_SIDE} to {MAX_SIDE} pixels a side")
        if not 1 <= self.spp <= MAX_SPP:
            raise RikError(f"--spp {self.spp}: give 1 to {MAX_SPP} samples per pixel")

    @property
    def sim(self) -> SimSettings:
        """MuJoCo's render settings at this size (the sim stream's; :func:`sim_settings`)."""
        return sim_settings(self.width, self.height)

    @property
    def key(self) -> str:
        size = f"{self.width}x{self.height}"
        if self.kind == "sim":
            return f"sim-{size}-{self.sim.tag}"
        return f"rerendered-{size}-{self.spp}spp-{'oidn' if self.denoise else 'raw'}"


def parse_resolution(text: str) -> tuple[int, int]:
    """``256`` (square) or ``320x240`` (width x height) to (width, height) in pixels."""
    try:
        parts = [int(p) for p in str(text).lower().split("x")]
    except ValueError:
        parts = []
    if len(parts) == 1:
        parts = parts * 2
    if len(parts) != 2 or min(parts) < MIN_SIDE or max(parts) > MAX_SIDE:
        raise RikError(f"--res {text}: give a size like 256 or 320x240, {MIN_SIDE} to {MAX_SIDE} pixels a side")
    return parts[0], parts[1]


def stream_dir(renders: Path, episode_id: str, spec: StreamSpec) -> Path:
    """``<renders>/<episode id>/<key>``, refused (:class:`RikError`) if the id would lead outside ``renders``."""
    return inside(Path(renders), episode_id, spec.key, what="episode id")


def frame_name(index: int) -> str:
    return f"{index:06d}.png"


def read_manifest(directory: Path) -> dict[str, Any] | None:
    """A finished stream's ``stream.json``, or None when the folder is not a finished stream."""
    try:
        return json.loads((Path(directory) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def is_done(directory: Path, states_sha256: str) -> bool:
    """Whether ``directory`` holds a finished stream of these states."""
    manifest = read_manifest(directory)
    return manifest is not None and manifest.get("states_sha256") == states_sha256


FRAME = re.compile(r"\d{6}\.png")
"""The name of a frame (:func:`frame_name`)."""


def is_stream(directory: Path) -> bool:
    """Whether ``directory`` is a stream rik rendered (finished, of any states): its ``stream.json`` and one folder
    per camera it names holding frames, nothing else at any depth."""
    manifest = json_object(Path(directory) / MANIFEST)
    cameras = manifest.get("cameras") if manifest is not None else None
    if not (isinstance(cameras, list) and all(isinstance(c, str) for c in cameras)):
        return False

    def ours(rel: str) -> bool:
        folder, _, name = rel.rpartition("/")
        return rel == MANIFEST or (folder in cameras and FRAME.fullmatch(name) is not None)

    return tree_holds_only(directory, ours)


STREAM_FOLDER = MadeFolder("an image stream rik rendered", is_stream, "choose another folder for the renders")
"""A stream's folder: an outdated one is replaced, and only if :func:`is_stream` recognises it."""


class StreamWriter:
    """Writes one stream's frames into its staging folder, skipping those already there, and publishes it."""

    def __init__(self, final: Path, spec: StreamSpec, cameras: list[str], frames: int, states_sha256: str):
        self.final, self.spec, self.cameras, self.frames = Path(final), spec, cameras, frames
        self.sha = states_sha256
        check_replaceable(self.final, STREAM_FOLDER)  # before any frame is rendered
        self.staging = self.final.with_name(f".{self.final.name}.partial")
        marker = self.staging / ".states_sha256"
        if self.staging.exists() and (not marker.is_file() or marker.read_text().strip() != states_sha256):
            remove_stage(self.staging)  # frames of other states: start again
        for cam in cameras:
            (self.staging / cam).mkdir(parents=True, exist_ok=True)
        write_text(marker, states_sha256, PRIVATE)

    def missing(self) -> Iterator[int]:
        """Indices of frames with at least one camera not written yet."""
        for k in range(self.frames):
            if not all((self.staging / cam / frame_name(k)).is_file() for cam in self.cameras):
                yield k

    def write(self, index: int, camera: str, image: np.ndarray) -> None:
        write_png(self.staging / camera / frame_name(index), image, PRIVATE, compress_level=4)

    def publish(self, info: dict[str, Any]) -> Path:
        """Write the manifest and move the finished stream into place (replacing an outdated one)."""
        settings = {"render_settings": asdict(self.spec.sim)} if self.spec.kind == "sim" else {}
        manifest = {"stream": self.spec.kind, "key": self.spec.key, **asdict(self.spec), **settings,
                    "cameras": self.cameras,
                    "frames": self.frames, "states_sha256": self.sha, **info}
        remove_file(self.staging / ".states_sha256", PRIVATE)
        write_text(self.staging / MANIFEST, json.dumps(manifest, indent=2) + "\n", PRIVATE)
        replace_directory(self.staging, self.final, STREAM_FOLDER)
        return self.final


def read_frame(directory: Path, camera: str, index: int) -> np.ndarray:
    """One frame of a finished stream as an (H, W, 3) uint8 array."""
    from PIL import Image

    path = Path(directory) / camera / frame_name(index)
    try:
        with Image.open(path) as img:
            return np.asarray(img.convert("RGB"))
    except OSError as exc:
        raise RikError(f"{path}: cannot read this frame ({exc}); render the stream again") from None
