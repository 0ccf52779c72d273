"""Scene assembly, gymnasium environment, teleop devices, scripted strategies, episode recorder, benchmark.

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
