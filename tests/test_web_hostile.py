"""The web app on a hostile web, continued (docs/reliability.md section 8): no page may frame the app (every
response says so, and a page on another port of this machine cannot frame the station in the operator's own
Chromium), the app serves no API docs and its pages load nothing from elsewhere, another localhost app's cookie that
does not parse does not lock the operator out, a token address of any path redirects cleanly, and hostile replay
ids are refused with a message while the station and its episode go on. Real server, real clients."""

from __future__ import annotations

import http.client
import json
import re
import shutil
import socket
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import urljoin, urlsplit

import pytest
from fastapi.responses import PlainTextResponse
from shared import BOW, BOW_HANDLE, DEMO_BASE, builtin_catalog
from web_fixtures import TOKEN, WAIT_MS, browser, served_app, signed
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

from rik.web.app import AppConfig, create_app
from rik.web.guard import cookie_name
from rik.web.pages import STATIC

CAT = builtin_catalog()
WAIT = WAIT_MS / 1000
COOKIE = f"{cookie_name(TOKEN)}={TOKEN}"
FOREIGN = 'prefs={"theme":"dark"}'
"""Another localhost app's cookie that http.cookies cannot parse (it stops at it, hiding every later cookie)."""
needs_chromium = pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")


# ---- helpers ------------------------------------------------------------------------------------------------------
def make_app(variants: Path, episodes: Path) -> Any:
    return create_app(AppConfig(CAT, variants=variants, episodes=episodes, token=TOKEN))


@pytest.fixture(scope="module")
def site(bow_variants: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Any, str]]:
    """One real app (the demo variant built, an empty episodes folder) served for the module's HTTP checks, with two
    routes of the test's own under ``/_test/``: one that fails (any bug of a route: a 500) and one that sets a
    policy of its own (the frame rule is merged into it)."""
    app = make_app(bow_variants, tmp_path_factory.mktemp("hostile") / "ep")

    def boom() -> None:
        raise RuntimeError("a route's bug")

    def own_policy() -> PlainTextResponse:
        return PlainTextResponse("x", headers={"Content-Security-Policy": "default-src 'self'; frame-ancestors *"})

    app.add_api_route("/_test/boom", boom)
    app.add_api_route("/_test/policy", own_policy)
    with served_app(app) as url:
        yield app, url


def request(url: str, path: str, headers: dict[str, str] | None = None, method: str = "GET") -> tuple[int, Any, bytes]:
    """One real HTTP request (exactly these headers, Host: localhost unless given); (status, headers, body)."""
    parts = urlsplit(url)
    conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=WAIT)
    try:
        conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        for k, v in {"Host": f"localhost:{parts.port}", **(headers or {})}.items():
            conn.putheader(k, v)
        conn.endheaders()
        answer = conn.getresponse()
        return answer.status, answer.msg, answer.read()
    finally:
        conn.close()


def raw_request(url: str, line: bytes) -> bytes:
    """The server's answer to one raw request line (bytes no HTTP client would send), read to the end."""
    parts = urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=WAIT) as sock:
        sock.sendall(line + f"\r\nHost: localhost:{parts.port}\r\nConnection: close\r\n\r\n".encode())
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
    return data


def ws_base(url: str) -> str:
    return url.replace("http://", "ws://")


