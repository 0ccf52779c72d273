"""Image evaluation renders only the frames a policy reads (issue 54): a chunking policy (ACT, diffusion) reads the
observation its next prediction stacks and drops the others, so ``rik eval`` renders a policy's cameras for those
steps only (:mod:`rik.lerobot.observation_use`) and hands the last frames to the steps in between.

The claim is checked on real lerobot policies, not on a model of them: the same observations fed in full and fed
with every unread one replaced by a stale one give the same actions; and an episode of ``rik eval`` with a real
image ACT policy in rik's environment ends in the same state whether every step or only the read ones are
rendered, counting the renders."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from shared import BOW, builtin_catalog

from rik.lerobot.features import OBS_ENV_STATE, OBS_STATE
from rik.lerobot.observation_use import every_observation, observation_use
from rik.lerobot.policy_io import PolicyIO

pytestmark = pytest.mark.slow  # real policies and an episode of rik eval: out of the everyday tier

SIZE = (16, 16)
IO = PolicyIO(cameras=("front", "wrist"), streams=("sim",), image_size=SIZE)


def _features(io: PolicyIO) -> tuple[dict[str, Any], dict[str, Any]]:
    """The policy's input and output features of a dataset of contract ``io``, as lerobot's ``make_policy`` makes
    them from a dataset's (``dataset_to_policy_features``)."""
    from lerobot.configs.types import FeatureType
    from lerobot.utils.feature_utils import dataset_to_policy_features

    features = dataset_to_policy_features(io.features())
    return ({k: f for k, f in features.items() if f.type is not FeatureType.ACTION},
            {k: f for k, f in features.items() if f.type is FeatureType.ACTION})


def _act(chunk: int, temporal: float | None = None) -> Any:
    """A small image ACT policy (random weights, no download) reading :data:`IO`'s state and cameras."""
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy

    inputs, outputs = _features(IO)
    config = ACTConfig(device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=16,
                       dim_feedforward=32, n_heads=2, n_encoder_layers=1, n_decoder_layers=1, chunk_size=chunk,
                       n_action_steps=1 if temporal is not None else chunk, temporal_ensemble_coeff=temporal,
                       latent_dim=4, use_vae=False, input_features=inputs, output_features=outputs)
    return ACTPolicy(config).eval()


def _diffusion() -> Any:
    """A small diffusion policy (two observations stacked, four actions per chunk, two denoising steps)."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy

    config = DiffusionConfig(device="cpu", push_to_hub=False, n_obs_steps=2, horizon=8, n_action_steps=4,
                             down_dims=(8, 16), diffusion_step_embed_dim=8, num_inference_steps=2,
                             input_features={OBS_STATE: PolicyFeature(FeatureType.STATE, (11,)),
                                             OBS_ENV_STATE: PolicyFeature(FeatureType.ENV, (13,))},
                             output_features={"action": PolicyFeature(FeatureType.ACTION, (7,))})
    return DiffusionPolicy(config).eval()


def _observations(policy: Any, steps: int) -> list[dict[str, Any]]:
    import torch

    gen = torch.Generator().manual_seed(0)
    return [{key: torch.randn((1, *feature.shape), generator=gen) for key, feature in
             policy.config.input_features.items()} for _ in range(steps)]


def _actions(policy: Any, observations: list[dict[str, Any]], stale: bool) -> tuple[np.ndarray, list[bool]]:
    """The policy's actions over ``observations`` (one episode), and whether each was read, as
    :func:`observation_use` says; with ``stale`` every observation it says is not read is replaced by the last one
    that was (as the environment hands the last frames on)."""
    import torch

    torch.manual_seed(0)  # diffusion draws its noise per prediction: the same draws in both runs
    policy.reset()
    reads_next = observation_use(policy)
    read, actions, given = [True], [], observations[0]
    with torch.no_grad():
        for k, obs in enumerate(observations):
            if k == 0 or not stale or read[-1]:
                given = obs
            actions.append(policy.select_action(dict(given)).numpy().copy())
            read.append(reads_next())
    return np.concatenate(actions), read[:-1]


@pytest.mark.parametrize("make", [lambda: _act(5), _diffusion], ids=["act", "diffusion"])
def test_a_chunking_policy_acts_the_same_on_the_observations_it_is_said_to_read(make: Any) -> None:
    """Fed every observation, or only those :func:`observation_use` says it reads (the others stale): the same
    actions, and most observations are not read (ACT: one in five; diffusion: two in four)."""
    policy = make()
    observations = _observations(policy, 20)
    fresh, read = _actions(policy, observations, stale=False)
    stale, read_again = _actions(policy, observations, stale=True)
    np.testing.assert_array_equal(fresh, stale)
    assert read == read_again
    expected = [k % 5 == 0 for k in range(20)] if policy.name == "act" else [k % 4 in (0, 3) for k in range(20)]
    assert read == expected


def test_the_reads_say_when_stale_observations_would_change_the_actions() -> None:
    """The check above can fail: said to read one observation in two instead of one in five, stale observations
    reach ACT's predictions and change its actions."""
    policy = _act(5)
    observations = _observations(policy, 20)
    fresh, _ = _actions(policy, observations, stale=False)
    policy.reset()
    import torch

    with torch.no_grad():
        given, wrong = observations[0], []
        for k, obs in enumerate(observations):
            given = obs if k % 2 == 0 else given  # a wrong rule: every other observation
            wrong.append(policy.select_action(dict(given)).numpy().copy())
    assert not np.array_equal(fresh, np.concatenate(wrong))


