"""Catalog pages of the web app: browse handles and base units (thumbnails, filters, dimensions, mesh statistics,
collision fidelity) and pick a pairing to build and teleoperate at ``/teleop/<variant id>``.

Pages: ``/catalog``, ``/catalog/handle/<id>``, ``/catalog/base/<id>`` (one static page; the script opens the
entry). Pictures: ``/catalog/img/<id>/thumbnail.png`` and ``fidelity.png`` (a handle's, from ``docs/catalog``;
a placeholder drawing where it has none) and ``/catalog/img/<id>/front.svg`` (a base unit's front view). JSON:
``/api/catalog/handles[/<id>]``, ``/api/catalog/bases[/<id>]``, ``/api/catalog/presets``. An unknown id is a 404
whose ``detail`` is one line with close matches.

3D models for the page's viewer (binary glTF, :mod:`rik.web.meshes`): ``/catalog/model/<handle id>/visual.glb`` (a
handle's visual mesh, made from its generator, no CoACD) and ``/catalog/variant/<variant id>/visual.glb`` (a variant
already built and current in the app's variants folder; otherwise a 404 naming the command that builds it: a GET
builds nothing). Both are memoised per app.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import FileResponse, Response

from rik.errors import RikError, UnknownIdError
from rik.web.catalog_view import PICTURES, CatalogView, base_unit_svg, build_view, placeholder_svg
from rik.web.meshes import GLB_MEDIA_TYPE, Memo, built_variant, handle_glb, variant_glb
from rik.web.pages import STATIC

router = APIRouter()

SVG = "image/svg+xml"


def catalog_view(request: Request) -> CatalogView:
    """The app's catalog view, built on first use from ``app.state.config.catalog``."""
    state = request.app.state
    view = getattr(state, "catalog_view", None)
    if view is None:
        view = state.catalog_view = build_view(state.config.catalog)
    return view


def _page() -> FileResponse:
    return FileResponse(STATIC / "catalog.html", media_type="text/html")


def _known(view: CatalogView, section: str, entry_id: str) -> dict[str, Any]:
    """The row of ``entry_id`` in ``section`` (handles or bases), or a 404 naming close ids."""
    rows = view.handles if section == "handles" else view.bases
    if entry_id not in rows:
        noun = "handle" if section == "handles" else "base unit"
        raise HTTPException(404, str(UnknownIdError(noun, entry_id, rows)))
    return rows[entry_id]


@router.get("/catalog", include_in_schema=False)
def catalog_page() -> FileResponse:
    return _page()


@router.get("/catalog/handle/{handle_id:path}", include_in_schema=False)
def handle_page(handle_id: str, request: Request) -> FileResponse:
    _known(catalog_view(request), "handles", handle_id)
    return _page()


@router.get("/catalog/base/{base_id:path}", include_in_schema=False)
def base_page(base_id: str, request: Request) -> FileResponse:
    _known(catalog_view(request), "bases", base_id)
    return _page()


@router.get("/catalog/img/{entry_id:path}/{name}", include_in_schema=False)
def picture(entry_id: str, name: str, request: Request) -> Response:
    """A handle's ``thumbnail.png`` or ``fidelity.png`` (a placeholder drawing when it has none), or a base
    unit's ``front.svg``."""
    view = catalog_view(request)
    if entry_id in view.bases:
        if name != "front.svg":
            raise HTTPException(404, f"base unit '{entry_id}' has no picture '{name}'; valid: front.svg")
        return Response(base_unit_svg(view.bases[entry_id]), media_type=SVG)
    _known(view, "handles", entry_id)
    stem = name.removesuffix(".png")
    if stem not in PICTURES or stem == name:
        raise HTTPException(404, f"handle '{entry_id}' has no picture '{name}'; valid: "
                            + " or ".join(f"{p}.png" for p in PICTURES))
    path = view.picture(entry_id, stem)
    if path is None:
        return Response(placeholder_svg(entry_id, stem), media_type=SVG, headers={"X-Rik-Placeholder": "1"})
    return FileResponse(path, media_type="image/png")


def _memo(request: Request) -> Memo:
    state = request.app.state
    memo = getattr(state, "glb_memo", None)
    if memo is None:
        memo = state.glb_memo = Memo()
    return memo


def _glb(data: bytes) -> Response:
    return Response(data, media_type=GLB_MEDIA_TYPE, headers={"Cache-Control": "no-store"})


@router.get("/catalog/model/{handle_id:path}/visual.glb", include_in_schema=False)
def handle_model(handle_id: str, request: Request) -> Response:
    """A handle's visual mesh as GLB (m, mount frame, its finish's material)."""
    _known(catalog_view(request), "handles", handle_id)
    catalog = request.app.state.config.catalog
    try:
        return _glb(_memo(request).get(("handle", handle_id), lambda: handle_glb(catalog, handle_id)))
    except RikError as exc:  # a user catalog's mesh file gone or changed: its one line, not a traceback
        raise HTTPException(404, str(exc).splitlines()[0]) from None


@router.get("/catalog/variant/{variant}/visual.glb", include_in_schema=False)
def variant_model(variant: str, request: Request) -> Response:
    """A built, current variant's visual geoms as GLB (posed closed, m, z up); a 404 with one line when the id is
    unknown or the variant is not built (nothing is built here)."""
    config = request.app.state.config
    try:
        vid, directory, digest = built_variant(config.catalog, config.variants, variant)
    except RikError as exc:
        raise HTTPException(404, str(exc)) from None
    report = (directory / "report.json").stat()
    key = ("variant", vid, digest, report.st_mtime_ns, report.st_size)
    return _glb(_memo(request).get(key, lambda: variant_glb(directory / "model.xml", config.catalog.finishes)))


@router.get("/api/catalog/handles")
def handles(request: Request) -> dict[str, Any]:
    """Every handle (SI units, ``dimensions_mm`` for display), with finish, split, mesh and fidelity numbers."""
    view = catalog_view(request)
    rows = list(view.handles.values())
    return {"count": len(rows), "handles": rows, "pairings": view.index.pairings,
            "finishes": [{"id": f["id"], "name": f["name"]} for f in view.index.entries("finishes")]}


@router.get("/api/catalog/handles/{handle_id:path}")
def handle(handle_id: str, request: Request) -> dict[str, Any]:
    """One handle and the base units it fits, with the variant id of each pairing per preset."""
    view = catalog_view(request)
    return {**_known(view, "handles", handle_id), "pairings": view.pairings_of_handle(handle_id)}


@router.get("/api/catalog/bases")
def bases(request: Request) -> dict[str, Any]:
    """Every base unit: carcass, fronts (mm copies for display), joint types, default preset, handles that fit."""
    rows = list(catalog_view(request).bases.values())
    return {"count": len(rows), "bases": rows}


@router.get("/api/catalog/bases/{base_id:path}")
def base(base_id: str, request: Request) -> dict[str, Any]:
    """One base unit and the handles that fit it, with the variant id of each pairing per preset."""
    view = catalog_view(request)
    return {**_known(view, "bases", base_id), "pairings": view.pairings_of_base(base_id)}


@router.get("/api/catalog/presets")
def presets(request: Request) -> dict[str, Any]:
    """The resistance presets (slide and hinge damping and friction, SI)."""
    rows = catalog_view(request).presets
    return {"count": len(rows), "presets": rows}
