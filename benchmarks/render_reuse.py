"""A variant's second episode rendered by a renderer kept from its first (``rik.render.renderers.reused_renderer``)
against one made for it, side by side in one run: seconds for the whole stream (the renderer's making, its first
frames' tracing and kernel compiling included), their ratio, and whether the frames are the same bytes.

Records two short scripted episodes (``contact_rich``, seeds 0 and 1) of the demo variant into a temporary folder,
then renders the ``rerendered`` stream (Mitsuba, 16 spp, denoised) of both cameras at ``--res`` pixels: episode 0
then episode 1 with the kept renderer, and episode 1 again after every kept renderer was dropped. Target: the kept
renderer is faster on a second episode, with identical frames.

Run: ``uv run python benchmarks/render_reuse.py [--res 128] [--seconds 2]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

VARIANT = "drawer-chest-80__two_point-bow-128__normal"


def _frames(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*.png"))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--res", type=int, default=128, help="image side, px (default 128, the demo's)")
    parser.add_argument("--seconds", type=float, default=2.0, help="length of each episode, simulated s")
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    from rik.episodes.record import record
    from rik.registry.load import load_catalog
    from rik.render.episodes import render_episode
    from rik.render.renderers import drop_renderers
    from rik.render.streams import StreamSpec

    catalog = load_catalog()
    spec = StreamSpec("rerendered", args.res, args.res, spp=16, denoise=True)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        variants, episodes = root / "variants", root / "episodes"
        metas = record(catalog, VARIANT, "contact_rich", episodes=2, out=episodes, variants=variants,
                       max_seconds=args.seconds)
        first, second = (episodes / m.id for m in metas)
        drop_renderers()
        render_episode(catalog, first, spec, renders=root / "kept", variants=variants)
        start = time.perf_counter()
        kept = render_episode(catalog, second, spec, renders=root / "kept", variants=variants)
        kept_s = time.perf_counter() - start
        drop_renderers()
        start = time.perf_counter()
        fresh = render_episode(catalog, second, spec, renders=root / "fresh", variants=variants)
        fresh_s = time.perf_counter() - start
        drop_renderers()
        same = _frames(kept.directory) == _frames(fresh.directory)
    print(f"second episode's rerendered stream, {kept.frames} frames x {len(kept.cameras)} cameras at "
          f"{args.res} px, 16 spp, denoised:")
    print(f"  renderer made for it      {fresh_s:7.2f} s  ({fresh_s / kept.frames:.3f} s per frame)")
    print(f"  renderer kept from ep. 0  {kept_s:7.2f} s  ({kept_s / kept.frames:.3f} s per frame)")
    print(f"  ratio made / kept         {fresh_s / kept_s:7.2f}x; frames identical: {same}")


if __name__ == "__main__":
    main()
