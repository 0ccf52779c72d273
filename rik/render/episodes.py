"""Rendering recorded episodes: set each recorded state back into the episode's scene and render every camera,
into a resumable stream folder (:mod:`rik.render.streams`). Episodes are only read, never changed; an episode read
once (:class:`RecordedEpisode`) gives every stream rendered from it, and the export's frames, its states and scene."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.episodes.recorded import RecordedEpisode
from rik.errors import RikError
from rik.render.renderers import reused_renderer
from rik.render.streams import StreamSpec, StreamWriter, is_done, read_manifest, stream_dir

if TYPE_CHECKING:
    import mujoco

    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.scene import SimScene


def check_renders_outside(renders: Path, episodes: dict[Path, str], option: str = "--out") -> None:
    """Refuse (one line) a renders folder that is an episode folder or inside one, or whose stream folder of an
    episode (``renders/<id>``) would be that episode's folder: episodes are only read, never written into.
    ``episodes`` maps each episode folder to its id."""
    root = Path(renders).resolve()
    for d, episode_id in episodes.items():
        home = Path(d).resolve()
        if root.is_relative_to(home) or (root / episode_id).resolve().is_relative_to(home):
            raise RikError(f"{option} {renders}: would write the streams inside episode folder {d}; rik never writes "
                           f"into an episode: give {option} outside the episodes, e.g. renders")


@dataclass(frozen=True)
class StreamResult:
    episode: str
    directory: Path
    frames: int
    cameras: tuple[str, ...]
    rendered: int
    """Frames rendered by this call (0 when the stream was already finished)."""
    seconds_per_frame: float
    """Render time per frame (all cameras) of the frames rendered by this call, s."""


def scene_cameras(model: mujoco.MjModel, wanted: Sequence[str] | None, where: str) -> list[str]:
    """The scene's camera names (all, in model order), or the ``wanted`` ones after checking they exist."""
    import mujoco

    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam)]
    if not wanted:
        return names
    for cam in wanted:
        if cam not in names:
            raise RikError(f"{where}: no camera '{cam}' in the scene (cameras: {', '.join(names)})")
    return list(wanted)


def _episode_scene(catalog: Catalog, episode: RecordedEpisode, variants: Path) -> SimScene:
    """The episode's scene for rendering; one that cannot be built names the episode's variant."""
    try:
        return episode.scene(catalog, variants)
    except RikError as exc:
        raise RikError(f"{episode.directory / 'meta.json'}: field 'variant': cannot load {episode.meta.variant} "
                       f"from {variants} or rebuild it from the catalog: {exc}") from None


def render_episode(catalog: Catalog, episode: Path | RecordedEpisode, spec: StreamSpec, *, renders: Path,
                   variants: Path = Path("variants"), cameras: Sequence[str] | None = None,
                   progress: Callable[[int], None] | None = None) -> StreamResult:
    """Render one stream of ``episode`` (its folder, or the episode already read, whose states and scene the
    caller's other streams share) into ``renders``; resumes an interrupted render and returns at once when the
    stream is already finished (reading only the meta). ``progress(n)`` is called as frames are done."""
    from rik.locks import exclusive

    recorded = episode if isinstance(episode, RecordedEpisode) else RecordedEpisode(episode)
    final = stream_dir(renders, recorded.meta.id, spec)
    done = _finished(final, recorded.meta, cameras, progress)
    if done is not None:
        return done
    with exclusive(final, "rik render", wait=True):  # one process renders a stream; others wait, then reuse it
        done = _finished(final, recorded.meta, cameras, progress)
        if done is not None:
            return done
        return _render_stream(catalog, recorded, spec, final, variants, cameras, progress)


def _finished(final: Path, meta: EpisodeMeta, cameras: Sequence[str] | None,
              progress: Callable[[int], None] | None) -> StreamResult | None:
    """The result of the finished stream at ``final`` when it holds these states and cameras, else None."""
    if not is_done(final, meta.states_sha256):
        return None
    manifest = read_manifest(final) or {}
    if cameras and not set(cameras) <= set(manifest.get("cameras", [])):
        return None
    if progress:
        progress(int(manifest.get("frames", 0)))
    return StreamResult(meta.id, final, int(manifest.get("frames", 0)), tuple(manifest.get("cameras", ())),
                        0, float(manifest.get("seconds_per_frame", 0.0)))


def _render_stream(catalog: Catalog, episode: Path | RecordedEpisode, spec: StreamSpec, final: Path, variants: Path,
                   cameras: Sequence[str] | None, progress: Callable[[int], None] | None) -> StreamResult:
    """Render (or resume) the stream of ``episode`` (its folder, or the episode read) into ``final``, holding its
    lock."""
    episode = episode if isinstance(episode, RecordedEpisode) else RecordedEpisode(episode)
    recorded = episode.states
    scene = _episode_scene(catalog, episode, variants)
    meta = episode.meta
    cams = scene_cameras(scene.model, cameras, str(episode.directory))
    writer = StreamWriter(final, spec, cams, len(recorded), meta.states_sha256)
    todo = list(writer.missing())
    if progress and len(recorded) > len(todo):
        progress(len(recorded) - len(todo))
    info: dict[str, Any] = {"renderer": "resumed", "render_seconds": 0.0}
    if todo:
        scene.restore(recorded[todo[0]])
        renderer = reused_renderer(scene.model, scene.data, cams, spec, catalog.finishes)
        for k in todo:
            scene.restore(recorded[k])
            for cam, image in renderer.render(scene.data, k).items():
                writer.write(k, cam, image)
            if progress:
                progress(1)
        info = renderer.info()
    per_frame = info["render_seconds"] / len(todo) if todo else 0.0
    info.update(episode=meta.id, episode_variant=meta.variant, fps=meta.fps, seconds_per_frame=round(per_frame, 4))
    info["render_seconds"] = round(info["render_seconds"], 3)
    writer.publish(info)
    return StreamResult(meta.id, final, len(recorded), tuple(cams), len(todo), per_frame)


def _render_one(spec: StreamSpec, renders: Path, variants: Path, cameras: tuple[str, ...] | None,
                catalog: Catalog, directory: str) -> StreamResult:
    return render_episode(catalog, Path(directory), spec, renders=renders, variants=variants, cameras=cameras)


def render_episodes(catalog: Catalog, episodes: Sequence[Path], spec: StreamSpec, *, renders: Path,
                    variants: Path = Path("variants"), cameras: Sequence[str] | None = None, workers: int = 1,
                    overlays: Sequence[Path] = (), progress: Callable[[int], None] | None = None
                    ) -> Iterator[StreamResult]:
    """Render ``spec``'s stream of every episode (in ``workers`` processes when more than one), yielding each
    result as it finishes. With one worker, ``progress`` advances frame by frame; with more, episode by episode."""
    from rik.episodes.episode import read_meta
    from rik.workers import map_ids

    metas = {str(d): read_meta(d) for d in episodes}  # every episode readable before any work starts
    check_renders_outside(renders, {Path(d): m.id for d, m in metas.items()})
    cams = tuple(cameras) if cameras else None
    if workers > 1 and len(episodes) > 1:
        fn = partial(_render_one, spec, Path(renders), Path(variants), cams)
        for _, result in map_ids(fn, catalog, list(metas), workers=workers, overlays=overlays):
            if progress:
                progress(result.frames)
            yield result
        return
    for d, meta in metas.items():
        yield render_episode(catalog, RecordedEpisode(Path(d), meta), spec, renders=renders, variants=variants,
                             cameras=cams, progress=progress)
