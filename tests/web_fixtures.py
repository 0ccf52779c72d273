"""Helpers for tests of the web app: the app served in a thread on a free port, and Debian's Chromium driven by
Playwright for Python through its ``executable_path`` (Playwright's own browser download is not used)."""

from __future__ import annotations

import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                 "--num-raster-threads=1", "--renderer-process-limit=2", "--disable-smooth-scrolling"]
"""Flags for a root, headless, offline machine (no sandbox as root; no background connections that this
machine's closed network would refuse), and a small one: one raster thread and at most two renderer processes,
so that Chromium does not pin a busy 2-core machine and starve the station it tests."""
ACTION_MS = 60_000
"""Bound of every Playwright action and navigation (Playwright's keyboard calls take none: the test's own bound,
``BROWSER_TEST_S`` in tests/conftest.py, ends those)."""
WAIT_MS = 90_000
"""Bound of every wait for the station (a loaded 2-core machine steps the simulation slowly)."""
TOKEN = "rik-web-tests-launch-token"
"""The launch token of every app :func:`served` serves (a real launch makes a random one)."""


def signed(url: str) -> str:
    """``url`` with the launch token, as rik prints it: the first page a browser context opens needs it."""
    from rik.web.guard import with_token

    return with_token(url, TOKEN)


def app_client(config: Any) -> Any:
    """A TestClient of ``create_app(config)`` that shows the launch token's cookie and a localhost Host."""
    from fastapi.testclient import TestClient

    from rik.web.app import create_app
    from rik.web.guard import cookie_name

    config.token = TOKEN
    client = TestClient(create_app(config), base_url="http://localhost")
    client.cookies.set(cookie_name(TOKEN), TOKEN)
    return client


@contextmanager
def served(config: Any) -> Iterator[str]:
    """Serve ``create_app(config)`` with rik's server settings in a thread on a free localhost port, with the launch
    token :data:`TOKEN`; yields the base URL (without the token: see :func:`signed`)."""
    from rik.web.app import create_app

    config.token = TOKEN
    with served_app(create_app(config)) as url:
        yield url


@contextmanager
def served_app(app: Any) -> Iterator[str]:
    """Serve ``app`` (from ``create_app``) with rik's server settings in a thread on a free localhost port; yields
    the base URL."""
    from rik.web.app import bind_socket, make_server

    sock = bind_socket("127.0.0.1", 0)
    server = make_server(app)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the web app did not start")
        time.sleep(0.05)
    try:
        yield f"http://127.0.0.1:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)
        sock.close()


@contextmanager
def station_process(*args: str, cwd: Path, procs: list[subprocess.Popen] | None = None) -> Iterator[str]:
    """``rik ARGS`` (a ``teleop ... --web --port 0``) in its own process, as a user runs it: yields the station's
    printed address (with its token) once it is printed; then Ctrl+C stops it (a kill after 60 s). Every wait is
    bounded. ``procs``: a list the process is appended to (to read its pid)."""
    env = {**os.environ, "COLUMNS": "200"}
    proc = subprocess.Popen([sys.executable, "-m", "rik", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=cwd)
    if procs is not None:
        procs.append(proc)
    lines: queue.Queue[str] = queue.Queue()
    err: list[str] = []
    assert proc.stdout is not None and proc.stderr is not None
    threading.Thread(target=lambda: [lines.put(x) for x in proc.stdout], daemon=True).start()  # type: ignore[union-attr]
    threading.Thread(target=lambda: err.extend(proc.stderr), daemon=True).start()  # type: ignore[arg-type]
    try:
        deadline = time.monotonic() + WAIT_MS / 1000
        url = None
        while url is None:
            try:
                found = re.search(r"http://localhost:(\d+)(/teleop/\S+)", lines.get(timeout=0.5))
                url = found and f"http://127.0.0.1:{found.group(1)}{found.group(2)}"
            except queue.Empty:
                assert proc.poll() is None, f"rik {' '.join(args)} ended with {proc.returncode}: {''.join(err)}"
                assert time.monotonic() < deadline, f"rik {' '.join(args)} printed no address in {WAIT_MS} ms"
        yield url
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=30)


def _bounded(b: Any, make: str) -> None:
    """Wrap ``b.<make>`` so the page or context it returns has :data:`ACTION_MS` as its default timeouts."""
    original = getattr(b, make)

    def made(*args: Any, **kwargs: Any) -> Any:
        thing = original(*args, **kwargs)
        thing.set_default_timeout(ACTION_MS)
        thing.set_default_navigation_timeout(ACTION_MS)
        return thing

    setattr(b, make, made)


@contextmanager
def browser(*args: str) -> Iterator[Any]:
    """A headless Debian Chromium (Playwright gives it a fresh temporary profile), through Playwright; ``args``:
    more command-line flags."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=[*CHROMIUM_ARGS, *args], timeout=ACTION_MS)
        for make in ("new_page", "new_context"):  # every page and context: actions and navigations bounded
            _bounded(b, make)
        try:
            yield b
        finally:
            b.close()
