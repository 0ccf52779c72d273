"""``rik render`` and ``rik rerender``: image streams of recorded episodes, from MuJoCo (the live ``sim`` stream)
and from Mitsuba 3 (the offline path-traced ``rerendered`` stream). Only parsing and printing here;
:mod:`rik.render` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TypedDict, Unpack

import typer

from rik.cli.common import CatalogOption, WorkersOpt, console, overlays, progress_bar
from rik.cli.sim import VariantsOpt
from rik.demo import DEMO_RES
from rik.paths import check_folder

if TYPE_CHECKING:
    from rik.render.streams import StreamKind

EpisodesArg = Annotated[list[Path], typer.Argument(help="Episode directories, or directories of them.",
                                                   show_default=False)]
ResOpt = Annotated[str, typer.Option("--res", help="Image size: 256 (square) or WIDTHxHEIGHT, px.")]
CamerasOpt = Annotated[str | None, typer.Option("--cameras", help="Comma-separated cameras (default: every "
                                                "camera of the scene: front, wrist).")]
RendersOpt = Annotated[Path, typer.Option("--out", "-o", help="Root of rendered streams: "
                                          "<out>/<episode>/<stream>/<camera>/<frame>.png.")]


class _Quality(TypedDict, total=False):
    """The re-render's quality options (:class:`rik.render.streams.StreamSpec`'s)."""

    spp: int
    denoise: bool
    variant: str


def _run(episodes: list[Path], kind: StreamKind, res: str, cameras: str | None, out: Path, variants: Path, workers: int,
         catalog: list[Path] | None, sheet: bool = False, **quality: Unpack[_Quality]) -> None:
    from rik.episodes.episode import find_episodes, read_meta
    from rik.registry.load import load_catalog
    from rik.render.episodes import check_renders_outside, render_episodes
    from rik.render.streams import StreamSpec, parse_resolution

    width, height = parse_resolution(res)
    spec = StreamSpec(kind, width, height, **quality)
    check_folder(out, "--out")
    check_folder(variants, "--variants")
    if kind == "rerendered":
        from rik.render.backend import use_variant

        use_variant(spec.variant)  # an unsupported or unavailable variant fails before any work
    dirs = find_episodes(episodes)
    metas = {d: read_meta(d) for d in dirs}
    check_renders_outside(out, {d: m.id for d, m in metas.items()})
    by_id = {m.id: d for d, m in metas.items()}
    total = sum(m.steps + 1 for m in metas.values())
    cams = [c.strip() for c in cameras.split(",") if c.strip()] if cameras else None
    cat = load_catalog(overlays(catalog))
    con = console()
    results = []
    with progress_bar() as progress:
        task = progress.add_task(f"{spec.key} frames", total=total, last="")
        for r in render_episodes(cat, dirs, spec, renders=out, variants=variants, cameras=cams, workers=workers,
                                 overlays=overlays(catalog), progress=lambda n: progress.update(task, advance=n)):
            progress.update(task, last=r.episode)
            results.append(r)
    for r in results:
        how = (f"{r.rendered} frames rendered, {r.seconds_per_frame:.2f} s per frame ({len(r.cameras)} cameras)"
               if r.rendered else "already rendered")
        con.print(f"{r.directory}: {r.frames} frames x {', '.join(r.cameras)}; {how}")
        if sheet:
            from rik.render.episodes import render_episode
            from rik.render.sheet import contact_sheet

            sim = render_episode(cat, by_id[r.episode], StreamSpec("sim", width, height), renders=out,
                                 variants=variants, cameras=list(r.cameras))
            png = contact_sheet([sim.directory, r.directory], r.directory.parent / f"compare-{spec.key}.png",
                                cameras=list(r.cameras))
            con.print(f"  side by side with the sim stream: {png}")


def render(episodes: EpisodesArg, res: ResOpt = "256", cameras: CamerasOpt = None,
           out: RendersOpt = Path("renders"), workers: WorkersOpt = 1, variants: VariantsOpt = Path("variants"),
           catalog: CatalogOption = None) -> None:
    """The sim stream: MuJoCo images of every camera, replayed from the recorded states (headless through EGL).
    Resumable: finished episodes are skipped, interrupted ones continue."""
    _run(episodes, "sim", res, cameras, out, variants, workers, catalog)


def rerender(episodes: EpisodesArg, res: ResOpt = "256",
             spp: Annotated[int, typer.Option("--spp", min=1, max=4096, help="Samples per pixel.")] = 16,
             denoise: Annotated[bool, typer.Option("--denoise/--no-denoise", help="Intel Open Image Denoise with "
                                                   "albedo and normal guides.")] = True,
             variant: Annotated[str, typer.Option("--variant", help="Mitsuba variant: auto (fastest that works "
                                                  "here), cuda_ad_rgb, llvm_ad_rgb or scalar_rgb.")] = "auto",
             cameras: CamerasOpt = None, out: RendersOpt = Path("renders"), workers: WorkersOpt = 1,
             sheet: Annotated[bool, typer.Option("--sheet/--no-sheet", help="Also render the sim stream at the "
                                                 "same size and write a PNG of the two side by side per "
                                                 "episode.")] = True,
             variants: VariantsOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """The re-rendered stream: every recorded state path-traced by Mitsuba 3 (materials from the catalog's
    finishes, a procedural room light, MuJoCo's cameras), denoised and tone-mapped to 8-bit sRGB. Resumable per
    frame. The LLVM and CUDA variants use every core: keep --workers 1 there."""
    _run(episodes, "rerendered", res, cameras, out, variants, workers, catalog, sheet=sheet, spp=spp,
         denoise=denoise, variant=variant)


def print_demo_renders(overlay_paths: list[Path], episodes: list[Path], out: Path = Path("renders"),
                       variants: Path = Path("variants"), res: int = DEMO_RES) -> None:
    """Render the demo episodes' sim streams and their Mitsuba re-renders (``res`` x ``res`` px), print how the two
    agree in silhouette on the first episode's first state and where the two streams are side by side
    (:mod:`rik.demo`)."""
    from rik.demo import DEMO_STREAMS, align_and_compare, frames_of, render_kind, stream_spec
    from rik.registry.load import load_catalog

    cat = load_catalog(overlay_paths)
    con = console()
    first = []
    for kind in DEMO_STREAMS:
        with progress_bar() as progress:
            task = progress.add_task(f"{stream_spec(kind, res).key} frames", total=frames_of(episodes), last="")
            # the ignore: mypy cannot infer the type of a lambda with a default argument
            results = render_kind(cat, episodes, kind, out, variants, res,
                                  progress=lambda n, t=task: progress.update(t, advance=n))  # type: ignore[misc]
        first.append(results[0])
        for r in results:
            con.print(f"stream {r.directory}: {r.frames} frames x {', '.join(r.cameras)}"
                      + (f", {r.seconds_per_frame:.2f} s per frame" if r.rendered else " (already rendered)"))
    ious, png = align_and_compare(cat, episodes[0], first, variants, res)
    con.print("alignment of the two streams, silhouette IoU at the first state: "
              + ", ".join(f"{cam} {v:.3f}" for cam, v in ious.items()))
    con.print(f"side by side: {png}")
    con.print("next: rik rerender episodes/ --res 256, rik visual-gap --real DIR --sim DIR --rerendered DIR")
