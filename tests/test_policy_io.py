"""rik's contract with LeRobot (rik.lerobot.policy_io.PolicyIO): said once by the export, carried to the policy folder,
read (never guessed) by ``rik eval`` and ``--env.*=auto``; a contract file is untrusted input (one line naming the
file and the field); policies trained before it exist are guessed, with a one-line note. The end-to-end run (an
export, lerobot-train with the plugin's hook, rik eval and lerobot-eval) is tests/test_policy_loop.py."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest
from shared import act_config_folder

from rik.errors import RikError
from rik.lerobot.policy_io import POLICY_IO_FILE, PolicyIO, read_policy


@pytest.fixture(scope="module")
def handle_export(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The metadata of a state-only export with the action in the handle frame and the handle's kind: its
    ``meta/info.json`` (what lerobot writes of the contract's features) and ``meta/rik_policy_io.json`` (exports
    themselves: tests/test_handle_shape.py, tests/test_action_frame.py, tests/test_policy_loop.py)."""
    root = tmp_path_factory.mktemp("contract") / "ds"
    (root / "meta").mkdir(parents=True)
    io = PolicyIO(action_frame="handle", handle_shape="kind")
    features = {k: {**f, "shape": list(f["shape"])} for k, f in io.features().items()}
    (root / "meta" / "info.json").write_text(json.dumps({"robot_type": "rik_hand_e", "fps": 20,
                                                         "features": features}))
    (root / "meta" / POLICY_IO_FILE).write_text(io.to_json())
    return root


def _policy(folder: Path, contract: dict | str | None = None, env_width: int = 18) -> Path:
    """A saved ACT config (no weights) reading a front's state ``env_width`` wide, with ``contract`` beside it."""
    act_config_folder(folder, env_width=env_width)
    if contract is not None:
        text = contract if isinstance(contract, str) else json.dumps(contract)
        (folder / POLICY_IO_FILE).write_text(text)
    return folder


HANDLE = {"format": 1, "robot": "hand-e", "action_frame": "handle", "handle_shape": "kind", "cameras": [],
          "streams": [], "image_size": [96, 128], "fps": 20, "environment_state": True}


def test_a_dataset_says_its_contract_and_an_older_one_its_features(handle_export: Path) -> None:
    """meta/rik_policy_io.json holds the dataset's contract; a dataset exported before the file is read from its
    info.json's feature names to the same contract; the file's JSON is the contract."""
    io = PolicyIO.from_dataset(handle_export)
    assert io == PolicyIO("hand-e", "handle", "kind", (), (), (96, 128))  # no images: the size of none
    assert json.loads((handle_export / "meta" / POLICY_IO_FILE).read_text()) == HANDLE
    older = handle_export.parent / "older"
    shutil.copytree(handle_export, older)
    (older / "meta" / POLICY_IO_FILE).unlink()
    assert PolicyIO.from_dataset(older) == io
    assert PolicyIO.from_json(json.loads(io.to_json()), "x") == io


def test_a_policy_reads_its_contract_not_its_widths(tmp_path: Path) -> None:
    """The handle frame cannot be told from widths (13 numbers either way) and, without statistics, the old guess
    says world: the contract beside the policy says handle."""
    said = read_policy(_policy(tmp_path / "p", {**HANDLE, "handle_shape": "none"}, env_width=13))
    assert (said.io.action_frame, said.source, said.note) == ("handle", tmp_path / "p" / POLICY_IO_FILE, None)
    guessed = read_policy(_policy(tmp_path / "old", env_width=13))
    assert guessed.io.action_frame == "world" and guessed.source is None
    assert guessed.note == (f"{tmp_path / 'old'}: no {POLICY_IO_FILE} beside the policy or its training data (a "
                            "policy trained before rik wrote its contract): its action frame and handle shape are "
                            "guessed from its input widths and training statistics")


def test_train_config_leads_to_the_datasets_contract(handle_export: Path, tmp_path: Path) -> None:
    """A policy folder without its own copy: its train_config.json names the dataset, whose contract is read."""
    folder = _policy(tmp_path / "p")
    (folder / "train_config.json").write_text(json.dumps({"dataset": {"repo_id": "local/contract",
                                                                      "root": str(handle_export)}}))
    said = read_policy(folder)
    assert said.source == handle_export / "meta" / POLICY_IO_FILE and said.io.action_frame == "handle"
    assert said.io.image_size == (96, 128)  # narrowed to what the policy reads: no images


