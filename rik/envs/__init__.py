"""The gymnasium environment ``rik/OpenFront-v0`` (:mod:`.open_front`): one front to open, with image and state
observations; the LeRobot env plugin (``packages/lerobot_env_rik``) and ``rik eval`` run policies in it."""
