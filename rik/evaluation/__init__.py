"""Policies on rik's benchmark: a saved LeRobot policy (or a scripted strategy) run on the episodes of a catalog
split with the policy's contract (:mod:`rik.lerobot.policy_io`), as the paper's Table 3 (``rik eval``)."""
