"""The browser teleop station: ``GET /teleop/{variant}`` serves the page, ``WS /teleop/{variant}/ws`` streams
the cameras and the status and takes the operator's input; the sessions live in :mod:`rik.teleop.station`.

Every request passes the gate of :mod:`rik.web.guard` first (this server's Host, the launch token, the app's
own Origin on the websocket). Opening the page starts nothing; opening its websocket starts the station, within
the app's bound (``max_stations``; the least recently watched station with no tab is released first, its episode
kept as a draft), and a station no tab watches for ``idle_release`` seconds is released the same way.

Both take ``?robot=<catalog robot id>`` (``hand-e``, ``panda-2f85``, ``so100``, or a user catalog's): the robot
that operates the front; without it, the app's (``rik serve --robot``, default ``hand-e``). Each variant and robot
is a station of its own, so the catalog's pairing picker links one address per furniture and robot, which a user
can bookmark or share. An unknown robot gets a 404 page with the one-line message; an arm that cannot reach the
handle gets the page, whose banner says why (the station's ``error``). ``GET /teleop/robots.json`` lists the
catalog's robots for the catalog's picker.

Protocol of ``WS /teleop/{variant}/ws``
---------------------------------------
Server -> browser, binary (a camera frame)::

    4 bytes: header length N, big-endian unsigned
    N bytes: JSON header {"camera": "front"|"wrist", "step": recorded steps (or replayed row), "seq": the last
             input seq applied to the simulation when this frame was rendered, "t": simulated time (s),
             "sent": server wall clock at render (s since the epoch), "width", "height", "replay": bool}
    rest:    the JPEG image (no shadows or reflections; quality 80). The "front" image is the operator's follow
             view (rik.teleop.view: it keeps the gripper, handle and front in frame), jaws and handle painted in
             colours of their own; recorded streams use the scene's fixed cameras and materials.

Server -> browser, text: JSON status {"type": "status", "variant", "robot", "ready" (variant built and session up),
"error" (why it cannot run, or null), "role" ("controller" | "watcher"), "notice" (a message for this tab),
"message" (the station's last message), "controlled" (whether a tab controls), "paused" and "draft" (a draft
kept after the controlling tab's connection was lost: the page offers Continue / Save / Discard), "replay"
(null or {episode, row, rows, opening: the replayed row's}), "seq", "fps" (frames rendered per second), "size"
([w, h] of this tab's frames), "view" ({azimuth, elevation}: the front view's turn,
degrees), "session": :meth:`rik.teleop.session.TeleopSession.status` (with "pose": gripper
base x, y, z m, pitch, yaw, roll rad, and "yaw_deg", "roll_deg")}.

Browser -> server, text JSON (anything else: a binary frame, text that is not JSON or holds ``NaN``/``Infinity``,
an unknown type or field of the wrong type, gets a notice in this tab's next status and changes nothing; a message
over 64 KiB closes the connection with code 1009):

- ``{"type": "input", "seq": n, "axes": [6 numbers in -1..1: x (left), y (away), z (up), pitch, yaw, roll],
  "grip": 0..1 or null (null: keep the grip), "fine": bool}``; an input older than 0.5 s without a newer one
  commands no motion (a tab that lost focus);
- ``{"type": "command", "name": "save" | "discard" | "toggle_grip" | "toggle_motion" | "replay" | "continue" |
  "take_control"}``;
- ``{"type": "command", "name": "replay", "episode": "<episode id>"}`` replays an episode saved in the app's episodes
  folder (the episodes page's link, ``/teleop/<variant>?robot=<id>&replay=<episode id>``, sends it once this tab
  controls the ready station): only one of this station's variant and robot, its states file at most 256 MiB;
  otherwise the station's message says why in one line (an id that is not printable text of at most 255 UTF-8
  bytes, such as one holding a NUL, gets a notice). Any command that fails is a one-line message; the station and
  its episode go on;
- ``{"type": "view", "azimuth": degrees, "elevation": degrees}`` turns the front view by that much (each within
  +-360), ``{"type": "view", "reset": true}`` puts it back; from the controlling tab (the view is the station's);
- ``{"type": "size", "width": 320|640, "height": 240|480}``.

Frames and status go to every tab through a latest-frame slot per tab (a slow tab skips frames). The world keeps
real time whatever a render costs (a slow render drops frames, not simulated time); while the station is behind,
the wrist camera is sent with every other ``front`` frame only. One tab controls
(the first); the others watch and their input is refused with a notice, until the controlling tab leaves and one
of them sends ``take_control``. The simulation steps only while a tab controls.
"""

from __future__ import annotations

import asyncio
import html
import json
from typing import TYPE_CHECKING, Any

from fastapi import APIRouter, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse

from rik.errors import RikError
from rik.web.pages import STATIC

if TYPE_CHECKING:
    from fastapi import FastAPI

    from rik.teleop.station import Stations

router = APIRouter()


def _stations(app: Any) -> Stations:
    return app.state.stations


def _variant(app: Any, text: str) -> str:
    """The canonical id of the variant ``text`` names, or a RikError with the catalog's one-line message."""
    from rik.registry.ids import parse_variant_id

    return parse_variant_id(app.state.config.catalog, text).id


