"""The browser teleop station's sessions: one :class:`Station` per variant, each running its own thread at the
control rate (20 Hz) that owns the :class:`rik.teleop.session.TeleopSession` and a ``mujoco.Renderer``, and
pushes camera frames and status to every connected browser through a latest-frame slot per client (a slow client
skips frames, never queues them). The wire protocol is described in :mod:`rik.web.teleop`, which serves the stations.

The simulated world keeps its own clock (:func:`rik.teleop.pacing.due_steps`): when the two cameras' renders
take longer than a control period (an arm's scene on a CPU rasteriser), the thread runs every control step that
came due before it renders again, so frames drop and simulated time keeps pace with the wall clock (up to
:data:`MAX_CATCH_UP` steps per render). Each is a whole control step with the input held at its time, recorded as
at one step per render; replay is unchanged. While behind, the wrist camera renders on every other frame only
(:func:`cameras_due`). The cameras render the scene's view model (:mod:`rik.teleop.frames`).

Threads: websocket handlers (the event loop) only hand inputs and commands to the station under its lock; the
station thread does all simulation and rendering (a MuJoCo GL context belongs to the thread that made it).
"""

from __future__ import annotations

import asyncio
import io
import json
import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError, os_error_text
from rik.paths import inside
from rik.teleop.frames import StationFrames
from rik.teleop.keys import FINE_FACTOR
from rik.teleop.pacing import due_steps
from rik.teleop.session import TeleopSession, check_time_limit
from rik.teleop.view import FOLLOWED

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.sim.scene import SimScene

OPERATOR = "browser"
"""Operator name of episodes recorded in the browser."""
CAMERAS = ("front", "wrist")
SIZES = ((320, 240), (640, 480))
"""Stream sizes a client may ask for, px (width, height)."""
INPUT_TIMEOUT = 0.5
"""An input older than this (s) without a newer one commands no motion (a tab that lost focus)."""
JPEG_QUALITY = 80
WATCHING = "another tab controls this session; you are watching"
LEFT = "the controlling tab left; press Take control to drive"
BUILDING = "building the variant..."
KEPT_IN_MEMORY = "the episode is kept in memory: free some space and press Save again"
PAUSED = "a draft was kept: Continue, Save or Discard first"
BAD_VIEW = "ignored a view message: give azimuth and elevation in degrees (each within +-360), or reset: true"


MAX_EPISODE_ID = 255
"""Longest episode id a replay command may name, UTF-8 bytes (a file name's limit)."""
BAD_REPLAY = ("ignored a replay command: its episode must be an episode id (text of printable characters, at most "
              f"{MAX_EPISODE_ID} bytes)")
MAX_REPLAY_BYTES = 256 * 2**20
"""Largest states file a station replays from its episodes folder, bytes (an hour at 20 Hz is a few MB)."""


DEFAULT_MAX_STATIONS = 4
MAX_STATIONS_LIMIT = 64
DEFAULT_IDLE_RELEASE = 600.0


@dataclass
class StationConfig:
    """What teleop stations work with: the catalog, where variants are built and episodes written, and their
    settings."""

    catalog: Catalog
    variants: Path = Path("variants")
    episodes: Path = Path("episodes")
    overlays: tuple[Path, ...] = ()
    max_seconds: float | None = None
    """Time limit of a teleoperated episode, simulated s (None: no limit)."""
    seed: int = 0
    """First seed of teleoperated episodes; each new episode takes the next free one."""
    front: str | None = None
    """Front to operate (None: each variant's first)."""
    robot: str = "hand-e"
    """Robot of a station whose page names none (``?robot=`` picks another): a catalog robot id."""
    max_stations: int = DEFAULT_MAX_STATIONS
    """Teleop stations alive at once (each holds a scene and renderers: 100-300 MB)."""
    idle_release: float = DEFAULT_IDLE_RELEASE
    """A station no tab has watched for this long (s) is released; its episode in progress is kept as a draft."""

    def check(self) -> None:
        """Settings a user gave that cannot work fail here, before a station starts."""
        from rik.episodes.record import check_seeds

        check_seeds(self.seed, 1)
        check_time_limit(self.max_seconds)
        self.catalog.robot(self.robot)  # an unknown robot: one line with close ids
        if not 1 <= self.max_stations <= MAX_STATIONS_LIMIT:
            raise RikError(f"--max-stations {self.max_stations}: give 1 to {MAX_STATIONS_LIMIT} (each station holds "
                           "a scene and its renderers)")
        if not 1.0 <= self.idle_release <= 7 * 24 * 3600:
            raise RikError(f"--idle-release {self.idle_release}: give 1 s to a week")


