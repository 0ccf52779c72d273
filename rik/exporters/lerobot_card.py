"""The dataset card (``README.md``) of an export: lerobot's card template filled with what rik knows: how the
data were made, the catalog version, the resistance presets, the features, how to train on one image stream,
and the paper's citation. ``push`` sends the same fields to the Hub's card."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.exporters.layout import MERGED_FILE, MERGING
from rik.lerobot.arrow_cache import scratch_arrow_cache
from rik.outputs import Replaces, write_text

if TYPE_CHECKING:
    from rik.exporters.spec import ExportSpec
    from rik.registry.catalog import Catalog
    from rik.schemas.robots import Robot
    from rik.sim.robots.layout import RobotLayout

CITATION = """@misc{realikea,
  title  = {Real-IKEA: Physical Fidelity is the Prerequisite for Robust Manipulation},
  note   = {The Real-IKEA paper; see the paper for its authors and venue},
}"""
NORMALIZATION = {"act": '{"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}',
                 "diffusion": '{"VISUAL": "MEAN_STD", "STATE": "MIN_MAX", "ENV": "MIN_MAX", "ACTION": "MIN_MAX"}'}
"""``--policy.normalization_mapping`` for ``lerobot-train``, per policy: its default mapping plus ``ENV`` (lerobot
0.6.1's ACT and diffusion leave ``observation.environment_state`` unnormalised otherwise)."""
UNIT_WORDS = {"rad": "rad", "deg": "degrees", "fraction": "closure: 0 open, 1 closed",
              "percent": "percent of the opening: 100 open, 0 closed"}
LEROBOT_STEPS = 4096
"""Steps per turn of the STS3215's encoder (lerobot's ``MODEL_RESOLUTION['sts3215']``); its DEGREES mode divides by
one less: ``(raw - mid) * 360 / 4095``, 0.024 % more than the angle, less than a step within a half turn."""
CARD_FIELDS = "rik_card.json"
"""The card's fields, kept beside the dataset so that ``push`` can give the Hub the same card."""


def _presets_table(catalog: Catalog) -> str:
    """The catalog's default presets (those variants are built with when none is named) as a markdown table, and
    how many measured presets it holds besides (built when named; their hinges have effects a table of damping and
    friction does not show)."""
    lines = ["| preset | slide damping (N·s/m) | slide friction (N) | hinge damping (N·m·s/rad) "
             "| hinge friction (N·m) |", "|---|---|---|---|---|"]
    for p in (catalog.presets[k] for k in catalog.default_presets):
        lines.append(f"| {p.id} | {p.slide.damping:g} | {p.slide.frictionloss:g} | {p.hinge.damping:g} | "
                     f"{p.hinge.frictionloss:g} |")
    named = len(catalog.presets) - len(catalog.default_presets)
    if named:
        lines += ["", f"The catalog also holds {named} presets measured on real doors (`rik catalog list --kind "
                      "presets`); an episode uses one only where its `rik/preset` names it."]
    return "\n".join(lines)


def _names(names: tuple[str, ...]) -> str:
    return ", ".join(f"`{n}`" for n in names)


def _range(values: list[float], unit: str) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:g} {unit}" if lo == hi else f"{lo:g}-{hi:g} {unit}"


