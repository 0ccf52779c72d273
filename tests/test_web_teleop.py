"""The browser teleop station driven by a real Chromium (Debian's, through Playwright): keys held on the page (and a
gamepad through the page's test hook) open the demo drawer, the saved episode replays exactly, with the Hand-E and
with the Panda (``rik teleop --web --robot panda-2f85`` in its own process); a second tab watches; a lost
connection keeps a draft; an unknown variant or robot gets a 404 page with the one-line message."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import pytest
from shared import BOW, builtin_catalog
from web_fixtures import WAIT_MS, browser, served, signed, station_process

CAT = builtin_catalog()
STATION = "document.getElementById('station').dataset"

pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")]


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One variants folder for the module: the first page that opens the demo variant builds it."""
    return tmp_path_factory.mktemp("variants")


def config(variants: Path, episodes: Path):
    from rik.web.app import AppConfig

    return AppConfig(CAT, variants=variants, episodes=episodes)


class Driver:
    """Holds keys on the page until a condition on its status holds; counts presses and seconds of holding."""

    def __init__(self, page) -> None:
        self.page = page
        self.presses = 0
        self.held = 0.0

    def value(self, name: str) -> float:
        return float(self.page.evaluate(f"{STATION}.{name}"))

    def wait(self, condition: str) -> None:
        """Wait (bounded: :data:`WAIT_MS`) until the JS ``condition`` on ``d`` (the station's data attributes)
        holds; past the bound, fail with the condition and the station's last status."""
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        try:
            self.page.wait_for_function(f"(() => {{ const d = {STATION}; return {condition}; }})()",
                                        timeout=WAIT_MS, polling=100)
        except PlaywrightTimeout:
            last = self.page.evaluate("JSON.stringify(window.rikTest.status())")
            raise AssertionError(f"the station never reached {condition} in {WAIT_MS / 1000:.0f} s; its last "
                                 f"status: {last}") from None

    def hold(self, key: str, condition: str) -> None:
        self.page.keyboard.down(key)
        start = time.monotonic()
        self.presses += 1
        try:
            self.wait(condition)
        finally:
            self.page.keyboard.up(key)
            self.held += time.monotonic() - start

    def press(self, key: str) -> None:
        self.page.keyboard.press(key)
        self.presses += 1


def open_station(b, url: str, variant: str = BOW):
    page = b.new_page(viewport={"width": 1400, "height": 1000})
    page.goto(signed(f"{url}/teleop/{variant}"))
    page.wait_for_function(f"{STATION}.ready === 'true' && document.getElementById('cam-front').dataset.step !== ''",
                           timeout=WAIT_MS, polling=100)
    return page


