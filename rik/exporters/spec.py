"""What an export writes (:class:`ExportSpec`: rik's contract with LeRobot, :class:`~rik.lerobot.policy_io.PolicyIO`,
and how it is encoded) and the checks of it made before any work: the streams, codecs and frame rates offered, and the
narrowest frame a codec encodes. Read by the export (:mod:`rik.exporters.lerobot_export`), its card
(:mod:`rik.exporters.lerobot_card`), ``rik dataset build`` and the CLI."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.lerobot.features import CAMERAS, STREAMS
from rik.lerobot.policy_io import PolicyIO

if TYPE_CHECKING:
    from rik.render.streams import StreamSpec

NO_STREAMS = "none"
"""``--streams none``: a state-only export (no video features, nothing rendered)."""
CODECS = ("libsvtav1", "h264", "hevc")
"""Video codecs offered: the software encoders of lerobot's PyAV build (never ``auto``: it picks NVENC)."""
ENCODER_OPTIONS: dict[str, dict[str, str]] = {"h264": {"x264-params": "mbtree=0"}}
"""Extra encoder options per codec, so that identical inputs give identical bytes. x264's macroblock-tree rate
control (on by default), in its AVX-512 code, reads memory it never wrote: the same frames encode to different bytes
and pixels from one process to the next (with ``MALLOC_PERTURB_`` at will). Without it, or without AVX-512, x264 is
repeatable; the cost is bigger files at the same CRF (measured +14..37% at 256x256, with +0.8..1.7 dB PSNR) and no
loss of speed. libsvtav1 and hevc were repeatable as they are."""
MIN_WIDTH: dict[str, int] = {"libsvtav1": 25}
"""Narrowest frame, px, that a codec encodes. SVT-AV1 (lerobot's PyAV build) dies of a floating-point exception
(SIGFPE, which takes the worker process with it) on frames less than 25 pixels wide, at any height (measured: 24x24,
24x64, 24x4096, 16x16 and 8x64 crash; 25x8, 25x64, 26x2048, 32x4 and 64x8 encode); h264 and hevc take rik's
smallest size (8 a side)."""
MAX_FPS = 240
"""Highest ``--fps`` of an export, Hz: SVT-AV1 (the default codec) encodes at most 240 frames per second (rik records
at 20 Hz; resampling above it only repeats rows and frames)."""
EXPORT_IO = PolicyIO(streams=STREAMS, image_size=(256, 256))
"""An export's contract unless told otherwise: both streams of every camera at 256x256 px, the world frame, no
handle shape (its robot is the episodes')."""
LABELS = {"action_frame": "--action-frame {}", "handle_shape": "--handle-shape {}", "streams": "--streams",
          "cameras": "--cameras", "image_size": "--res {}", "robot": "--robot {}",
          "environment_state": "--no-environment-state"}
"""How a problem of the contract names ``rik export-lerobot``'s options."""
SIZE_OPTIONS = ("width", "height")
"""Keyword arguments of :class:`ExportSpec` that set one side of the contract's image size (px)."""


@dataclass(frozen=True, init=False)
class ExportSpec:
    """What an export writes: the dataset's id, its contract (:attr:`io`; cameras none: every camera of rik's
    scenes) and how it is encoded. Keyword arguments named as a field of the contract (``streams=()``,
    ``action_frame="handle"``, ``width=``/``height=`` for its image size) set that field of :data:`EXPORT_IO`."""

    repo_id: str
    io: PolicyIO
    fps: int | None
    """Dataset frame rate, Hz (None: the episodes' own rate, which must then agree)."""
    codec: str
    spp: int
    denoise: bool
    variant: str
    shard_episodes: int
    outcomes: tuple[str, ...]
    """Outcomes of the episodes exported (``("S",)``: the successful demonstrations only); the others are left out."""

    def __init__(self, repo_id: str, io: PolicyIO | None = None, *, fps: int | None = None, codec: str = "libsvtav1",
                 spp: int = 16, denoise: bool = True, variant: str = "auto", shard_episodes: int = 16,
                 outcomes: tuple[str, ...] = ("F", "P", "S"), **contract: Any) -> None:
        io = io or EXPORT_IO
        if any(k in contract for k in SIZE_OPTIONS):
            height, width = io.image_size
            contract["image_size"] = (contract.pop("height", height), contract.pop("width", width))
        values = {"repo_id": repo_id, "io": io.with_options(contract, LABELS), "fps": fps, "codec": codec,
                  "spp": spp, "denoise": denoise, "variant": variant, "shard_episodes": shard_episodes,
                  "outcomes": tuple(outcomes)}
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def stream(self, kind: str) -> StreamSpec:
        """The image stream ``kind`` (``sim`` or ``rerendered``) at this export's size and quality."""
        from rik.render.streams import StreamSpec

        return StreamSpec(kind, self.io.width, self.io.height, spp=self.spp,  # type: ignore[arg-type]
                          denoise=self.denoise, variant=self.variant)

    def exported_cameras(self) -> tuple[str, ...]:
        """The cameras exported: the contract's, or every camera of rik's scenes; none without streams."""
        return (self.io.cameras or CAMERAS) if self.io.streams else ()

    def plan_data(self) -> dict[str, Any]:
        """The settings as an interrupted export's ``plan.json`` records them (the contract's fields beside the
        others, the image size as ``width`` and ``height``), so that exports interrupted before the contract
        existed are continued."""
        io = self.io
        return {"repo_id": self.repo_id, "streams": list(io.streams), "cameras": list(io.cameras),
                "width": io.width, "height": io.height, "fps": self.fps, "codec": self.codec, "spp": self.spp,
                "denoise": self.denoise, "variant": self.variant, "shard_episodes": self.shard_episodes,
                "outcomes": list(self.outcomes), "action_frame": io.action_frame, "handle_shape": io.handle_shape,
                **({} if io.environment_state else {"environment_state": False})}


