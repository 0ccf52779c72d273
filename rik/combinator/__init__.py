"""Base unit x handle x preset pairing, placement on mount sites, named validation checks, MJCF through mujoco.MjSpec.

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