@pytest.mark.parametrize("pull", ["gamepad", "keyboard"])
def test_browser_opens_the_demo_drawer_and_the_episode_replays_exactly(rik, variants: Path, tmp_path: Path,
                                                                       pull: str) -> None:
    """Roll ~90 deg (Q), approach (W) until the pads reach the handle, grasp (Space), pull (the gamepad's left
    stick, or S) until the drawer is 90 % open, save (Enter); closed-loop on the status the page shows."""
    from rik.teleop.keys import keymap_rows

    episodes = tmp_path / "episodes"
    fresh = not any(variants.iterdir())
    with served(config(variants, episodes)) as url, browser() as b:
        page = open_station(b, url)
        assert page.evaluate(f"{STATION}.role") == "controller"
        if fresh:  # opening the page built the variant (its "building the variant..." notice may pass unseen when the
            assert (variants / BOW / "model.xml").is_file()  # asset cache is warm: the build then takes < 1 s)
        shown = page.inner_text("#keymap")  # the keymap the viewer shows too
        assert all(keys in shown and does in shown for keys, does in keymap_rows())
        hint = page.inner_text("#hint", timeout=WAIT_MS)  # before the first input: how to grasp this handle
        assert page.is_visible("#hint") and "140 mm wide" in hint and "roll 90 deg" in hint, hint
        drive = Driver(page)
        drive.hold("q", "Number(d.roll) >= 1.50")  # roll the gripper ~90 deg: jaws across the bow handle
        drive.hold("w", "Number(d.ahead) <= 0.0")  # towards the furniture until the pads reach the handle
        steps = drive.value("steps")
        drive.press("Space")  # close the grip, then let the fingers close for 1 s
        drive.wait(f"d.grip === 'closed' && d.grasp === 'holding' && Number(d.steps) >= {steps + 20}")
        assert not page.is_visible("#hint")  # the hint folds away once the episode records
        assert page.inner_text("#st-grasp", timeout=WAIT_MS) == "holding"
        stick = 0.0
        if pull == "keyboard":
            drive.hold("s", "Number(d.opening) >= 0.9")
        else:  # the gamepad's left stick pulled back (through the page's test hook)
            start = time.monotonic()
            page.evaluate("window.rikTest.setGamepad({axes: [0, 1, 0, 0], buttons: []})")
            try:
                drive.wait("Number(d.opening) >= 0.9")
            finally:
                page.evaluate("window.rikTest.setGamepad({axes: [0, 0, 0, 0], buttons: []})")
            stick = time.monotonic() - start
        simulated = drive.value("steps") / 20
        shot = tmp_path / "station.png"
        page.screenshot(path=str(shot))
        drive.press("Enter")
        drive.wait("d.lastSaved !== ''")
        saved = page.evaluate(f"{STATION}.lastSaved")
        assert "saved" in page.inner_text("#banner")
        if pull == "keyboard":
            _check_saved(rik, episodes / saved, variants, drive, stick, simulated, shot)
            return
        page.click("#btn-replay")  # the saved episode plays back in the stream, then the stream is live again
        drive.wait("d.replaying === 'true'")
        drive.wait("d.replaying === 'true' && Number(d.shownOpening) >= 0.5 && Number(d.opening) < 0.05")  # the
        drive.wait("d.replaying === 'false'")  # replayed drawer's opening is shown, not the live one (closed again)
        assert f"replayed {saved}; back to live" in page.inner_text("#banner")
        page.select_option("#size", "640x480")
        page.wait_for_function("document.getElementById('cam-front').naturalWidth === 640", timeout=WAIT_MS, polling=100)
    _check_saved(rik, episodes / saved, variants, drive, stick, simulated, shot)


IDLE_PAGE_JS = """(ms) => new Promise((done) => {
  const changes = [];
  const observer = new MutationObserver((records) => { for (const r of records) changes.push(
    (r.target.id || (r.target.parentElement && r.target.parentElement.id)) + " " + r.type + " " + (r.attributeName || "")); });
  observer.observe(document.getElementById("station"), {attributes: true});
  for (const id of ["status", "banner", "hint", "role", "robot", "btn-take", "draft-offer", "pad-state"]) {
    observer.observe(document.getElementById(id), {attributes: true, childList: true, characterData: true, subtree: true});
  }
  let statuses = 0, last = window.rikTest.status();
  const poll = setInterval(() => { const s = window.rikTest.status(); if (s !== last) { statuses++; last = s; } }, 5);
  setTimeout(() => { observer.disconnect(); clearInterval(poll);
                     done({statuses: statuses, changes: changes.length, first: changes.slice(0, 8)}); }, ms);
})"""
"""Over ``ms`` ms: how many statuses the page received, and how many changes (mutation records) they made to the
station's data attributes and the status texts; the first few changes."""


def test_dragging_the_front_view_orbits_it_and_a_double_click_puts_it_back(variants: Path, tmp_path: Path) -> None:
    """The page's front view turns with a mouse drag (the station renders the turned view and reports the turn) and
    a double-click resets it; so do the gamepad's right stick with LT held, and R3; nothing is recorded by looking
    around."""
    with served(config(variants, tmp_path / "episodes")) as url, browser() as b:
        page = open_station(b, url)
        # a station nobody moves: its statuses (about 20 a second) leave the page as it is, where each status once
        # rewrote some 40 attributes and texts with their same values (a fifth of a core in Chromium, restyling)
        idle = page.evaluate(IDLE_PAGE_JS, 1500)
        assert idle["statuses"] >= 5 and idle["changes"] < idle["statuses"], idle
        drive = Driver(page)
        box = page.locator("#cam-front").bounding_box(timeout=WAIT_MS)
        assert box is not None
        x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        before = page.evaluate("document.getElementById('cam-front').src")
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x + 100, y + 30, steps=10)
        page.mouse.up()
        drive.wait("Number(d.viewAzimuth) < -20 && Number(d.viewElevation) < -5")
        page.wait_for_function(f"document.getElementById('cam-front').src !== {before!r}", timeout=WAIT_MS,
                               polling=100)  # a new frame of the turned view, with nothing moving
        assert page.evaluate(f"{STATION}.steps") == "0"
        page.dblclick("#cam-front", timeout=WAIT_MS)
        drive.wait("Number(d.viewAzimuth) === 0 && Number(d.viewElevation) === 0")
        # the gamepad: LT held, the right stick to the right and down orbits the same way; R3 puts the view back
        lt = [{"pressed": i == 6, "value": float(i == 6)} for i in range(17)]
        page.evaluate("b => window.rikTest.setGamepad({axes: [0, 0, 1, 0.6], buttons: b})", lt)
        drive.wait("Number(d.viewAzimuth) < -20 && Number(d.viewElevation) < -5")
        page.evaluate("b => window.rikTest.setGamepad({axes: [0, 0, 0, 0], buttons: b})",
                      [{"pressed": i == 11, "value": float(i == 11)} for i in range(17)])
        drive.wait("Number(d.viewAzimuth) === 0 && Number(d.viewElevation) === 0")
        page.evaluate("window.rikTest.setGamepad(null)")
        assert page.evaluate(f"{STATION}.steps") == "0"  # the stick turned the view, not the gripper