OUTCOMES = ("F", "P", "S")
"""Episode outcomes: failed, partly opened, succeeded (:mod:`rik.sim.outcome`)."""


def parse_outcomes(text: str) -> tuple[str, ...]:
    """The outcomes of ``--outcomes`` (comma-separated letters, e.g. ``S``), in F, P, S order."""
    items = {s.strip().upper() for s in text.split(",") if s.strip()}
    unknown = sorted(items - set(OUTCOMES))
    if unknown or not items:
        raise RikError(f"--outcomes {text}: give some of F, P, S (failed, partly opened, succeeded), comma-separated"
                       + (f"; '{unknown[0]}' is none of them" if unknown else ""))
    return tuple(o for o in OUTCOMES if o in items)


def keep_outcomes(metas: dict[Any, Any], outcomes: tuple[str, ...], where: str) -> dict[Any, Any]:
    """The episodes of ``metas`` (path -> meta) whose outcome is one of ``outcomes``; none is one line."""
    kept = {d: m for d, m in metas.items() if m.outcome in outcomes}
    if metas and not kept:
        from collections import Counter

        counts = ", ".join(f"{k} {v}" for k, v in sorted(Counter(m.outcome for m in metas.values()).items()))
        raise RikError(f"{where}: none of the {len(metas)} episodes has outcome {' or '.join(outcomes)} (they are "
                       f"{counts}): nothing to export")
    return kept


def parse_streams(text: str) -> tuple[str, ...]:
    """The streams of ``--streams`` (comma-separated); ``none`` alone gives () (a state-only export)."""
    items = tuple(s.strip() for s in text.split(",") if s.strip())
    if NO_STREAMS in items:
        if len(items) > 1:
            raise RikError(f"--streams {text}: '{NO_STREAMS}' (a state-only export) cannot be combined with image "
                           "streams; give either none or some of " + ", ".join(STREAMS))
        return ()
    if not items:
        raise RikError(f"--streams: give at least one of {', '.join(STREAMS)}, or {NO_STREAMS} for a state-only "
                       "export")
    return items


def check_spec(spec: ExportSpec) -> None:
    """Refuse (one line) a spec the export cannot write: a contract that is not valid (unknown streams, cameras,
    frame, handle shape), cameras without streams, an unknown codec, a repo id not OWNER/NAME, a frame rate or
    samples per pixel out of range, a size the codec cannot encode."""
    for s in spec.io.streams:
        if s not in STREAMS:
            raise RikError(f"--streams: unknown stream '{s}' (streams: {', '.join(STREAMS)}, or {NO_STREAMS})")
    if not spec.io.streams and spec.io.cameras:
        raise RikError(f"--cameras {','.join(spec.io.cameras)}: a state-only export (--streams {NO_STREAMS}) has no "
                       "cameras; drop --cameras or give --streams")
    spec.io.validate(labels=LABELS)
    if spec.codec not in CODECS:
        raise RikError(f"--codec: '{spec.codec}' is not offered (codecs: {', '.join(CODECS)})")
    if spec.repo_id.count("/") != 1 or not all(spec.repo_id.split("/")):
        raise RikError(f"--repo-id '{spec.repo_id}': give it as OWNER/NAME, e.g. local/rik-drawers")
    if spec.fps is not None and not 1 <= spec.fps <= MAX_FPS:
        raise RikError(f"--fps {spec.fps}: give 1 to {MAX_FPS} Hz")
    from rik.render.streams import MAX_SPP

    if "rerendered" in spec.io.streams and not 1 <= spec.spp <= MAX_SPP:  # as StreamSpec says, before the size
        raise RikError(f"--spp {spec.spp}: give 1 to {MAX_SPP} samples per pixel")
    check_codec_size(spec)


def least_width(codec: str, width: int, images: bool) -> int | None:
    """The narrowest frame ``codec`` encodes (:data:`MIN_WIDTH`, px) when ``width`` is narrower and images are
    exported; None when the width is fine."""
    least = MIN_WIDTH.get(codec)
    return least if images and least is not None and width < least else None


def check_codec_size(spec: ExportSpec) -> None:
    """Refuse (one line) an image size that ``spec.codec`` cannot encode (:data:`MIN_WIDTH`), before any work: the
    encoder would otherwise crash its process once the frames are rendered."""
    least = least_width(spec.codec, spec.io.width, bool(spec.io.streams))
    if least is not None:
        raise RikError(f"--res {spec.io.width}x{spec.io.height}: --codec {spec.codec} encodes frames at least {least} "
                       f"pixels wide (narrower ones crash its encoder); give a width of {least} or more, or "
                       f"--codec h264")
