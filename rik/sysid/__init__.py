"""Measured joint trajectories: baseline fit, residual diagnosis, the effect library, the extended joint model.

Built so far:

- :mod:`rik.sysid.trials`: measured trials in (CSV, Parquet, a LeRobot v3.0 dataset), units declared in the
  column headers and converted to SI, every bad input refused with a one-line :class:`~rik.errors.RikError`;
- :mod:`rik.sysid.preprocess`: uniform resampling, Savitzky–Golay smoothing and derivatives, force-to-position
  delay, and the moving, opening, closing, sticking and near-limit masks.

The fit, the diagnosis and the effect library come next; see ../shared/DESIGN.md. Heavy libraries (scipy,
pyarrow, mujoco) are imported inside functions, never here."""
