"""Which of a rollout's observations a LeRobot policy reads: the answer that lets an image evaluation render a
frame only for the steps whose images reach the policy.

A chunking policy predicts a chunk of actions from one observation (ACT) or from its last ``n_obs_steps`` ones
(diffusion) and then plays the chunk; the observations of the steps between predictions are passed to its
``select_action`` and dropped. Between two steps of a rollout (its ``select_action`` has taken its action) the
next observation is read when the actions still queued are fewer than the observations its next prediction
stacks: for ACT ``n_obs_steps`` is 1, so only when its queue is empty. The queues are lerobot 0.6.1's
(``ACTPolicy._action_queue``, ``DiffusionPolicy._queues["action"]``); a policy of another type, ACT with temporal
ensembling (it predicts every step) or a policy whose queue is not where it is expected reads every observation.
"""

from __future__ import annotations

from collections.abc import Callable, Sized
from typing import Any

ObservationUse = Callable[[], bool]
"""``f()``: whether the policy reads the next observation (asked after its action of this step is taken)."""


def _queued(policy: Any) -> Sized | None:
    """The actions a policy has queued, where lerobot keeps them for its type; None where not found."""
    queue = getattr(policy, "_action_queue", None)
    if queue is None:
        queues = getattr(policy, "_queues", None)
        queue = queues.get("action") if isinstance(queues, dict) else None
    return queue if isinstance(queue, Sized) else None


def _chunked(policy: Any) -> ObservationUse:
    config = policy.config
    stacked = int(getattr(config, "n_obs_steps", 1) or 1)
    if getattr(config, "temporal_ensemble_coeff", None) is not None:
        return every_observation

    def reads_next() -> bool:
        queue = _queued(policy)
        return queue is None or len(queue) < stacked

    return reads_next


def every_observation() -> bool:
    return True


CHUNKING: dict[str, Callable[[Any], ObservationUse]] = {"act": _chunked, "diffusion": _chunked}
"""Policy type (lerobot's ``policy.name``) -> its :data:`ObservationUse`, for the types whose queues are known."""


def observation_use(policy: Any) -> ObservationUse:
    """When ``policy`` reads the next observation of a rollout (:data:`ObservationUse`); every time for a type
    :data:`CHUNKING` does not know."""
    make = CHUNKING.get(str(getattr(policy, "name", "")))
    return make(policy) if make is not None else every_observation
