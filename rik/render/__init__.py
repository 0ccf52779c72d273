"""The MuJoCo image stream, the Mitsuba 3 re-renderer and the visual-gap metrics (FID, EMD, KID).

Not built yet; see ../shared/DESIGN.md. Heavy libraries are imported inside functions, never here."""
