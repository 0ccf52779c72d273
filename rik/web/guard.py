"""The web app's gate: what a request must show before the app answers it (see docs/reliability.md, "The web app on
a hostile web").

``rik serve`` and ``rik teleop --web`` run on a person's laptop, in the browser they also use for the rest of the
web, so any page that browser opens may send requests to ``localhost``. The gate, an ASGI middleware around the
whole app, answers only requests that show:

- **a Host header naming this server**: a localhost name (``localhost``, ``127.0.0.1``, ``[::1]``), the ``--host``
  given, a name of ``allowed_hosts``, or any IP address literal. A DNS-rebinding page reaches the app under its own
  host name, never an IP literal, so this refuses it (400);
- **the launch token**: a secret made per launch and printed in the address (``?token=...``, as Jupyter does). The
  first request that carries it gets it back as a cookie (``HttpOnly``, ``SameSite=Strict``: another site's page
  never sends it) and a redirect to the same address without it; every later request shows the cookie. Without
  either: 403 and a page saying to open the printed address. ``/static/`` (the app's own scripts and styles) is
  public;
- **the app's own Origin** on every websocket handshake and on every request that is not a GET or HEAD: a browser
  always sends Origin there, and a page of another origin (another site, or another port of this machine) is
  refused (403) even when the browser would send the cookie. A client that sends no Origin is not a browser page
  and still needs the token.

GETs never start work (the station starts on its websocket), so a GET that gets through (an ``<img>`` pointed at
the app from a page in the same browser) costs nothing.

Every response the app sends (pages, static files, JSON, the gate's refusals and redirects, errors) also says that
no page may frame it (:class:`NoFraming`: ``Content-Security-Policy: frame-ancestors 'none'`` and ``X-Frame-Options:
DENY``): a page on another port of ``localhost`` is the same *site*, so the browser sends the ``SameSite=Strict``
cookie with its ``<iframe>`` of the station, whose own script would then pass the Origin check.

The cookie is found by splitting the ``Cookie`` header on ``;`` and skipping what does not parse: another app on
``localhost`` may set a cookie that :class:`http.cookies.SimpleCookie` cannot read, which would hide rik's.
"""

from __future__ import annotations

import hashlib
import hmac
import html
import ipaddress
import json
import secrets
from collections.abc import Awaitable, Callable, Iterable
from typing import Any
from urllib.parse import parse_qsl, quote, urlencode, urlsplit

Scope = dict[str, Any]
Receive = Callable[[], Awaitable[dict[str, Any]]]
Send = Callable[[dict[str, Any]], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

LOCAL_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})
"""Host names that always mean this machine."""
WILDCARDS = frozenset({"", "0.0.0.0", "::"})
"""``--host`` values that listen on every address (they name no host to accept)."""
PUBLIC_PREFIX = "/static/"
"""Paths served without the token: the app's own scripts, styles and pictures, the same for everyone."""
SAFE_METHODS = frozenset({"GET", "HEAD"})
TOKEN_PARAM = "token"
FRAME_ANCESTORS = "frame-ancestors 'none'"
"""The Content-Security-Policy directive every response carries: no page may frame the app."""
PATH_SAFE = "/!$&'()*+,;=:@-._~"
"""Characters a redirect's path keeps as they are (RFC 3986's ``pchar`` and ``/``); others are percent-encoded."""


def new_token() -> str:
    """A fresh launch token: 32 random bytes, URL-safe base64 (43 characters)."""
    return secrets.token_urlsafe(32)


def cookie_name(token: str) -> str:
    """The cookie that carries ``token``: named after a hash of it, so two servers on one machine (which share
    cookies: ports do not separate them) never overwrite each other's."""
    return "rik-token-" + hashlib.sha256(token.encode()).hexdigest()[:12]


def with_token(path: str, token: str) -> str:
    """``path`` (an app path, possibly with a query) with ``?token=...`` added: the address to print."""
    return f"{path}{'&' if '?' in path else '?'}{TOKEN_PARAM}={token}"


