"""Where the app's pages live: plain HTML, CSS and JavaScript, no build step."""

from pathlib import Path

STATIC = Path(__file__).parent / "static"
"""Pages, scripts and styles of the app."""
