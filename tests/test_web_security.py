"""The web app on a hostile web (issue 29): a page of another origin in the operator's own Chromium cannot drive
the station nor read the API (also under a DNS-rebinding name), a real websocket client with a foreign Origin or
Host or without the launch token is refused, a GET starts no station, stations are bounded and released when
idle with their drafts kept, malformed messages get a notice and keep the tab, and a Save on a full disk keeps the
episode and the station (the real ``rik teleop --web`` under a file-size limit)."""

from __future__ import annotations

import http.client
import json
import resource
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest
from shared import BOW, builtin_catalog
from web_fixtures import TOKEN, WAIT_MS, app_client, browser, served_app, signed, station_process
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import ClientConnection, connect

from rik.web.app import WS_MAX_MESSAGE, AppConfig, create_app
from rik.web.guard import cookie_name

CAT = builtin_catalog()
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"
WAIT = WAIT_MS / 1000
needs_chromium = pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    """The demo variant, built once for the module (stations that open it start without building)."""
    return bow_variants  # the demo variant, built once per test process (conftest)


def make_app(variants: Path, episodes: Path, **settings: Any) -> Any:
    config = AppConfig(CAT, variants=variants, episodes=episodes, token=TOKEN, **settings)
    return create_app(config)


def ws_url(url: str, variant: str = BOW, query: str = f"token={TOKEN}") -> str:
    return url.replace("http://", "ws://") + f"/teleop/{variant}/ws" + (f"?{query}" if query else "")


def statuses(ws: ClientConnection, until: Callable[[dict[str, Any]], bool], what: str) -> dict[str, Any]:
    """Read the station's messages until a status satisfies ``until`` (bounded: :data:`WAIT` s)."""
    deadline = time.monotonic() + WAIT
    last: dict[str, Any] = {}
    while time.monotonic() < deadline:
        message = ws.recv(timeout=WAIT)
        if isinstance(message, str):
            last = json.loads(message)
            if until(last):
                return last
    raise AssertionError(f"the station never reached {what} in {WAIT:.0f} s; its last status: {last}")


def record_steps(ws: ClientConnection, steps: int, seq: int = 1) -> dict[str, Any]:
    """Hold 'up' (z) until ``steps`` control steps are recorded; returns the status, with the input released."""
    statuses(ws, lambda s: s.get("ready") is True, "ready")
    deadline = time.monotonic() + WAIT
    st: dict[str, Any] = {}
    while time.monotonic() < deadline:
        ws.send(json.dumps({"type": "input", "seq": seq, "axes": [0, 0, 0.5, 0, 0, 0], "grip": None}))
        seq += 1
        st = statuses(ws, lambda s: s.get("session") is not None, "a session")
        if st["session"]["steps"] >= steps:
            ws.send(json.dumps({"type": "input", "seq": seq, "axes": [0] * 6, "grip": None}))
            return st
    raise AssertionError(f"never recorded {steps} steps: {st}")


def handshake(url: str, path: str, headers: dict[str, str]) -> int:
    """A real websocket upgrade request with exactly these headers; the HTTP status of the answer."""
    parts = urlsplit(url)
    conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=WAIT)
    try:
        conn.putrequest("GET", path, skip_host=True)
        for k, v in {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
                     "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==", **headers}.items():
            conn.putheader(k, v)
        conn.endheaders()
        return conn.getresponse().status
    finally:
        conn.close()


