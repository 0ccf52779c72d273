"""scripts/setup.sh's own logic, run for real by bash with the system tools it calls replaced by stubs on PATH.

The stubs (``dpkg-query``, ``apt-get``, ``sudo``, ``id``, ``uv``) log how they were called, so the tests see the
install call a fresh machine would make, as root (every container: no sudo) and as a user (through sudo).
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
from pathlib import Path

import pytest
from conftest import REPO

STUBS = {
    # Installed: every package but those named in $MISSING (space-separated).
    "dpkg-query": """for a in "$@"; do p="$a"; done
case " $MISSING " in *" $p "*) exit 1;; esac
printf 'install ok installed'""",
    "apt-get": 'echo "apt-get $* | DEBIAN_FRONTEND=${DEBIAN_FRONTEND:-unset} | uid=$(id -u)" >> "$LOG"',
    "sudo": 'echo "sudo $*" >> "$LOG"; FAKE_UID=0 exec "$@"',
    "id": 'if [ "$1" = "-u" ]; then echo "${FAKE_UID:-0}"; else /usr/bin/id "$@"; fi',
    # Python 3.12: found on the machine ($PYTHON=found), downloadable (download) or neither (none).
    "uv": """[ "$1" = --version ] && exit 0
echo "uv $*" >> "$LOG"
case "$1 $2 ${PYTHON:-found}" in "python find found") exit 0;; "python find "*) exit 2;;
  "python install download") exit 0;; "python install "*) echo "error: dns error" >&2; exit 2;; esac""",
}


@pytest.fixture
def setup_run(tmp_path: Path):
    """Run a copy of scripts/setup.sh with stubbed tools; returns (exit code, stderr, logged calls)."""
    repo = tmp_path / "repo"
    (repo / "scripts").mkdir(parents=True)
    for name in ("setup.sh", "apt-packages.txt"):
        shutil.copy(REPO / "scripts" / name, repo / "scripts" / name)
    shutil.copy(REPO / ".python-version", repo / ".python-version")
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, body in STUBS.items():
        stub = bin_dir / name
        stub.write_text(f"#!/bin/bash\n{body}\n")
        stub.chmod(stub.stat().st_mode | stat.S_IXUSR)
    log = tmp_path / "calls.log"

    def run(*, uid: int, missing: str, python: str = "found") -> tuple[int, str, list[str]]:
        log.write_text("")
        env = {"PATH": f"{bin_dir}:/usr/bin:/bin", "HOME": str(tmp_path / "home"), "LOG": str(log),
               "MISSING": missing, "FAKE_UID": str(uid), "PYTHON": python}
        done = subprocess.run(["bash", str(repo / "scripts" / "setup.sh")], env=env, capture_output=True,
                              text=True, timeout=60)
        return done.returncode, done.stderr, log.read_text().splitlines()

    return run


def test_as_root_installs_the_missing_package_without_sudo(setup_run) -> None:
    code, err, calls = setup_run(uid=0, missing="libllvm19")
    assert code == 0, err
    assert calls == [
        "apt-get update -qq | DEBIAN_FRONTEND=noninteractive | uid=0",
        "apt-get install -y -qq libllvm19 | DEBIAN_FRONTEND=noninteractive | uid=0",
        "uv python find",
        "uv sync --locked --compile-bytecode --quiet",
    ]


def test_as_a_user_installs_through_sudo(setup_run) -> None:
    code, err, calls = setup_run(uid=1000, missing="libllvm19 libegl1")
    assert code == 0, err
    assert calls == [
        "sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq",
        "apt-get update -qq | DEBIAN_FRONTEND=noninteractive | uid=0",
        "sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libegl1 libllvm19",
        "apt-get install -y -qq libegl1 libllvm19 | DEBIAN_FRONTEND=noninteractive | uid=0",
        "uv python find",
        "uv sync --locked --compile-bytecode --quiet",
    ]


def test_nothing_missing_installs_nothing(setup_run) -> None:
    code, err, calls = setup_run(uid=0, missing="")
    assert code == 0, err
    assert calls == ["uv python find", "uv sync --locked --compile-bytecode --quiet"]


def test_a_missing_python_is_downloaded_by_uv(setup_run) -> None:
    code, err, calls = setup_run(uid=0, missing="", python="download")
    assert code == 0, err
    assert calls == ["uv python find", "uv python install --quiet", "uv sync --locked --compile-bytecode --quiet"]


def test_no_python_and_no_download_is_one_line_that_says_what_to_install(setup_run) -> None:
    """A machine without Python 3.12 where uv cannot reach github.com: one line, exit 1, no sync (uv's own error
    is a chain of DNS causes that names no remedy)."""
    code, err, calls = setup_run(uid=0, missing="", python="none")
    version = (REPO / ".python-version").read_text().strip()
    assert code == 1
    assert err.strip() == (f"setup: error: no Python {version} on this machine, and uv could not download one (is "
                           f"github.com reachable?): install Python {version} (pyenv, or your distribution's "
                           f"python{version}) so that it is on PATH, and run this again")
    assert calls == ["uv python find", "uv python install --quiet"]


def test_the_stubs_stand_in_for_the_real_tools() -> None:
    """The stubs replace tools the real set-up calls by these names (a rename in setup.sh would make the tests
    above pass without exercising it)."""
    text = (REPO / "scripts" / "setup.sh").read_text()
    for tool in ("dpkg-query -W", "apt-get update", "apt-get install", "(sudo)", "id -u", "uv python find",
                 "uv python install", "uv sync"):
        assert tool in text, tool
    assert os.access(REPO / "scripts" / "setup.sh", os.R_OK)