def test_policies_that_read_every_observation_are_rendered_every_step() -> None:
    """ACT with temporal ensembling predicts every step; a type whose queues rik does not know reads every
    observation too."""
    assert observation_use(_act(5, temporal=0.01)) is every_observation

    class Other:
        name = "pi0"

    assert observation_use(Other()) is every_observation


@pytest.fixture(scope="module")
def image_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small image ACT policy (5 actions a chunk) saved by LeRobot with its processors and rik's contract."""
    from shared import save_untrained

    return save_untrained(_act(5), tmp_path_factory.mktemp("image-policy") / "policy", IO.to_json())


def test_rik_eval_renders_only_the_frames_an_image_policy_reads(image_policy: Path, bow_variants: Path,
                                                                 tmp_path: Path) -> None:
    """One 20-step episode of rik eval (the train split's draw of seed 22 is the bow drawer), rendered every step
    and then only where the policy reads: 21 observations rendered against 5 (the start and every fifth step; the
    vector environment resets a finished episode on its next step, which never comes, so no variant is drawn or
    rendered after the last step: RikEnvConfig.create_envs), and the same episode to the last joint of the robot."""
    from rik.evaluation import evaluate

    variants = tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    spec = evaluate.prepare(builtin_catalog(), evaluate.EvalSpec(
        str(image_policy), split="train", handle_types=("two_point",), presets=("normal",), kinds=("drawer",),
        episodes_per_cell=1, seed=22, episode_length=20, videos=0, variants=str(variants)))
    assert spec.io.cameras == ("front", "wrist") and spec.io.image_size == SIZE
    ends, rendered = {}, {}
    for mode in ("every step", "read only"):
        vec = evaluate._context(spec)["vec"]
        env = vec.envs[0].unwrapped
        assert env.reads_next is not None  # rik eval gave the environment the policy's reads
        if mode == "every step":
            env.reads_next = None
        before = env.frames_rendered
        row = evaluate.run_episode(spec, 22)
        assert row["variant"] == BOW and row["steps"] == 20
        rendered[mode] = env.frames_rendered - before
        ends[mode] = (env.scene.data.qpos.copy(), row["final_opening"], row["sum_reward"])
        evaluate._CONTEXT.clear()  # the next mode's environment and policy made anew
        vec.close()
    assert rendered == {"every step": 21, "read only": 5}
    # and no variant drawn beyond the environment's first (seed 0 of its draw, built as it is made) and the episode's
    from rik.episodes.draw import Draw

    first = Draw("train", ("two_point",), ("normal",), ("drawer",), "paper").episode(builtin_catalog(), 0).variant
    assert {p.name for p in variants.iterdir() if p.is_dir() and not p.name.startswith(".")} == {BOW, first}
    np.testing.assert_array_equal(ends["every step"][0], ends["read only"][0])
    assert ends["every step"][1:] == ends["read only"][1:]


# ---- the visual gap: a policy's streams drawn by the other renderer (rik eval --renderer) ---------------------------
def _fronts(variants: Path, streams: tuple[str, ...], renderer: str | None = None, spp: int = 4,
            size: tuple[int, int] = (24, 32)) -> dict[str, np.ndarray]:
    """The front camera's first images of the bow drawer (reset seed 0), one per stream, in an environment of
    ``streams`` at ``size``, drawn by ``renderer`` (None: each stream its own)."""
    from rik.envs.open_front import OpenFrontEnv

    env = OpenFrontEnv(BOW, variants_dir=variants, spp=spp, renderer=renderer,
                       io=PolicyIO(cameras=("front",), streams=streams, image_size=size))
    try:
        return dict(env.reset(seed=0)[0]["pixels"])
    finally:
        env.close()


