"""Measured joint trajectories: baseline fit, residual diagnosis, the effect library, the extended joint model.

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
