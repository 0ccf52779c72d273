"""Episodes to LeRobot v3.0 datasets and their dataset cards.

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