FRONTS = {
    "a left door with a knob": "door-base-60-left__knob-mushroom-30__normal",
    "a right door with a bar": "door-base-40-right__two_point-bow-128__normal",
    "a lift-up flap": "flap-lift-up-60__two_point-bow-128__normal",
    "a drop-down flap": "flap-drop-down-60__knob-mushroom-30__normal",
    "a left door with a vertical D-pull": "door-wall-60-left__two_point-d-pull-128__normal",
}
"""Every kind of hinged front, each with a handle of its own (the drawers are the tests above), and the vertical
D-pull on a wall cabinet's left door that issue 53 saw slip under a person's keys (here, by the hint's keys, it opens
in 4 presses; so does the double door's hex bar, left out to keep the suite's time)."""


@pytest.fixture(scope="module")
def station_server(variants: Path, tmp_path_factory: pytest.TempPathFactory):
    """One server (any variant) for the hinged fronts' tests: (url, episodes folder). Each test has its own browser
    (Playwright's sync API allows one at a time, and the other tests of the module start theirs)."""
    episodes = tmp_path_factory.mktemp("fronts") / "episodes"
    with served(config(variants, episodes)) as url:
        yield url, episodes


def _grasp(drive: Driver, hint: str) -> None:
    """What the hint says, as keys: the roll it names (Q), in (W) until the pads reach the handle or the fingertips
    meet the front ("blocked"), then the grip (Space) until the contacts read holding."""
    if "roll 90 deg" in hint:
        drive.hold("q", "Number(d.roll) >= 1.50")
    drive.hold("w", "Number(d.ahead) <= 0.0 || d.blocked === 'true'")
    drive.press("Space")
    drive.wait("d.grasp === 'holding'")


@pytest.mark.parametrize("front", list(FRONTS))
def test_every_hinged_front_opens_in_a_few_presses_along_its_arc_and_replays_exactly(
        rik, station_server, variants: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], front: str) -> None:
    """The door the issue's operator needed 53 presses for, and the other hinged fronts: the hint says which roll;
    Q rolls, W approaches, Space grasps, and one held S follows the front's arc (path motion, the default while
    holding) to 90 % open (S); the episode replays exactly. On the left door, the next episode checks that a grip let
    go part way mid-pull shows "slipped", and that M switches to frame-fixed motion."""
    url, episodes = station_server
    with browser() as b:
        _open_the_front(rik, b, url, episodes, variants, tmp_path, capsys, front)


