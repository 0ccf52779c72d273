"""scripts/average_checkpoints.py: the averaged policy folder is the last checkpoint's with the mean weights."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parents[1]


def _script():
    spec = importlib.util.spec_from_file_location("average_checkpoints", ROOT / "scripts" / "average_checkpoints.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_average_is_the_mean_of_the_chosen_checkpoints(tmp_path: Path) -> None:
    from safetensors.numpy import load_file, save_file

    run = tmp_path / "run"
    for step, value in ((1000, 1.0), (2000, 2.0), (3000, 6.0), (4000, 100.0)):
        folder = run / "checkpoints" / f"{step:06d}" / "pretrained_model"
        folder.mkdir(parents=True)
        save_file({"w": np.full((2, 3), value, np.float32), "b": np.array([value], np.float32)},
                  str(folder / "model.safetensors"))
        (folder / "config.json").write_text(f'{{"step": {step}}}')
    (run / "checkpoints" / "last").symlink_to("004000")
    script = _script()
    assert script.main([str(run), "--from", "1000", "--to", "3000", "--out", str(tmp_path / "avg")]) == 0
    weights = load_file(str(tmp_path / "avg" / "model.safetensors"))
    np.testing.assert_array_equal(weights["w"], np.full((2, 3), 3.0, np.float32))
    assert weights["w"].dtype == np.float32 and weights["b"].tolist() == [3.0]
    assert (tmp_path / "avg" / "config.json").read_text() == '{"step": 3000}'  # the last averaged one's
    assert not (tmp_path / "avg.partial").exists()
    assert json.loads((tmp_path / "avg" / "averaged.json").read_text()) == {"run": "run",
                                                                            "steps": [1000, 2000, 3000]}
    assert script.main([str(run), "--from", "3500", "--to", "9000", "--out", str(tmp_path / "one")]) == 2
    assert not (tmp_path / "one").exists()


def test_a_folder_that_is_no_run_or_no_average_is_named_and_left_alone(tmp_path: Path, capsys) -> None:
    script = _script()
    assert script.main([str(tmp_path / "nothing"), "--from", "1", "--to", "2", "--out", str(tmp_path / "a")]) == 2
    assert "nothing: no checkpoints/ folder here" in capsys.readouterr().err
    (tmp_path / "run" / "checkpoints").mkdir(parents=True)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    assert script.main([str(tmp_path / "run"), "--from", "1", "--to", "2", "--out", str(mine)]) == 2
    assert "mine: exists and is no averaged policy (no averaged.json); it is left as it is" in capsys.readouterr().err
    assert (mine / "notes.txt").read_text() == "keep"
