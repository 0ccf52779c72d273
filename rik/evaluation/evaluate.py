"""``rik eval``: a saved LeRobot policy (or a scripted strategy) on rik's benchmark, as the paper's Table 3.

Episodes are the seeds ``seed .. seed + cells x N - 1`` of a draw (:mod:`rik.episodes.draw`): each falls in one cell
(handle type x preset) and names one variant, front and start pose, the same as ``lerobot-eval --env.type=rik
--seed S`` runs. A learned policy runs through lerobot's own ``rollout`` (``lerobot.scripts.lerobot_eval``) on a
one-environment vector env made by the ``--env.type=rik`` config (:mod:`rik.lerobot.env_config`), so both tools
execute the same code per episode, with the policy's contract (:mod:`rik.lerobot.policy_io`: read from its folder,
not guessed, where it was trained on a rik export that wrote one). A scripted strategy (``strategy:contact_rich``)
runs its operator in the same environment, so scripted and learned rows are paired episode by episode. ``robot`` (a
catalog id) runs either with that robot: a learned policy must read and write that robot's layout
(:mod:`rik.sim.robots.layout`; an arm takes joint actions), a scripted strategy drives any robot by target poses.

Outputs (in ``--out``): ``table.md`` (F/P/S per handle type x preset, with Wilson intervals for S),
``episodes.csv`` (one row per episode), ``eval_info.json`` (lerobot-eval's layout: ``per_task``, ``per_group``,
``overall``; rik's rows under ``rik``) and ``videos/`` (the front camera of the first few episodes).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.episodes.draw import DEFAULT_KINDS, DEFAULT_PRESETS, DEFAULT_TYPES
from rik.errors import RikError
from rik.lerobot.features import check_renderer
from rik.lerobot.observation_use import observation_use
from rik.lerobot.policy_files import check_policy_folder
from rik.lerobot.policy_io import AUTO, PolicyIO, read_policy
from rik.outputs import Replaces, check_own_files, recorded, save_figure, write_text, writing
from rik.paths import json_object, pyplot
from rik.scheduling import normal_scheduling

if TYPE_CHECKING:
    from rik.outputs import Replaces

STRATEGY_PREFIX = "strategy:"
DEFAULT_SEED = 1000
"""lerobot-eval's default first seed."""
LABELS = {"robot": "--robot {}", "action_frame": "--action-frame {}"}
"""How a problem of the contract names ``rik eval``'s options."""
NEEDS = ("cameras", "streams", "image_size")
"""The fields of a policy's contract ``eval_info.json`` always names under ``needs``; the others where they are not
their default (so that runs from before a field existed stay finished)."""