# ---- 1. no page may frame the app --------------------------------------------------------------------------------
def test_every_response_says_no_page_may_frame_it(site: tuple[Any, str]) -> None:
    """Pages, static files, JSON, 404s (a route's, an unknown path's, a static file's, the station's page), the
    gate's refusals (400, 403 as HTML and as JSON) and redirects (its login, the index), a 405, a HEAD and a 500 of
    a failing route all carry ``frame-ancestors 'none'`` and ``X-Frame-Options: DENY``, once each; a response with
    a policy of its own keeps it, its frame-ancestors replaced."""
    _, url = site
    port = urlsplit(url).port
    ok = {"Cookie": COOKIE}
    cases = [("/catalog", ok, "GET", 200), (f"/teleop/{BOW}", ok, "GET", 200), ("/episodes", ok, "GET", 200),
             ("/static/teleop.js", {}, "GET", 200), ("/static/nope.js", {}, "GET", 404),
             ("/api/catalog/presets", ok, "GET", 200), ("/api/catalog/handles/nope", ok, "GET", 404),
             ("/teleop/nope", ok, "GET", 404), ("/nope", ok, "GET", 404), ("/", ok, "GET", 307),
             (f"/catalog?token={TOKEN}", {}, "GET", 303), ("/catalog", {}, "GET", 403),
             ("/api/catalog/presets", {}, "GET", 403), ("/catalog", {"Host": f"evil.example:{port}", **ok}, "GET", 400),
             ("/catalog", ok, "POST", 405), ("/static/teleop.css", {}, "HEAD", 200), ("/_test/boom", ok, "GET", 500),
             ("/_test/policy", ok, "GET", 200)]
    for path, headers, method, status in cases:
        got, answer, _ = request(url, path, headers, method)
        assert got == status, (method, path, got)
        assert answer.get_all("X-Frame-Options") == ["DENY"], (method, path, answer.items())
        policies = answer.get_all("Content-Security-Policy") or []
        assert len(policies) == 1 and policies[0].endswith("frame-ancestors 'none'"), (method, path, policies)
        assert policies[0].count("frame-ancestors") == 1
    assert request(url, "/_test/policy", ok)[1]["Content-Security-Policy"] == "default-src 'self'; frame-ancestors 'none'"


@contextmanager
def other_port_page(html: str) -> Iterator[str]:
    """A real HTTP server on another port of 127.0.0.1 (another local app: the same site as rik's server) that
    answers every GET with ``html``; yields its base URL."""
    body = html.encode()

    class Page(BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 -- http.server's name
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args: Any) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Page)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=WAIT)


@pytest.mark.browser
@needs_chromium
def test_a_page_on_another_local_port_cannot_frame_the_station(bow_variants: Path, tmp_path: Path) -> None:
    """The operator has the app open in Chromium (the token's cookie is set); a page served on another port of the
    same machine (same site: the SameSite=Strict cookie goes with its frames) frames the station, the catalog and
    the episodes page: Chromium blocks every frame (its error page), so no script of the app runs in it and no
    station starts."""
    app = make_app(bow_variants, tmp_path / "ep")
    with served_app(app) as url:
        pages = [f"/teleop/{BOW}", "/catalog", "/episodes"]
        frames = "".join(f'<iframe src="{url}{p}" onload="window.loaded = (window.loaded || 0) + 1"></iframe>'
                         for p in pages)
        with other_port_page(f"<!doctype html><html><body>{frames}</body></html>") as other, browser() as b:
            context = b.new_context()
            own = context.new_page()
            own.goto(signed(f"{url}/catalog"))  # the operator's tab: the cookie is set
            assert own.url == f"{url}/catalog"
            evil = context.new_page()
            evil.goto(f"{other}/attack.html")
            evil.wait_for_function(f"window.loaded === {len(pages)}", timeout=WAIT_MS, polling=100)
            framed = [f.url for f in evil.frames if f != evil.main_frame]
            assert framed == ["chrome-error://chromewebdata/"] * len(pages), framed  # blocked, not the app's page
            context.close()
    assert not app.state.stations.stations and not (tmp_path / "ep").exists()


# ---- 2. no API docs; nothing loaded from elsewhere ----------------------------------------------------------------
PARAMS = {"variant": BOW, "handle_id": BOW_HANDLE, "base_id": DEMO_BASE, "entry_id": BOW_HANDLE,
          "name": "thumbnail.png"}
"""A value of each path parameter of the app's GET routes (a route with another parameter fails the test: add it)."""
REFERENCE = re.compile(r"""(?:\b(?:src|href|action|formaction|poster|srcset)\s*=\s*["']?|url\(\s*["']?|@import\s+["']|"""
                       r"""\bfrom\s+["']|\bimport\s*\(\s*["']|\bimport\s+["'])([^"'\s>)]+)""", re.IGNORECASE)