def test_foreign_origin_host_or_no_token_is_refused_by_a_real_client(variants: Path, tmp_path: Path) -> None:
    """The websocket handshake with another site's Origin, another port's Origin, a DNS-rebinding Host or no token is
    refused (403/400) before any station starts; the API answers a rebinding Host with 400; the app's own origin
    with the token is let in."""
    app = make_app(variants, tmp_path / "ep")
    with served_app(app) as url:
        port = urlsplit(url).port
        own = f"localhost:{port}"
        path = f"/teleop/{BOW}/ws?token={TOKEN}"
        for origin in ("http://evil.example", f"http://localhost:{port + 1}", "null", f"https://{own}"):
            with pytest.raises(InvalidStatus) as refused:
                connect(ws_url(url), origin=origin, open_timeout=WAIT)  # type: ignore[arg-type]
            assert refused.value.response.status_code == 403, origin
        # a rebinding name, with the token and an Origin that matches it (a websocket refusal is always a 403)
        assert handshake(url, path, {"Host": f"evil.example:{port}", "Origin": f"http://evil.example:{port}"}) == 403
        assert handshake(url, f"/teleop/{BOW}/ws", {"Host": own, "Origin": f"http://{own}"}) == 403  # no token
        assert handshake(url, f"/teleop/{BOW}/ws?token=wrong{TOKEN}", {"Host": own}) == 403
        assert not app.state.stations.stations  # nothing started
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=WAIT)
        conn.request("GET", "/api/catalog/handles", headers={"Host": f"rebound.evil.example:{port}",
                                                              "Cookie": f"{cookie_name(TOKEN)}={TOKEN}"})
        answer = conn.getresponse()
        assert answer.status == 400 and "is not this server's address" in answer.read().decode()
        conn.request("GET", "/api/catalog/handles", headers={"Host": own})  # no cookie, no token
        answer = conn.getresponse()
        assert answer.status == 403 and "needs the token" in answer.read().decode()
        conn.close()
        assert handshake(url, path, {"Host": own, "Origin": f"http://{own}"}) == 101  # the same, from the app
        with connect(ws_url(url), origin=url, open_timeout=WAIT) as ws:  # type: ignore[arg-type]
            statuses(ws, lambda s: s.get("variant") == BOW, "a status")
        assert list(app.state.stations.stations) == [(BOW, "hand-e")]


def test_a_get_of_a_station_page_starts_nothing(variants: Path, tmp_path: Path) -> None:
    """Six GETs of station pages and two of variants' 3D models (what an <img> on any page in the browser would
    send, cookie included) build no variant and start no station; the token in the address gives a cookie and a redirect that drops it."""
    fresh = tmp_path / "variants"
    with app_client(AppConfig(CAT, variants=fresh, episodes=tmp_path / "ep")) as client:
        for robot in ("hand-e", "panda-2f85", "so100"):
            for variant in (BOW, KNOB):
                assert client.get(f"/teleop/{variant}?robot={robot}").status_code == 200
        for url in (f"/catalog/variant/{BOW}/visual.glb", f"/catalog/variant/{KNOB}/visual.glb"):  # 3D views
            answer = client.get(url)
            assert answer.status_code == 404 and "is not built" in answer.json()["detail"]
        assert not client.app.state.stations.stations and not fresh.exists()
        client.cookies.clear()
        assert client.get(f"/teleop/{BOW}").status_code == 403
        login = client.get(f"/teleop/{BOW}?robot=so100&token={TOKEN}", follow_redirects=False)
        assert login.status_code == 303 and login.headers["location"] == f"/teleop/{BOW}?robot=so100"
        cookie = login.headers["set-cookie"]
        assert cookie.startswith(f"{cookie_name(TOKEN)}={TOKEN};") and "HttpOnly" in cookie and \
            "SameSite=Strict" in cookie
        assert client.get(f"/teleop/{BOW}?robot=so100").status_code == 200  # the cookie now
        assert client.post("/teleop/keymap.json", headers={"Origin": "http://evil.example"}).status_code == 403


@pytest.mark.browser
@needs_chromium
def test_a_page_of_another_origin_in_the_same_browser_cannot_act(variants: Path, tmp_path: Path) -> None:
    """The operator has the station open (the token's cookie is in the browser); a page of another site in the
    same Chromium tries a websocket to the station, a POST, <img> GETs of station pages, and a DNS-rebinding read of
    the API (its own name mapped to 127.0.0.1): every one fails, no station starts, nothing is written."""
    episodes = tmp_path / "ep"
    app = make_app(variants, episodes)
    with served_app(app) as url:
        port = urlsplit(url).port
        with browser("--host-resolver-rules=MAP rebind.evil.example 127.0.0.1") as b:
            context = b.new_context()
            own = context.new_page()
            own.goto(signed(f"{url}/catalog"))  # the operator's tab: the cookie is set
            assert own.url == f"{url}/catalog"
            attack = f"""<!doctype html><html><body><script>
              window.results = {{}};
              const ws = new WebSocket("ws://127.0.0.1:{port}/teleop/{BOW}/ws");
              ws.onopen = () => {{ window.results.ws = "open"; ws.send(JSON.stringify({{type: "command",
                                                                                        name: "save"}})); }};
              ws.onerror = () => {{ window.results.ws = window.results.ws || "refused"; }};
              for (const r of ["hand-e", "panda-2f85", "so100"]) {{
                const img = new Image(); img.src = "http://127.0.0.1:{port}/teleop/{KNOB}?robot=" + r;
                document.body.appendChild(img);
              }}
              fetch("http://127.0.0.1:{port}/teleop/keymap.json", {{method: "POST", mode: "no-cors"}})
                .then(() => {{ window.results.post = "sent"; }}, () => {{ window.results.post = "failed"; }});
            </script></body></html>"""
            context.route("http://evil.example/**", lambda route: route.fulfill(content_type="text/html",
                                                                               body=attack))
            evil = context.new_page()
            evil.goto("http://evil.example/attack.html")
            evil.wait_for_function("window.results.ws && window.results.post", timeout=WAIT_MS, polling=100)
            assert evil.evaluate("window.results.ws") == "refused"
            # a rebinding name (resolving to this machine, as the attacker's DNS answers after its page loaded)
            # reaches the app only with its own name in Host, which the app refuses
            rebound = context.new_page()
            answer = rebound.goto(f"http://rebind.evil.example:{port}/api/catalog/handles")
            assert answer is not None and answer.status == 400 and "is not this server's address" in answer.text()
            context.close()
    assert not app.state.stations.stations and not episodes.exists()


