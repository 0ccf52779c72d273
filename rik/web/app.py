"""The web app: one FastAPI application with the catalog (``/catalog``), the teleop station (``/teleop``) and the
page of recorded episodes and built datasets (``/episodes``), served by uvicorn on a socket bound before anything
else starts, so that a port in use fails at once."""

from __future__ import annotations

import errno
import socket
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.teleop.station import StationConfig
from rik.web.guard import Guard, new_token, with_token
from rik.web.pages import STATIC

if TYPE_CHECKING:
    from fastapi import FastAPI


DEFAULT_PORT = 8765
DEFAULT_HOST = "127.0.0.1"


@dataclass
class AppConfig(StationConfig):
    """What the app serves: the teleop stations' settings (:class:`rik.teleop.station.StationConfig`: the catalog,
    where variants are built and episodes written) and the gate's."""

    token: str = field(default_factory=new_token)
    """The launch token every request must show (:mod:`rik.web.guard`): in the printed address, then a cookie."""
    allowed_hosts: tuple[str, ...] = ()
    """Host names the app answers to besides localhost's, the ``--host`` it listens on and IP literals."""
    datasets: Path = Path("datasets")
    """Folder of built datasets (each subfolder one, from ``rik dataset build``) that ``/episodes`` lists."""

    def check(self) -> None:
        """Settings a user gave that cannot work fail here, before the server starts."""
        super().check()
        if len(self.token) < 16:
            raise RikError("the launch token must be at least 16 characters")


def bind_socket(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (``port`` 0: a free one), or a one-line error when it is taken."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            raise RikError(f"--port {port}: port {port} on {host} is in use (another rik serve?); choose another "
                           "with --port, or --port 0 for a free one") from None
        raise RikError(f"--host {host} --port {port}: cannot listen there: {exc.strerror or exc}") from None
    sock.listen(64)
    sock.set_inheritable(True)
    return sock


def serve_station(config: AppConfig, variant: str, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
                  on_ready: object = None) -> None:
    """``rik teleop VARIANT --web``: build the variant and the scene with ``config.robot`` first (an unknown or
    rejected variant, an unknown robot, an arm that cannot reach the handle fail here, before any port is taken),
    then serve the app with the station of ``variant`` as the printed address; the station starts from that
    scene."""
    from urllib.parse import quote

    from rik.registry.ids import parse_variant_id
    from rik.teleop.station import build_station_scene

    config.check()
    vid = parse_variant_id(config.catalog, variant).id
    scene = build_station_scene(config, vid, config.robot)
    serve(config, host=host, port=port, path=f"/teleop/{quote(vid)}", on_ready=on_ready,
          scenes={(vid, config.robot): scene})


def create_app(config: AppConfig, scenes: dict[tuple[str, str], Any] | None = None, *,
               host: str = DEFAULT_HOST) -> FastAPI:
    """The application: the catalog's and the teleop station's routes, and the static files, behind the gate of
    :mod:`rik.web.guard` (``host``: the address it listens on, a name it answers to); ``scenes``: scenes already
    built, by (variant id, robot id), that those stations start from."""
    from fastapi.responses import RedirectResponse
    from fastapi.staticfiles import StaticFiles

    from rik import __version__
    from rik.web import catalog as catalog_routes
    from rik.web import episodes as episode_routes
    from rik.web import teleop as teleop_routes
    from rik.web.asgi import RikApp

    # no /docs, /redoc, /openapi.json: FastAPI's docs load Swagger UI from a CDN into the app's origin
    app = RikApp(title="rik", version=__version__, docs_url=None, redoc_url=None, openapi_url=None)
    app.add_middleware(Guard, token=config.token, host=host, allowed_hosts=config.allowed_hosts)
    app.state.config = config
    app.include_router(catalog_routes.router)
    app.include_router(teleop_routes.router)
    app.include_router(episode_routes.router)
    teleop_routes.install(app, scenes)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")

    @app.get("/", include_in_schema=False)
    def index() -> RedirectResponse:
        return RedirectResponse("/catalog")

    return app


WS_MAX_MESSAGE = 64 * 1024
"""Largest websocket message a tab may send, bytes (the protocol's messages are under 300): a larger one closes the
connection with code 1009 before it is read whole."""


def make_server(app: Any) -> Any:
    """A uvicorn server of ``app`` with rik's settings (websocket message bound, quiet log, lifespan on)."""
    import uvicorn

    return uvicorn.Server(uvicorn.Config(app, log_level="warning", ws="websockets-sansio", lifespan="on",
                                         ws_max_size=WS_MAX_MESSAGE))


def serve(config: AppConfig, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, path: str = "/",
          on_ready: object = None, scenes: dict[tuple[str, str], Any] | None = None) -> None:
    """Serve the app until interrupted (Ctrl+C, a normal stop: the function returns). The socket is bound first (a
    port in use fails here); the URL of ``path``, with the launch token, is given to ``on_ready(url)`` once it
    listens."""
    config.check()
    sock = bind_socket(host, port)
    bound = sock.getsockname()[1]
    server = make_server(create_app(config, scenes, host=host))
    if callable(on_ready):
        shown = "localhost" if host in ("127.0.0.1", "::1", "localhost") else host
        on_ready(f"http://{shown}:{bound}{with_token(path, config.token)}")
    try:
        server.run(sockets=[sock])
    except KeyboardInterrupt:  # Ctrl+C is how a server is stopped: uvicorn has shut down, re-raising the signal
        pass
    finally:
        sock.close()