@dataclass
class Client:
    """One connected browser tab: its latest-frame slots and the loop that sends them."""

    loop: asyncio.AbstractEventLoop
    size: tuple[int, int] = SIZES[0]
    notice: str = ""
    """A message for this tab only (why its input was refused...)."""
    slots: dict[str, bytes | str] = field(default_factory=dict)
    event: asyncio.Event = field(default_factory=asyncio.Event)
    lock: threading.Lock = field(default_factory=threading.Lock)
    sent: dict[str, object] = field(default_factory=dict)
    """Per camera, the key of the last frame pushed to this client (a frame is pushed once)."""

    def push(self, slot: str, payload: bytes | str) -> None:
        """Replace ``slot``'s payload (dropping an unsent older one) and wake the sender. Any thread."""
        with self.lock:
            self.slots[slot] = payload
        try:
            self.loop.call_soon_threadsafe(self.event.set)
        except RuntimeError:  # the loop is closed: the server is going down
            pass

    def take(self) -> list[bytes | str]:
        with self.lock:
            items, self.slots = list(self.slots.values()), {}
        return items


def frame_message(header: dict[str, Any], jpeg: bytes) -> bytes:
    """A binary frame: 4-byte big-endian header length, the JSON header, the JPEG bytes."""
    head = json.dumps(header, separators=(",", ":")).encode()
    return len(head).to_bytes(4, "big") + head + jpeg


def encode_jpeg(rgb: np.ndarray, quality: int = JPEG_QUALITY) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, "JPEG", quality=quality)
    return buf.getvalue()


MAX_SEQ = 2**53
"""Input sequence numbers are integers in 0 .. 2**53 (what a browser's numbers hold exactly)."""
BAD_INPUT = ("ignored an input: axes must be 6 finite numbers in -1..1, grip a number in 0..1 or null, seq an "
             f"integer in 0..{MAX_SEQ}")


def parse_input(msg: dict[str, Any]) -> tuple[np.ndarray, float | None, int] | str:
    """An ``input`` message's axes (6, clipped to -1..1), grip (0..1 or None) and seq, or the notice saying why it
    is ignored (a wrong type, a non-finite number, a seq that is not an integer in range)."""
    try:
        axes = np.asarray(msg.get("axes"), np.float64).reshape(6)
        grip = msg.get("grip")
        grip = None if grip is None else float(grip)
        seq = msg.get("seq", 0)
        if isinstance(seq, bool) or not isinstance(seq, (int, float)) or not math.isfinite(seq) or seq != int(seq):
            return BAD_INPUT
        seq = int(seq)
    except (TypeError, ValueError, OverflowError):
        return BAD_INPUT
    if not np.all(np.isfinite(axes)) or (grip is not None and not math.isfinite(grip)) or not 0 <= seq <= MAX_SEQ:
        return BAD_INPUT
    return np.clip(axes, -1.0, 1.0), (None if grip is None else min(max(grip, 0.0), 1.0)), seq


def is_episode_id(episode: object) -> bool:
    """Whether a replay command's ``episode`` can name a folder: text of printable characters (no NUL, no control
    character, no lone surrogate), 1 to :data:`MAX_EPISODE_ID` bytes in UTF-8."""
    if not isinstance(episode, str) or not episode or not episode.isprintable():
        return False
    return len(episode.encode("utf-8", "surrogatepass")) <= MAX_EPISODE_ID


MAX_VIEW_TURN = 360.0
"""Largest azimuth or elevation change one ``view`` message may ask for, degrees."""


def parse_view(msg: dict[str, Any]) -> tuple[float, float] | None | str:
    """A ``view`` message's turn of the front view (azimuth, elevation degrees), None for ``reset``, or the notice
    saying why it is ignored."""
    if msg.get("reset") is True:
        return None
    try:
        turn = (float(msg.get("azimuth", 0.0)), float(msg.get("elevation", 0.0)))
    except (TypeError, ValueError, OverflowError):
        return BAD_VIEW
    if isinstance(msg.get("azimuth"), bool) or isinstance(msg.get("elevation"), bool) or \
            not all(math.isfinite(t) and abs(t) <= MAX_VIEW_TURN for t in turn):
        return BAD_VIEW
    return turn