"""An address an HTML page, style sheet or module script loads or links (attributes, url(), imports)."""
COMMENT = re.compile(r"/\*.*?\*/|^[ \t]*//[^\n]*|<!--.*?-->", re.DOTALL | re.MULTILINE)
"""Comments of scripts, styles and pages (whole-line ``//`` ones only: ``//`` in a string is an address)."""


def page_paths(app: Any) -> list[str]:
    """A concrete path of every GET route of ``app`` (its own and its routers'), but the binary 3D models."""
    from fastapi.routing import APIRoute
    from starlette.routing import Route

    from rik.web import catalog, episodes, teleop

    routes = [*app.routes, *catalog.router.routes, *episodes.router.routes, *teleop.router.routes]
    paths = []
    for r in routes:
        if isinstance(r, (APIRoute, Route)) and "GET" in (r.methods or ()) and not r.path.startswith("/_test/"):
            names = re.findall(r"{(\w+)(?::\w+)?}", r.path)
            missing = [n for n in names if n not in PARAMS]
            assert not missing, f"route {r.path}: give its parameter {missing} a value in PARAMS"
            path = re.sub(r"{(\w+)(?::\w+)?}", lambda m: PARAMS[m.group(1)], r.path)
            if not path.endswith(".glb"):
                paths.append(path)
    return sorted(set(paths))


def foreign(ref: str) -> bool:
    """Whether ``ref`` is an address outside the app (another scheme's or host's, or scheme-relative)."""
    return ref.startswith(("//", "\\\\")) or re.match(r"(?i)(https?|wss?|ftp):", ref) is not None


def test_no_api_docs_and_no_page_loads_anything_from_elsewhere(site: tuple[Any, str]) -> None:
    """FastAPI's docs (which load Swagger UI from a CDN) are off: /api/docs, /docs, /redoc and the OpenAPI JSON are
    404s. Every page the app serves (each GET route's, every static page, the 404 and refusal pages), and the
    scripts and styles they load, reference nothing outside the app; every address of the app they link answers."""
    app, url = site
    for path in ("/api/docs", "/docs", "/redoc", "/api/redoc", "/openapi.json", "/api/openapi.json",
                 "/docs/oauth2-redirect"):
        assert request(url, path, {"Cookie": COOKIE})[0] == 404, path
    pages = [*page_paths(app), *(f"/static/{p.name}" for p in STATIC.glob("*.html")), "/teleop/nope"]
    seen: set[str] = set()
    queued: set[str] = set()
    queue = [(p, {"Cookie": COOKIE}) for p in pages] + [("/catalog", {})]  # the last: the gate's refusal page
    bad: list[str] = []
    while queue:
        path, headers = queue.pop()
        status, answer, body = request(url, path, headers)
        kind = answer.get("Content-Type", "")
        if not any(t in kind for t in ("text/html", "text/css", "javascript")):
            continue
        assert status < 400 or path in ("/teleop/nope", "/catalog"), (path, status)
        for ref in REFERENCE.findall(COMMENT.sub("", body.decode("utf-8", "replace"))):
            local = urljoin(path, ref).split("#")[0]
            if foreign(ref):
                bad.append(f"{path}: {ref}")
            elif "${" in ref or local in seen:
                continue
            elif "text/html" in kind and ref.startswith("/"):  # a page's link or file: it must answer
                seen.add(local)
                got = request(url, local, {"Cookie": COOKIE})[0]
                assert got < 400, f"{path} links {ref}, which answers {got}"
            if local.startswith("/static/") and local not in queued:  # its scripts and styles, and theirs
                queued.add(local)
                queue.append((local, {}))
    assert not bad, bad
    assert {"/static/teleop.js", "/static/viewer3d.js", "/static/vendor/three/three.core.js"} <= queued  # all read


