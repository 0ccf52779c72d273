"""``rik serve``: the web app (catalog pages and the browser teleop station). Only parsing and printing here;
:mod:`rik.web` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rik.cli.common import DEFAULT_ROBOT, CatalogOption, RobotOpt, console, overlays


def serve(port: Annotated[int, typer.Option("--port", help="Port to listen on (0: a free one).")] = 8765,
          host: Annotated[str, typer.Option("--host", help="Address to listen on (default: this machine only; "
                                            "reach it from elsewhere through an SSH tunnel).")] = "127.0.0.1",
          out: Annotated[Path, typer.Option("--out", "-o", help="Directory the station writes episodes to.")]
          = Path("episodes"),
          variants: Annotated[Path, typer.Option("--variants", help="Directory of built variants.")]
          = Path("variants"),
          datasets: Annotated[Path, typer.Option("--datasets", help="Directory of built datasets (each subfolder "
                                                 "one) that the episodes page lists.")] = Path("datasets"),
          max_seconds: Annotated[float | None, typer.Option("--max-seconds", help="Time limit of a teleoperated "
                                                            "episode, simulated s (default: none).")] = None,
          max_stations: Annotated[int, typer.Option("--max-stations", help="Teleop stations alive at once (each "
                                                    "holds a scene and renderers, 100-300 MB).")] = 4,
          idle_release: Annotated[float, typer.Option("--idle-release", help="Release a station no tab has "
                                                      "watched for this long, s (its episode is kept as a "
                                                      "draft).")] = 600.0,
          allow_host: Annotated[list[str] | None, typer.Option("--allow-host", help="Another host name the app "
                                                               "answers to (a name of this machine; repeatable). "
                                                               "localhost, --host and IP addresses always "
                                                               "are.")] = None,
          robot: RobotOpt = DEFAULT_ROBOT, catalog: CatalogOption = None) -> None:
    """Serve the web app: browse the catalog (thumbnails, filters, fidelity) and teleoperate any pairing in the
    browser (keyboard, gamepad) with any robot of the catalog (--robot: the stations' default; a station page
    takes ?robot=), recording episodes into --out; /episodes lists them (each with a link that replays it) and the
    datasets in --datasets. The printed address carries a token made for this launch:
    other pages in the same browser cannot use the app (docs/reliability.md)."""
    from rik.registry.load import load_catalog
    from rik.web.app import AppConfig
    from rik.web.app import serve as serve_app

    con = console()
    config = AppConfig(load_catalog(overlays(catalog)), variants=variants, episodes=out,
                       overlays=tuple(overlays(catalog)), max_seconds=max_seconds, robot=robot,
                       max_stations=max_stations, idle_release=idle_release, allowed_hosts=tuple(allow_host or ()),
                       datasets=datasets)

    def ready(url: str) -> None:
        p = url.rsplit(":", 1)[1].split("/")[0]
        con.print(f"rik serve: [bold]{url}[/] (Ctrl+C to stop; from another machine: ssh -L {p}:localhost:{p} "
                  "THIS_HOST, then open the same address there)", soft_wrap=True)

    serve_app(config, host=host, port=port, on_ready=ready)
    con.print("rik serve: stopped")
