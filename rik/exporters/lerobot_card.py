"""The dataset card (``README.md``) of an export: lerobot's card template filled with what rik knows: how the
data were made, the catalog version, the resistance presets, the features, how to train on one image stream,
and the paper's citation. ``push`` sends the same fields to the Hub's card."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rik.exporters.lerobot_export import ExportSpec
    from rik.registry.catalog import Catalog

CITATION = """@misc{realikea,
  title  = {Real-IKEA: Physical Fidelity is the Prerequisite for Robust Manipulation},
  note   = {The Real-IKEA paper; see the paper for its authors and venue},
}"""
CARD_FIELDS = "rik_card.json"
"""The card's fields, kept beside the dataset so that ``push`` can give the Hub the same card."""


def _presets_table(catalog: Catalog) -> str:
    lines = ["| preset | slide damping (N·s/m) | slide friction (N) | hinge damping (N·m·s/rad) "
             "| hinge friction (N·m) |", "|---|---|---|---|---|"]
    for p in catalog.presets.values():
        lines.append(f"| {p.id} | {p.slide.damping:g} | {p.slide.frictionloss:g} | {p.hinge.damping:g} | "
                     f"{p.hinge.frictionloss:g} |")
    return "\n".join(lines)


def _description(catalog: Catalog, spec: ExportSpec, fps: int, checks: dict[str, Any], info: dict[str, Any]) -> str:
    import rik
    images = [k for k, f in info["features"].items() if f.get("dtype") == "video"]
    sim_only = [k for k in images if not k.endswith("_rerendered")]
    return f"""Episodes of a simulated gripper opening articulated furniture (drawers, doors and flaps with real
handle geometry), scripted or teleoperated in MuJoCo, exported by rik (Real-IKEA kit) {rik.__version__}, catalog
schema {rik.CATALOG_SCHEMA}.

- **Episodes:** {checks['episodes']}, **frames:** {checks['frames']} at {fps} Hz; every episode's decoded video
  frames were checked to equal its rows.
- **Image streams:** {', '.join(f'`{k}`' for k in images)}. Keys without a suffix are MuJoCo's own rendering
  (the sim stream); `_rerendered` keys are the same states path-traced offline by Mitsuba 3
  ({spec.spp} spp{', denoised by Intel Open Image Denoise' if spec.denoise else ''}), pixel-aligned with the sim
  stream. Images are {spec.width}x{spec.height}, codec {spec.codec}.
- **`observation.state`:** gripper base pose (m, rad), jaw opening (m), the front's joint position and velocity,
  the pads' centre (m), the opening (fraction of the range) and the gripper's normal force on the front (N).
- **`action`:** the commanded target pose of the gripper base (m, rad) and the gripper command (0 open, 1 closed).
- **Task:** one instruction per episode, e.g. "open the drawer by its bow handle".
- **Episode metadata:** columns `rik/variant`, `rik/base_unit`, `rik/handle`, `rik/handle_type`, `rik/preset`,
  `rik/front`, `rik/operator`, `rik/operator_kind`, `rik/outcome` (F, P or S), `rik/seed`, `rik/final_opening`
  of `meta/episodes`; filter with `LeRobotDataset(..., episode_filter=lambda e: e["rik/outcome"] == "S")`.

**Training on one stream.** Policies take every `observation.*` feature by default. To train on the sim stream only,
give the policy's `input_features` just `observation.state` and {', '.join(f'`{k}`' for k in sim_only)} (or the
`_rerendered` keys for the re-rendered stream), or drop the other keys in your data loader.

**Joint resistance presets** of the catalog:

{_presets_table(catalog)}
"""


def card_fields(root: Path) -> dict[str, str]:
    """The fields of lerobot's card template that rik fills (saved at export time)."""
    return json.loads((Path(root) / "meta" / CARD_FIELDS).read_text(encoding="utf-8"))


def write_card(catalog: Catalog, root: Path, spec: ExportSpec, fps: int, checks: dict[str, Any]) -> Path:
    """Write ``README.md`` (lerobot's dataset card, filled in) and the card's fields into the dataset."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import create_lerobot_dataset_card

    from rik.paths import write_atomic

    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    fields = {"dataset_description": _description(catalog, spec, fps, checks, info),
              "paper": "Real-IKEA (see CITATION below)", "citation_bibtex": CITATION}
    write_atomic(root / "meta" / CARD_FIELDS, json.dumps(fields, indent=1) + "\n")
    meta = LeRobotDatasetMetadata(spec.repo_id, root=root)
    card = create_lerobot_dataset_card(tags=["rik", "mujoco", "articulated-furniture"], dataset_info=meta.info,
                                       license="apache-2.0", repo_id=spec.repo_id, **fields)
    write_atomic(root / "README.md", str(card))
    return root / "README.md"