def host_name(host_header: str) -> str | None:
    """The host name of a ``Host`` header value (``name``, ``name:port``, ``[v6]:port``), lower case; None when it
    is malformed."""
    text = host_header.strip().lower()
    if not text or any(c.isspace() or c in "/?#@" for c in text):
        return None
    if text.startswith("["):
        end = text.find("]")
        if end < 0 or (text[end + 1:] and not text[end + 1:].startswith(":")):
            return None
        return text[1:end]
    name, _, port = text.partition(":") if text.count(":") == 1 else (text, "", "")
    if port and not port.isdigit():
        return None
    return name


def is_ip_literal(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def cookie_values(header: str, name: str) -> list[str]:
    """The values of every cookie called ``name`` in a ``Cookie`` header, skipping pairs that do not parse (another
    app's ``prefs={"theme":"dark"}`` hides nothing after it); a value in double quotes loses them."""
    found = []
    for pair in header.split(";"):
        key, eq, value = pair.partition("=")
        if eq and key.strip() == name:
            value = value.strip()
            found.append(value[1:-1] if len(value) > 1 and value[0] == value[-1] == '"' else value)
    return found


def request_headers(scope: Scope) -> dict[str, str]:
    """A request's headers by lower-case name (the last of repeated ones; ``cookie`` headers joined with ``;``)."""
    headers: dict[str, str] = {}
    cookies = []
    for k, v in scope.get("headers", []):
        key, value = k.decode("latin-1").lower(), v.decode("latin-1")
        headers[key] = value
        if key == "cookie":
            cookies.append(value)
    if cookies:
        headers["cookie"] = "; ".join(cookies)
    return headers


def login_location(scope: Scope) -> str:
    """Where a GET that carried the token is sent: its own path (percent-encoded: a path of any characters is a
    valid ``Location``, one leading ``/``: never another host's ``//name``) and query without the token."""
    query = scope.get("query_string", b"").decode("latin-1")
    rest = [(k, v) for k, v in parse_qsl(query, keep_blank_values=True) if k != TOKEN_PARAM]
    path = quote(scope.get("root_path", "") + scope.get("path", "/"), safe=PATH_SAFE, errors="surrogatepass")
    return "/" + path.lstrip("/") + (f"?{urlencode(rest)}" if rest else "")


def no_framing(headers: Iterable[tuple[bytes, bytes]]) -> list[tuple[bytes, bytes]]:
    """``headers`` of a response with ``X-Frame-Options: DENY`` and ``frame-ancestors 'none'`` in its
    Content-Security-Policy (merged into one it has, replacing any frame-ancestors there)."""
    out: list[tuple[bytes, bytes]] = []
    policy: list[str] = []
    for k, v in headers:
        name = bytes(k).lower()
        if name == b"content-security-policy":
            policy += [d.strip() for d in bytes(v).decode("latin-1").split(";")
                       if d.strip() and d.split()[0].lower() != "frame-ancestors"]
        elif name != b"x-frame-options":
            out.append((bytes(k), bytes(v)))
    csp = "; ".join([*policy, FRAME_ANCESTORS])
    return [*out, (b"content-security-policy", csp.encode("latin-1")), (b"x-frame-options", b"DENY")]


class NoFraming:
    """ASGI middleware, around the whole app: every HTTP response it sends gets the headers of :func:`no_framing`
    (a page on another port of ``localhost`` cannot frame the station and act in it with the operator's cookie)."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def framed(message: dict[str, Any]) -> None:
            if message["type"] == "http.response.start":
                message = {**message, "headers": no_framing(message.get("headers", []))}
            await send(message)

        await self.app(scope, receive, framed)


class Guard:
    """ASGI middleware that lets through only requests that name this server, carry the launch token and, where
    a browser sends one, this app's Origin (see the module docstring)."""

    def __init__(self, app: ASGIApp, *, token: str, host: str = "127.0.0.1",
                 allowed_hosts: Iterable[str] = ()) -> None:
        self.app = app
        self.token = token
        self.cookie = cookie_name(token)
        names = set(LOCAL_NAMES) | {h.strip("[]").lower() for h in allowed_hosts}
        if host.strip("[]") not in WILDCARDS:
            names.add(host.strip("[]").lower())
        self.hosts = frozenset(names)

    # ---- checks -------------------------------------------------------------------------------------------------
    def host_allowed(self, name: str | None) -> bool:
        return name is not None and (name in self.hosts or is_ip_literal(name))

    def _valid(self, candidate: str | None) -> bool:
        return bool(candidate) and hmac.compare_digest(candidate.encode(), self.token.encode())  # type: ignore[union-attr]

    def refusal(self, scope: Scope, headers: dict[str, str]) -> tuple[int, str] | None:
        """Why the request may not reach the app, as (HTTP status, one line), or None when it may."""
        host = headers.get("host", "")
        if not self.host_allowed(host_name(host)):
            return 400, (f"Host {host!r} is not this server's address: open it as localhost (or the --host it was "
                         "started with); a page that reaches it under another name is refused")
        origin = headers.get("origin")
        needs_origin = scope["type"] == "websocket" or scope.get("method", "GET") not in SAFE_METHODS
        if needs_origin and origin is not None and not self._same_origin(origin, host, scope):
            return 403, f"Origin {origin!r} is not this app's: only the app's own pages may act on it"
        if scope.get("path", "").startswith(PUBLIC_PREFIX):
            return None
        if self._valid(self._query_token(scope)) or self._cookie_valid(headers):
            return None
        return 403, ("this address needs the token that rik printed with it: open the address `rik serve` (or `rik "
                     "teleop --web`) printed, which ends in ?token=...")

    @staticmethod
    def _same_origin(origin: str, host: str, scope: Scope) -> bool:
        parts = urlsplit(origin)
        scheme = "https" if scope.get("scheme") in ("https", "wss") else "http"
        return parts.scheme == scheme and parts.netloc.lower() == host.strip().lower() and not parts.path

    @staticmethod
    def _query_token(scope: Scope) -> str | None:
        query = scope.get("query_string", b"").decode("latin-1")
        return next((v for k, v in parse_qsl(query, keep_blank_values=True) if k == TOKEN_PARAM), None)

    def _cookie_valid(self, headers: dict[str, str]) -> bool:
        return any(self._valid(v) for v in cookie_values(headers.get("cookie", ""), self.cookie))

    # ---- the middleware -----------------------------------------------------------------------------------------
    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = request_headers(scope)
        refused = self.refusal(scope, headers)
        if refused is not None:
            await self._refuse(scope, receive, send, *refused)
            return
        if (scope["type"] == "http" and scope.get("method") in SAFE_METHODS
                and self._valid(self._query_token(scope))):
            await self._login(scope, send)
            return
        await self.app(scope, receive, send)

    async def _login(self, scope: Scope, send: Send) -> None:
        """The token in a GET's query: set the cookie and redirect to the same address without the token (so it
        stays out of the page's history and of links the page makes)."""
        location = login_location(scope)
        cookie = f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"
        await send({"type": "http.response.start", "status": 303,
                    "headers": [(b"location", location.encode("ascii")), (b"set-cookie", cookie.encode()),
                                (b"cache-control", b"no-store"), (b"content-length", b"0")]})
        await send({"type": "http.response.body", "body": b""})

    @staticmethod
    async def _refuse(scope: Scope, receive: Receive, send: Send, status: int, message: str) -> None:
        if scope["type"] == "websocket":
            await receive()  # websocket.connect; closing before accepting answers the handshake with 403
            await send({"type": "websocket.close", "code": 1008, "reason": message[:120]})
            return
        wants_json = scope.get("path", "").startswith("/api/") or scope.get("path", "").endswith(".json")
        if wants_json:
            body = json.dumps({"detail": f"rik: error: {message}"}).encode()
            kind = b"application/json"
        else:
            body = (f"<!doctype html><html><head><meta charset='utf-8'><title>rik: refused</title>"
                    f"<link rel='stylesheet' href='/static/teleop.css'></head><body><main class='error'><h1>rik</h1>"
                    f"<p id='error'>rik: error: {html.escape(message)}</p></main></body></html>").encode()
            kind = b"text/html; charset=utf-8"
        await send({"type": "http.response.start", "status": status,
                    "headers": [(b"content-type", kind), (b"content-length", str(len(body)).encode()),
                                (b"cache-control", b"no-store")]})
        await send({"type": "http.response.body", "body": body})