MAX_CATCH_UP = 4
"""Control steps a station runs at most between two renders (0.2 s simulated at 20 Hz)."""
WRIST = "wrist"


def cameras_due(stale: list[str], behind: bool, skipped: bool) -> list[str]:
    """Which of the ``stale`` cameras (their last image shows an older state) to render now: all of them, except
    that while the station is ``behind`` real time (it ran more than one control step since the last render) the
    wrist camera is left out of every other render (``skipped``: it was left out of the last one). The operator
    steers on the front view; the wrist image is at most one render old, and up to date as soon as the scene rests
    (the front is then current and only the wrist is stale)."""
    if behind and not skipped and FOLLOWED in stale and WRIST in stale:
        return [cam for cam in stale if cam != WRIST]
    return list(stale)


def failure(command: str, exc: Exception) -> str:
    """The station's one-line message for ``command`` (a queued name, ``replay:<id>`` included) that raised
    ``exc``: a RikError's or OSError's own line (a saved episode removed before its replay...), else the error's
    type too (a fault of rik's: the station and its episode go on)."""
    name = command.lstrip("_").split(":")[0]
    text = str(exc).splitlines()[0] if str(exc) else ""
    if isinstance(exc, (RikError, OSError)):
        return f"{name} failed: {text}"
    return f"{name} failed: {type(exc).__name__}: {text}"


def build_station_scene(config: StationConfig, variant: str, robot: str) -> SimScene:
    """The scene of a station: ``variant`` (built into ``config.variants`` when needed) operated by the catalog
    robot ``robot``; an arm that cannot reach the operated handle is refused (one line naming the handle)."""
    from rik.combinator.build import ensure_variant
    from rik.sim.build import build_scene
    from rik.sim.robots.checks import require_reach

    c = config
    entry = c.catalog.robot(robot)
    arm = entry.as_arm
    scene = build_scene(ensure_variant(c.catalog, variant, c.variants), c.front, robot=arm)
    require_reach(scene)
    return scene