def test_malformed_messages_get_a_notice_and_keep_the_tab(variants: Path, tmp_path: Path) -> None:
    """A binary frame, non-JSON text, Infinity and NaN, a seq out of range, deep nesting, a list, an unknown type, a
    replay of an episode that is no id: each is answered with a notice in the tab's status; a replay of a path out
    of the episodes folder or of a hidden folder is refused in one line; the tab stays connected and a good input
    then moves."""
    app = make_app(variants, tmp_path / "ep")
    bad = [(b"\x00\x01binary", "binary message"),
           ("not json", "not JSON"),
           ('{"type": "input", "seq": Infinity, "axes": [0, 0, 0, 0, 0, 0]}', "NaN or Infinity"),
           ('{"type": "input", "seq": 1, "axes": [NaN, 0, 0, 0, 0, 0]}', "NaN or Infinity"),
           ('{"type": "input", "seq": 1e300, "axes": [0, 0, 0, 0, 0, 0]}', "seq an integer"),
           ('{"type": "input", "seq": 1.5, "axes": [0, 0, 0, 0, 0, 0]}', "seq an integer"),
           ('{"type": "input", "seq": 1, "axes": [0, 0, 0]}', "axes must be 6"),
           ('{"type": "input", "seq": 1, "axes": [0, 0, 0, 0, 0, 0], "grip": "x"}', "grip a number"),
           ("[" * 30_000 + "]" * 30_000, "nested too deeply"),
           ("[1, 2]", "not a JSON object"),
           ('{"type": "launch"}', "ignored message type 'launch'"),
           ('{"type": "size", "width": 1e9, "height": 2}', "choose one of"),
           ('{"type": "command", "name": "replay", "episode": 7}', "its episode must be an episode id"),
           ('{"type": "command", "name": "replay", "episode": "' + "x" * 300 + '"}', "its episode must be")]
    with served_app(app) as url, connect(ws_url(url), open_timeout=WAIT, max_size=None) as ws:
        statuses(ws, lambda s: s.get("ready") is True, "ready")
        for message, notice in bad:
            ws.send(message)
            st = statuses(ws, lambda s, n=notice: n in (s.get("notice") or ""), f"the notice {notice!r}")
            assert st["role"] == "controller"
        for episode, says in (("../../etc", "would lead outside"), (".drafts", "no episode '.drafts'")):
            ws.send(json.dumps({"type": "command", "name": "replay", "episode": episode}))  # outside the folder
            st = statuses(ws, lambda s, w=says: w in (s.get("message") or ""), f"the refusal of {episode}")
            assert st["message"].startswith("replay failed: ") and st["replay"] is None
        st = record_steps(ws, 3, seq=7)
        assert st["notice"] == "" and st["session"]["steps"] >= 3
        with connect(ws_url(url), open_timeout=WAIT) as big:  # over 64 KiB: closed (1009) before it is read whole
            big.send(" " * (WS_MAX_MESSAGE + 1))
            with pytest.raises(ConnectionClosed) as closed:
                while True:
                    big.recv(timeout=WAIT)
            assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
        assert app.state.stations.stations  # the station lived through it


