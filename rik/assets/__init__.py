"""Parametric handle and base-unit meshes, CoACD collision (content-addressed cache), collision fidelity.

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