@dataclass(frozen=True)
class EvalSpec:
    """What ``rik eval`` runs."""

    operator: str
    """A saved policy's folder, or ``strategy:<name>`` for a scripted strategy."""
    split: str | None = "test"
    handle_types: tuple[str, ...] = DEFAULT_TYPES
    presets: tuple[str, ...] = DEFAULT_PRESETS
    kinds: tuple[str, ...] = DEFAULT_KINDS
    episodes_per_cell: int = 10
    seed: int = DEFAULT_SEED
    episode_length: int = 400
    allow_rerendered: bool = False
    videos: int = 4
    """Episodes filmed (the first ones), front camera."""
    variants: str = "variants"
    label: str = ""
    """Name of the operator in tables (default: the strategy, or the policy's type and folder)."""
    io: PolicyIO = PolicyIO(action_frame=AUTO)
    """The contract the episodes run with: as asked (the robot, and an action frame or ``auto``) until
    :func:`prepare` fills in the policy's (:func:`rik.lerobot.policy_io.read_policy`: its cameras, streams, image
    size, handle shape and frame)."""
    policy_type: str = ""
    """Filled by :func:`prepare` for a policy: its LeRobot type (``act``)."""
    note: str = ""
    """Filled by :func:`prepare`: one line where the policy's contract was guessed (an older policy)."""
    protocol: str = ""
    """The name of the frozen protocol (``rik eval --protocol``) whose episodes these are; empty for none."""
    joints: str = "paper"
    """The hinges of doors (:data:`rik.episodes.draw.JOINTS`): the cell's preset, or the split's real
    doors."""
    renderer: str = ""
    """Empty: each image stream the policy reads drawn by its own renderer; ``sim`` or ``rerendered``: every one
    drawn by that renderer (the visual gap a policy pays, ``rik eval --renderer``)."""

    def draw(self) -> Any:
        """The :class:`rik.episodes.draw.Draw` of these episodes."""
        from rik.episodes.draw import Draw

        return Draw(self.split, self.handle_types, self.presets, self.kinds, self.joints)

    @property
    def strategy(self) -> str | None:
        return self.operator[len(STRATEGY_PREFIX):] if self.operator.startswith(STRATEGY_PREFIX) else None

    @property
    def robot(self) -> str:
        return self.io.robot

    def seeds(self) -> list[int]:
        cells = len(self.handle_types) * len(self.presets)
        return list(range(self.seed, self.seed + cells * self.episodes_per_cell))

    def to_data(self) -> dict[str, Any]:
        """The spec as JSON data, as ``eval_info.json`` keeps it: the robot and action frame beside the options, the
        policy's inputs under ``needs``; without the action frame where it is the world's and the handle's shape
        where it is none (runs from before the handle frame and the handle's shape stay finished)."""
        plain = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("io", "policy_type", "note")}
        data: dict[str, Any] = json.loads(json.dumps(plain, default=list))
        data |= {"robot": self.io.robot, "action_frame": self.io.action_frame, "needs": {}}
        if self.policy_type:
            data["needs"] = {"policy_type": self.policy_type}
            for f in fields(PolicyIO):
                value = getattr(self.io, f.name)
                if f.name != "robot" and (f.name in NEEDS or value != getattr(PolicyIO(), f.name)):
                    data["needs"][f.name] = list(value) if isinstance(value, tuple) else value
        if data["action_frame"] in (AUTO, "world"):
            del data["action_frame"]
        if data["joints"] == "paper":  # runs from before measured joints stay finished
            del data["joints"]
        if not data["protocol"]:
            del data["protocol"]
        if not data["renderer"]:  # runs from before --renderer stay finished
            del data["renderer"]
        return data

    @classmethod
    def from_data(cls, data: dict[str, Any]) -> EvalSpec:
        """The spec of :meth:`to_data`'s data (an ``eval_info.json``'s ``rik.spec``)."""
        own = {f.name for f in fields(cls)}
        plain = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items() if k in own}
        needs = dict(data.get("needs") or {})
        policy_type = needs.pop("policy_type", "")
        io = PolicyIO(robot=data.get("robot", "hand-e"), action_frame=data.get("action_frame", "world"))
        return cls(**{**plain, "io": io.with_options(needs), "policy_type": policy_type})


