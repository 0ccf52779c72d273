"""Catalog pages of the web app (placeholder: filled in by the catalog work of issue 20)."""

from __future__ import annotations

from fastapi import APIRouter

router = APIRouter()