def _open_the_front(rik, b, url: str, episodes: Path, variants: Path, tmp_path: Path,
                    capsys: pytest.CaptureFixture[str], front: str) -> None:
    page = open_station(b, url, FRONTS[front])
    try:
        hint = page.inner_text("#hint", timeout=WAIT_MS)
        assert page.is_visible("#hint") and "arc" in hint, hint
        drive = Driver(page)
        start = time.monotonic()
        _grasp(drive, hint)
        # one held key along the arc; the motion is read from the status that reached 90 % (S still down): once the key
        # is up the next status says frame-fixed, and on a busy machine it can arrive before a later read
        drive.hold("s", "Number(d.opening) >= 0.9 && (window.rikMotionAtGoal = d.motion) !== undefined")
        assert page.evaluate("window.rikMotionAtGoal") == "path"
        if front == "a left door with a knob":
            page.screenshot(path=str(tmp_path / "door.png"))
        drive.press("Enter")
        drive.wait("d.lastSaved !== ''")
        presses, seconds = drive.presses, time.monotonic() - start
        saved = page.evaluate(f"{STATION}.lastSaved")
        with capsys.disabled():  # shown in every run (-s or not): the effort a person needs
            print(f"\n{front}: 90 % open in {presses} key presses, {seconds:.1f} s ({drive.held:.1f} s of holding)")
        assert presses <= 15
        res = rik("replay", str(episodes / saved), "--variants", str(variants))
        assert res.code == 0 and "exact" in res.out, res.out + res.err
        if front != "a left door with a knob":
            return
        _grasp(drive, hint)  # the next episode: the grip let go mid-pull lets the knob go, and the page says so
        drive.hold("s", "Number(d.opening) >= 0.1")
        page.evaluate("window.rikTest.setGamepad({axes: [0, 0, 0, 0], buttons: [...Array(7).fill({pressed: false, "
                      "value: 0}), {pressed: true, value: 0.05}]})")  # the right trigger let go to 5 %
        try:
            drive.wait("d.grasp === 'slipped'")
        finally:
            page.evaluate("window.rikTest.setGamepad(null)")
        assert "slipped" in page.inner_text("#st-grasp", timeout=WAIT_MS)
        drive.press("m")
        drive.wait("d.motionMode === 'frame'")
    finally:
        page.close()


def _check_saved(rik, episode: Path, variants: Path, drive: Driver, stick: float, simulated: float,
                 shot: Path) -> None:
    """The saved episode is there, opened the drawer 90 %, and replays exactly; prints the drive's effort."""
    from rik.episodes.episode import read_meta

    assert (episode / "meta.json").is_file() and (episode / "states.parquet").is_file()
    meta = read_meta(episode)
    assert meta.operator == "browser" and meta.max_opening >= 0.9, meta
    res = rik("replay", str(episode), "--variants", str(variants))
    assert res.code == 0 and "exact" in res.out, res.out + res.err
    print(f"\nbrowser drive: {drive.presses} key presses, {drive.held:.1f} s of key holding, {stick:.1f} s of "
          f"gamepad stick, {simulated:.1f} s simulated (final opening {meta.final_opening:.0%}); screenshot {shot}")


def test_second_tab_watches_and_a_lost_connection_keeps_a_draft(variants: Path, tmp_path: Path) -> None:
    from rik.teleop.station import LEFT, PAUSED, WATCHING

    episodes = tmp_path / "episodes"
    with served(config(variants, episodes)) as url, browser() as b:
        first = open_station(b, url)
        drive = Driver(first)
        drive.hold("w", "Number(d.steps) >= 10")  # mid-episode: something recorded
        watcher = open_station(b, url)
        assert watcher.evaluate(f"{STATION}.role") == "watcher"
        assert WATCHING in watcher.inner_text("#banner")
        watcher.keyboard.down("s")
        watcher.keyboard.up("s")
        Driver(watcher).wait(f"document.getElementById('banner').textContent.includes({WATCHING!r})")
        episode = first.evaluate(f"{STATION}.episode")
        first.close()  # the controlling tab's connection is lost mid-episode
        Driver(watcher).wait(f"document.getElementById('banner').textContent.includes({LEFT!r})")
        draft = episodes / ".drafts" / episode
        Driver(watcher).wait("d.paused === 'true'")
        assert (draft / "meta.json").is_file()
        third = open_station(b, url)  # a new tab controls and is offered the draft
        Driver(third).wait("d.role === 'controller' && d.paused === 'true'")
        assert third.is_visible("#draft-offer") and str(draft) in third.inner_text("#draft-offer")
        third.keyboard.down("w")  # moving waits for the operator's choice
        Driver(third).wait(f"document.getElementById('banner').textContent.includes({PAUSED!r})")
        third.keyboard.up("w")
        third.close()
        watcher.click("#btn-take")  # the watcher takes over once nobody controls
        Driver(watcher).wait("d.role === 'controller'")
        assert watcher.is_visible("#draft-offer")
        watcher.click("#btn-draft-save")
        Driver(watcher).wait("d.lastSaved !== ''")
    assert (episodes / episode / "meta.json").is_file() and not draft.exists()


def test_unknown_variant_gets_a_404_page_with_the_message(variants: Path, tmp_path: Path) -> None:
    with served(config(variants, tmp_path / "episodes")) as url, browser() as b:
        page = b.new_page()
        response = page.goto(signed(f"{url}/teleop/drawer-chest-80__two_point-bow-999__normal"))
        assert response is not None and response.status == 404
        assert "rik: error: no handle 'two_point-bow-999' in the catalog" in page.inner_text("#error")