# ---- 3. another app's cookie does not hide rik's ----------------------------------------------------------------
def test_another_local_apps_unparsable_cookie_does_not_lock_the_operator_out(site: tuple[Any, str]) -> None:
    """Cookies of other localhost apps that Python's cookie parser stops at, before rik's, in one Cookie header or
    in two: pages and the websocket handshake still let the operator in; a wrong value of rik's cookie, or none,
    is still refused."""
    _, url = site
    name = cookie_name(TOKEN)
    good = [f"{FOREIGN}; {COOKIE}", f'{FOREIGN}; a=b; c; d="unterminated; {COOKIE}; e=f',
            f"{name}=wrong; {FOREIGN}; {COOKIE}", f"{FOREIGN};{COOKIE};", f'x=1; {name}="{TOKEN}"']
    for cookie in good:
        assert request(url, "/api/catalog/presets", {"Cookie": cookie})[0] == 200, cookie
    for cookie in (f"{FOREIGN}; {name}=wrong{TOKEN}", FOREIGN, f"{FOREIGN}; x{COOKIE}", f"{FOREIGN}; {name}"):
        assert request(url, "/api/catalog/presets", {"Cookie": cookie})[0] == 403, cookie
    parts = urlsplit(url)
    conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=WAIT)  # two Cookie headers
    try:
        conn.putrequest("GET", "/api/catalog/presets")
        conn.putheader("Cookie", FOREIGN)
        conn.putheader("Cookie", COOKIE)
        conn.endheaders()
        assert conn.getresponse().status == 200
    finally:
        conn.close()
    # the websocket's handshake, from the app's own page, cookie only (an unknown variant: the station's one line,
    # after the gate let it in; nothing starts)
    with connect(f"{ws_base(url)}/teleop/nope/ws", origin=url,  # type: ignore[arg-type]
                 additional_headers={"Cookie": f"{FOREIGN}; {COOKIE}"}, open_timeout=WAIT) as ws:
        status = json.loads(ws.recv(timeout=WAIT))
        assert status["ready"] is False and "nope" in status["error"]
    with pytest.raises(InvalidStatus) as refused:
        connect(f"{ws_base(url)}/teleop/nope/ws", origin=url,  # type: ignore[arg-type]
                additional_headers={"Cookie": FOREIGN}, open_timeout=WAIT)
    assert refused.value.response.status_code == 403


# ---- 4. a token address of any path --------------------------------------------------------------------------------
def test_a_token_address_of_any_path_redirects_cleanly(site: tuple[Any, str]) -> None:
    """The printed token with a path that is not Latin-1 (a snowman, an invalid UTF-8 byte, a NUL, a handle id
    that is no handle) gets the cookie and a redirect to the same path, percent-encoded, never a 500; following it
    gives the app's 404. A path that starts with two slashes (or a backslash) is redirected on this host, never to
    another. A raw non-ASCII request line is the server's 400."""
    _, url = site
    cases = {"/%E2%98%83": "/%E2%98%83", "/%E9": "/%EF%BF%BD", "/a%00b": "/a%00b", "/%C3%A9t%C3%A9": "/%C3%A9t%C3%A9",
             "/catalog/handle/%E2%98%83": "/catalog/handle/%E2%98%83", "//evil.example/x": "/evil.example/x",
             "/%2F%2Fevil.example": "/evil.example", "/%5Cevil.example": "/%5Cevil.example"}
    for path, location in cases.items():
        status, answer, _ = request(url, f"{path}?token={TOKEN}&replay=%E2%98%83")
        assert status == 303, (path, status)
        assert answer["Location"] == f"{location}?replay=%E2%98%83", (path, answer["Location"])
        assert COOKIE in answer["Set-Cookie"]
        assert request(url, answer["Location"], {"Cookie": COOKIE})[0] == 404, path
    answer = raw_request(url, f"GET /\u2603?token={TOKEN} HTTP/1.1".encode())
    assert answer.startswith(b"HTTP/1.1 400 "), answer[:80]