def robot_text(robot: Robot, layout: RobotLayout) -> str:
    """The card's section on the robot: its catalog name and id, its model's origin and licence, its mount, its
    joints' and gripper's simulation parameters with their sources, and (for LeRobot's SO follower) how a real
    arm's calibration maps onto its numbers (:func:`calibration_text`; markdown)."""
    g = robot.gripper
    lines = [f"**Robot: {robot.name}** (rik catalog robot `{robot.id}`, `robot_type` `{layout.robot_type}`).", "",
             f"- **Model:** {robot.model.origin}; licence {robot.model.licence}."]
    if robot.mount is not None:
        m = robot.mount
        side = ", on the side nearer the handle" if m.mirror else ""
        lines.append(f"- **Mount:** the base stands at ({', '.join(f'{v:g}' for v in m.offset)}) m from the handle's "
                     f"grasp point with the front closed (+x left, +y out of the front, +z up), heading {m.yaw:.3g} "
                     f"rad{side}: {m.reason}")
    if robot.joints is not None:
        j = robot.joints
        gravity = ("compensated by the controller (counted against each torque)" if j.gravity_compensation
                   else "not compensated")
        lines.append(f"- **Joints:** {len(j.joints)} position servos, torque capped at "
                     f"{_range([x.torque for x in j.joints], 'N·m')}, speed at most "
                     f"{_range([x.speed for x in j.joints], 'rad/s')}, stiffness "
                     f"{_range([x.stiffness for x in j.joints], 'N·m/rad')}; gravity {gravity}. Sources: {j.source}.")
    else:
        from rik.sim.robots.gripper import HAND_E

        lines.append(f"- **Base:** six servoed axes, forces capped at {HAND_E.arm_force:g} N and torques at "
                     f"{HAND_E.arm_torque:g} N·m (a collaborative arm's order of magnitude; an assumption).")
    lines.append(f"- **Gripper:** {g.name} ({g.kind}, {g.stroke * 1000:g} mm stroke); grip force "
                 f"{g.grip_force.value:g} N ({g.grip_force.source}); pad friction {g.pad_friction.value:g} "
                 f"({g.pad_friction.source}); finger speed {g.finger_speed.value:g} m/s ({g.finger_speed.source}).")
    if g.actuation is not None and g.actuation.force_limit is not None:
        lines.append(f"- **Gripper servo:** force capped at {g.actuation.force_limit.value:g} N·m "
                     f"({g.actuation.force_limit.source}).")
    if robot.joints is not None:
        feature = {joint: name for name, (joint, _) in zip(layout.state_names, layout.joints, strict=True)}
        lines += ["", "| joint | feature | range (rad) | torque (N·m) | speed (rad/s) | stiffness (N·m/rad) "
                      "| damping (N·m·s/rad) |", "|---|---|---|---|---|---|---|"]
        lines += [f"| {x.name} | `{feature.get(x.name, '-')}` | {x.range[0]:g} .. {x.range[1]:g} | {x.torque:g} | "
                  f"{x.speed:g} | {x.stiffness:g} | {x.damping:g} |" for x in robot.joints.joints]
    note = calibration_text(robot, layout)
    if note:
        lines += ["", note]
    return "\n".join(lines)


def calibration_text(robot: Robot, layout: RobotLayout) -> str:
    """For an arm whose layout counts joints from mid-range (LeRobot's SO follower): how a real follower's
    calibration file maps onto the dataset's numbers, with each joint's 0 and the gripper's ends (markdown; empty
    for other layouts)."""
    import math

    act = robot.gripper.actuation
    if layout.is_pose or robot.joints is None or act is None or not any(
            e.zero == "mid_range" for e in robot.lerobot.joints):
        return ""
    mid = [(name, joint, zero) for name, (joint, _), zero in zip(layout.state_names, layout.joints, layout.zeros,
                                                                  strict=True) if joint is not None]
    ranges = {j.name: j.range for j in robot.joints.joints}
    rows = "\n".join(f"| `{name}` | {joint} | {math.degrees(ranges[joint][0]):.1f} .. "
                     f"{math.degrees(ranges[joint][1]):.1f} | {math.degrees(zero):.1f} |" for name, joint, zero in mid)
    same = act.ctrl_open == act.joint_open and act.ctrl_closed == act.joint_closed
    command = ("the jaw servo's goal on the same scale, as a real follower's `Goal_Position`" if same else
               f"rik's grip command on the same scale: 100 sets the jaw's goal at {act.ctrl_open:g} rad, 0 at "
               f"{act.ctrl_closed:g} rad, past the closed end, so that the jaw presses what it holds with its servo's "
               "capped force (a real follower's goal of 0 is the closed end, where its servo presses what it holds "
               "with the force its P gain and torque limit give)")
    return f"""**Calibration (LeRobot's SO follower).** The body joints are in degrees from the middle of each joint's
range in the simulated model, where LeRobot's calibration puts a real arm's 0: `lerobot-calibrate` homes each motor
at the middle of its travel and records its range of motion (`range_min`, `range_max` in the calibration file
`~/.cache/huggingface/lerobot/calibration/robots/so_follower/<id>.json`, in steps of {LEROBOT_STEPS} a turn;
`wrist_roll` gets the whole turn, 0-4095, so its 0 is the pose it was homed in), and the follower then reports
`(raw - (range_min + range_max) / 2) * 360 / 4095` degrees. So a real arm reads the numbers here where its recorded
range of motion is the model's range below, centred where the model's is (for `wrist_roll`: homed at the middle of
the model's range); a real joint whose recorded range is off-centre from the model's by some degrees reads those
degrees more or less than rik (measure it once, e.g. with the arm in a pose you can set in both, and add it to one
side). The model's joint directions are taken as the servos'. rik writes plain degrees; LeRobot's 360/4095 scale
differs from them by less than one step (0.088 degrees) within a half turn.

| feature | model joint | model range (degrees) | 0 of the feature at the model's (degrees) |
|---|---|---|---|
{rows}

`gripper.pos` is 0 with the jaw at {act.joint_closed:g} rad (closed) and 100 at {act.joint_open:g} rad (open), linear
in the jaw's angle between: LeRobot's `RANGE_0_100`, `(raw - range_min) / (range_max - range_min) * 100`, with a
calibration whose `range_min` is the closed jaw and `range_max` the open one (the follower's gripper is recorded so:
0 closed, 100 open). Its action is {command}."""