@pytest.mark.parametrize(("contract", "message"), [
    ("[1, 2]", "not a JSON object (rik's policy contract)"),
    ("{", "not readable JSON ("),
    ({**HANDLE, "format": 2}, "field 'format': 2 is not 1 (a file of another rik"),
    ({**HANDLE, "code": "import os"}, "field 'code': not a field of rik's policy contract (robot, action_frame, "),
    ({**HANDLE, "action_frame": "up"}, "field 'action_frame' up: use one of world, handle, gripper"),
    ({**HANDLE, "handle_shape": 3}, "field 'handle_shape': 3 is not a name (a string of 1 to 64 characters)"),
    ({**HANDLE, "cameras": ["top"], "streams": ["sim"]},
     "field 'cameras' top: no camera 'top' in the scene (cameras: front, wrist)"),
    ({**HANDLE, "cameras": "front"}, "field 'cameras': 'front' is not a list of at most 16 names"),
    ({**HANDLE, "image_size": [96, "x"]}, "field 'image_size': give (height, width), two whole numbers of pixels"),
    ({**HANDLE, "handle_shape": "full"}, "input 'observation.environment_state' has shape [18]; "),
    ({**HANDLE, "robot": "so100"}, "the policy was trained for robot so100; run it with --robot so100"),
    (" " * 70_000, "larger than 64 KiB"),
])
def test_a_bad_contract_file_is_one_line_naming_the_file_and_field(tmp_path: Path, contract: dict | str,
                                                                   message: str) -> None:
    folder = _policy(tmp_path / "p", contract)
    with pytest.raises(RikError) as exc:
        read_policy(folder)
    text = str(exc.value)
    assert len(text.splitlines()) == 1 and message in text, text
    assert str(folder) in text


def test_a_contract_file_that_leads_out_of_the_folder_is_refused(handle_export: Path, tmp_path: Path) -> None:
    folder = _policy(tmp_path / "p")
    (folder / POLICY_IO_FILE).symlink_to(handle_export / "meta" / POLICY_IO_FILE)
    with pytest.raises(RikError, match=r"leads to .*, outside the policy folder"):
        read_policy(folder)


def test_env_config_and_rik_eval_follow_the_contract_and_refuse_to_contradict_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from lerobot_env_rik import RikEnvConfig, env_kwargs

    from rik.evaluation.evaluate import EvalSpec, prepare
    from rik.registry.load import load_catalog

    folder = _policy(tmp_path / "p", HANDLE)
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={folder}", "--env.type=rik"])
    config = RikEnvConfig()
    assert (config.action_frame, config.handle_shape, env_kwargs(config)["action_mode"]) == ("handle", "kind",
                                                                                            "handle")
    assert config.features["environment_state"].shape == (18,)
    with pytest.raises(ValueError, match=r"^--env\.action_frame=world: the policy's .*rik_policy_io\.json says "
                                         r"handle; leave it out \(auto\) or pass handle$"):
        RikEnvConfig(action_frame="world")
    with pytest.raises(RikError, match=r"^--action-frame world: the policy's .*rik_policy_io\.json says handle"):
        prepare(load_catalog(), EvalSpec(str(folder), io=PolicyIO(action_frame="world")))


def test_the_training_hook_copies_the_contract_beside_each_checkpoint(handle_export: Path, tmp_path: Path) -> None:
    """lerobot-train's save_checkpoint, wrapped: after LeRobot's save the dataset's contract is in
    ``pretrained_model/`` (again at a later save of the same checkpoint); a dataset without one adds nothing."""
    from rik.lerobot import train_hook

    saved = []

    def save_checkpoint(checkpoint_dir: Path, step: int, cfg: object, **_: object) -> None:
        (checkpoint_dir / "pretrained_model").mkdir(parents=True, exist_ok=True)
        saved.append(step)

    wrapped = train_hook.with_contract(save_checkpoint)
    cfg = SimpleNamespace(dataset=SimpleNamespace(root=str(handle_export), repo_id="local/contract"))
    for step in (1, 1):
        wrapped(checkpoint_dir=tmp_path / "ckpt", step=step, cfg=cfg)
    assert saved == [1, 1]
    assert PolicyIO.read(tmp_path / "ckpt" / "pretrained_model" / POLICY_IO_FILE) == PolicyIO.from_dataset(
        handle_export)
    plain = SimpleNamespace(dataset=SimpleNamespace(root=str(tmp_path / "not-rik"), repo_id="x/y"))
    wrapped(checkpoint_dir=tmp_path / "other", step=2, cfg=plain)
    assert not (tmp_path / "other" / "pretrained_model" / POLICY_IO_FILE).exists()
    assert train_hook.install() is False  # not inside lerobot-train


