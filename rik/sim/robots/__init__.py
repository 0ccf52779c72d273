"""The robots that open fronts: the Robotiq Hand-E (:mod:`.gripper`), on a force-limited floating base or on an
arm (:mod:`.arm`, solved by :mod:`.ik`), both driven through one interface (:mod:`.drive`); each robot's
LeRobot state and action layout (:mod:`.layout`) and the checks that it can reach and pull a front
(:mod:`.checks`)."""
