"""MuJoCo render settings against today's: what each costs and what it changes in the picture, per resolution.

How issue 54's render settings were chosen. "Today's" are rik's scenes' own (and every sim stream's before issue
54): a 2048 px shadow map, 4x multisampling, shadows of both lights (key and fill) and reflections at every size;
sim streams now take the shadow map's size from the image's (:func:`rik.render.streams.sim_settings`). For
each candidate setting and image size this renders the same frames as today's settings (four variants: a drawer, a
door, a knob drawer, a flap; the front opened in 24 steps over its range; the ``front`` and ``wrist`` cameras) and
prints, side by side in one run: milliseconds per frame and the speed-up against today's, and the picture against
today's frame for frame (PSNR on 8-bit sRGB and SSIM, median and worst). ``--png`` writes a side-by-side sheet
(one door frame per setting and size) to look at, and ``<png>-worst.png`` the frame of each variant and size that
the chosen setting (:data:`CHOSEN`) changes most. Nothing in rik changes: the settings are set on the model and
scene for this run only.

Run: ``uv run python benchmarks/render_settings.py [--sizes 64,128] [--steps 24] [--png sheet.png]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

VARIANTS = ("drawer-chest-80__two_point-bow-128__normal", "door-wall-60-left__two_point-d-pull-128__normal",
            "drawer-bedside-45__knob-mushroom-30__high", "flap-lift-up-60__finger_pull-edge-j-150__smooth")
CAMERAS = ("front", "wrist")
SETTINGS = {  # name: (shadow map px, multisamples, shadows: "all" lights, the "key" light only or "none", reflections,
    #               supersampling: rendered at this many times the size a side, averaged down in blocks)
    "today": (2048, 4, "all", True, 1),
    "shadow 1024": (1024, 4, "all", True, 1),
    "shadow 512": (512, 4, "all", True, 1),
    "shadow 512, no reflections": (512, 4, "all", False, 1),
    "shadow 512, key light only": (512, 4, "key", True, 1),
    "shadow 1024, key light only": (1024, 4, "key", True, 1),
    "shadow 512, key light only, 2x multisampling": (512, 2, "key", True, 1),
    "shadow 512, no multisampling": (512, 0, "all", True, 1),
    "shadow 512, 2x2 supersampled": (512, 0, "all", True, 2),
    "shadow 256, 2x2 supersampled": (256, 0, "all", True, 2),
    "shadow 1024, 2x2 supersampled": (1024, 0, "all", True, 2),
    "no shadows": (2048, 4, "none", True, 1),
}
CHOSEN = "shadow 512"
"""The setting rik renders 64-128 px sim frames with (:func:`rik.render.streams.sim_settings`): ``--png`` also
writes its worst frame per variant and size beside today's (``<png>-worst.png``)."""
WARMUP = 2


def ssim(a, b) -> float:  # noqa: ANN001  (uint8 images, H x W x 3)
    """The mean structural similarity of two images (Gaussian window, sigma 1.5; per channel, averaged)."""
    import numpy as np
    from scipy.ndimage import gaussian_filter

    x_all, y_all = a.astype(np.float64) / 255, b.astype(np.float64) / 255
    out = []
    for c in range(3):
        x, y = x_all[..., c], y_all[..., c]
        mx, my = gaussian_filter(x, 1.5), gaussian_filter(y, 1.5)
        sxx, syy = gaussian_filter(x * x, 1.5) - mx * mx, gaussian_filter(y * y, 1.5) - my * my
        sxy = gaussian_filter(x * y, 1.5) - mx * my
        c1, c2 = 0.01 ** 2, 0.03 ** 2
        out.append(float(np.mean((2 * mx * my + c1) * (2 * sxy + c2) / ((mx * mx + my * my + c1) * (sxx + syy + c2)))))
    return float(np.mean(out))


