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
NORMALIZATION = {"act": '{"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}',
                 "diffusion": '{"VISUAL": "MEAN_STD", "STATE": "MIN_MAX", "ENV": "MIN_MAX", "ACTION": "MIN_MAX"}'}
"""``--policy.normalization_mapping`` for ``lerobot-train``, per policy: its default mapping plus ``ENV`` (lerobot
0.6.1's ACT and diffusion leave ``observation.environment_state`` unnormalised otherwise)."""
CARD_FIELDS = "rik_card.json"
"""The card's fields, kept beside the dataset so that ``push`` can give the Hub the same card."""


def _presets_table(catalog: Catalog) -> str:
    lines = ["| preset | slide damping (N·s/m) | slide friction (N) | hinge damping (N·m·s/rad) "
             "| hinge friction (N·m) |", "|---|---|---|---|---|"]
    for p in catalog.presets.values():
        lines.append(f"| {p.id} | {p.slide.damping:g} | {p.slide.frictionloss:g} | {p.hinge.damping:g} | "
                     f"{p.hinge.frictionloss:g} |")
    return "\n".join(lines)


def _names(names: tuple[str, ...]) -> str:
    return ", ".join(f"`{n}`" for n in names)


def training_text() -> str:
    """How to train ACT or diffusion on an export with ``lerobot-train`` (markdown; the card and docs say it)."""
    return f"""**Training with `lerobot-train`.** `observation.environment_state` is a feature of type ENV, and the
default `normalization_mapping` of lerobot 0.6.1's ACT and diffusion policies covers VISUAL, STATE and ACTION only,
so without help the front's state reaches the policy unnormalised. Pass the mapping with ENV added, e.g. for ACT

```bash
lerobot-train --dataset.repo_id=OWNER/NAME --dataset.root=DIR --policy.type=act --policy.push_to_hub=false \\
  --policy.normalization_mapping='{NORMALIZATION["act"]}'
```

and for diffusion (its defaults normalise state and action by min and max)
`--policy.normalization_mapping='{NORMALIZATION["diffusion"]}'`."""


def _description(catalog: Catalog, spec: ExportSpec, fps: int, checks: dict[str, Any], info: dict[str, Any]) -> str:
    import rik
    images = [k for k, f in info["features"].items() if f.get("dtype") == "video"]
    sim_only = [k for k in images if not k.endswith("_rerendered")]
    from rik.sim.observation import ENV_STATE_NAMES, ROBOT_STATE_NAMES

    if images:
        streams = f"""- **Image streams:** {', '.join(f'`{k}`' for k in images)}. Keys without a suffix are MuJoCo's own
  rendering (the sim stream); `_rerendered` keys are the same states path-traced offline by Mitsuba 3
  ({spec.spp} spp{', denoised by Intel Open Image Denoise' if spec.denoise else ''}), pixel-aligned with the sim
  stream. Images are {spec.width}x{spec.height}, codec {spec.codec}.
"""
        one_stream = f"""**Training on one stream.** Policies take every `observation.*` feature by default. To train on
the sim stream only, give the policy's `input_features` just `observation.state`, `observation.environment_state` and
{', '.join(f'`{k}`' for k in sim_only)} (or the `_rerendered` keys for the re-rendered stream), or drop the other keys
in your data loader.

"""
        frames = "every episode's decoded video\n  frames were checked to equal its rows."
    else:
        streams = """- **Images:** none: a state-only export (`--streams none`), for policies that learn from the two
  state vectors alone (ACT and diffusion accept `observation.environment_state` in place of an image).
"""
        one_stream = ""
        frames = "a state-only export (no videos)."
    return f"""Episodes of a simulated gripper opening articulated furniture (drawers, doors and flaps with real
handle geometry), scripted or teleoperated in MuJoCo, exported by rik (Real-IKEA kit) {rik.__version__}, catalog
schema {rik.CATALOG_SCHEMA}.

- **Episodes:** {checks['episodes']}, **frames:** {checks['frames']} at {fps} Hz; {frames}
{streams}- **`observation.state`** (the robot's state, {len(ROBOT_STATE_NAMES)} numbers, rik's state layout
  {checks.get('layout', 2)}): {_names(ROBOT_STATE_NAMES)}: the gripper base's position (m, world) and pitch, yaw,
  roll (rad), the jaw opening (m), the pads' centre (m, world) and the fingers' normal force on the front (N).
- **`observation.environment_state`** (the front's state, {len(ENV_STATE_NAMES)} numbers):
  {_names(ENV_STATE_NAMES)}: the front's joint position (m for a drawer, rad for a door or flap) and velocity (m/s
  or rad/s), its opening (fraction of the range), the handle's grasp point (m, world), its orientation (unit
  quaternion w, x, y, z with w >= 0, world) and the unit direction in which the grasp point moves as the front
  opens (world).
- **`action`:** the commanded target pose of the gripper base (m, rad) and the gripper command (0 open, 1 closed).
- **Task:** one instruction per episode, e.g. "open the drawer by its bow handle".
- **Episode metadata:** columns `rik/variant`, `rik/base_unit`, `rik/handle`, `rik/handle_type`, `rik/preset`,
  `rik/front`, `rik/operator`, `rik/operator_kind`, `rik/outcome` (F, P or S), `rik/seed`, `rik/final_opening`
  of `meta/episodes`; filter with `LeRobotDataset(..., episode_filter=lambda e: e["rik/outcome"] == "S")`.

{training_text()}

{one_stream}**Joint resistance presets** of the catalog:

{_presets_table(catalog)}
"""


def card_fields(root: Path) -> dict[str, str]:
    """The fields of lerobot's card template that rik fills (saved at export time)."""
    return json.loads((Path(root) / "meta" / CARD_FIELDS).read_text(encoding="utf-8"))


def write_card(catalog: Catalog, root: Path, spec: ExportSpec, fps: int, checks: dict[str, Any],
               extra: str = "") -> Path:
    """Write ``README.md`` (lerobot's dataset card, filled in) and the card's fields into the dataset; ``extra``
    (markdown) is added to the description (how a built dataset was made: :mod:`rik.dataset.build`)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import create_lerobot_dataset_card

    from rik.paths import write_atomic

    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    description = _description(catalog, spec, fps, checks, info) + (f"\n{extra}\n" if extra else "")
    fields = {"dataset_description": description,
              "paper": "Real-IKEA (see CITATION below)", "citation_bibtex": CITATION}
    write_atomic(root / "meta" / CARD_FIELDS, json.dumps(fields, indent=1) + "\n")
    meta = LeRobotDatasetMetadata(spec.repo_id, root=root)
    card = create_lerobot_dataset_card(tags=["rik", "mujoco", "articulated-furniture"], dataset_info=meta.info,
                                       license="apache-2.0", repo_id=spec.repo_id, **fields)
    write_atomic(root / "README.md", str(card))
    return root / "README.md"
