"""The visual gap between real images and simulated (and re-rendered) ones: encode each folder with an image
encoder, then FID, KID and EMD under the split-half protocol of :mod:`rik.render.metrics`, with report writers.

``visual_gap(real, sim, rerendered, encoder_spec, n, bootstrap, seed)`` is the whole pipeline; the CLI
(``rik visual-gap``) only parses and prints. docs/visual-gap.md describes the protocol.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rik.errors import RikError
from rik.render.encoders import Encoder, load_encoder, parse_spec
from rik.render.images import common_subsets, list_images
from rik.render.metrics import FLOOR, Interval, PairMetrics, RowTable, split_half

RANDOM_NOTE = ("random weights: the encoder is randomly initialised (fixed seed), so these numbers are only a "
               "random-feature baseline; pass --encoder NAME:WEIGHTS for meaningful features")
Progress = Callable[[int, int, str], None]
"""progress(images encoded so far, images to encode, set name)."""


@dataclass
class VisualGapResult(RowTable):
    """One encoder's visual-gap table and how it was made; ``to_dict`` gives its JSON form."""

    encoder: str
    weights: str | None
    random_weights: bool
    feature_dim: int
    image_size: int
    """Side of the square every image was resized to (pixels)."""
    folders: dict[str, str]
    images_found: dict[str, int]
    n_per_set: int
    """N: images used from every set."""
    n_half: int
    """h = N // 2: images on each side of every comparison."""
    bootstrap: int
    level: float
    seed: int
    rows: list[PairMetrics] = field(default_factory=list)
    note: str = ""


MAX_BOOTSTRAP = 10_000
"""Most bootstrap resamples per row (``--bootstrap``): each computes FID, KID and EMD again."""


def visual_gap(real: Path, sim: Path | None = None, rerendered: Path | None = None,
               encoder_spec: str = "resnet18", n: int | None = None, bootstrap: int = 200, seed: int = 0,
               level: float = 0.95, kid_subsets: int = 100, image_size: int | None = None,
               progress: Progress | None = None) -> VisualGapResult:
    """FID, KID and EMD of ``sim`` and ``rerendered`` (either may be None, not both) against ``real``, with the
    real split-half floor and ``bootstrap`` percentile intervals at ``level``, in ``encoder_spec``'s features.

    Every folder is read recursively (PNG/JPEG). With ``n`` None all folders must hold the same number of
    images; otherwise each is subsampled to ``n`` (seeded). ``image_size`` (pixels) overrides the encoder's input
    side (ResNets only; see :func:`rik.render.encoders.load_encoder`). A RikError for any bad input, before any
    encoding where it can be checked up front (encoder name, folders, counts, weights file).
    """
    if not 1 <= bootstrap <= MAX_BOOTSTRAP:
        raise RikError(f"--bootstrap {bootstrap}: give 1 to {MAX_BOOTSTRAP:,} resamples")
    spec = parse_spec(encoder_spec)
    folders = {"real": real, "sim": sim, "rerendered": rerendered}
    given = {name: Path(p) for name, p in folders.items() if p is not None}
    if len(given) < 2:
        raise RikError("visual-gap: give --sim or --rerendered (or both) to compare with --real")
    found = {name: list_images(path, name) for name, path in given.items()}
    chosen = common_subsets(found, n, seed)
    count = len(chosen["real"])
    if count < 4:
        raise RikError(f"visual-gap: {count} images per set; needs at least 4 (two halves of at least 2)")
    encoder = load_encoder(spec, image_size)
    feats = _encode_all(encoder, chosen, progress)
    table = split_half(feats.pop("real"), feats, resamples=bootstrap, level=level, seed=seed,
                       kid_subsets=kid_subsets)
    return VisualGapResult(encoder=spec.name, weights=None if spec.weights is None else str(spec.weights),
                           random_weights=encoder.random, feature_dim=encoder.dim,
                           image_size=encoder.image_size,
                           folders={k: str(v) for k, v in given.items()},
                           images_found={k: len(v) for k, v in found.items()}, n_per_set=table.n_per_set,
                           n_half=table.n_half, bootstrap=bootstrap, level=level, seed=seed, rows=table.rows,
                           note=RANDOM_NOTE if encoder.random else "")


def _encode_all(encoder: Encoder, sets: dict[str, list[Path]], progress: Progress | None) -> dict[str, np.ndarray]:
    total = sum(len(v) for v in sets.values())
    done = 0
    out = {}
    for name, paths in sets.items():
        def step(k: int, name: str = name) -> None:
            nonlocal done
            done += k
            if progress is not None:
                progress(done, total, name)

        out[name] = encoder.encode(paths, progress=step)
    return out


# --- reports -------------------------------------------------------------------------------------------------


def fmt(x: float) -> str:
    """A number for a table: four significant digits."""
    return f"{x:.4g}"


def cell(v: Interval) -> str:
    """``value [low, high]``, or ``value ± std [low, high]`` for a KID averaged over distinct subsets."""
    spread = f" ± {fmt(v.std)}" if v.std else ""
    return f"{fmt(v.value)}{spread} [{fmt(v.low)}, {fmt(v.high)}]"


def encoder_label(r: VisualGapResult) -> str:
    """E.g. ``resnet18 (weights: /w/resnet18.pth)`` or ``resnet18 (RANDOM weights: random-feature baseline)``."""
    if r.random_weights:
        return f"{r.encoder} (RANDOM weights: random-feature baseline only)"
    return f"{r.encoder} (weights: {r.weights})"


def protocol_line(r: VisualGapResult) -> str:
    """One sentence saying how the numbers were made."""
    return (f"N = {r.n_per_set} images per set, every comparison {r.n_half} vs {r.n_half} images (split halves); "
            f"{r.bootstrap} bootstrap resamples, {r.level:.0%} intervals; seed {r.seed}. "
            f"Gaps mean something only above the '{FLOOR}' row.")


def results_markdown(results: Sequence[VisualGapResult]) -> str:
    """A markdown report: one table per encoder (rows: each set and the floor; FID, KID, EMD with intervals)."""
    lines = ["# Visual gap", ""]
    for r in results:
        pct = f"{r.level:.0%}"
        lines += [f"## {encoder_label(r)}", "", protocol_line(r), ""]
        if r.note:
            lines += [f"**Note:** {r.note}.", ""]
        lines += [f"| set | images per side | FID [{pct} CI] | KID [{pct} CI] | EMD [{pct} CI] |",
                  "|---|---|---|---|---|"]
        lines += [f"| {row.name} | {row.n} | {cell(row.fid)} | {cell(row.kid)} | {cell(row.emd)} |" for row in r.rows]
        lines.append("")
    return "\n".join(lines)


def results_json(results: Sequence[VisualGapResult]) -> str:
    """The results as indented JSON: ``{"results": [one object per encoder]}``."""
    return json.dumps({"results": [r.to_dict() for r in results]}, indent=2, ensure_ascii=False) + "\n"