def _layout_bullets(layout: RobotLayout, joint_driven: int = 0) -> tuple[str, str]:
    """The card's bullets of an arm: on ``observation.state`` (and ``observation.ee_pose``), and on ``action``;
    ``joint_driven`` episodes were driven joint by joint (a leader arm), not through the IK."""
    from rik.sim.robots.layout import EE_NAMES

    numbers = ", ".join(f"`{name}` ({UNIT_WORDS[unit]})"
                        for name, (_, unit) in zip(layout.state_names, layout.joints, strict=True))
    state = (f"- **`observation.state`** (robot {layout.robot_id}'s joints, {len(layout.state_names)} numbers, "
             f"LeRobot's names for this robot): {numbers}.\n")
    if layout.ee_pose:
        state += (f"- **`observation.ee_pose`**: the gripper frame (between the pads) in the arm's base frame, "
                  f"{_names(EE_NAMES[:3])} (m) and the rotation vector {_names(EE_NAMES[3:])} (rad).\n")
    action = ("- **`action`:** the joint targets the arm's position servos were given at each step (rik's "
              "differential IK turns the operator's target pose into them), in the names and units of "
              "`observation.state`; the gripper's entry is the gripper command.\n")
    if joint_driven:  # a leader arm's episodes: its readings were the targets, no IK between
        action = ("- **`action`:** the joint targets the arm's position servos were given at each step, in the names "
                  "and units of `observation.state`; the gripper's entry is the gripper command. In "
                  f"{joint_driven} episode(s) a leader arm drove the joints (its readings are the targets, as a real "
                  "follower takes them); in the others rik's differential IK turned the operator's target pose into "
                  "them.\n")
    return state, action


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


