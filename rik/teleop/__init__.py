"""Teleoperation: a session that turns an operator's device input into gripper targets and records the episode
(:mod:`.session`), the shared keymap (:mod:`.keys`), the desktop viewer (:mod:`.desktop`, :mod:`.window`) and the
browser station (:mod:`.station`) that :mod:`rik.web` serves over a websocket."""