def prepare(catalog: Any, spec: EvalSpec) -> EvalSpec:
    """The spec checked (split, presets, types, the policy folder and its inputs, the strategy), with its label
    and the contract the episodes run with filled in: a policy's (its contract file, or the guess for an older
    policy, noted in :attr:`EvalSpec.note`), an explicit ``--action-frame`` over it only where it was guessed."""
    from rik.episodes.operators import make_operator

    if spec.episodes_per_cell < 1:
        raise RikError(f"--episodes-per-cell {spec.episodes_per_cell}: must be at least 1")
    if spec.seed < 0:
        raise RikError(f"--seed {spec.seed}: must be 0 or more")
    spec.draw().check(catalog)
    catalog.robot(spec.io.robot)  # an unknown robot: one line with suggestions
    asked = spec.io.action_frame
    check_renderer(spec.renderer, f"--renderer {spec.renderer}")
    if spec.strategy is not None:
        make_operator(spec.strategy)
        if spec.renderer:
            raise RikError(f"--renderer {spec.renderer}: {spec.operator} reads no images; leave --renderer out")
        io = replace(spec.io, action_frame="world" if asked == AUTO else asked).validate(labels=LABELS)
        prepared = replace(spec, label=spec.label or spec.strategy, io=io)
        env_config(prepared)  # what the --env.type=rik config refuses, before anything is built
        return prepared
    # a policy of Mitsuba's images drawn by MuJoCo needs no Mitsuba: --renderer says which renderer runs
    contract = read_policy(Path(spec.operator), robot=spec.io.robot,
                           allow_rerendered=spec.allow_rerendered or bool(spec.renderer))
    io = contract.io
    if spec.renderer and not io.streams:
        raise RikError(f"--renderer {spec.renderer}: the policy in {spec.operator} reads no images; leave --renderer "
                       "out")
    if asked != AUTO and asked != io.action_frame:
        if contract.source is not None:
            raise RikError(f"--action-frame {asked}: the policy's {contract.source} says {io.action_frame}; leave "
                           f"--action-frame out (auto) or pass {io.action_frame}")
        io = replace(io, action_frame=asked)
    io.validate(catalog, LABELS)  # a handle frame for an arm: one line
    label = spec.label or f"{contract.policy_type}:{run_name(Path(spec.operator))}"
    prepared = replace(spec, label=label, io=io, policy_type=contract.policy_type, note=contract.note or "")
    env_config(prepared)  # what the --env.type=rik config refuses (a rate the environment does not step at)
    check_policy_folder(Path(spec.operator))  # processors and weights: before anything is built or written
    return prepared


def run_name(policy_dir: Path) -> str:
    """The training run a saved policy comes from: ``outputs/train/act-drawers/checkpoints/last/pretrained_model``
    is ``act-drawers``; any other folder is its own name."""
    path = policy_dir.resolve()
    if path.name == "pretrained_model" and len(path.parents) > 2 and path.parents[1].name == "checkpoints":
        return path.parents[2].name
    return path.name


def env_config(spec: EvalSpec) -> Any:
    """The ``--env.type=rik`` config that runs ``spec``'s episodes (what ``lerobot-eval --env.*`` would say): its
    contract, and the draw."""
    from rik.lerobot.env_config import RikEnvConfig

    try:
        return RikEnvConfig.for_contract(spec.io, episode_length=spec.episode_length, split=spec.split or "all",
                                         handle_types=",".join(spec.handle_types), presets=",".join(spec.presets),
                                         kinds=",".join(spec.kinds), joints=spec.joints,
                                         variants_dir=spec.variants, renderer=spec.renderer)
    except ValueError as exc:  # the config's refusals, in LeRobot's words (draccus shows them to lerobot-eval)
        where = "" if spec.strategy is not None else f"{spec.operator}: "
        raise RikError(f"{where}{exc}") from None


# ---- one worker's episodes ----------------------------------------------------------------------------------
_CONTEXT: dict[str, Any] = {}
OUT_OF_STATS_SD = 5.0
"""An observation this many standard deviations of the training data beyond the range of that data (its minimum
and maximum; from its mean where the statistics have no range) is far outside what the policy was trained on
(``rik eval`` warns; the dimension's standard deviation counts as at least 1e-6). The range, not the mean: a
dimension that is nearly constant with a few outliers (the gripper's yaw, turned level within a few steps of each
start) has a small deviation, and a start inside the training starts' range is no extrapolation."""


