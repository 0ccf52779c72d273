"""Render speed and quality: the MuJoCo stream against the Mitsuba 3 re-render, and what denoising buys.

Records one short scripted episode (``contact_rich`` on a chest of drawers with a bow handle), then prints, side by
side in one run, seconds per frame of the ``front`` camera (one 8-bit image, everything included: posing the scene,
rendering, denoising, tone mapping) for:

- MuJoCo's rasteriser (EGL) at 128 and 256 pixels;
- Mitsuba's path tracer, ``llvm_ad_rgb`` (when a libLLVM 16+ is installed) and ``scalar_rgb``, at 128 and 256
  pixels, 16 samples per pixel, with and without Intel Open Image Denoise (guided by albedo and normals);

the ratio of each to the MuJoCo stream at the same size, and the PSNR (on sRGB values in [0, 1]) of one 256-pixel
frame at 16 spp, raw and denoised, against a 1,024-spp reference (16 renders of 64 spp with different seeds,
averaged). Times are the mean over ``--frames`` frames of the episode after three warm-up frames (the JIT variants
compile, record and then replay frozen kernels). Targets on 2 CPU cores: at most 1 s per 256-pixel frame with denoising,
PSNR at least 35 dB.

Run: ``uv run python benchmarks/render_speed.py [--frames 6] [--variants llvm_ad_rgb,scalar_rgb]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

VARIANT = "drawer-chest-80__two_point-bow-128__normal"
WARMUP = 3


def psnr(a, b) -> float:  # noqa: ANN001  (numpy arrays in [0, 1])
    import numpy as np

    mse = float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))
    return float("inf") if mse == 0 else 10.0 * np.log10(1.0 / mse)


def srgb(linear):  # noqa: ANN001, ANN201
    from rik.render.materials import linear_to_srgb8

    return linear_to_srgb8(linear).astype("float64") / 255.0


def time_frames(renderer, scene, recorded, frames: int) -> float:  # noqa: ANN001
    """Mean seconds per frame over ``frames`` states after the warm-up ones."""
    import numpy as np

    picks = [int(i) for i in np.linspace(0, len(recorded) - 1, frames + WARMUP)]
    spent = []
    for n, k in enumerate(picks):
        scene.restore(recorded[k])
        start = time.perf_counter()
        renderer.render(scene.data, k)
        if n >= WARMUP:
            spent.append(time.perf_counter() - start)
    return sum(spent) / len(spent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--variants", default="llvm_ad_rgb,scalar_rgb")
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")

    from rik.episodes.episode import read_episode, states
    from rik.episodes.record import record
    from rik.episodes.replay import episode_scene
    from rik.registry.load import load_catalog
    from rik.render.backend import available_variants
    from rik.render.renderers import MitsubaFrames, MujocoFrames
    from rik.render.streams import StreamSpec

    catalog = load_catalog()
    here = available_variants()
    variants = [v for v in args.variants.split(",") if v in here]
    print(f"CPU cores: {os.cpu_count()}; Mitsuba variants here: {', '.join(here)}; timing: {', '.join(variants)}")
    with tempfile.TemporaryDirectory() as tmp:
        meta = record(catalog, VARIANT, "contact_rich", out=Path(tmp) / "episodes", variants=Path(tmp) / "variants",
                      max_seconds=2.0)[0]
        directory = Path(tmp) / "episodes" / meta.id
        meta, table = read_episode(directory)
        scene = episode_scene(catalog, directory, Path(tmp) / "variants", meta)
        recorded = states(table)
        scene.restore(recorded[0])
        rows = []
        base: dict[int, float] = {}
        for size in (128, 256):
            mj = MujocoFrames(scene.model, ["front"], StreamSpec("sim", size, size))
            base[size] = time_frames(mj, scene, recorded, args.frames)
            mj.close()
            rows.append(("mujoco (EGL)", size, "-", "-", base[size]))
        for variant in variants:
            for size in (128, 256):
                for denoise in (False, True):
                    spec = StreamSpec("rerendered", size, size, spp=16, denoise=denoise, variant=variant)
                    scene.restore(recorded[0])
                    mf = MitsubaFrames(scene.model, scene.data, ["front"], spec, catalog.finishes)
                    rows.append((f"mitsuba {variant}", size, 16, "oidn" if denoise else "raw",
                                 time_frames(mf, scene, recorded, args.frames)))
                    mf.close()
        print(f"\n{'renderer':<26}{'px':>5}{'spp':>5}{'denoise':>9}{'s/frame':>10}{'x mujoco':>10}")
        for name, size, spp, dn, sec in rows:
            print(f"{name:<26}{size:>5}{spp!s:>5}{dn:>9}{sec:>10.3f}{sec / base[size]:>10.1f}")

        # Quality: 16 spp raw and denoised against a 1,024-spp reference, same frame, same variant.
        variant = variants[0]
        k = len(recorded) // 2
        scene.restore(recorded[k])

        def linear(spp: int, denoise: bool, seed: int):  # noqa: ANN202
            spec = StreamSpec("rerendered", 256, 256, spp=spp, denoise=denoise, variant=variant)
            return MitsubaFrames(scene.model, scene.data, ["front"], spec, catalog.finishes).render_linear(
                scene.data, seed)["front"]

        reference = srgb(sum(linear(64, False, 1000 + s) for s in range(16)) / 16)
        raw, clean = srgb(linear(16, False, 1)), srgb(linear(16, True, 1))
        print(f"\nPSNR against 1,024 spp ({variant}, 256 px, frame {k}): 16 spp raw {psnr(raw, reference):.1f} dB, "
              f"16 spp denoised {psnr(clean, reference):.1f} dB")
        best = min(sec for name, size, spp, dn, sec in rows if size == 256 and dn == "oidn")
        print(f"target: at most 1 s per 256-px frame with denoising -> best {best:.2f} s: "
              f"{'met' if best <= 1.0 else 'NOT met'}; PSNR at least 35 dB -> {psnr(clean, reference):.1f} dB: "
              f"{'met' if psnr(clean, reference) >= 35 else 'NOT met'}")


if __name__ == "__main__":
    main()
