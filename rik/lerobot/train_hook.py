"""The contract travels with the policy: inside ``lerobot-train``, each checkpoint's ``pretrained_model/`` gets the
training dataset's ``meta/rik_policy_io.json`` beside the policy's ``config.json``.

LeRobot 0.6.1 imports rik's plugin (``lerobot_env_rik``) at the start of every command, after the command's own
module; the plugin calls :func:`install`, which, only in ``lerobot-train`` (its module ``lerobot.scripts.lerobot_train``
is loaded), wraps that module's ``save_checkpoint``: LeRobot saves the checkpoint as before, then the dataset's
contract (``--dataset.root``, or LeRobot's cache folder of ``--dataset.repo_id``) is copied beside it. A dataset
without one (not rik's, or exported before rik wrote it) adds nothing, and a copy that fails is one warning: training
goes on. So a policy folder holds its own contract wherever it is copied or pushed (``push_checkpoint_to_hub``
uploads the folder after the save); ``rik eval`` also follows ``train_config.json`` to the dataset where a folder
has no copy (:func:`rik.lerobot.policy_io.contract_file`).
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rik.errors import RikError
from rik.lerobot.policy_io import POLICY_IO_FILE, PolicyIO
from rik.outputs import Replaces, write_text

TRAIN_MODULE = "lerobot.scripts.lerobot_train"
PRETRAINED = "pretrained_model"
"""The folder of a checkpoint that holds the policy (LeRobot's ``PRETRAINED_MODEL_DIR``)."""


def install() -> bool:
    """Wrap ``lerobot-train``'s ``save_checkpoint`` (once); whether it is wrapped (False outside
    ``lerobot-train``)."""
    module = next((m for m in (sys.modules.get(TRAIN_MODULE), sys.modules.get("__main__"))
                   if m is not None and getattr(getattr(m, "__spec__", None), "name", None) == TRAIN_MODULE), None)
    save = getattr(module, "save_checkpoint", None)
    if module is None or save is None:
        return False
    if not getattr(save, "rik_contract", False):
        setattr(module, "save_checkpoint", with_contract(save))  # noqa: B010  (a module's attribute)
    return True


def with_contract(save: Callable[..., Any]) -> Callable[..., Any]:
    """``save`` (LeRobot's ``save_checkpoint(checkpoint_dir, step, cfg, ...)``), then :func:`copy_contract`."""
    def save_checkpoint(*args: Any, **kwargs: Any) -> Any:
        result = save(*args, **kwargs)
        checkpoint = kwargs.get("checkpoint_dir", args[0] if args else None)
        cfg = kwargs.get("cfg", args[2] if len(args) > 2 else None)
        if checkpoint is not None and cfg is not None:
            copy_contract(Path(checkpoint) / PRETRAINED, cfg)
        return result

    save_checkpoint.rik_contract = True  # type: ignore[attr-defined]
    return save_checkpoint


def dataset_root(cfg: Any) -> Path | None:
    """The root of a training config's dataset: ``dataset.root``, else LeRobot's cache folder of its repo id."""
    dataset = getattr(cfg, "dataset", None)
    root, repo_id = getattr(dataset, "root", None), getattr(dataset, "repo_id", None)
    if root:
        return Path(root)
    if isinstance(repo_id, str) and repo_id:
        from lerobot.utils.constants import HF_LEROBOT_HOME

        return Path(HF_LEROBOT_HOME) / repo_id
    return None


def copy_contract(folder: Path, cfg: Any) -> Path | None:
    """Write the contract of ``cfg``'s dataset into the policy ``folder`` (None where the dataset has none); a
    problem is one warning, never the end of training."""

    root = dataset_root(cfg)
    source = None if root is None else root / "meta" / POLICY_IO_FILE
    if source is None or not source.is_file():
        return None
    ours = Replaces("rik's contract of an earlier save of this checkpoint", _is_contract)
    try:
        return write_text(folder / POLICY_IO_FILE, PolicyIO.read(source).to_json(), ours)
    except (RikError, OSError) as exc:
        logging.getLogger(__name__).warning(f"rik: the checkpoint in {folder} has no copy of {source}: {exc}")
        return None


def _is_contract(path: Path) -> bool:
    """Whether ``path`` holds a contract (what an earlier save of the same checkpoint wrote)."""

    try:
        PolicyIO.read(path)
    except RikError:
        return False
    return True
