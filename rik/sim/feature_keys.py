"""The LeRobot feature keys rik writes and reads, named once. Each equals the constant of lerobot 0.6.1 of the same
name (``lerobot.utils.constants``: ``OBS_STATE``, ``OBS_ENV_STATE``, ``OBS_IMAGES``, ``ACTION``), which is not
imported here because importing lerobot loads torch; ``tests/test_export.py`` checks that they agree. LeRobot has no
constant for :data:`EE_POSE` and :data:`TASK`: those are rik's."""

OBS_STATE = "observation.state"
"""The robot's state (:data:`rik.sim.observation.ROBOT_STATE_NAMES`, or an arm's joints)."""
OBS_ENV_STATE = "observation.environment_state"
"""The front's state (:data:`rik.sim.observation.ENV_STATE_NAMES`)."""
OBS_IMAGES = "observation.images"
"""The prefix of the image features: ``observation.images.<camera>[_rerendered]``."""
ACTION = "action"
"""The action: the Hand-E's target pose and gripper command, an arm's joint targets."""
EE_POSE = "observation.ee_pose"
"""The feature of an arm's end-effector pose in its base frame (:data:`rik.sim.robots.layout.EE_NAMES`), where its
catalog entry asks for one (lerobot passes the environment's ``ee_pose`` through under this name)."""
TASK = "task"
"""The key of a frame's task string in lerobot's ``add_frame`` (lerobot writes it as a literal)."""