def test_stations_are_bounded_and_released_when_idle_with_their_drafts(variants: Path, tmp_path: Path) -> None:
    """With one station allowed: a second station is refused while the first has a tab; once the tab leaves, the
    first is released after the idle time (its episode kept as a draft) and the second may start."""
    episodes = tmp_path / "ep"
    app = make_app(variants, episodes, max_stations=1, idle_release=1.0)
    stations = app.state.stations
    with served_app(app) as url:
        with connect(ws_url(url), open_timeout=WAIT) as first:
            st = record_steps(first, 5)
            episode = st["session"]["episode"]
            with connect(ws_url(url, query=f"robot=so100&token={TOKEN}"), open_timeout=WAIT) as second:
                refused = statuses(second, lambda s: bool(s.get("error")), "an error")
            assert "1 teleop stations are open, each with a tab" in refused["error"]
        deadline = time.monotonic() + WAIT
        while stations.stations or not stations.released:
            assert time.monotonic() < deadline, "the idle station was never released"
            time.sleep(0.1)
        (key, draft), = stations.released
        assert key == (BOW, "hand-e") and draft == episodes / ".drafts" / episode
        assert (draft / "meta.json").is_file() and (draft / "states.parquet").is_file()
        with connect(ws_url(url), open_timeout=WAIT) as again:  # a new station, on the next free episode id
            st = statuses(again, lambda s: s.get("session") is not None, "a session")
            assert st["session"]["episode"] != episode


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(resource, "prlimit"), reason="needs Linux's prlimit")
def test_a_save_on_a_full_disk_keeps_the_episode_and_the_station(variants: Path, tmp_path: Path) -> None:
    """The real ``rik teleop --web`` whose file-size limit is 1 KiB (a full disk to it): Save fails with a message and
    the station goes on; with the limit lifted, the tab leaving keeps a draft and Save writes the whole episode."""
    episodes = tmp_path / "episodes"
    procs: list[Any] = []
    with station_process("teleop", BOW, "--web", "--port", "0", "--variants", str(variants), "--out", str(episodes),
                         cwd=tmp_path, procs=procs) as printed:
        pid = procs[0].pid
        _, hard = resource.prlimit(pid, resource.RLIMIT_FSIZE)
        resource.prlimit(pid, resource.RLIMIT_FSIZE, (1024, hard))
        parts = urlsplit(printed)
        url = f"http://127.0.0.1:{parts.port}"
        with connect(ws_url(url, query=parts.query), open_timeout=WAIT) as ws:
            st = record_steps(ws, 10)
            episode = st["session"]["episode"]
            ws.send(json.dumps({"type": "command", "name": "save"}))
            st = statuses(ws, lambda s: "could not save" in (s.get("message") or ""), "the failed save")
            assert "File too large (EFBIG)" in st["message"] and "press Save again" in st["message"]
            assert st["ready"] and st["error"] is None and st["session"]["steps"] >= 10
            assert not (episodes / episode).exists() and not list(episodes.glob(".*staging*"))
            st = record_steps(ws, st["session"]["steps"] + 2, seq=100)  # still alive: it steps and records
            resource.prlimit(pid, resource.RLIMIT_FSIZE, (resource.RLIM_INFINITY, hard))  # space freed
        draft = episodes / ".drafts" / episode
        deadline = time.monotonic() + WAIT
        while not (draft / "meta.json").is_file():  # the tab left: a draft is kept
            assert time.monotonic() < deadline, "no draft was kept when the tab left"
            time.sleep(0.1)
        with connect(ws_url(url, query=parts.query), open_timeout=WAIT) as ws:
            statuses(ws, lambda s: s.get("paused") is True and s.get("role") == "controller", "the draft offer")
            ws.send(json.dumps({"type": "command", "name": "save"}))
            st = statuses(ws, lambda s: (s.get("session") or {}).get("last_saved") == episode, "the save")
    from rik.episodes.episode import read_meta

    meta = read_meta(episodes / episode)
    assert meta.steps >= 12 and not draft.exists()


def test_a_replay_of_an_episode_removed_meanwhile_is_a_message_not_a_dead_station(variants: Path,
                                                                                   tmp_path: Path) -> None:
    """The saved episode's folder is removed (by the person, in a file manager) before Replay: the station says why
    and goes on recording."""
    episodes = tmp_path / "ep"
    app = make_app(variants, episodes)
    with served_app(app) as url, connect(ws_url(url), open_timeout=WAIT) as ws:
        record_steps(ws, 3)
        ws.send(json.dumps({"type": "command", "name": "save"}))
        st = statuses(ws, lambda s: bool((s.get("session") or {}).get("last_saved")), "the save")
        shutil.rmtree(episodes / st["session"]["last_saved"])
        ws.send(json.dumps({"type": "command", "name": "replay"}))
        st = statuses(ws, lambda s: (s.get("message") or "").startswith("replay failed: "), "the replay's failure")
        assert st["ready"] and st["error"] is None
        st = record_steps(ws, 3, seq=50)
        assert st["session"]["steps"] >= 3