# ---- 5. hostile replay ids ----------------------------------------------------------------------------------------
def statuses(ws: ClientConnection, until: Callable[[dict[str, Any]], bool], what: str) -> dict[str, Any]:
    """Read the station's statuses until one satisfies ``until`` or says the station stopped (bounded: WAIT s)."""
    deadline = time.monotonic() + WAIT
    last: dict[str, Any] = {}
    while time.monotonic() < deadline:
        message = ws.recv(timeout=WAIT)
        if isinstance(message, str):
            last = json.loads(message)
            if until(last) or last.get("error"):
                return last
    raise AssertionError(f"the station never reached {what} in {WAIT:.0f} s; its last status: {last}")


def record(ws: ClientConnection, seq: int) -> dict[str, Any]:
    """Hold 'up' until the gripper has risen 5 mm on recorded steps; the status then, with the input released."""
    st = statuses(ws, lambda s: s.get("ready") is True and s.get("session") is not None, "ready")
    start = st["session"]["pose"][2]
    deadline = time.monotonic() + WAIT
    while st["session"]["pose"][2] < start + 0.005 or st["session"]["state"] != "recording":
        assert time.monotonic() < deadline and not st.get("error"), f"never moved: {st}"
        ws.send(json.dumps({"type": "input", "seq": seq, "axes": [0, 0, 0.5, 0, 0, 0], "grip": None}))
        seq += 1
        st = statuses(ws, lambda s: s.get("session") is not None, "a session")
    ws.send(json.dumps({"type": "input", "seq": seq, "axes": [0] * 6, "grip": None}))
    return st


def test_hostile_replay_ids_are_refused_and_the_episode_is_kept(bow_variants: Path, tmp_path: Path) -> None:
    """Replays (what the page's websocket sends, also for a ``?replay=`` link) of an id holding a NUL, a lone
    surrogate, non-Latin-1 text, too many bytes for a file name or far too many characters: each gets a notice or a
    one-line message, the station goes on recording, and Save then writes the episode with all its steps."""
    episodes = tmp_path / "ep"
    refused = "ignored a replay command: its episode must be an episode id"
    cases = [('"ep\\u0000../x"', refused), ('"\\u2603\\u2603 snow"', "no episode '☃☃ snow'"),
             ('"\\ud800"', refused), ('"épisode-ü"', "no episode 'épisode-ü'"), (json.dumps("é" * 200), refused),
             (json.dumps("x" * 255), f"no episode '{'x' * 255}'"), (json.dumps("\x00"), refused),
             (json.dumps("y" * 10_000), refused)]
    with served_app(make_app(bow_variants, episodes)) as url, \
            connect(f"{ws_base(url)}/teleop/{BOW}/ws?token={TOKEN}", open_timeout=WAIT) as ws:
        record(ws, seq=1)
        for i, (episode, says) in enumerate(cases):
            ws.send(f'{{"type": "command", "name": "replay", "episode": {episode}}}')
            where = "notice" if says == refused else "message"
            st = statuses(ws, lambda s, w=where, t=says: t in (s.get(w) or ""), f"the answer to replay {i}")
            assert st["error"] is None and st["ready"] and st["replay"] is None, (episode, st)
            ws.send(json.dumps({"type": "input", "seq": 10_000 + i, "axes": [0] * 6, "grip": None}))
            statuses(ws, lambda s, k=10_000 + i: s.get("seq") == k and s.get("notice") == "", "the notice cleared")
        before = st["session"]["steps"]  # recorded before and during the hostile replays
        st = record(ws, seq=20_000)  # the station goes on: it moves and records
        episode = st["session"]["episode"]
        ws.send(json.dumps({"type": "command", "name": "save"}))
        st = statuses(ws, lambda s: (s.get("session") or {}).get("last_saved") == episode, "the save")
        assert st["error"] is None
    from rik.episodes.episode import read_episode

    meta, table = read_episode(episodes / episode)  # whole and sealed
    assert meta.steps > before > 0 and table.num_rows == meta.steps + 1