def _state_stats(pre: Any, robot: str) -> dict[str, tuple[Any, Any, Any, Any, tuple[str, ...]]]:
    """The training data's mean, standard deviation, minimum and maximum of each state feature the policy
    normalises (from its preprocessor's normaliser; the mean for both ends where there is no range), with the
    dimensions' names: feature -> (mean, std, min, max, names)."""
    import numpy as np

    from rik.lerobot.features import EE_POSE, ENV_STATE_LAYOUTS, OBS_ENV_STATE, OBS_STATE
    from rik.registry.load import load_catalog
    from rik.sim.robots.layout import EE_NAMES, robot_layout

    layout = robot_layout(load_catalog().robot(robot).as_arm)
    names = {OBS_STATE: (tuple(layout.state_names),), OBS_ENV_STATE: tuple(ENV_STATE_LAYOUTS.values()),
             EE_POSE: (EE_NAMES,)}
    out = {}
    for step in getattr(pre, "steps", []):
        stats = getattr(step, "stats", None) or {}
        for key, layouts in names.items():
            feature = stats.get(key) or {}
            if "mean" in feature and "std" in feature:
                mean = np.asarray(feature["mean"], np.float64).reshape(-1)
                std = np.maximum(np.asarray(feature["std"], np.float64).reshape(-1), 1e-6)
                has_range = "min" in feature and "max" in feature
                low = np.asarray(feature["min"], np.float64).reshape(-1) if has_range else mean
                high = np.asarray(feature["max"], np.float64).reshape(-1) if has_range else mean
                for dims in layouts:
                    if len(mean) == len(dims) == len(low) == len(high):
                        out[key] = (mean, std, low, high, dims)
    return out


def _worst_state(observations: dict[str, Any], stats: dict[str, tuple[Any, Any, Any, Any, tuple[str, ...]]],
                 last: int) -> tuple[float, str]:
    """The largest distance of an episode's states beyond the training data's range, in its standard deviations,
    and the dimension (``observation.environment_state.grasp_y``); 0 inside the range."""
    import numpy as np

    worst, where = 0.0, ""
    for key, (mean, std, low, high, dims) in stats.items():
        if key not in observations:
            continue
        values = observations[key][0][:last + 1].double().numpy().reshape(-1, len(mean))
        z = np.maximum(np.maximum(values - high, low - values), 0.0) / std
        i = int(np.argmax(z.max(axis=0)))
        if float(z[:, i].max()) > worst:
            worst, where = float(z[:, i].max()), f"{key}.{dims[i]}"
    return worst, where


def out_of_stats_warning(label: str, rows: Sequence[dict[str, Any]]) -> str | None:
    """One line when some episodes' states fell more than :data:`OUT_OF_STATS_SD` standard deviations outside the
    range of the policy's training data (None otherwise, and for scripted operators)."""
    far = [r for r in rows if isinstance(r.get("stats_sd"), int | float) and r["stats_sd"] > OUT_OF_STATS_SD]
    if not far:
        return None
    worst = max(far, key=lambda r: r["stats_sd"])
    return (f"{label}: in {len(far)} of {len(rows)} episodes the states fell more than {OUT_OF_STATS_SD:g} standard "
            f"deviations outside the range of the policy's training data (worst: {worst['stats_dim']} at "
            f"{worst['stats_sd']:.1f}, seed {worst['seed']}): its results there are extrapolation; train on data "
            "that covers those handles and units")


def _context(spec: EvalSpec) -> dict[str, Any]:
    """The environment (and policy with its processors) of this process, made once per spec."""
    key = json.dumps(asdict(spec), sort_keys=True, default=list)
    if _CONTEXT.get("key") == key:
        return _CONTEXT
    _CONTEXT.clear()
    cfg = env_config(spec)
    ctx: dict[str, Any] = {"key": key, "cfg": cfg}
    if spec.strategy is None:
        from lerobot.envs.factory import make_env_pre_post_processors
        from lerobot.policies.factory import make_policy, make_pre_post_processors

        # LeRobot imports and calls what the folder names: check it first; its config as LeRobot parses it
        policy_cfg = check_policy_folder(Path(spec.operator))
        policy_cfg.pretrained_path = Path(spec.operator)
        if getattr(policy_cfg, "pretrained_backbone_weights", None) is not None:
            # ACT's and diffusion's image backbone would first load torchvision's ImageNet weights (a download, read
            # with torch.load): model.safetensors replaces every one of them, so nothing is fetched or unpickled
            policy_cfg.pretrained_backbone_weights = None
        policy = make_policy(cfg=policy_cfg, env_cfg=cfg)
        policy.eval()
        pre, post = make_pre_post_processors(policy_cfg=policy_cfg, pretrained_path=str(spec.operator),
                                             preprocessor_overrides={"device_processor":
                                                                     {"device": str(policy.config.device)}})
        env_pre, env_post = make_env_pre_post_processors(env_cfg=cfg, policy_cfg=policy_cfg)
        # the states are kept per step only for state policies: with images every step's frames would be copied
        stats = {} if spec.io.cameras else _state_stats(pre, spec.io.robot)
        vec = cfg.create_envs(n_envs=1)[cfg.type][0]
        # an image policy's frames are rendered only for the steps whose images it reads (a chunk's first)
        vec.envs[0].unwrapped.reads_next = observation_use(policy)
        ctx |= {"policy": policy, "processors": (env_pre, env_post, pre, post), "stats": stats, "vec": vec}
    else:
        import gymnasium as gym

        # operators give target poses: the absolute action, for any robot
        kwargs = {**cfg.gym_kwargs, "action_mode": "absolute"}
        ctx["env"] = gym.make(cfg.gym_id, disable_env_checker=True, **kwargs).unwrapped
    _CONTEXT.update(ctx)
    return _CONTEXT


