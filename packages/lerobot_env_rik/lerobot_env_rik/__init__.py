"""rik as a LeRobot environment: ``--env.type=rik`` for ``lerobot-train`` and ``lerobot-eval``.

LeRobot 0.6.1 imports this package at start-up (``register_third_party_plugins`` imports every installed
distribution named ``lerobot_env_*``). It is a shim: importing rik's config (:mod:`rik.lerobot.env_config`) registers
:class:`RikEnvConfig` under the name ``rik``, importing rik's environment registers ``rik/OpenFront-v0`` with
gymnasium, and inside ``lerobot-train`` the dataset's contract is copied beside each checkpoint
(:mod:`rik.lerobot.train_hook`). It imports rik's environment and its LeRobot contract, nothing else of rik.
"""

from __future__ import annotations

import rik.envs.open_front  # noqa: F401  (registers rik/OpenFront-v0 with gymnasium)
from rik.lerobot import train_hook
from rik.lerobot.env_config import AUTO, RikEnvConfig, action_mode, env_kwargs

__all__ = ["AUTO", "RikEnvConfig", "action_mode", "env_kwargs"]

train_hook.install()
