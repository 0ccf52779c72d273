"""A unit that fails is retried, recorded with its message and listed; the rest goes on, nothing is published, and
a rerun redoes what failed. Here the failure is real: an episode's states file is corrupted between its record and
its render."""

from __future__ import annotations

import json
from pathlib import Path

from shared import builtin_catalog

CAT = builtin_catalog()
SPEC = """repo_id: local/rik-fail
variants:
  ids: [drawer-chest-80__two_point-bow-128__normal]
operators:
  - strategy: contact_rich
episodes_per_variant: 2
max_seconds: 0.4
streams: [sim]
cameras: [front]
resolution: 32
"""


def test_a_corrupt_episode_fails_its_render_and_a_rerun_records_it_again(tmp_path: Path) -> None:
    from rik.dataset.build import build_dataset
    from rik.dataset.engines import InlineEngine
    from rik.dataset.plan import make_plan
    from rik.dataset.spec import load_spec

    (tmp_path / "spec.yaml").write_text(SPEC)
    variants = tmp_path / "variants"
    plan = make_plan(CAT, load_spec(tmp_path / "spec.yaml"), source="spec.yaml", variants_dir=variants)
    out, work = tmp_path / "ds", tmp_path / "ds.work"
    first = plan.episodes[0].episode_id
    corrupted: list[str] = []

    def corrupt_after_first_record(stage: str, done: int, total: int) -> None:
        if stage == "record" and not corrupted:
            states = work / "episodes" / first / "states.parquet"
            states.write_bytes(states.read_bytes()[:-64])  # truncated, as a full disk or a bad copy leaves it
            corrupted.append(first)

    result = build_dataset(CAT, plan, out, InlineEngine(CAT), variants=variants, retries=1,
                           progress=corrupt_after_first_record, register=False)
    assert corrupted
    assert len(result.failures) == 1
    failure = result.failures[0]
    assert failure.stage == "render" and failure.attempts == 2
    assert failure.what == f"sim frames of {first}"
    assert "states.parquet" in failure.message and "sha256" in failure.message
    assert result.ran["record"] == 2 and result.ran["render"] == 1  # the other episode went on
    assert not out.exists()
    recorded = json.loads((work / "units" / "failed" / f"{failure.key}.json").read_text())
    assert recorded["message"] == failure.message

    again = build_dataset(CAT, plan, out, InlineEngine(CAT), variants=variants, register=False)
    assert not again.failures
    assert again.ran == {"record": 1, "render": 1, "shard": 1}  # the corrupt episode recorded anew
    assert again.reused["record"] == 1 and again.reused["render"] == 1
    assert again.episodes == 2 and out.is_dir()
    assert not (work / "units" / "failed" / f"{failure.key}.json").exists()