def test_the_specs_embed_one_contract() -> None:
    """ExportSpec takes the contract's fields by keyword (its old keywords), and records them in an interrupted
    export's plan as before; rik eval's spec keeps eval_info.json's layout (finished runs stay finished)."""
    from rik.evaluation.evaluate import EvalSpec
    from rik.exporters.spec import ExportSpec

    spec = ExportSpec("local/x", streams=("sim",), cameras=("front",), width=32, height=24, fps=10,
                      action_frame="handle")
    assert spec.io == PolicyIO(action_frame="handle", cameras=("front",), streams=("sim",), image_size=(24, 32))
    assert list(spec.plan_data()) == ["repo_id", "streams", "cameras", "width", "height", "fps", "codec", "spp",
                                      "denoise", "variant", "shard_episodes", "outcomes", "action_frame",
                                      "handle_shape"]
    with pytest.raises(RikError, match=r"^handle: not a field of rik's policy contract"):
        ExportSpec("local/x", handle="bow")
    policy = EvalSpec("p", io=PolicyIO(handle_shape="kind", cameras=("front",), streams=("sim",)),
                      policy_type="act", label="act:p")
    data = policy.to_data()
    assert data["needs"] == {"policy_type": "act", "cameras": ["front"], "streams": ["sim"],
                             "image_size": [96, 128], "handle_shape": "kind"}
    assert "action_frame" not in data and data["robot"] == "hand-e"
    assert EvalSpec.from_data(data) == policy


def test_the_rate_a_policy_acts_at_travels_and_is_refused_where_the_environment_steps_at_another(
        handle_export: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``fps``, the contract's latest field (added in rik/lerobot/policy_io.py, env_config.py and envs/open_front.py):
    a dataset exported at 10 Hz says so, and a policy trained on it is refused in one line by the environment, the
    --env.type=rik config and rik eval, before any episode (it used to run at 20 Hz, twice as fast as it learnt)."""
    from lerobot_env_rik import RikEnvConfig

    from rik.envs.open_front import OpenFrontEnv
    from rik.evaluation.evaluate import EvalSpec, prepare
    from rik.registry.load import load_catalog

    slow = tmp_path / "slow"
    shutil.copytree(handle_export, slow)
    (slow / "meta" / POLICY_IO_FILE).unlink()
    info = json.loads((slow / "meta" / "info.json").read_text())
    (slow / "meta" / "info.json").write_text(json.dumps({**info, "fps": 10}))
    assert PolicyIO.from_dataset(slow).fps == 10 and PolicyIO.from_dataset(handle_export).fps == 20
    folder = _policy(tmp_path / "p", {**HANDLE, "fps": 10})
    assert read_policy(folder).io.fps == 10
    with pytest.raises(RikError, match=r"^fps 10: the environment steps at 20 Hz, and a policy acts at its dataset's "
                                       r"rate; export the episodes at their own rate \(without --fps\)"):
        OpenFrontEnv(io=PolicyIO(fps=10))
    with pytest.raises(RikError, match=r"rik_policy_io.json: field 'fps' 0: give 1 to 1000 frames per second$"):
        read_policy(_policy(tmp_path / "zero", {**HANDLE, "fps": 0}))
    with pytest.raises(RikError, match=r"^.*/p: --env\.fps=10: rik's environment steps at 20 Hz"):
        prepare(load_catalog(), EvalSpec(str(folder)))
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={folder}", "--env.type=rik"])
    with pytest.raises(ValueError, match=r"^--env\.fps=10: rik's environment steps at 20 Hz"):
        RikEnvConfig()


def test_the_env_config_draws_real_doors_and_refuses_bad_joints(monkeypatch) -> None:
    """``--env.joints=measured`` reaches the environment's draw; a bad name or a drawer-only draw is refused when the
    config is made, in LeRobot's words (a ValueError that draccus shows), before any environment is built."""
    from lerobot_env_rik import RikEnvConfig, env_kwargs

    monkeypatch.setattr("sys.argv", ["lerobot-eval", "--env.type=rik"])
    config = RikEnvConfig(split="val", kinds="drawer,door", joints="measured")
    kwargs = env_kwargs(config)
    assert kwargs["joints"] == "measured" and kwargs["kinds"] == ("drawer", "door")
    with pytest.raises(ValueError, match=r"^--env\.\*: unknown joints 'real' \(joints: paper, measured\)$"):
        RikEnvConfig(kinds="door", joints="real")
    with pytest.raises(ValueError, match=r"^--env\.\*: joints 'measured': real doors' presets go on doors"):
        RikEnvConfig(joints="measured")
