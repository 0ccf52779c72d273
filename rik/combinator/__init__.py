"""Base unit x handle x preset pairing, placement on mount sites, named validation checks, MJCF through mujoco.MjSpec.

Heavy libraries (mujoco, coacd, trimesh) are imported inside functions, never here."""