def test_on_screen_button_moves_and_a_server_shut_down_mid_episode_keeps_a_draft(variants: Path, tmp_path: Path) -> None:
    episodes = tmp_path / "episodes"
    with served(config(variants, episodes)) as url, browser() as b:
        page = open_station(b, url)
        page.hover("#hold-KeyR")  # the on-screen hold-to-move button "R: up", held with the mouse
        z = float(page.evaluate(f"{STATION}.z"))
        page.mouse.down()
        Driver(page).wait(f"Number(d.steps) >= 5 && Number(d.z) > {z + 0.005}")
        page.mouse.up()
        episode = page.evaluate(f"{STATION}.episode")
    assert (episodes / ".drafts" / episode / "meta.json").is_file()
    assert not (episodes / episode).exists()


def test_the_panda_opens_the_demo_drawer_from_the_keyboard_and_its_episode_replays_exactly(
        variants: Path, tmp_path: Path) -> None:
    """``rik teleop BOW --web --robot panda-2f85``: the same held keys drive the Panda's gripper frame through its
    IK: roll ~90 deg (Q), approach (W) until the pads reach the bar, grip (Space), pull (S) until the drawer is 90 %
    open, save (Enter). The episode names the Panda, records its 7 joints and its gripper, and replays exactly. A
    robot the catalog lacks gets a 404 page with the one-line message."""
    from rik.episodes.episode import read_episode, read_meta
    from rik.episodes.replay import verify_episode

    episodes = tmp_path / "episodes"
    with station_process("teleop", BOW, "--web", "--port", "0", "--robot", "panda-2f85", "--variants",
                         str(variants), "--out", str(episodes), cwd=tmp_path) as url, browser() as b:
        page = b.new_page(viewport={"width": 1400, "height": 1000})
        page.goto(url)
        drive = Driver(page)
        drive.wait("d.ready === 'true' && document.getElementById('cam-front').dataset.step !== '' && "
                   "document.getElementById('cam-wrist').dataset.step !== ''")  # the arm's own wrist camera
        assert page.evaluate(f"{STATION}.robot") == "panda-2f85" and page.inner_text("#st-robot") == "panda-2f85"
        drive.hold("q", "Number(d.roll) >= 1.50")  # jaws across the bow's bar
        drive.hold("w", "Number(d.ahead) <= 0.0")  # towards the front until the pads' centre reaches the bar
        steps = drive.value("steps")
        drive.press("Space")  # close, and let the 2F-85 close for 1 s
        drive.wait(f"d.grip === 'closed' && Number(d.steps) >= {steps + 20}")
        drive.hold("s", "Number(d.opening) >= 0.9")
        simulated = drive.value("steps") / 20
        page.select_option("#size", "640x480")  # the picture in docs/teleop.md: the cameras and the status
        drive.wait("document.getElementById('cam-front').naturalWidth === 640 && "
                   "document.getElementById('cam-wrist').naturalWidth === 640")
        page.locator("section.views").screenshot(path=str(tmp_path / "station-panda.png"))
        drive.press("Enter")
        drive.wait("d.lastSaved !== ''")
        saved = page.evaluate(f"{STATION}.lastSaved")
        response = page.goto(url.split("/teleop/")[0] + f"/teleop/{BOW}?robot=so10")
        assert response is not None and response.status == 404
        assert page.inner_text("#error") == "rik: error: no robot 'so10' in the catalog; did you mean 'so101' or 'so100'? (the catalog's robots: hand-e, panda-2f85, so100, so101)"
    episode = episodes / saved
    meta = read_meta(episode)
    assert saved == f"{BOW}__drawer-1__browser.panda-2f85__s0000" and meta.robot == "panda-2f85"
    assert meta.robot_joints == (*(f"joint{i}" for i in range(1, 8)), "gripper")
    assert meta.max_opening >= 0.9 and meta.operator == "browser", meta
    _, table = read_episode(episode)
    assert len(table.column("robot_joints")[0]) == 8
    check = verify_episode(CAT, episode, variants)
    assert check.exact, check
    print(f"\nPanda drive: {drive.presses} key presses, {drive.held:.1f} s of key holding, {simulated:.1f} s "
          f"simulated (final opening {meta.final_opening:.0%}); screenshot {tmp_path / 'station-panda.png'}")
