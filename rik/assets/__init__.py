"""Parametric handle and base-unit meshes, CoACD collision (content-addressed cache), collision fidelity.

Heavy libraries (mujoco, coacd, trimesh) are imported inside functions, never here."""