def run_episode(spec: EvalSpec, seed: int, video_dir: Path | None = None) -> dict[str, Any]:
    """Run the episode of ``seed``; its row (with the path of its video when ``video_dir`` is given)."""
    ctx = _context(spec)
    start = time.perf_counter()
    frames: list[Any] = []
    if spec.strategy is None:
        result = _policy_episode(ctx, seed, frames if video_dir else None)
    else:
        result = _scripted_episode(ctx, spec.strategy, seed, frames if video_dir else None)
    row = {"seed": seed, "handle_type": result["handle_type"], "preset": result["preset"], "strategy": spec.label,
           "variant": result["variant"], "front": result["front"], "outcome": result["outcome"],
           "success": bool(result["success"]), "final_opening": round(float(result["final_opening"]), 4),
           "max_opening": round(float(result["max_opening"]), 4), "steps": int(result["steps"]),
           "sum_reward": float(result["sum_reward"]), "max_reward": float(result["max_reward"]),
           "seconds": round(time.perf_counter() - start, 3), "video": "",
           "stats_sd": result.get("stats_sd"), "stats_dim": result.get("stats_dim", "")}
    if video_dir is not None and frames:
        from lerobot.utils.io_utils import write_video

        from rik.sim.scene import CONTROL_FPS

        video_dir.mkdir(parents=True, exist_ok=True)
        path = video_dir / f"episode_{seed}.mp4"
        ours = Replaces("a video of an earlier rik eval", lambda p: _is_eval(p.parent.parent) or recorded(p), True)
        # a video encoder may leave the thread at real-time priority (rik.scheduling)
        with normal_scheduling(), writing(path, ours, keep_suffix=True) as tmp:
            write_video(str(tmp), frames, CONTROL_FPS)
        row["video"] = str(path)
    return row


def _policy_episode(ctx: dict[str, Any], seed: int, frames: list[Any] | None) -> dict[str, Any]:
    import contextlib
    import io

    import numpy as np
    import torch
    from lerobot.scripts.lerobot_eval import rollout

    vec = ctx["vec"]
    env_pre, env_post, pre, post = ctx["processors"]
    callback: Callable[[Any], None] | None = None
    if frames is not None:
        def callback(env: Any) -> None:
            frames.append(env.call("render")[0])
    torch.manual_seed(seed)  # stochastic policies (diffusion) draw the same noise for the same episode
    with contextlib.redirect_stderr(io.StringIO()), torch.no_grad():  # rollout's own progress bar, per episode
        data = rollout(vec, ctx["policy"], env_pre, env_post, pre, post, seeds=[seed], render_callback=callback,
                       return_observations=bool(ctx["stats"]))
    done = data["done"][0].numpy()
    last = int(np.argmax(done)) if done.any() else len(done) - 1
    if frames is not None:
        del frames[last + 1:]  # the vector env resets a finished episode at once: drop the next one's start
    env = vec.envs[0].unwrapped
    result = dict(env.last_result or {})
    if not result:
        raise RikError(f"episode {seed}: the environment recorded no end of episode")
    rewards = data["reward"][0].numpy()[:last + 1]
    out = {**result, "success": bool(data["success"][0].numpy()[:last + 1].any()),
           "sum_reward": float(rewards.sum()), "max_reward": float(rewards.max(initial=0.0))}
    if ctx["stats"]:
        worst, where = _worst_state(data["observation"], ctx["stats"], last)
        out |= {"stats_sd": round(worst, 2), "stats_dim": where}
    return out