def _robot(app: Any, robot: str | None) -> str:
    """The robot id a page asks for (None: the app's), or a RikError with the catalog's one-line message."""
    config = app.state.config
    return config.catalog.robot(robot).id if robot else config.robot


@router.get("/teleop/robots.json", include_in_schema=False)
def robots(request: Request) -> JSONResponse:
    """The catalog's robots (id, name, kind) and the app's default, for the catalog's pairing picker."""
    config = request.app.state.config
    rows = [{"id": r.id, "name": r.name, "kind": r.kind.value} for r in config.catalog.robots.values()]
    return JSONResponse({"default": config.robot, "robots": rows})


@router.get("/teleop/keymap.json", include_in_schema=False)
def keymap() -> JSONResponse:
    """The keymap shared with the viewer (:mod:`rik.teleop.keys`), for the page's keyboard and its table."""
    from rik.teleop import keys as k

    motion = [{"code": b.code, "label": b.label, "axis": b.axis, "sign": b.sign, "does": b.does}
              for b in k.MOTION_KEYS]
    commands = {name: {"code": code, "label": label, "does": does}
                for name, (code, _, label, does) in k.COMMAND_KEYS.items()}
    return JSONResponse({"axes": list(k.AXES), "motion": motion, "commands": commands,
                         "rows": [list(r) for r in k.keymap_rows()], "fine_factor": k.FINE_FACTOR,
                         "linear_speed": k.LINEAR_SPEED, "angular_speed": k.ANGULAR_SPEED})


def error_page(message: str, status: int = 404) -> HTMLResponse:
    text = html.escape(message)
    return HTMLResponse(f"<!doctype html><html><head><meta charset='utf-8'><title>rik: error</title>"
                        f"<link rel='stylesheet' href='/static/teleop.css'></head><body><main class='error'>"
                        f"<h1>rik teleop</h1><p id='error'>rik: error: {text}</p>"
                        f"<p><a href='/catalog'>the catalog</a></p></main></body></html>", status_code=status)


@router.get("/teleop/{variant}", include_in_schema=False, response_model=None)
async def page(request: Request, variant: str, robot: str | None = None) -> FileResponse | HTMLResponse:
    """The station's page. Only the ids are checked here (the catalog's one line on a 404 page): a GET starts no
    work; the station starts when the page opens its websocket."""
    try:
        _variant(request.app, variant)
        _robot(request.app, robot)
    except RikError as exc:
        return error_page(str(exc))
    return FileResponse(STATIC / "teleop.html", headers={"Cache-Control": "no-store"})


def parse_message(text: str) -> tuple[Any, str]:
    """A tab's text message as JSON, or (None, the notice saying why it was ignored): not JSON, nested too deeply,
    or holding a non-finite number (``NaN``, ``Infinity``: JSON has none, Python's parser reads them)."""

    class NonFinite(ValueError):
        pass

    def non_finite(name: str) -> Any:
        raise NonFinite(name)

    try:
        return json.loads(text, parse_constant=non_finite), ""
    except RecursionError:
        return None, "ignored a message nested too deeply"
    except NonFinite:
        return None, "ignored a message holding NaN or Infinity: numbers must be finite"
    except ValueError:
        return None, "ignored a message that is not JSON"


@router.websocket("/teleop/{variant}/ws")
async def stream(websocket: WebSocket, variant: str, robot: str | None = None) -> None:
    """One tab's connection: frames and status out, input and commands in (see the module docstring). Opening it
    starts the station (building the variant in its thread when needed), within the app's bound on stations."""
    from rik.teleop.station import Client

    await websocket.accept()
    try:
        vid = _variant(websocket.app, variant)
        rid = _robot(websocket.app, robot)
        client = Client(asyncio.get_running_loop())
        station = await asyncio.to_thread(_stations(websocket.app).get, vid, rid, client)
    except RikError as exc:
        await websocket.send_text(json.dumps({"type": "status", "ready": False, "error": str(exc)}))
        await websocket.close(code=1008)
        return

    async def sender() -> None:
        while True:
            await client.event.wait()
            client.event.clear()
            for item in client.take():
                if isinstance(item, bytes):
                    await websocket.send_bytes(item)
                else:
                    await websocket.send_text(item)

    task = asyncio.create_task(sender())
    try:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                break
            text = message.get("text")
            if text is None:
                client.notice = "ignored a binary message: send JSON text (input, command or size)"
                continue
            msg, notice = parse_message(text)
            if notice:
                client.notice = notice
                continue
            station.receive(client, msg)
    except (WebSocketDisconnect, RuntimeError):
        pass
    finally:
        task.cancel()
        station.disconnect(client)


def install(app: FastAPI, scenes: dict[tuple[str, str], Any] | None = None) -> None:
    """The stations of ``app`` (``scenes``: scenes already built, by variant and robot id); on shut-down their
    threads stop and episodes in progress are kept as drafts."""
    from contextlib import asynccontextmanager

    from rik.teleop.station import Stations

    stations = Stations(app.state.config, scenes)
    app.state.stations = stations
    inner = app.router.lifespan_context

    @asynccontextmanager
    async def lifespan(a: Any) -> Any:
        async with inner(a) as state:
            try:
                yield state
            finally:
                await asyncio.to_thread(stations.shutdown)

    app.router.lifespan_context = lifespan
