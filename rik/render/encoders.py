"""Image encoders for the visual-gap metrics: ResNet-18, ResNet-50 (torchvision) and CLIP ViT-B/32 (OpenCLIP), built
with random weights and loaded from a local weights file. Nothing is ever downloaded; docs/visual-gap.md says
where to get the files.

An encoder is named by a spec ``NAME[:WEIGHTS]``, e.g. ``resnet50:/data/resnet50-11ad3fa6.pth``. Without WEIGHTS
the network keeps a fixed-seed random initialisation: its numbers are only a random-feature baseline.

torch, torchvision and open_clip are imported inside functions (``rik catalog`` must start fast).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.render.images import load_batch

if TYPE_CHECKING:
    import torch

RANDOM_INIT_SEED = 0
"""Seed of the random initialisation used when no weights file is given."""
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
CLIP_MEAN = (0.48145466, 0.4578275, 0.40821073)  # OpenAI CLIP, as open_clip.constants.OPENAI_DATASET_MEAN
CLIP_STD = (0.26862954, 0.26130258, 0.27577711)
BATCH_SIZE = 32


@dataclass(frozen=True)
class EncoderSpec:
    """A parsed ``NAME[:WEIGHTS]``."""

    name: str
    weights: Path | None

    def __str__(self) -> str:
        return self.name if self.weights is None else f"{self.name}:{self.weights}"


Features = Callable[["torch.Tensor"], "torch.Tensor"]
"""A network as a function: a normalised image batch (N, 3, H, W) → its features (N, dim)."""


@dataclass(frozen=True)
class Architecture:
    """One registry entry: how to build the network and how its inputs and outputs look."""

    build: Callable[[Path | None], Features]
    """Weights file (or None: random init) -> a function from a normalised image batch to features."""
    dim: int
    """Feature dimension."""
    mean: tuple[float, float, float]
    std: tuple[float, float, float]
    image_size: int
    """Side of the square the images are resized to (pixels)."""
    about: str
    fixed_size: bool = False
    """True when the network only takes image_size (a ViT's position embedding); else any side >= 32 works."""


@dataclass
class Encoder:
    """A ready encoder: ``encode(paths)`` gives one feature row per image."""

    spec: EncoderSpec
    arch: Architecture
    forward: Features
    image_size: int
    """Side of the square the images are resized to (pixels)."""

    @property
    def random(self) -> bool:
        """True when the weights are a random initialisation (numbers are only a random-feature baseline)."""
        return self.spec.weights is None

    @property
    def dim(self) -> int:
        return self.arch.dim

    def encode(self, paths: Sequence[Path], batch_size: int = BATCH_SIZE,
               progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Features of the images at ``paths`` as a float64 (n, dim) array; CPU, no gradients, deterministic.

        Images are read as RGB, resized to image_size x image_size (bicubic, whole image, no crop), scaled to
        [0, 1] and normalised with the architecture's mean/std. ``progress`` gets the count of each batch done.
        """
        import torch


        out = np.empty((len(paths), self.dim), dtype=np.float64)
        with torch.inference_mode():
            for start, batch in _batches(paths, batch_size):
                pixels = load_batch(batch, self.image_size)  # (b, H, W, 3) float32 in [0, 1]
                x = torch.from_numpy(pixels).permute(0, 3, 1, 2)
                mean = torch.tensor(self.arch.mean).view(1, 3, 1, 1)
                std = torch.tensor(self.arch.std).view(1, 3, 1, 1)
                feats = self.forward(((x - mean) / std).contiguous())
                out[start:start + len(batch)] = feats.double().numpy()
                if progress is not None:
                    progress(len(batch))
        return out


def _batches(paths: Sequence[Path], size: int) -> Iterator[tuple[int, Sequence[Path]]]:
    for start in range(0, len(paths), size):
        yield start, paths[start:start + size]


# --- building and loading ------------------------------------------------------------------------------------


def _seeded[T](build: Callable[[], T]) -> T:
    """``build()`` with torch's RNG seeded by RANDOM_INIT_SEED, leaving the caller's RNG state as it was."""
    import torch

    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(RANDOM_INIT_SEED)
        return build()


def _read_state_dict(path: Path) -> dict[str, torch.Tensor]:
    """Tensors of a .safetensors file or a torch.save'd state dict (optionally under 'state_dict', keys optionally
    prefixed 'module.'); never unpickles arbitrary objects."""
    import pickle

    import torch

    if _is_torchscript(path):
        raise RikError(f"{path}: a TorchScript archive, not a state dict; save its weights with "
                       f"torch.save(torch.jit.load(file).state_dict(), 'weights.pth')")
    try:
        if path.suffix == ".safetensors":
            from safetensors.torch import load_file

            data: object = load_file(str(path), device="cpu")
        else:
            data = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError:
        raise RikError(f"{path}: cannot read weights: not a state dict of tensors saved with torch.save (files "
                       f"holding other Python objects are refused)") from None
    except Exception as exc:  # noqa: BLE001 - any reader failure is the file's fault
        raise RikError(f"{path}: cannot read weights ({_first_line(exc)}); expected a state dict saved with "
                       f"torch.save or a .safetensors file") from None
    if isinstance(data, dict) and isinstance(data.get("state_dict"), dict):
        data = data["state_dict"]
    if not isinstance(data, dict) or not data or not all(isinstance(v, torch.Tensor) for v in data.values()):
        raise RikError(f"{path}: not a state dict of tensors (got {type(data).__name__}); expected the weights "
                       f"of the network, e.g. torchvision's resnet18-f37072fd.pth")
    return {k.removeprefix("module."): v for k, v in data.items()}


def _first_line(exc: BaseException, limit: int = 160) -> str:
    """The first line of an exception's message, cut to ``limit`` characters."""
    text = str(exc).strip().splitlines()
    line = text[0] if text else type(exc).__name__
    return line if len(line) <= limit else line[:limit - 3] + "..."


def _mismatch(model_state: Mapping[str, torch.Tensor], loaded: Mapping[str, torch.Tensor]) -> str:
    """'' when ``loaded`` fits ``model_state`` key for key and shape for shape, else a short account of the first
    differences. BatchNorm's num_batches_tracked may be absent (old torchvision files lack it)."""
    missing = [k for k in model_state if k not in loaded and not k.endswith("num_batches_tracked")]
    unexpected = [k for k in loaded if k not in model_state]
    shapes = [f"{k} (file {tuple(v.shape)}, model {tuple(model_state[k].shape)})" for k, v in loaded.items()
              if k in model_state and tuple(v.shape) != tuple(model_state[k].shape)]
    parts = []
    for label, keys in (("missing keys", missing), ("unexpected keys", unexpected), ("shape mismatch", shapes)):
        if keys:
            more = f" and {len(keys) - 3} more" if len(keys) > 3 else ""
            parts.append(f"{label} {', '.join(keys[:3])}{more}")
    return "; ".join(parts)


def _load_into(model: torch.nn.Module, path: Path, name: str) -> None:
    """Load a weights file into ``model``, exactly: any missing, unexpected or mis-shaped key is a RikError."""
    state = _read_state_dict(path)
    problem = _mismatch(model.state_dict(), state)
    if problem:
        raise RikError(f"{path}: weights do not match encoder '{name}': {problem}")
    model.load_state_dict(state, strict=False)


def _resnet(arch: str) -> Callable[[Path | None], Features]:
    def build(weights: Path | None) -> Features:
        import torch
        import torchvision

        model = _seeded(lambda: getattr(torchvision.models, arch)(weights=None))
        if weights is not None:
            _load_into(model, weights, arch)
        model.fc = torch.nn.Identity()  # features: the global-average-pooled penultimate layer
        return model.eval()

    return build


def _clip(config: str, name: str) -> Callable[[Path | None], Features]:
    def build(weights: Path | None) -> Features:
        import logging

        import open_clip

        root = logging.getLogger()
        level = root.level
        root.setLevel(logging.ERROR)  # open_clip warns on the root logger that no pretrained weights were loaded
        try:
            model = _seeded(lambda: open_clip.create_model(config, pretrained=None, device="cpu"))
        finally:
            root.setLevel(level)
        if weights is not None:
            _load_clip(model, weights, name)
        model.eval()
        return lambda x: model.encode_image(x, normalize=True)

    return build


def _load_clip(model: torch.nn.Module, path: Path, name: str) -> None:
    """Load a CLIP checkpoint the way open_clip does (its own state dicts, OpenAI's TorchScript .pt archives,
    .safetensors, timm-style keys), but refuse one that does not fit exactly."""
    import warnings

    import open_clip

    try:
        # OpenAI's ViT-B-32.pt is a TorchScript archive: torch.load hands it to torch.jit.load, which open_clip only
        # allows with weights_only=False. Every other file is read with weights_only=True (no unpickling).
        with warnings.catch_warnings():  # torch.load warns that it hands a TorchScript archive to torch.jit.load
            warnings.simplefilter("ignore", UserWarning)
            result = open_clip.load_checkpoint(model, str(path), strict=False,
                                               weights_only=not _is_torchscript(path))
    except Exception as exc:  # noqa: BLE001 - any loader failure is the file's fault
        detail = _first_line(exc)
        sizes = re.findall(r"size mismatch for ([\w.]+)", str(exc))
        if sizes:
            detail = f"shape mismatch {', '.join(sizes[:3])}" + (f" and {len(sizes) - 3} more" if len(sizes) > 3
                                                                 else "")
        raise RikError(f"{path}: weights do not match encoder '{name}': {detail}") from None
    missing = list(getattr(result, "missing_keys", []))
    unexpected = list(getattr(result, "unexpected_keys", []))
    if missing or unexpected:
        parts = [f"{label} {', '.join(keys[:3])}" + (f" and {len(keys) - 3} more" if len(keys) > 3 else "")
                 for label, keys in (("missing keys", missing), ("unexpected keys", unexpected)) if keys]
        raise RikError(f"{path}: weights do not match encoder '{name}': {'; '.join(parts)}")


def _is_torchscript(path: Path) -> bool:
    """True for a TorchScript archive (a zip holding constants.pkl), as torch.load tells them apart."""
    import zipfile

    if not zipfile.is_zipfile(path):
        return False
    with zipfile.ZipFile(path) as zf:
        return any(n == "constants.pkl" or n.endswith("/constants.pkl") for n in zf.namelist())


ENCODERS: dict[str, Architecture] = {
    "resnet18": Architecture(_resnet("resnet18"), 512, IMAGENET_MEAN, IMAGENET_STD, 224,
                             "torchvision ResNet-18, 512-d global-pooled penultimate features"),
    "resnet50": Architecture(_resnet("resnet50"), 2048, IMAGENET_MEAN, IMAGENET_STD, 224,
                             "torchvision ResNet-50, 2048-d global-pooled penultimate features"),
    "clip-vit-b-32": Architecture(_clip("ViT-B-32-quickgelu", "clip-vit-b-32"), 512, CLIP_MEAN, CLIP_STD, 224,
                                  "OpenCLIP ViT-B/32 with QuickGELU (OpenAI's CLIP weights), 512-d L2-normalised "
                                  "image embedding", fixed_size=True),
    "clip-vit-b-32-gelu": Architecture(_clip("ViT-B-32", "clip-vit-b-32-gelu"), 512, CLIP_MEAN, CLIP_STD, 224,
                                       "OpenCLIP ViT-B/32 with GELU (LAION-2B / DataComp weights), 512-d "
                                       "L2-normalised image embedding", fixed_size=True),
}
"""Encoder name -> architecture. Add an entry to add an encoder."""


def parse_spec(spec: str) -> EncoderSpec:
    """``NAME[:WEIGHTS]`` -> EncoderSpec; an unknown NAME is a RikError that suggests the closest names. The file
    is checked when the encoder is loaded."""
    name, sep, weights = spec.strip().partition(":")
    name = name.strip().lower()
    if name not in ENCODERS:
        close = [k for k in ENCODERS if name and k.startswith(name)]
        close += [k for k in difflib.get_close_matches(name, list(ENCODERS), n=3, cutoff=0.6) if k not in close]
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise RikError(f"unknown encoder '{name}' (encoders: {', '.join(ENCODERS)}){hint}")
    if sep and not weights.strip():
        raise RikError(f"encoder '{spec}': empty weights path after ':' (leave out ':' for random weights)")
    return EncoderSpec(name, Path(weights.strip()).expanduser() if sep else None)


def load_encoder(spec: str | EncoderSpec, image_size: int | None = None) -> Encoder:
    """Build the encoder named by ``spec`` and load its weights file, if any (a RikError when the file is missing,
    unreadable or made for another architecture). CPU, eval mode.

    ``image_size`` (pixels) overrides the architecture's input side (224) for the ResNets, e.g. for quick tests;
    pretrained weights are meant for 224."""
    parsed = parse_spec(spec) if isinstance(spec, str) else spec
    arch = ENCODERS[parsed.name]
    size = arch.image_size if image_size is None else image_size
    if size != arch.image_size and (arch.fixed_size or size < 32):
        allowed = f"only {arch.image_size}" if arch.fixed_size else "at least 32"
        raise RikError(f"encoder '{parsed.name}': image size {size} not supported ({allowed})")
    if parsed.weights is not None and not parsed.weights.is_file():
        raise RikError(f"{parsed.weights}: weights file for encoder '{parsed.name}' not found "
                       f"(docs/visual-gap.md says where to get it)")
    return Encoder(parsed, arch, arch.build(parsed.weights), size)