def _description(catalog: Catalog, spec: ExportSpec, fps: int, checks: dict[str, Any], info: dict[str, Any],
                 robot: Robot, joint_driven: int = 0) -> str:
    import rik
    from rik.sim.robots.layout import robot_layout

    layout = robot_layout(robot.as_arm, spec.io.action_frame)
    handle_shape = spec.io.handle_shape
    images = [k for k, f in info["features"].items() if f.get("dtype") == "video"]
    sim_only = [k for k in images if not k.endswith("_rerendered")]
    from rik.sim.observation import ENV_STATE_NAMES, GRIPPER_GRASP_NAMES, HANDLE_SHAPES, ROBOT_STATE_NAMES

    if images:
        streams = f"""- **Image streams:** {', '.join(f'`{k}`' for k in images)}. Keys without a suffix are MuJoCo's own
  rendering (the sim stream); `_rerendered` keys are the same states path-traced offline by Mitsuba 3
  ({spec.spp} spp{', denoised by Intel Open Image Denoise' if spec.denoise else ''}), pixel-aligned with the sim
  stream. Images are {spec.io.width}x{spec.io.height}, codec {spec.codec}.{sim_settings_text(spec)}
"""
        one_stream = f"""**Training on one stream.** Policies take every `observation.*` feature by default. To train on
the sim stream only, give the policy's `input_features` just `observation.state`, \
{'`observation.ee_pose`, ' if layout.ee_pose else ''}`observation.environment_state` and
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
    if layout.is_pose:
        action = ("- **`action`:** the commanded target pose of the gripper base (m, rad) and the gripper "
                  "command (0 open, 1 closed).\n")
        if layout.action_frame == "handle":
            action = ("- **`action`** (in the handle frame, `--action-frame handle`): the commanded target position "
                      "of the gripper base less the handle's grasp point of the same step's "
                      "`observation.environment_state` (`target_dx`, `target_dy`, `target_dz`: m, world axes), its "
                      "pitch, yaw, roll (rad) and the gripper command (0 open, 1 closed). rik's environment takes it "
                      "with `action_mode=\"handle\"` (`--env.action_frame=handle`; `auto` reads it from the "
                      "policy's training statistics).\n")
        if layout.action_frame == "gripper":
            action = ("- **`action`** (in the gripper frame, `--action-frame gripper`): the commanded target position "
                      "of the gripper base less the gripper base's position of the same step's `observation.state` "
                      "(`target_from_gripper_x`, `_y`, `_z`: m, world axes), its pitch, yaw, roll (rad) and the "
                      "gripper command (0 open, 1 closed); `observation.environment_state` holds the handle's grasp "
                      "point from the gripper base too (`grasp_from_gripper_x`, `_y`, `_z`, m). rik's environment "
                      "takes it with `action_mode=\"gripper\"` (`--env.action_frame=gripper`; `auto` reads it from "
                      "the policy's environment-state width).\n")
        state = f"""- **`observation.state`** (the robot's state, {len(ROBOT_STATE_NAMES)} numbers, rik's state layout
  {checks.get('layout', 2)}): {_names(ROBOT_STATE_NAMES)}: the gripper base's position (m, world) and pitch, yaw,
  roll (rad), the jaw opening (m), the pads' centre (m, world) and the fingers' normal force on the front (N).
"""
    else:
        state, action = _layout_bullets(layout, joint_driven)
    state_text = state + (f"""- **`observation.environment_state`** (the front's state, {len(ENV_STATE_NAMES)} numbers):
  {_names(ENV_STATE_NAMES)}: the front's joint position (m for a drawer, rad for a door or flap) and velocity (m/s
  or rad/s), its opening (fraction of the range), the handle's grasp point (m, world), its orientation (unit
  quaternion w, x, y, z with w >= 0, world) and the unit direction in which the grasp point moves as the front
  opens (world).
""" if spec.io.environment_state else """- **No `observation.environment_state`** (`--no-environment-state`): the
  simulator's state of the front and its handle is left out, so a policy learns from the robot's own state and the
  images, as a real robot would have them; rik's environment then gives none either (its contract,
  `meta/rik_policy_io.json`, says `environment_state: false`).
