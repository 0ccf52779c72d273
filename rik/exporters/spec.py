"""What an export writes (:class:`ExportSpec`) and the checks of it made before any work: the streams, codecs and
frame rates offered, and the narrowest frame a codec encodes. Read by the export (:mod:`rik.exporters.lerobot_export`),
its card (:mod:`rik.exporters.lerobot_card`), ``rik dataset build`` and the CLI."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.sim.observation import STREAM_SUFFIX

if TYPE_CHECKING:
    from rik.render.streams import StreamSpec

STREAMS = tuple(STREAM_SUFFIX)
"""The image streams an export can hold: ``sim`` (MuJoCo) and ``rerendered`` (Mitsuba)."""
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


@dataclass(frozen=True)
class ExportSpec:
    """What an export writes."""

    repo_id: str
    streams: tuple[str, ...] = STREAMS
    """Image streams to export (empty: a state-only dataset, nothing rendered)."""
    cameras: tuple[str, ...] = ()
    """Cameras to export (empty: those of rik's scenes, :data:`rik.sim.observation.CAMERAS`)."""
    width: int = 256
    height: int = 256
    fps: int | None = None
    """Dataset frame rate, Hz (None: the episodes' own rate, which must then agree)."""
    codec: str = "libsvtav1"
    spp: int = 16
    denoise: bool = True
    variant: str = "auto"
    shard_episodes: int = 16
    outcomes: tuple[str, ...] = ("F", "P", "S")
    """Outcomes of the episodes exported (``("S",)``: the successful demonstrations only); the others are left out."""
    action_frame: str = "world"
    """The Hand-E's ``action`` position: in the world (``world``), from the handle's grasp point (``handle``,
    :data:`rik.sim.robots.layout.HANDLE_ACTION_NAMES`) or from the gripper base (``gripper``,
    :data:`rik.sim.robots.layout.GRIPPER_ACTION_NAMES`, with the grasp point from the gripper in the environment
    state); an arm's joint action is always ``world``."""
    handle_shape: str = "none"
    """What of the handle's shape ends ``observation.environment_state``
    (:data:`rik.sim.observation.HANDLE_SHAPES`): ``none``, ``kind`` (its type and mount), ``full`` (and its grasp
    dimensions)."""

    def stream(self, kind: str) -> StreamSpec:
        """The image stream ``kind`` (``sim`` or ``rerendered``) at this export's size and quality."""
        from rik.render.streams import StreamSpec

        return StreamSpec(kind, self.width, self.height, spp=self.spp, denoise=self.denoise,  # type: ignore[arg-type]
                          variant=self.variant)


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
    """Refuse (one line) a spec the export cannot write: unknown streams or codec, cameras without streams, a
    repo id not OWNER/NAME, a frame rate or samples per pixel out of range, a size the codec cannot encode."""
    for s in spec.streams:
        if s not in STREAMS:
            raise RikError(f"--streams: unknown stream '{s}' (streams: {', '.join(STREAMS)}, or {NO_STREAMS})")
    if not spec.streams and spec.cameras:
        raise RikError(f"--cameras {','.join(spec.cameras)}: a state-only export (--streams {NO_STREAMS}) has no "
                       "cameras; drop --cameras or give --streams")
    from rik.sim.robots.layout import ACTION_FRAMES

    if spec.action_frame not in ACTION_FRAMES:
        raise RikError(f"--action-frame {spec.action_frame}: use one of {', '.join(ACTION_FRAMES)}")
    from rik.sim.observation import check_handle_shape

    check_handle_shape(spec.handle_shape)
    if spec.codec not in CODECS:
        raise RikError(f"--codec: '{spec.codec}' is not offered (codecs: {', '.join(CODECS)})")
    if spec.repo_id.count("/") != 1 or not all(spec.repo_id.split("/")):
        raise RikError(f"--repo-id '{spec.repo_id}': give it as OWNER/NAME, e.g. local/rik-drawers")
    if spec.fps is not None and not 1 <= spec.fps <= MAX_FPS:
        raise RikError(f"--fps {spec.fps}: give 1 to {MAX_FPS} Hz")
    from rik.render.streams import MAX_SPP

    if "rerendered" in spec.streams and not 1 <= spec.spp <= MAX_SPP:  # as StreamSpec says, before the codec's size
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
    least = least_width(spec.codec, spec.width, bool(spec.streams))
    if least is not None:
        raise RikError(f"--res {spec.width}x{spec.height}: --codec {spec.codec} encodes frames at least {least} "
                       f"pixels wide (narrower ones crash its encoder); give a width of {least} or more, or "
                       f"--codec h264")
