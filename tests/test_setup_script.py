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
    "uv": '[ "$1" = --version ] || echo "uv $*" >> "$LOG"',
}


@pytest.fixture
def setup_run(tmp_path: Path):
    """Run a copy of scripts/setup.sh with stubbed tools; returns (exit code, stderr, logged calls)."""
    repo = tmp_path / "repo"
    (repo / "scripts").mkdir(parents=True)
    for name in ("setup.sh", "apt-packages.txt"):
        shutil.copy(REPO / "scripts" / name, repo / "scripts" / name)
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, body in STUBS.items():
        stub = bin_dir / name
        stub.write_text(f"#!/bin/bash\n{body}\n")
        stub.chmod(stub.stat().st_mode | stat.S_IXUSR)
    log = tmp_path / "calls.log"

    def run(*, uid: int, missing: str) -> tuple[int, str, list[str]]:
        log.write_text("")
        env = {"PATH": f"{bin_dir}:/usr/bin:/bin", "HOME": str(tmp_path / "home"), "LOG": str(log),
               "MISSING": missing, "FAKE_UID": str(uid)}
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
        "uv sync --locked --compile-bytecode --quiet",
    ]


def test_nothing_missing_installs_nothing(setup_run) -> None:
    code, err, calls = setup_run(uid=0, missing="")
    assert code == 0, err
    assert calls == ["uv sync --locked --compile-bytecode --quiet"]


def test_the_stubs_stand_in_for_the_real_tools() -> None:
    """The stubs replace tools the real set-up calls by these names (a rename in setup.sh would make the tests
    above pass without exercising it)."""
    text = (REPO / "scripts" / "setup.sh").read_text()
    for tool in ("dpkg-query -W", "apt-get update", "apt-get install", "(sudo)", "id -u", "uv sync"):
        assert tool in text, tool
    assert os.access(REPO / "scripts" / "setup.sh", os.R_OK)