def _scripted_episode(ctx: dict[str, Any], strategy: str, seed: int, frames: list[Any] | None) -> dict[str, Any]:
    from rik.episodes.operators import make_operator

    env = ctx["env"]
    env.reset(seed=seed)
    operator = make_operator(strategy)
    operator.reset(env.scene, env.np_random)  # the rng after the start pose, as rik record hands it over
    if frames is not None:
        frames.append(env.render())
    rewards, info, success = [], env._info(), False
    for _ in range(env._max_episode_steps):
        if operator.done:
            break
        _, reward, terminated, truncated, info = env.step(operator.act(env.scene))
        rewards.append(reward)
        success = success or info["is_success"]
        if frames is not None:
            frames.append(env.render())
        if terminated or truncated:
            break
    return {**info, "final_opening": info["opening"], "success": success, "sum_reward": float(sum(rewards)),
            "max_reward": float(max(rewards, default=0.0))}


# ---- the whole evaluation -----------------------------------------------------------------------------------
def _episode_item(spec_json: str, video_root: str, threads: int | None, catalog: Any, item: str) -> dict[str, Any]:
    """One episode of :func:`run_eval` (``item``: ``"<seed>:<film 0|1>"``); ``threads`` caps PyTorch's threads
    in worker processes, where several evaluations share the cores."""
    if threads is not None:
        import torch

        torch.set_num_threads(threads)
    seed, film = (int(x) for x in item.split(":"))
    return run_episode(EvalSpec.from_data(json.loads(spec_json)), seed, Path(video_root) if film else None)


EVAL_FILES = ("table.md", "episodes.csv", "eval_info.json", "success.png", "videos")
"""What ``rik eval`` writes into ``--out`` (and, with several policies, into a folder per policy there)."""


def _is_eval(folder: Path) -> bool:
    """Whether ``folder`` holds an earlier rik eval's output: its ``eval_info.json`` with rik's rows and settings."""

    info = json_object(folder / "eval_info.json")
    return info is not None and isinstance(info.get("rik"), dict) and "spec" in info["rik"]


def eval_file() -> Replaces:
    """What a file rik eval writes may replace: the same file of an earlier rik eval in that folder (the folder, or
    a policy's folder in it, holds its ``eval_info.json``), or one rik recorded writing there."""

    def ours(path: Path) -> bool:
        folder = Path(path).parent
        return (_is_eval(folder) or recorded(path)
                or any(_is_eval(Path(e.path)) for e in os.scandir(folder) if e.is_dir(follow_symlinks=False)))

    return Replaces("an output of an earlier rik eval", ours, record=True)


def check_eval_out(out: Path, policy_folders: Sequence[str] = ()) -> None:
    """Refuse (one line), before any episode, an ``--out`` (or a policy's folder in it, ``policy_folders``) where a
    file rik eval writes (:data:`EVAL_FILES`) is there and the folder is not an earlier rik eval's output: a rerun
    may write over its own results, never a user's file."""

    out = Path(out)
    ours_below = any(_is_eval(out / f) for f in policy_folders)
    for folder in (out, *(out / f for f in policy_folders)):
        check_own_files(folder, EVAL_FILES, lambda d: _is_eval(d) or (d == out and ours_below), "rik eval",
                        "eval_info.json")


def eval_folders(outs: Sequence[Path], specs: Sequence[EvalSpec]) -> list[Path]:
    """Where each spec's outputs go, checked (:func:`check_eval_out`) before any episode runs: with one folder in
    ``outs``, that folder for one spec and a folder per spec in it (named by its label, :func:`label_folders`) for
    several; with one per spec, each its own."""
    if len(outs) > 1:
        for out in outs:
            check_eval_out(out)
        return list(outs)
    if len(specs) == 1:
        check_eval_out(outs[0])
        return [outs[0]]
    names = label_folders(outs[0], [s.label for s in specs])
    check_eval_out(outs[0], names)
    return [outs[0] / name for name in names]


