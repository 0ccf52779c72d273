"""Exporters of recorded episodes: :mod:`rik.exporters.lerobot_export` (LeRobot v3.0 datasets, ``rik
export-lerobot``), with :mod:`~rik.exporters.spec` (what an export writes and its checks),
:mod:`~rik.exporters.lerobot_frames` (episodes read once, features and frames), :mod:`~rik.exporters.lerobot_check`
(frame counts) and :mod:`~rik.exporters.lerobot_card` (the dataset card); the feature keys and the contract each export
writes into ``meta/rik_policy_io.json`` are :mod:`rik.lerobot`'s. lerobot is imported inside functions."""