""")
    if layout.action_frame == "gripper":
        before = ", before the handle's shape" if handle_shape != "none" else ""
        count = len(GRIPPER_GRASP_NAMES)
        state_text += f"""- **The grasp point from the gripper** (`--action-frame gripper`: {count} more numbers after
  the front's state{before}): {_names(GRIPPER_GRASP_NAMES)}: the handle's grasp point less the gripper base's
  position (m, world axes).
"""
    if handle_shape != "none":
        shape = HANDLE_SHAPES[handle_shape]
        what = ("the handle's type and mount as 0/1 flags, then the catalog's length, width, projection, grip "
                "diameter and finger clearance (depth, width; 0 where none), m" if handle_shape == "full"
                else "the handle's type and mount as 0/1 flags")
        state_text += f"""- **The handle's shape** (`--handle-shape {handle_shape}`: {len(shape)} more numbers at
  the end of `observation.environment_state`, constant through an episode): {_names(shape)}: {what}. rik's
  environment appends them with `handle_shape="{handle_shape}"`
  (`--env.handle_shape={handle_shape}`; `rik eval` and `auto` read it from the policy's input width).
"""
    state_text += action
    if checks.get("constant"):
        parts = "; ".join(f"`{k}`: {', '.join(f'`{n}`' for n in v)}" for k, v in checks["constant"].items())
        state_text += f"""- **Constant dimensions** (standard deviation below 1e-6 over the whole dataset): {parts}.
  They never change here (one variant, one handle pose), so `MEAN_STD` normalisation divides by about zero
  there: a policy trained on this dataset reads any other value (another handle, another unit) as far out of its
  training range. Train on more variants, or leave those dimensions out.
"""
    who = "gripper" if layout.is_pose else f"robot arm ({robot.name})"
    return f"""Episodes of a simulated {who} opening articulated furniture (drawers, doors and flaps with real
handle geometry), scripted or teleoperated in MuJoCo, exported by rik (Real-IKEA kit) {rik.__version__}, catalog
schema {rik.CATALOG_SCHEMA}.

- **Episodes:** {checks['episodes']}, **frames:** {checks['frames']} at {fps} Hz; {frames}
{streams}{state_text}- **Task:** one instruction per episode, e.g. "open the drawer by its bow handle".
- **Episode metadata:** columns `rik/variant`, `rik/base_unit`, `rik/handle`, `rik/handle_type`, `rik/preset`,
  `rik/front`, `rik/operator`, `rik/operator_kind`, `rik/outcome` (F, P or S), `rik/seed`, `rik/final_opening`
  of `meta/episodes`; filter with `LeRobotDataset(..., episode_filter=lambda e: e["rik/outcome"] == "S")`.

{robot_text(robot, layout)}

{training_text()}

{one_stream}**Joint resistance presets** of the catalog:

{_presets_table(catalog)}
"""


def card_fields(root: Path) -> dict[str, str]:
    """The fields of lerobot's card template that rik fills (saved at export time)."""
    return json.loads((Path(root) / "meta" / CARD_FIELDS).read_text(encoding="utf-8"))


@scratch_arrow_cache()
def write_card(catalog: Catalog, root: Path, spec: ExportSpec, fps: int, checks: dict[str, Any],
               extra: str = "", robot: str = "hand-e", joint_driven: int = 0) -> Path:
    """Write ``README.md`` (lerobot's dataset card, filled in) and the card's fields into the dataset; ``extra``
    (markdown) is added to the description (how a built dataset was made: :mod:`rik.dataset.build`); ``robot``: the
    catalog robot whose episodes it holds; ``joint_driven``: how many of them a leader arm drove joint by joint."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import create_lerobot_dataset_card


    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    description = (_description(catalog, spec, fps, checks, info, catalog.robot(robot), joint_driven)
                   + (f"\n{extra}\n" if extra else ""))
    fields = {"dataset_description": description,
              "paper": "Real-IKEA (see CITATION below)", "citation_bibtex": CITATION}
    write_text(root / "meta" / CARD_FIELDS, json.dumps(fields, indent=1) + "\n", MERGED_FILE)
    meta = LeRobotDatasetMetadata(spec.repo_id, root=root)
    card = create_lerobot_dataset_card(tags=["rik", "mujoco", "articulated-furniture"], dataset_info=meta.info,
                                       license="apache-2.0", repo_id=spec.repo_id, **fields)
    write_text(root / "README.md", str(card), Replaces.in_folder(MERGING))
    return root / "README.md"


def sim_settings_text(spec: ExportSpec) -> str:
    """The sim stream's render settings as the card says them (empty without a sim stream)."""
    if "sim" not in spec.io.streams:
        return ""
    stream = spec.stream("sim")
    return (f" MuJoCo rendered the sim stream with {stream.sim.shadow_size} px shadow maps and "
            f"{stream.sim.multisamples}x multisampling (stream `{stream.key}`; another setting is another stream).")