MAX_NAME_BYTES = 255
"""Longest folder name (bytes of UTF-8) that Linux, macOS and Windows file systems all take."""


def label_folders(out: Path, labels: Sequence[str]) -> list[str]:
    """The folder in ``out`` of each label (:func:`slug`), refused (one line naming the labels) where it is not a
    plain folder name of its own: empty, ``.`` or ``..`` (``out`` itself, or above it), too long, one of the files
    rik eval writes beside them (:data:`EVAL_FILES`), or the same as another label's (compared as written: two
    labels that differ only in characters :func:`slug` turns into ``-`` share one)."""
    names = [slug(label) for label in labels]
    for label, name in zip(labels, names, strict=True):
        if not name or name in (".", "..") or len(name.encode()) > MAX_NAME_BYTES or name in EVAL_FILES:
            raise RikError(f"label {label!r}: its folder in {out} would be {name!r}, which is not a folder of its "
                           f"own (not empty, '.', '..', {', '.join(EVAL_FILES)}, nor over {MAX_NAME_BYTES} bytes); "
                           "give the policy another --label")
    first: dict[str, str] = {}
    for label, name in zip(labels, names, strict=True):
        if name in first:
            raise RikError(f"labels {first[name]!r} and {label!r} would share the folder {out / name} (characters "
                           "other than letters, digits, '-', '_' and '.' become '-'): give the policies labels that "
                           "differ there (--label), or each its own --out")
        first[name] = label
    return names


def run_eval(catalog: Any, spec: EvalSpec, out: Path, *, workers: int = 1,
             progress: Callable[[dict[str, Any]], None] | None = None) -> list[dict[str, Any]]:
    """Run every episode of ``spec`` (in ``workers`` processes, one PyTorch thread each) and write the outputs
    into ``out``; rows in seed order."""
    from functools import partial

    from rik.combinator.build import require_variants
    from rik.workers import map_ids

    check_eval_out(out)
    draw = spec.draw()
    seeds = spec.seeds()
    require_variants(catalog, (draw.episode(catalog, s).variant for s in seeds), Path(spec.variants),
                     workers=workers)
    items = [f"{s}:{int(i < spec.videos)}" for i, s in enumerate(seeds)]
    parallel = workers > 1 and len(items) > 1  # as map_ids decides
    fn = partial(_episode_item, json.dumps(spec.to_data()), str(out / "videos"), 1 if parallel else None)
    started = time.perf_counter()
    rows: dict[int, dict[str, Any]] = {}
    for _, row in map_ids(fn, catalog, items, workers=workers):
        rows[row["seed"]] = row
        if progress is not None:
            progress(row)
    ordered = [rows[s] for s in seeds]
    write_outputs(out, spec, ordered, time.perf_counter() - started)
    return ordered


def finished_rows(out: Path, spec: EvalSpec) -> list[dict[str, Any]] | None:
    """The rows of an earlier run of exactly ``spec`` into ``out`` (its ``eval_info.json``), or None."""
    try:
        info = json.loads((out / "eval_info.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict) or info.get("rik", {}).get("spec") != spec.to_data():
        return None
    return list(info["rik"]["per_episode"])


def slug(label: str) -> str:
    """A folder name for an operator's label (``act:act-cr`` -> ``act-act-cr``)."""
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in label)


def write_tables(out: Path, specs: Sequence[EvalSpec], rows: Sequence[dict[str, Any]]) -> None:
    """``table.md`` and ``episodes.csv`` of one operator's rows, or of several operators' on the same episodes side
    by side (with ``success.png``)."""
    from rik.tables import rows_csv, table_markdown

    first, n = specs[0], len(specs[0].seeds())
    seeds = f"seeds {first.seed}..{first.seed + n - 1}, {first.episodes_per_cell} per cell"
    episodes = f"The same {n} episodes for each ({seeds})" if len(specs) > 1 else f"{n} episodes, {seeds}"
    robot = f" with robot {first.robot}" if first.robot != "hand-e" else ""
    head = (f"# {', '.join(s.label for s in specs)} on the {first.split or 'all'} split{robot}\n\n{episodes}; F/P/S "
            "fractions, S with its 95 % Wilson interval.\n\n")
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "table.md", head + table_markdown(rows, first.presets, ci=True), eval_file())
    write_text(out / "episodes.csv", rows_csv(rows), eval_file())
    if len(specs) > 1:
        success_plot(rows, out / "success.png", title=f"{first.split or 'all'} split, {n} episodes each")


