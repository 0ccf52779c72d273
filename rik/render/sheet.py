"""Contact sheets: frames of an episode's streams side by side (rows: moments of the episode; columns: each
camera in each stream), so the sim stream and its re-render can be compared at a glance."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rik.outputs import Replaces, write_png
from rik.render.streams import is_stream, read_frame, read_manifest

GAP_PX = 4
SHEET = Replaces.when("a contact sheet rik drew beside an episode's streams",
                      lambda p: p.suffix == ".png" and any(is_stream(d) for d in p.parent.iterdir() if d.is_dir()))
"""What a contact sheet may replace: rik's earlier sheet, in a folder of an episode's streams."""


def contact_sheet(streams: list[Path], out: Path, rows: int = 3, cameras: list[str] | None = None) -> Path:
    """Write a PNG of ``rows`` evenly spaced frames from each finished stream folder in ``streams`` (which must
    share frame count and image size), every camera of each; returns ``out``."""
    from PIL import Image, ImageDraw

    manifests = [read_manifest(s) or {} for s in streams]
    frames = min(int(m.get("frames", 0)) for m in manifests)
    cams = cameras or list(manifests[0].get("cameras", []))
    picks = [int(k) for k in np.linspace(0, frames - 1, rows)]
    tiles = [[read_frame(s, cam, k) for cam in cams for s in streams] for k in picks]
    h, w = tiles[0][0].shape[:2]
    label_h = 14
    ncol = len(tiles[0])
    sheet = Image.new("RGB", (ncol * w + (ncol - 1) * GAP_PX, label_h + rows * h + (rows - 1) * GAP_PX), "white")
    draw = ImageDraw.Draw(sheet)
    for c, (cam, m) in enumerate((cam, m) for cam in cams for m in manifests):
        draw.text((c * (w + GAP_PX) + 2, 1), f"{cam}: {m.get('stream', '?')}", fill="black")
    for r, row in enumerate(tiles):
        for c, tile in enumerate(row):
            sheet.paste(Image.fromarray(tile), (c * (w + GAP_PX), label_h + r * (h + GAP_PX)))
    write_png(out, np.asarray(sheet), SHEET)
    return out
