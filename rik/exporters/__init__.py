"""Exporters of recorded episodes: :mod:`rik.exporters.lerobot_export` (LeRobot v3.0 datasets, ``rik
export-lerobot``), with :mod:`~rik.exporters.lerobot_frames` (features and frames), :mod:`~rik.exporters.lerobot_check`
(frame counts) and :mod:`~rik.exporters.lerobot_card` (the dataset card). lerobot is imported inside functions."""
