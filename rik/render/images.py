"""Image folders for the visual-gap metrics: find the PNG/JPEG files under a directory, check them, choose a common
number of them, and read them as RGB arrays."""

from __future__ import annotations

import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from rik.errors import RikError

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")


def list_images(folder: Path, role: str = "images") -> list[Path]:
    """Every .png/.jpg/.jpeg file under ``folder`` (recursively, any case of suffix, hidden files skipped), sorted
    by path; other files are ignored. A RikError when the folder is missing or holds no image, and for an image
    file PIL cannot identify (the message names it)."""
    if not folder.is_dir():
        raise RikError(f"--{role} {folder}: not a directory")
    paths = sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
                   and not any(part.startswith(".") for part in p.relative_to(folder).parts))
    if not paths:
        raise RikError(f"--{role} {folder}: no images (.png, .jpg or .jpeg files) in the folder")
    for p in paths:
        check_image(p)
    return paths


def check_image(path: Path) -> None:
    """A RikError naming ``path`` unless PIL can identify it as an image (reads the header only)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            im.verify()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError, Image.DecompressionBombError) as exc:
        raise RikError(f"{path}: not a readable image ({exc})") from None


def load_image(path: Path, size: int) -> np.ndarray:
    """The image at ``path`` as RGB, resized to size x size (bicubic, whole image), float32 in [0, 1], (H, W, 3).
    A RikError naming the file when it cannot be decoded (e.g. truncated)."""
    from PIL import Image

    try:
        with Image.open(path) as im:
            rgb = im.convert("RGB").resize((size, size), Image.Resampling.BICUBIC)
    except (OSError, SyntaxError, ValueError, Image.DecompressionBombError) as exc:
        raise RikError(f"{path}: not a readable image ({exc})") from None
    return np.asarray(rgb, dtype=np.float32) / 255.0


def load_batch(paths: Sequence[Path], size: int) -> np.ndarray:
    """Images at ``paths`` stacked as a float32 (n, size, size, 3) array in [0, 1]."""
    return np.stack([load_image(p, size) for p in paths])


def common_subsets(sets: Mapping[str, list[Path]], n: int | None, seed: int = 0) -> dict[str, list[Path]]:
    """The image lists cut to one common count, so FID and EMD are compared at equal N.

    With ``n`` None every set must already have the same count (else a RikError giving the counts and suggesting
    ``--n``); with ``n`` each set is subsampled to n images at random (seeded per set, kept in path order), and a
    set with fewer than n images is a RikError."""
    counts = {name: len(paths) for name, paths in sets.items()}
    listing = ", ".join(f"{name} {count}" for name, count in counts.items())
    smallest = min(counts.values())
    if n is None:
        if len(set(counts.values())) > 1:
            raise RikError(f"image folders differ in size ({listing} images); FID and EMD are only comparable "
                           f"at equal N: pass --n {smallest} (or fewer) to subsample every set to the same count")
        return {name: list(paths) for name, paths in sets.items()}
    if n < 4:
        raise RikError(f"--n {n}: needs at least 4 images per set (two halves of at least 2)")
    if n > smallest:
        raise RikError(f"--n {n}: more than the smallest set ({listing} images); pass --n {smallest} or fewer")
    out = {}
    for name, paths in sets.items():
        rng = np.random.default_rng([seed, zlib.crc32(name.encode())])  # a set's draw does not depend on the others
        out[name] = [paths[i] for i in np.sort(rng.choice(len(paths), n, replace=False))]
    return out
