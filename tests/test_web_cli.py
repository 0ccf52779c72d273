"""``rik serve`` and ``rik teleop --web`` from the command line: the server starts, prints its address, answers and
stops cleanly on Ctrl+C; a port in use, an unknown variant and options that do not go together get one line."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

BOW = "drawer-chest-80__two_point-bow-128__normal"


def test_a_port_in_use_is_named(rik) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        r = rik("serve", "--port", str(port))
        assert r.code == 2 and "Traceback" not in r.err
        assert f"--port {port}: port {port} on 127.0.0.1 is in use (another rik serve?)" in r.err
        assert "--port 0 for a free one" in r.err


def test_an_unknown_variant_fails_before_any_port_is_taken(rik, tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        r = rik("teleop", "drawer-chest-80__two_point-bow-12__normal", "--web", "--port", str(port),
                "--variants", str(tmp_path / "v"))
    assert r.code == 2 and "no handle 'two_point-bow-12'" in r.err and "in use" not in r.err
    r = rik("teleop", BOW, "--web", "--device", "spacemouse", "--variants", str(tmp_path / "v"))
    assert r.code == 2 and "--device spacemouse: the browser station takes the browser's keyboard" in r.err
    r = rik("teleop", BOW, "--web", "--max-seconds", "0", "--variants", str(tmp_path / "v"))
    assert r.code == 2 and "--max-seconds 0.0: a time limit must be positive (or none at all)" in r.err
    r = rik("serve", "--max-seconds", "-5", "--port", "0")
    assert r.code == 2 and "--max-seconds -5.0: a time limit must be positive" in r.err
    assert not (tmp_path / "v").exists()  # refused before anything was built


def test_rik_serve_answers_and_stops_on_ctrl_c(tmp_path: Path) -> None:
    """The real command in its own process, as a user runs it: the printed address answers, Ctrl+C stops it with
    exit 0 and no traceback."""
    env = {**os.environ, "COLUMNS": "200"}
    proc = subprocess.Popen([sys.executable, "-m", "rik", "serve", "--port", "0", "--out", str(tmp_path / "ep"),
                             "--variants", str(tmp_path / "v")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=tmp_path)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()  # blocks until the address is printed (or the process ends)
        found = re.search(r"http://localhost:(\d+)/", line)
        assert found, (line, proc.stderr.read() if proc.poll() is not None else "")
        url = f"http://127.0.0.1:{found.group(1)}"
        assert f"ssh -L {found.group(1)}:localhost:{found.group(1)}" in line
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(url + "/api/docs", timeout=10) as page:
                    assert page.status == 200
                    break
            except OSError:
                assert time.monotonic() < deadline, "rik serve never answered"
                time.sleep(0.2)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