def _front(variants: Path, streams: tuple[str, ...], renderer: str | None = None, spp: int = 4,
           size: tuple[int, int] = (24, 32)) -> np.ndarray:
    """The front camera's first image of a single stream (:func:`_fronts`)."""
    (image,) = _fronts(variants, streams, renderer, spp, size).values()
    return image


def test_a_stream_drawn_by_the_other_renderer_is_that_renderers_picture_under_the_streams_key(
        bow_variants: Path) -> None:
    """A policy of MuJoCo's pictures shown Mitsuba's (``renderer="rerendered"``) gets, under its own key, the very
    image the Mitsuba stream gives; and the other way. The two renderers' pictures differ, so the check can fail."""
    sim, mitsuba = _front(bow_variants, ("sim",)), _front(bow_variants, ("rerendered",))
    assert np.abs(sim.astype(int) - mitsuba).mean() > 2.0  # two renderers, two pictures
    np.testing.assert_array_equal(_front(bow_variants, ("sim",), "rerendered"), mitsuba)
    np.testing.assert_array_equal(_front(bow_variants, ("rerendered",), "sim"), sim)
    both = _fronts(bow_variants, ("sim", "rerendered"), "sim")  # both streams drawn once, by MuJoCo
    assert set(both) == {"front", "front_rerendered"}
    for image in both.values():
        np.testing.assert_array_equal(image, sim)


def test_rik_eval_shows_a_sim_policy_mitsubas_pictures_and_records_it(image_policy: Path, bow_variants: Path,
                                                                       tmp_path: Path) -> None:
    """``--renderer rerendered`` (the CLI passes it to the spec, as the refusals below show): the spec keeps it for
    ``eval_info.json`` and back, and the environment rik eval makes for the policy shows Mitsuba's picture under
    MuJoCo's key."""
    from rik.evaluation import evaluate

    variants = tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    spec = evaluate.prepare(builtin_catalog(), evaluate.EvalSpec(
        str(image_policy), split="train", handle_types=("two_point",), presets=("normal",), episodes_per_cell=1,
        seed=22, episode_length=5, videos=0, variants=str(variants), renderer="rerendered"))
    data = spec.to_data()  # what eval_info.json keeps under rik.spec
    assert data["renderer"] == "rerendered" and evaluate.EvalSpec.from_data(data).renderer == "rerendered"
    assert "renderer" not in evaluate.EvalSpec(str(image_policy)).to_data()  # earlier runs' specs stay as they were
    vec = evaluate._context(spec)["vec"]
    try:
        shown = vec.envs[0].unwrapped.reset(seed=0, options={"variant": BOW})[0]["pixels"]["front"]
    finally:
        evaluate._CONTEXT.clear()
        vec.close()
    np.testing.assert_array_equal(shown, _front(variants, ("rerendered",), spp=16, size=SIZE))


@pytest.mark.parametrize(("operator", "renderer", "message"), [
    ("image", "mitsuba", "--renderer mitsuba: use one of sim, rerendered"),
    ("image", "sim\x00", "--renderer sim"),
    ("strategy:planned", "sim", "--renderer sim: strategy:planned reads no images; leave --renderer out"),
    ("state", "rerendered", "reads no images; leave --renderer out"),
])
def test_rik_eval_refuses_a_renderer_it_cannot_use_in_one_line(image_policy: Path, rik, tmp_path: Path,
                                                                operator: str, renderer: str, message: str) -> None:
    from shared import act_config_folder

    folder = {"image": str(image_policy), "state": str(tmp_path / "state")}.get(operator, operator)
    if operator == "state":
        act_config_folder(tmp_path / "state")
    r = rik("eval", folder, "--renderer", renderer, "-n", "1", "--out", str(tmp_path / "eval"),
            "--variants", str(tmp_path / "variants"))
    assert r.code == 2 and message in r.err and len(r.err.strip().splitlines()) == 1, r.out + r.err
    assert "Traceback" not in r.err and not (tmp_path / "eval").exists() and not (tmp_path / "variants").exists()


def test_the_environment_and_its_config_refuse_an_unknown_renderer() -> None:
    from rik.envs.open_front import OpenFrontEnv
    from rik.errors import RikError
    from rik.lerobot.env_config import RikEnvConfig

    with pytest.raises(RikError, match="renderer 'mitsuba': use one of sim, rerendered"):
        OpenFrontEnv(BOW, renderer="mitsuba")
    with pytest.raises(ValueError, match="--env.renderer=mitsuba: use one of sim, rerendered"):
        RikEnvConfig(renderer="mitsuba")
