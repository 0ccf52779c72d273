"""The app's FastAPI class: its middleware stack is wrapped in :class:`rik.web.guard.NoFraming`, so every response
it sends, whatever made it (a page, a static file, the gate's refusal or redirect, a 404, a 500 of an unexpected
error), says that no page may frame it."""

from __future__ import annotations

from typing import Any, cast

from fastapi import FastAPI
from starlette.types import ASGIApp

from rik.web.guard import NoFraming


class RikApp(FastAPI):
    """FastAPI with :class:`NoFraming` outside every other middleware (Starlette's error handler included)."""

    def build_middleware_stack(self) -> ASGIApp:
        stack: Any = super().build_middleware_stack()  # Starlette types scopes as mappings, rik.web.guard as dicts
        return cast(ASGIApp, NoFraming(stack))