class Station:
    """One variant's teleop session with one robot, shared by every tab that opens it; one tab controls, the
    others watch. ``scene``: the scene already built (``rik teleop --web`` builds it to check it first)."""

    def __init__(self, config: StationConfig, variant: str, robot: str = "hand-e",
                 scene: SimScene | None = None) -> None:
        self.config = config
        self.variant = variant
        self.robot = robot
        self._scene = scene
        self.lock = threading.Lock()
        self.clients: list[Client] = []
        self.controller: Client | None = None
        self.commands: deque[tuple[Client, str]] = deque()
        self.axes: np.ndarray = np.zeros(6)
        self.grip: float | None = None
        self.input_time = 0.0
        self.seq = 0
        """Sequence number of the last input received from the controller."""
        self.applied_seq = 0
        """Sequence number of the last input applied to the simulation."""
        self.ready = False
        self.error: str | None = None
        self.paused = False
        self.draft: str | None = None
        self.message = BUILDING
        self.replay: dict[str, Any] | None = None
        self.view_turn = (0.0, 0.0)
        """How far the controlling tab turned the front view: azimuth, elevation, degrees (``view`` messages)."""
        self.fps = 0.0
        self.session: TeleopSession | None = None
        self.last_seen = time.monotonic()
        """When a tab last left (or the station started), monotonic s: what the idle release measures from."""
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name=f"rik-station-{variant}-{robot}", daemon=True)
        self.thread.start()

    # ---- called from the event loop ---------------------------------------------------------------------------
    def connect(self, client: Client) -> None:
        """A new tab: it controls when nobody does, else it watches."""
        with self.lock:
            self.clients.append(client)
            if self.controller is None:
                self.controller = client
                for c in self.clients:
                    if c is not client:
                        c.notice = WATCHING
            else:
                client.notice = WATCHING

    def disconnect(self, client: Client) -> None:
        with self.lock:
            self.last_seen = time.monotonic()
            if client in self.clients:
                self.clients.remove(client)
            if self.controller is client:
                self.controller = None
                self.axes = np.zeros(6)
                self.commands.append((client, "_lost"))
                for c in self.clients:
                    c.notice = LEFT

    def idle_for(self) -> float | None:
        """Seconds since the last tab left, or None while a tab is connected."""
        with self.lock:
            return None if self.clients else time.monotonic() - self.last_seen

    def receive(self, client: Client, msg: Any) -> None:
        """One JSON message from a tab (see :mod:`rik.web.teleop`); bad ones are answered with a notice."""
        if not isinstance(msg, dict):
            client.notice = "ignored a message that is not a JSON object"
            return
        kind = msg.get("type")
        with self.lock:
            if kind == "size":
                size = (msg.get("width"), msg.get("height"))
                if size in SIZES:
                    client.size = (int(size[0]), int(size[1]))
                    client.sent = {}
                else:
                    sizes = ", ".join(f"{w}x{h}" for w, h in SIZES)
                    client.notice = f"size {size[0]}x{size[1]}: choose one of {sizes}"
                return
            if kind == "command" and msg.get("name") == "take_control":
                if self.controller is None:
                    self.controller = client
                    client.notice = ""
                    for c in self.clients:
                        if c is not client:
                            c.notice = WATCHING
                elif self.controller is not client:
                    client.notice = WATCHING
                return
            if client is not self.controller:
                client.notice = WATCHING if self.controller is not None else LEFT
                return
            client.notice = ""
            if kind == "input":
                parsed = parse_input(msg)
                if isinstance(parsed, str):
                    client.notice = parsed
                    return
                axes, grip, seq = parsed
                if self.paused and (np.any(axes) or grip is not None):
                    client.notice = PAUSED
                self.axes = axes * (FINE_FACTOR if msg.get("fine") else 1.0)
                if grip is not None:
                    self.grip = grip
                self.seq = seq
                self.input_time = time.monotonic()
            elif kind == "view":
                turn = parse_view(msg)
                if isinstance(turn, str):
                    client.notice = turn
                    return
                self.view_turn = (0.0, 0.0) if turn is None else (self.view_turn[0] + turn[0],
                                                                   self.view_turn[1] + turn[1])
            elif kind == "command" and msg.get("name") == "replay" and "episode" in msg:
                episode = msg["episode"]
                if not is_episode_id(episode):
                    client.notice = BAD_REPLAY
                    return
                self.commands.append((client, f"replay:{episode}"))
            elif kind == "command" and msg.get("name") in ("save", "discard", "toggle_grip", "toggle_motion", "replay",
                                                          "continue"):
                self.commands.append((client, str(msg["name"])))
            else:
                client.notice = (f"ignored message type {kind!r}: use input, command (save, discard, toggle_grip, "
                                 "toggle_motion, replay, continue, take_control), view or size")

    # ---- the station thread -----------------------------------------------------------------------------------
    def _build(self) -> None:
        c = self.config
        try:
            scene = self._scene if self._scene is not None else build_station_scene(c, self.variant, self.robot)
            self._scene = None
            self.session = TeleopSession(scene, c.episodes, operator=OPERATOR, seed=c.seed, max_seconds=c.max_seconds)
        except RikError as exc:
            self.error = str(exc)
        except Exception as exc:  # noqa: BLE001 -- shown on the page instead of killing the thread silently
            self.error = f"building {self.variant} failed: {type(exc).__name__}: {exc}"
        else:
            self.ready = True
        self.message = ""

    def _run(self) -> None:
        builder = threading.Thread(target=self._build, name=f"rik-build-{self.variant}", daemon=True)
        builder.start()
        while builder.is_alive() and not self.stop.is_set():  # the page says "building the variant..." meanwhile
            self._push_status()
            builder.join(0.2)
        if not self.ready:
            while not self.stop.wait(0.2):
                self._push_status()
            return
        import mujoco

        session = self.session
        assert session is not None
        renderers = StationFrames(session.scene)  # the follow view and a renderer per size, on this thread
        frames: dict[tuple[int, int], dict[str, tuple[object, bytes]]] = {}  # per size, camera: (key, frame)
        skipped: dict[tuple[int, int], bool] = {}  # per size: the wrist was left out of the last render
        replay_data = mujoco.MjData(session.scene.model)
        dt = 1.0 / session.scene.control_fps
        next_tick = time.monotonic()
        sent: deque[float] = deque(maxlen=20)
        try:
            while not self.stop.is_set():
                steps, next_tick = due_steps(time.monotonic(), next_tick, dt, MAX_CATCH_UP)
                for _ in range(steps):  # the world keeps its own clock: a slow render drops frames, not time
                    self._step(replay_data)
                with self.lock:  # each tab's size as it is now: a tab may ask for another while this renders
                    sizes = [(c, c.size) for c in self.clients]
                    clients = [c for c, _ in sizes]
                data = replay_data if self.replay is not None else session.scene.data
                key = (session.episode, session.recorder.steps, float(data.time), self.replay and self.replay["row"],
                       self.view_turn)
                for size in {size for _, size in sizes}:
                    shown = frames.setdefault(size, {})
                    stale = [cam for cam in CAMERAS if cam not in shown or shown[cam][0] != key]
                    due = cameras_due(stale, behind=steps > 1, skipped=skipped.get(size, False))
                    skipped[size] = WRIST in stale and WRIST not in due
                    for cam, payload in zip(due, self._render(renderers, size, data, session, due), strict=True):
                        shown[cam] = (key, payload)
                    if FOLLOWED in due:
                        sent.append(time.monotonic())
                for c, size in sizes:
                    for cam, (k, payload) in frames.get(size, {}).items():
                        if c.sent.get(cam) != (k, size):
                            c.sent[cam] = (k, size)
                            c.push(cam, payload)
                self._push_status(clients)
                if len(sent) > 1:
                    span = sent[-1] - sent[0]
                    self.fps = (len(sent) - 1) / span if span > 0 and time.monotonic() - sent[-1] < 1.0 else 0.0
                delay = next_tick - time.monotonic()
                if delay > 0:
                    self.stop.wait(delay)
        except Exception as exc:  # noqa: BLE001 -- shown on the page instead of a station that says nothing
            self.error = f"the station stopped: {type(exc).__name__}: {exc}" + self._draft_after_failure(session)
            self.ready = False
            while not self.stop.wait(0.2):
                self._push_status()
        finally:
            renderers.close()

    def _step(self, replay_data: Any) -> None:
        """Apply commands and input, then advance one control step (or one replayed row)."""
        session = self.session
        assert session is not None
        with self.lock:
            commands = list(self.commands)
            self.commands.clear()
            controlled = self.controller is not None
            fresh = time.monotonic() - self.input_time <= INPUT_TIMEOUT
            axes = self.axes.copy() if fresh else np.zeros(6)
            grip, self.grip = self.grip, None
            seq = self.seq
        for _, name in commands:
            try:
                self._command(name, replay_data)
            except Exception as exc:  # noqa: BLE001 -- a command's failure is said on the page, never fatal
                self.message = failure(name, exc)
        if self.replay is not None:
            try:
                self._replay_row(replay_data)
            except Exception as exc:  # noqa: BLE001 -- the replay stops; the station and its episode go on
                self.replay = None
                self.message = failure("replay", exc)
            return
        if not controlled or self.paused:
            return
        session.set_input(axes, grip)
        session.tick()
        self.applied_seq = seq

    def _command(self, name: str, replay_data: Any) -> None:
        session = self.session
        assert session is not None
        if name == "_lost":
            if session.recording:
                self.paused = True
                try:
                    path = session.keep_draft()
                except OSError as exc:
                    self.message = f"could not keep a draft ({os_error_text(exc)}); {KEPT_IN_MEMORY}"
                else:
                    self.draft = None if path is None else str(path)
            return
        if self.replay is not None and not name.startswith("replay"):
            self.message = "replaying the last saved episode: wait until it ends"
            return
        self.message = ""
        if name == "toggle_grip" and not self.paused:
            session.toggle_grip()
        elif name == "toggle_motion":
            session.toggle_motion_mode()
        elif name == "save":
            try:
                session.save()
            except OSError as exc:  # a full disk, a quota: the episode stays recorded, and Save works again later
                self.message = f"could not save {session.episode} ({os_error_text(exc)}); {KEPT_IN_MEMORY}"
                return
            self.draft, self.paused = None, False
        elif name == "discard":
            session.discard()
            self.draft, self.paused = None, False
        elif name == "continue":
            self.draft, self.paused = None, False
            session.message = "continuing the episode"
        elif name.startswith("replay"):
            self._start_replay(name.partition(":")[2] or None)
        elif self.paused:
            self.message = PAUSED

    def _start_replay(self, episode: str | None = None) -> None:
        """Replay the last episode saved here, or ``episode``: one saved in this station's episodes folder for its
        variant and robot (the episodes page's replay link), bounded and checked first
        (:func:`rik.episodes.states.read_states`)."""
        from rik.episodes.episode import read_episode, states

        session = self.session
        assert session is not None
        if self.replay is not None:
            self.replay = None
            self.message = "replay stopped"
            return
        if episode is not None:
            path = self._saved_episode(episode)
        elif session.last_saved is None:
            self.message = "nothing saved in this session yet: save an episode to replay it"
            return
        else:
            path = session.last_saved.path
        meta, table = read_episode(path, ("state", "opening"))  # bounded first; only these two decoded
        self.replay = {"episode": meta.id, "states": states(table), "row": 0,
                       "openings": table.column("opening").to_numpy()}

    def _saved_episode(self, episode: str) -> Path:
        """The folder of ``episode`` in the episodes folder, when it is this station's variant's and robot's and
        its states file is at most :data:`MAX_REPLAY_BYTES`; else a one-line RikError."""
        import mujoco

        from rik.episodes.episode import STATES, read_meta

        assert self.session is not None
        path = inside(self.config.episodes, episode, what="episode id")
        if episode.startswith(".") or not (path / "meta.json").is_file():
            raise RikError(f"no episode {episode!r} in {self.config.episodes}")
        meta = read_meta(path)
        if (meta.variant, meta.robot) != (self.variant, self.robot):
            raise RikError(f"episode {episode} is of variant {meta.variant} with robot {meta.robot}, not this "
                           f"station's ({self.variant} with {self.robot}): open its own replay link")
        model = self.session.scene.model
        if meta.state_size != mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_INTEGRATION):
            raise RikError(f"episode {episode}: its states ({meta.state_size} numbers) do not fit this station's model")
        size = (path / STATES).stat().st_size
        if size > MAX_REPLAY_BYTES:
            raise RikError(f"episode {episode}: {path / STATES} is {size / 2**20:.0f} MiB, more than a station "
                           f"replays ({MAX_REPLAY_BYTES / 2**20:.0f} MiB)")
        return path

    def _replay_row(self, data: Any) -> None:
        import mujoco

        r = self.replay
        assert r is not None and self.session is not None
        if r["row"] >= len(r["states"]):
            self.replay = None
            self.message = f"replayed {r['episode']}; back to live"
            return
        model = self.session.scene.model
        mujoco.mj_setState(model, data, r["states"][r["row"]], mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(model, data)
        r["row"] += 1

    def _render(self, renderers: StationFrames, size: tuple[int, int], data: Any, session: TeleopSession,
                cameras: list[str]) -> list[bytes]:
        out = []
        step = session.recorder.steps if self.replay is None else self.replay["row"]
        for cam in cameras:  # the page's front view follows the work; the wrist camera is the scene's
            jpeg = encode_jpeg(renderers.render(data, cam, size, self.view_turn))
            header = {"camera": cam, "step": step, "seq": self.applied_seq, "t": round(float(data.time), 4),
                      "sent": time.time(), "width": size[0], "height": size[1], "replay": self.replay is not None}
            out.append(frame_message(header, jpeg))
        return out

    def status(self) -> dict[str, Any]:
        """The station's status without the per-tab fields (see :mod:`rik.web.teleop`)."""
        s = self.session
        st: dict[str, Any] = {"type": "status", "variant": self.variant, "robot": self.robot, "ready": self.ready,
                              "error": self.error,
                              "paused": self.paused, "draft": self.draft, "seq": self.applied_seq,
                              "fps": round(self.fps, 1), "controlled": self.controller is not None,
                              "replay": None, "session": None, "message": self.message,
                              "view": {"azimuth": round(self.view_turn[0], 1),
                                       "elevation": round(self.view_turn[1], 1)}}
        if self.replay is not None:
            row = min(max(self.replay["row"] - 1, 0), len(self.replay["states"]) - 1)  # the row now shown
            st["replay"] = {"episode": self.replay["episode"], "row": self.replay["row"],
                            "rows": len(self.replay["states"]),
                            "opening": round(float(self.replay["openings"][row]), 4)}
        if s is not None and self.ready:
            st["session"] = s.status()
        return st

    def _push_status(self, clients: list[Client] | None = None) -> None:
        if clients is None:
            with self.lock:
                clients = list(self.clients)
        base = self.status()
        for c in clients:
            st = dict(base, role="controller" if c is self.controller else "watcher", notice=c.notice,
                      size=list(c.size))
            c.push("status", json.dumps(st))

    @staticmethod
    def _draft_after_failure(session: TeleopSession) -> str:
        """Keep the episode in progress of a station whose thread failed as a draft (a person's recording is never
        lost with the station); what the page says about it."""
        if not session.recording:
            return ""
        try:
            return f"; its {session.recorder.steps} recorded steps were kept as a draft: {session.keep_draft()}"
        except Exception as exc:  # noqa: BLE001 -- the station is gone already; say what became of the episode
            return f"; its {session.recorder.steps} recorded steps could not be kept ({type(exc).__name__}: {exc})"

    def shutdown(self) -> Path | None:
        """Stop the thread; keep the episode in progress as a draft. Returns the draft's path, if one was kept."""
        self.stop.set()
        self.thread.join(timeout=30)
        s = self.session
        if s is not None and self.ready and s.recording and not self.thread.is_alive():
            try:
                return s.keep_draft()
            except OSError as exc:
                import sys

                print(f"rik: error: could not keep the draft of {s.episode} ({os_error_text(exc)}); "
                      f"{s.recorder.steps} steps lost", file=sys.stderr)
        return None


class Stations:
    """Every station of the app, one per variant id and robot, created when a tab's websocket asks for it; at most
    ``config.max_stations`` at once, and one that no tab has watched for ``config.idle_release`` s is released
    (its thread stopped, its renderers and scene freed, its episode in progress kept as a draft). ``scenes``:
    scenes already built, by (variant id, robot id), that those stations start from."""

    def __init__(self, config: StationConfig, scenes: dict[tuple[str, str], SimScene] | None = None) -> None:
        self.config = config
        self.lock = threading.Lock()
        self.stations: dict[tuple[str, str], Station] = {}
        self.scenes = dict(scenes or {})
        self.released: list[tuple[tuple[str, str], Path | None]] = []
        """Stations released so far (key, draft kept), oldest first."""
        self._stop = threading.Event()
        self._reaper = threading.Thread(target=self._reap, name="rik-stations-reaper", daemon=True)
        self._reaper.start()

    def get(self, variant: str, robot: str | None = None, client: Client | None = None) -> Station:
        """The station of ``variant`` (a canonical variant id) with ``robot`` (a catalog robot id; None: the
        app's), started (and its variant built) on first use, with ``client`` connected to it (under the lock, so
        the idle release never takes a station between its lookup and its tab). At the bound, the station with no
        tab that was left longest ago is released first; when every station has a tab, a RikError says so.
        Blocks while a station is released (its thread stops within seconds): call it off the event loop."""

        key = (variant, robot or self.config.robot)
        with self.lock:
            if key in self.stations:
                if client is not None:
                    self.stations[key].connect(client)
                return self.stations[key]
            victim = None
            if len(self.stations) >= self.config.max_stations:
                idle = [(t, k) for k, st in self.stations.items() if (t := st.idle_for()) is not None]
                if not idle:
                    raise RikError(f"{len(self.stations)} teleop stations are open, each with a tab (the bound is "
                                   f"{self.config.max_stations}: rik serve --max-stations): close one's tabs first")
                victim = max(idle)[1]
                old = self.stations.pop(victim)
            station = self.stations[key] = Station(self.config, *key, scene=self.scenes.pop(key, None))
            if client is not None:
                station.connect(client)
        if victim is not None:
            self._release(victim, old)
        return station

    def _release(self, key: tuple[str, str], station: Station) -> None:
        draft = station.shutdown()
        with self.lock:
            self.released.append((key, draft))

    def _reap(self) -> None:
        """Release stations idle past the bound, checking a few times per bound (at most every 5 s)."""
        period = min(5.0, max(0.2, self.config.idle_release / 4))
        while not self._stop.wait(period):
            with self.lock:
                stale = [(k, st) for k, st in self.stations.items()
                         if (t := st.idle_for()) is not None and t >= self.config.idle_release]
                for k, _ in stale:
                    del self.stations[k]
            for k, st in stale:
                self._release(k, st)

    def shutdown(self) -> list[Path]:
        self._stop.set()
        with self.lock:
            stations = list(self.stations.values())
            self.stations.clear()
        return [p for s in stations if (p := s.shutdown()) is not None]