def downsample(image, factor: int):  # noqa: ANN001, ANN201  (uint8 H x W x 3 -> uint8 H/f x W/f x 3)
    """The mean of each ``factor`` x ``factor`` block, rounded to 8 bits (a copy, also at factor 1)."""
    import numpy as np

    if factor == 1:
        return image.copy()
    h, w, c = image.shape
    blocks = image.reshape(h // factor, factor, w // factor, factor, c).astype(np.float32)
    return np.rint(blocks.mean(axis=(1, 3))).astype(np.uint8)


def psnr(a, b) -> float:  # noqa: ANN001
    import numpy as np

    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)) / 255 ** 2
    return 99.0 if mse == 0 else float(10 * np.log10(1 / mse))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="64,128")
    parser.add_argument("--steps", type=int, default=24, help="openings per variant")
    parser.add_argument("--png", type=Path, help="write a side-by-side sheet here")
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco
    import numpy as np

    from rik.combinator.build import ensure_variant
    from rik.registry.load import load_catalog
    from rik.sim.build import build_scene

    catalog = load_catalog()
    sizes = [int(s) for s in args.sizes.split(",")]
    seconds: dict[tuple[int, str], list[float]] = {}
    quality: dict[tuple[int, str], list[tuple[float, float]]] = {}
    sheet: dict[tuple[int, str], np.ndarray] = {}
    worst: dict[tuple[str, int], tuple[float, np.ndarray, np.ndarray]] = {}
    print(f"CPU cores: {os.cpu_count()}; {len(VARIANTS)} variants x {args.steps} openings x {len(CAMERAS)} cameras "
          f"per setting and size")
    with tempfile.TemporaryDirectory() as tmp:
        for vid in VARIANTS:
            scene = build_scene(ensure_variant(catalog, vid, Path(tmp) / "variants"), None)
            model, lo, hi = scene.model, *scene.front.range
            saved = (model.vis.quality.shadowsize, model.vis.quality.offsamples)
            for size in sizes:
                frames: dict[str, list[np.ndarray]] = {}
                casts = model.light_castshadow.copy()
                for name, (shadow, samples, shadows, reflections, ss) in SETTINGS.items():
                    model.vis.quality.shadowsize, model.vis.quality.offsamples = shadow, samples
                    model.light_castshadow[:] = casts
                    if shadows == "key":  # the fill light's shadow off: one shadow map per frame instead of two
                        model.light_castshadow[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_LIGHT, "fill")] = 0
                    renderer = mujoco.Renderer(model, size * ss, size * ss)
                    data = mujoco.MjData(model)
                    images = []
                    for k in range(args.steps + WARMUP):
                        data.qpos[:] = scene.data.qpos
                        data.qpos[scene.front.qpos_adr] = lo + (hi - lo) * max(0, k - WARMUP) / args.steps
                        mujoco.mj_forward(model, data)
                        for cam in CAMERAS:
                            start = time.perf_counter()
                            renderer.update_scene(data, camera=cam)
                            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows != "none"
                            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = reflections
                            image = downsample(renderer.render(), ss)
                            if k >= WARMUP:
                                seconds.setdefault((size, name), []).append(time.perf_counter() - start)
                                images.append(image)
                    renderer.close()
                    model.light_castshadow[:] = casts
                    frames[name] = images
                    if vid.startswith("door"):
                        sheet[(size, name)] = images[len(images) // 2]
                for name in SETTINGS:
                    quality.setdefault((size, name), []).extend(
                        (psnr(a, b), ssim(a, b)) for a, b in zip(frames["today"], frames[name], strict=True))
                scores = [psnr(a, b) for a, b in zip(frames["today"], frames[CHOSEN], strict=True)]
                k = int(np.argmin(scores))
                worst[(vid, size)] = (scores[k], frames["today"][k], frames[CHOSEN][k])
            model.vis.quality.shadowsize, model.vis.quality.offsamples = saved
    print(f"\n{'setting':<46}{'px':>5}{'ms/frame':>10}{'x today':>9}{'PSNR med':>10}{'PSNR min':>10}"
          f"{'SSIM med':>10}{'SSIM min':>10}")
    for size in sizes:
        base = float(np.mean(seconds[(size, "today")]))
        for name in SETTINGS:
            t = float(np.mean(seconds[(size, name)]))
            p, s = np.array(quality[(size, name)]).T
            print(f"{name:<46}{size:>5}{1000 * t:>10.1f}{base / t:>9.2f}{np.median(p):>10.1f}{p.min():>10.1f}"
                  f"{np.median(s):>10.4f}{s.min():>10.4f}")
    if args.png:
        from rik.outputs import RECORDED, save_figure
        from rik.paths import pyplot

        fig, axes = pyplot().subplots(len(sizes), len(SETTINGS), figsize=(2.2 * len(SETTINGS), 2.4 * len(sizes)),
                                      dpi=120, squeeze=False)
        for i, size in enumerate(sizes):
            for j, name in enumerate(SETTINGS):
                axes[i][j].imshow(sheet[(size, name)], interpolation="nearest")
                axes[i][j].set_title(f"{name}\n{size} px", fontsize=6)
                axes[i][j].axis("off")
        fig.tight_layout()
        print(f"sheet: {save_figure(fig, args.png, RECORDED)}")
        fig, axes = pyplot().subplots(len(worst), 3, figsize=(6.6, 2.3 * len(worst)), dpi=120, squeeze=False)
        for i, ((vid, size), (score, today, chosen)) in enumerate(worst.items()):
            diff = np.clip(4 * np.abs(today.astype(np.int16) - chosen.astype(np.int16)), 0, 255).astype(np.uint8)
            for j, (image, title) in enumerate(((today, "today"), (chosen, CHOSEN), (diff, "|difference| x4"))):
                axes[i][j].imshow(image, interpolation="nearest")
                axes[i][j].set_title(f"{title}, {size} px" + (f"\n{vid[:34]}, PSNR {score:.1f} dB" if j == 0 else ""),
                                     fontsize=6)
                axes[i][j].axis("off")
        fig.tight_layout()
        path = args.png.with_name(f"{args.png.stem}-worst{args.png.suffix}")
        print(f"worst frames of {CHOSEN!r}: {save_figure(fig, path, RECORDED)}")


if __name__ == "__main__":
    main()
