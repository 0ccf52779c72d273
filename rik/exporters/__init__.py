"""Exporters of recorded episodes: :mod:`rik.exporters.lerobot_export` (LeRobot v3.0 datasets, ``rik
export-lerobot``), with :mod:`~rik.exporters.spec` (what an export writes and its checks),
:mod:`~rik.exporters.lerobot_frames` (episodes read once, features and frames), :mod:`~rik.exporters.lerobot_check`
(frame counts), :mod:`~rik.exporters.lerobot_card` (the dataset card) and :mod:`~rik.sim.feature_keys` (LeRobot's
feature keys). lerobot is imported inside functions."""