def success_plot(rows: Sequence[dict[str, Any]], png: Path, title: str = "") -> Path:
    """Success rate (S) per operator, overall and per handle type, with 95 % Wilson intervals: one group of bars
    per operator."""
    import numpy as np

    from rik.tables import wilson

    operators = list(dict.fromkeys(r["strategy"] for r in rows))
    groups = ["all", *dict.fromkeys(r["handle_type"] for r in rows)]
    fig, ax = pyplot().subplots(figsize=(max(6.4, 1.3 * len(operators) + 1.5), 3.6), dpi=120)
    width = 0.8 / len(groups)
    for gi, group in enumerate(groups):
        rates, lows, highs = [], [], []
        for op in operators:
            sel = [r["outcome"] == "S" for r in rows if r["strategy"] == op and group in ("all", r["handle_type"])]
            lo, hi = wilson(sum(sel), len(sel))
            rate = sum(sel) / max(len(sel), 1)
            rates.append(rate)
            lows.append(max(0.0, rate - lo))
            highs.append(max(0.0, hi - rate))
        x = np.arange(len(operators)) + (gi - (len(groups) - 1) / 2) * width
        ax.bar(x, rates, width, yerr=[lows, highs], capsize=2, label=group, alpha=0.9 if group == "all" else 0.6)
    ax.set_xticks(np.arange(len(operators)), operators, rotation=20, ha="right")
    ax.set_ylabel("success rate (S: at least 90 % open)")
    ax.set_ylim(0, 1.05)
    ax.set_title(title, fontsize=10)
    ax.legend(frameon=False, fontsize=8, ncols=len(groups))
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, png, eval_file())


def eval_info(spec: EvalSpec, rows: Sequence[dict[str, Any]], seconds: float) -> dict[str, Any]:
    """lerobot-eval's ``eval_info.json`` layout for the rows, with rik's own rows and settings under ``rik``."""
    n = len(rows)
    sums = [r["sum_reward"] for r in rows]
    maxes = [r["max_reward"] for r in rows]
    successes = [bool(r["success"]) for r in rows]
    videos = [r["video"] for r in rows if r["video"]]
    metrics = {"sum_rewards": sums, "max_rewards": maxes, "successes": successes, "video_paths": videos}
    aggregate = {"avg_sum_reward": sum(sums) / max(n, 1), "avg_max_reward": sum(maxes) / max(n, 1),
                 "pc_success": 100.0 * sum(successes) / max(n, 1), "n_episodes": n, "eval_s": seconds,
                 "eval_ep_s": seconds / max(n, 1), "video_paths": videos}
    return {"per_task": [{"task_group": "rik", "task_id": 0, "metrics": metrics}],
            "per_group": {"rik": {k: v for k, v in aggregate.items() if k != "eval_s"}},
            "overall": aggregate,
            "rik": {"spec": spec.to_data(), "per_episode": list(rows)}}


def write_outputs(out: Path, spec: EvalSpec, rows: Sequence[dict[str, Any]], seconds: float) -> None:
    """``table.md``, ``episodes.csv`` and ``eval_info.json`` of one operator (atomically)."""

    write_tables(out, [spec], rows)
    write_text(out / "eval_info.json", json.dumps(eval_info(spec, rows, seconds), indent=2, default=list) + "\n",
               eval_file())
