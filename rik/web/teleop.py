"""The browser teleop station (placeholder: filled in by the teleop work of issue 20)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from fastapi import APIRouter

if TYPE_CHECKING:
    from fastapi import FastAPI

router = APIRouter()


def install(app: FastAPI) -> None:
    """Start-up and shut-down of the station's sessions."""
