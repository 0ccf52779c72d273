"""The README's promise: exactly two commands for a fresh machine, and they exist as written."""

from __future__ import annotations

import re

from conftest import REPO


def test_quick_start_has_exactly_two_commands_that_exist() -> None:
    text = (REPO / "README.md").read_text()
    block = re.search(r"## Quick start.*?```bash\n(.*?)```", text, re.S)
    assert block, "README has no Quick start code block"
    commands = [line.split("#")[0].strip() for line in block.group(1).splitlines() if line.split("#")[0].strip()]
    assert commands == ["bash scripts/demo.sh", "bash scripts/test.sh"]
    for command in commands:
        assert (REPO / command.split()[1]).is_file()
    ci = (REPO / ".ci" / "run").read_text()
    assert "bash scripts/test.sh" in ci, ".ci/run must run the README's test command"
