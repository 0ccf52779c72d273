"""One policy from the average of a training run's saved checkpoints (stochastic weight averaging, applied after
training): docs/policies.md measured S on unseen handles swing from 44 % to 28 % between two checkpoints 6,000 steps
apart of the same run, and an average of the weights along the flat end of the run is the usual remedy.

Writes a saved-policy folder (the last averaged checkpoint's config, processors and statistics; its
``model.safetensors`` the element-wise mean of every checkpoint's in ``--from`` .. ``--to``; ``averaged.json`` names
the run and the steps), which ``rik eval`` and ``lerobot-eval`` run as any other. Checkpoints of one run share their
dataset statistics, so the processors fit.

    uv run python scripts/average_checkpoints.py runs/act-pl --from 20000 --to 30000 --out runs/act-pl-swa
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

WEIGHTS = "model.safetensors"
AVERAGED = "averaged.json"
"""The averaged folder's note of what it averages: ``{"run": ..., "steps": [...]}``."""


def checkpoints(run: Path, first: int, last: int) -> list[Path]:
    """The ``pretrained_model`` folders of ``run``'s numbered checkpoints from step ``first`` to ``last``."""
    found = sorted((int(p.name), p / "pretrained_model") for p in (run / "checkpoints").iterdir()
                   if p.name.isdigit() and first <= int(p.name) <= last)
    return [p for _, p in found]


def _is_average(folder: Path) -> bool:
    """Whether ``folder`` is an averaged policy this script wrote: its ``averaged.json``, and only the plain files of
    a saved policy beside it (no folder)."""
    from rik.outputs import tree_holds_only

    return (folder / AVERAGED).is_file() and tree_holds_only(folder, lambda rel: "/" not in rel)


def average(folders: list[Path], out: Path) -> Path:
    """``out``: a copy of the last folder whose weights are the mean of all ``folders``' (float32). An earlier
    average at ``out`` is replaced whole; anything else there is refused (:mod:`rik.outputs`)."""
    import numpy as np
    from safetensors.numpy import load_file, save_file

    from rik.outputs import NEW, MadeFolder, staged_directory, write_bytes, write_text, writing

    total: dict[str, np.ndarray] = {}
    dtypes: dict[str, np.dtype] = {}
    for folder in folders:
        for name, tensor in load_file(str(folder / WEIGHTS)).items():
            total[name] = total.get(name, 0) + tensor.astype(np.float64)
            dtypes[name] = tensor.dtype  # the last checkpoint's, as its copy keeps
    kind = MadeFolder("an averaged policy of scripts/average_checkpoints.py", _is_average, "give another --out")
    with staged_directory(out, kind) as staged:
        for file in sorted(folders[-1].iterdir()):
            if file.is_file() and file.name != WEIGHTS:
                write_bytes(staged / file.name, file.read_bytes(), NEW)
        with writing(staged / WEIGHTS, NEW) as tmp:
            save_file({name: (t / len(folders)).astype(dtypes[name]) for name, t in total.items()}, str(tmp))
        write_text(staged / AVERAGED, json.dumps({"run": folders[0].parents[2].name,
                                                  "steps": [int(f.parent.name) for f in folders]}) + "\n", NEW)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a lerobot-train output folder (with checkpoints/)")
    parser.add_argument("--from", dest="first", type=int, required=True, help="first step averaged")
    parser.add_argument("--to", dest="last", type=int, required=True, help="last step averaged")
    parser.add_argument("--out", type=Path, required=True,
                        help="the averaged policy's folder (an earlier average there is replaced)")
    args = parser.parse_args(argv)
    if not (args.run / "checkpoints").is_dir():
        print(f"{args.run}: no checkpoints/ folder here; give a lerobot-train output folder", file=sys.stderr)
        return 2
    if os.path.lexists(args.out) and not (args.out.is_dir() and _is_average(args.out)):
        print(f"{args.out}: exists and is no averaged policy (no {AVERAGED}); it is left as it is: give another --out",
              file=sys.stderr)
        return 2
    folders = checkpoints(args.run, args.first, args.last)
    if len(folders) < 2:
        print(f"{args.run}/checkpoints: {len(folders)} checkpoint(s) between steps {args.first} and {args.last}; "
              "give a range with at least two", file=sys.stderr)
        return 2
    average(folders, args.out)
    print(f"{args.out}: the mean of {len(folders)} checkpoints ({folders[0].parent.name} .. "
          f"{folders[-1].parent.name})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
