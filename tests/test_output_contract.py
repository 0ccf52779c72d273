"""rik's output contract (rik.outputs, docs/reliability.md section 3b): the source scanned for writes that bypass it,
and each fault it was made against, tried as a clumsy or hostile user would, through the real CLI and real
concurrent processes."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import rik

ROOT = Path(rik.__file__).parent.parent
SCANNED = (ROOT / "rik", ROOT / "packages", ROOT / "scripts")
CONTRACT = {ROOT / "rik" / "outputs.py", ROOT / "rik" / "locks.py"}
"""The modules that may create, write, rename and remove files: the output contract and its locks. (benchmarks/
write only into temporary folders of their own and are not scanned.)"""

FORBIDDEN_CALLS = {
    "os.replace", "os.rename", "os.renames", "os.remove", "os.unlink", "os.rmdir", "os.removedirs", "os.link",
    "os.symlink", "os.truncate", "os.open", "os.mkfifo", "shutil.rmtree", "shutil.move", "shutil.copy",
    "shutil.copy2", "shutil.copyfile", "shutil.copytree", "tempfile.mkstemp", "tempfile.NamedTemporaryFile",
}
"""Module functions that write, rename or remove outside the contract."""
FORBIDDEN_NAMES = {"write_atomic", "atomic_path", "rmtree", "copyfile", "copytree"}
"""Names that are writers without an ownership check (rik's old ``write_atomic``, imported ``shutil`` functions)."""
FORBIDDEN_METHODS = {"write_text", "write_bytes", "unlink", "rmdir", "rename", "touch", "symlink_to", "hardlink_to"}
"""``pathlib.Path`` methods that write or remove."""
LIBRARY_WRITERS = {"write_table", "savez", "savez_compressed", "savefig", "write_video", "save_file"}
"""Library functions that write a file at a path: allowed only into a temporary of ``rik.outputs.writing`` or a
stage rik made (their destination's first name is bound by ``with writing(...) as X``, ``with staged_directory(...)
as X`` or ``X = make_stage(...)`` in the same function)."""
STAGING_CALLS = {"writing", "staged_directory", "make_stage"}


def _dotted(node: ast.expr) -> str:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return f"{_dotted(node.value)}.{node.attr}"
    return ""


def _root_name(node: ast.expr) -> str | None:
    """The first name of a path expression: ``stage`` in ``stage / "a" / b``, ``str(tmp)``, ``tmp.with_name(..)``."""
    while True:
        if isinstance(node, ast.Name):
            return node.id
        if isinstance(node, ast.BinOp):
            node = node.left
        elif isinstance(node, ast.Call) and node.args and _dotted(node.func) in ("str", "Path", "os.fspath"):
            node = node.args[0]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            node = node.func.value
        else:
            return None


def _write_mode(call: ast.Call, position: int) -> bool:
    mode = call.args[position] if len(call.args) > position else next(
        (k.value for k in call.keywords if k.arg == "mode"), None)
    return isinstance(mode, ast.Constant) and isinstance(mode.value, str) and any(c in mode.value for c in "wax+")


def _staged_names(function: ast.AST) -> set[str]:
    """Names bound in ``function`` to a temporary or a stage of rik.outputs."""
    names = set()
    for node in ast.walk(function):
        if isinstance(node, ast.withitem) and isinstance(node.context_expr, ast.Call) \
                and _dotted(node.context_expr.func).split(".")[-1] in STAGING_CALLS \
                and isinstance(node.optional_vars, ast.Name):
            names.add(node.optional_vars.id)
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) \
                and _dotted(node.value.func).split(".")[-1] in STAGING_CALLS:
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return names


def bypasses(path: Path, root: Path = ROOT) -> list[str]:
    """Every call in the Python file ``path`` that writes, renames or removes a file without the output contract:
    ``file:line: what`` (the file named relative to ``root``), in line order."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    found: list[tuple[int, str]] = []
    functions = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]
    staged_in: dict[int, set[str]] = {}
    for function in functions:  # outer functions first (ast.walk is breadth-first): an inner one's names win
        names = _staged_names(function)
        staged_in.update({id(call): names for call in ast.walk(function) if isinstance(call, ast.Call)})
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = _dotted(node.func)
        method = node.func.attr if isinstance(node.func, ast.Attribute) else None
        what = None
        if name in FORBIDDEN_CALLS or name in FORBIDDEN_NAMES:
            what = name
        elif name == "open" and _write_mode(node, 1):
            what = "open(..., write mode)"
        elif method == "open" and _write_mode(node, 0):
            what = ".open(write mode)"
        elif method in FORBIDDEN_METHODS:
            what = f".{method}()"
        elif method == "replace" and len(node.args) == 1 and not node.keywords:  # Path.replace(target); str's has 2
            what = ".replace(target)"
        elif (method or name) in LIBRARY_WRITERS and node.args:
            second = (method or name.split(".")[-1]) in ("write_table", "save_file")  # (data, path)
            destination = node.args[1] if second and len(node.args) > 1 else node.args[0]
            if _root_name(destination) not in staged_in.get(id(node), set()):
                what = f"{method or name}() to a path that is not a temporary or stage of rik.outputs"
        if what:
            found.append((node.lineno, f"{path.relative_to(root)}:{node.lineno}: {what}"))
    return [hit for _, hit in sorted(found)]


def scan(roots: tuple[Path, ...] = SCANNED) -> list[str]:
    return [hit for root in roots for file in sorted(root.rglob("*.py")) if file not in CONTRACT
            for hit in bypasses(file)]


def test_every_write_goes_through_the_output_contract() -> None:
    """No module but rik.outputs and rik.locks writes, renames or removes a file itself."""
    hits = scan()
    assert not hits, "writes outside rik.outputs (use its writers, which check what they replace):\n" + "\n".join(hits)


def test_the_scan_finds_each_kind_of_bypass(tmp_path: Path) -> None:
    """The scan is not vacuous: each way of writing around the contract is found, and reads, string replacements
    and a library writing into the contract's temporary are not."""
    module = tmp_path / "rik" / "bad.py"
    module.parent.mkdir()
    module.write_text(textwrap.dedent('''
        import os, shutil
        from rik.paths import write_atomic
        def f(path, stage):
            open(path, "w").write("x")
            open(path, mode="ab")
            path.open("w")
            path.write_text("x")
            path.unlink()
            path.replace(stage)
            os.replace(path, stage)
            shutil.rmtree(path)
            write_atomic(path, "x")
            pq.write_table(table, path / "states.parquet")
            fig.savefig(path)
            "a".replace("a", "b")        # a string: fine
            open(path).read()            # a read: fine
            with writing(path, NEW) as tmp:
                pq.write_table(table, tmp)   # into the contract's temporary: fine
    '''))
    found = [hit.split(": ", 1)[1] for hit in bypasses(module, tmp_path)]
    assert found == ["open(..., write mode)", "open(..., write mode)", ".open(write mode)", ".write_text()",
                     ".unlink()", ".replace(target)", "os.replace", "shutil.rmtree", "write_atomic",
                     "write_table() to a path that is not a temporary or stage of rik.outputs",
                     "savefig() to a path that is not a temporary or stage of rik.outputs"]


def test_the_scan_fails_on_the_tree_before_the_contract(tmp_path: Path) -> None:
    """On c210781 (before rik.outputs) the scan finds the bypasses the contract replaced; run only where git has that
    commit (a shallow clone may not)."""
    git = subprocess.run(["git", "-C", str(ROOT), "cat-file", "-e", "c210781^{commit}"], capture_output=True)
    if git.returncode != 0:
        pytest.skip("commit c210781 is not in this clone")
    tree = tmp_path / "old"
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "c210781", "rik", "packages"], capture_output=True,
                             check=True).stdout
    tree.mkdir()
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    hits = [h for root in (tree / "rik", tree / "packages") for f in sorted(root.rglob("*.py"))
            if f.name != "locks.py" for h in bypasses(f, tree)]
    assert len(hits) > 50, hits
    assert any("write_atomic" in h for h in hits) and any("shutil.rmtree" in h for h in hits)



# ---- the faults the contract was made against (each failed on c210781) -----------------------------------------------
def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rik: error: "), err
    return lines[0]


def tree(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root`` with its bytes (None for folders, the target for links)."""
    return {str(p.relative_to(root)): (os.readlink(p).encode() if p.is_symlink() else
                                       None if p.is_dir() else p.read_bytes()) for p in sorted(root.rglob("*"))}


def test_probe_keeps_a_measured_profile_at_its_csv(rik, bow_variants: Path, tmp_path: Path) -> None:
    """``rik variants probe V --csv fridge.csv`` (the docs' own example name) replaced the user's measured profile
    with the simulated pull; rik's own earlier profile there is replaced, and a missing folder is made."""
    from shared import BOW

    fridge = tmp_path / "fridge.csv"
    fridge.write_text("trial,position [m],force [N]\n0,0.0,12.5\n0,0.01,13.0\n")  # measured: rik's own format
    before = tree(tmp_path)
    probe = ("variants", "probe", BOW, "--dir", str(bow_variants), "--stroke", "4", "--speed", "20")
    res = rik(*probe, "--csv", str(fridge))
    assert res.code == 2 and res.out == ""  # refused before the pull
    assert one_line(res.err) == (f"rik: error: {fridge}: exists and is not a file rik wrote there before (rik keeps a "
                                 "record of the files it writes where you say), so nothing was written: choose "
                                 "another path, or move it away yourself")
    assert tree(tmp_path) == before
    mine = tmp_path / "results" / "pull.csv"  # in a folder that is not there yet (was a traceback after the pull)
    assert rik(*probe, "--csv", str(mine)).code == 0
    first = mine.read_text()
    assert rik(*probe, "--csv", str(mine)).code == 0 and mine.read_text() == first  # its own: replaced
    mine.write_text(first + "0,0.5,1.0\n")  # edited by a person: no longer rik's
    assert rik(*probe, "--csv", str(mine)).code == 2 and mine.read_text().endswith("0,0.5,1.0\n")
    res = rik(*probe, "--csv", str(fridge / "x.csv"))  # below a file: before the pull too
    assert res.code == 2 and res.out == "" and "is not a folder" in one_line(res.err)


def test_simulate_keeps_a_measured_csv_beside_simulated_trials(rik, tmp_path: Path) -> None:
    """A measured CSV with rik's header (the documented format of measured trials) beside simulated trials was
    taken as rik's and deleted by the next ``rik sysid simulate --out``."""
    data = tmp_path / "data"
    assert rik("sysid", "simulate", "--out", str(data), "--trials", "2", "--duration", "1").code == 0
    measured = data / "measured.csv"
    measured.write_bytes(sorted(data.glob("*.csv"))[0].read_bytes())  # a person's trial: rik's header and format
    before = tree(tmp_path)
    res = rik("sysid", "simulate", "--out", str(data), "--trials", "2", "--duration", "1", "--seed", "1")
    assert res.code == 2
    assert f"{data}: exists and is not a folder of trials rik sysid simulate wrote" in one_line(res.err)
    assert tree(tmp_path) == before
    measured.unlink()
    assert rik("sysid", "simulate", "--out", str(data), "--trials", "2", "--duration", "1", "--seed", "1").code == 0


def test_a_file_deep_in_a_variant_or_a_stream_stops_its_replacement(rik, bow_variants: Path, tmp_path: Path) -> None:
    """Only a folder's top-level names were checked: ``rik variants build`` over a variant folder deleted the
    user's file in its ``meshes/``, and a stream's camera folders were checked the same way."""
    import shutil

    from shared import BOW

    from rik.errors import RikError
    from rik.outputs import check_replaceable
    from rik.render.streams import MANIFEST, STREAM_FOLDER

    out = tmp_path / "variants"
    shutil.copytree(bow_variants, out)
    notes = out / BOW / "meshes" / "notes.txt"
    notes.write_text("my measurements of the handle")
    before = tree(out)
    res = rik("variants", "build", BOW, "--out", str(out), "--force")
    assert res.code == 2 and f"{out / BOW}: exists and is not a variant rik built" in one_line(res.err)
    assert tree(out) == before
    notes.unlink()
    assert rik("variants", "build", BOW, "--out", str(out), "--force").code == 0  # rik's own: rebuilt

    stream = tmp_path / "renders" / "ep" / "sim-16x16-shadow512-msaa4"
    (stream / "front").mkdir(parents=True)
    (stream / "front" / "000000.png").write_bytes(b"png")
    (stream / MANIFEST).write_text('{"cameras": ["front"]}')
    check_replaceable(stream, STREAM_FOLDER)  # rik's: may be replaced
    (stream / "front" / "notes.txt").write_text("mine")
    with pytest.raises(RikError, match="exists and is not an image stream rik rendered"):
        check_replaceable(stream, STREAM_FOLDER)


def test_export_keeps_a_users_file_named_like_a_lock(rik, knob_recording: Path, tmp_path: Path) -> None:
    """``rik export-lerobot ... --out data`` deleted a user's ``data.lock`` beside it (rik's lock took that name);
    a file of the user's at rik's own lock name is refused, not emptied."""
    args = ("export-lerobot", str(knob_recording / "episodes"), "--repo-id", "local/x", "--streams", "none",
            "--variants", str(knob_recording / "variants"))
    (tmp_path / "data.lock").write_text("my lab's booking of the robot\n")
    assert rik(*args, "--out", str(tmp_path / "data")).code == 0
    assert (tmp_path / "data.lock").read_text() == "my lab's booking of the robot\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "data.lock"]  # rik's own lock is gone again
    (tmp_path / ".other.rik-lock").write_text("not a lock\n")
    res = rik(*args, "--out", str(tmp_path / "other"))
    assert res.code == 2 and "is not a lock file of rik's" in one_line(res.err)
    assert (tmp_path / ".other.rik-lock").read_text() == "not a lock\n" and not (tmp_path / "other").exists()


def test_export_into_a_dangling_link_is_refused_before_the_work(rik, knob_recording: Path, tmp_path: Path) -> None:
    """``--out LINK`` with a dangling symbolic link ran the whole export, then failed and left ``LINK.partial``."""
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "nowhere")
    res = rik("export-lerobot", str(knob_recording / "episodes"), "--repo-id", "local/x", "--streams", "none",
              "--variants", str(knob_recording / "variants"), "--out", str(link))
    assert res.code == 2 and f"{link}: is a symbolic link" in one_line(res.err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link"] and os.readlink(link) == str(tmp_path / "nowhere")


def _run_all(scripts: list[str], cwd: Path, timeout: float = 240, args: tuple[list[str], ...] = ()
             ) -> list[subprocess.CompletedProcess]:
    """Start every Python script at once (real concurrent processes; ``args[i]``: the i-th one's arguments) and wait
    for all of them."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "tests"), str(ROOT)])}  # this test's rik
    procs = [subprocess.Popen([sys.executable, "-c", s, *(args[i] if args else [])], cwd=cwd, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i, s in enumerate(scripts)]
    done = []
    for p in procs:
        out, err = p.communicate(timeout=timeout)
        done.append(subprocess.CompletedProcess(p.args, p.returncode, out, err))
    return done


def test_two_stations_on_one_folder_save_two_episodes(bow_variants: Path, tmp_path: Path) -> None:
    """Two teleop sessions (``rik teleop V --web --out eps`` twice) both started at ``...__browser__s0000``; the
    second Save replaced the first episode and both said "saved". Two processes record and save at once here."""
    station = textwrap.dedent(f"""
        import time
        from pathlib import Path
        from shared import BOW
        from rik.sim.build import build_scene
        from rik.teleop.session import TeleopSession
        out = Path({str(tmp_path / "eps")!r})
        s = TeleopSession(build_scene(Path({str(bow_variants)!r}) / BOW), out, operator="browser")
        s.set_input([0, -1, 0, 0, 0, 0])
        for _ in range(6):
            s.tick()
        Path({str(tmp_path)!r}, f"ready-{{s.episode}}-{{id(s)}}").touch()
        while len(list(Path({str(tmp_path)!r}).glob("ready-*"))) < 2:  # both have recorded: save together
            time.sleep(0.01)
        print(s.save().path.name)
    """)
    a, b = _run_all([station, station], tmp_path)
    assert a.returncode == 0 and b.returncode == 0, (a.stderr, b.stderr)
    names = {a.stdout.split()[-1], b.stdout.split()[-1]}
    assert len(names) == 2, names  # two episodes, neither written over
    assert sorted(p.name for p in (tmp_path / "eps").iterdir()) == sorted(names)
    assert all(n.endswith(("__s0000", "__s0001")) for n in names)


def test_two_writers_of_one_folder_each_stage_their_own(tmp_path: Path) -> None:
    """Two processes inside ``staged_directory`` for the same folder at once (what two ``rik sysid fit --report
    rep`` do): they shared one staging folder, so the second removed the first's files under it; now each stages
    its own, both finish, and the folder is one writer's whole."""
    writer = textwrap.dedent(f"""
        import os, sys, time
        from pathlib import Path
        try:
            from rik.outputs import MadeFolder, staged_directory
        except ImportError:  # before rik.outputs
            from rik.paths import MadeFolder, staged_directory
        root = Path({str(tmp_path)!r})
        kind = MadeFolder("a report", lambda d: (d / "who").is_file())
        with staged_directory(root / "rep", kind) as stage:
            (stage / "who").write_text(sys.argv[1])
            (root / f"inside-{{sys.argv[1]}}").touch()
            while len(list(root.glob("inside-*"))) < 2:  # both are writing their stage now
                time.sleep(0.01)
            (stage / "plot").write_text(sys.argv[1])
    """)
    a, b = _run_all([writer, writer], tmp_path, args=(["a"], ["b"]))
    assert a.returncode == 0 and b.returncode == 0, (a.stderr, b.stderr)
    who = (tmp_path / "rep" / "who").read_text()
    assert who in "ab" and (tmp_path / "rep" / "plot").read_text() == who  # one writer's, whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["inside-a", "inside-b", "rep"]  # no stage left


@pytest.mark.slow  # two fits in two processes, 11 s: the primitive is tested above
def test_two_fits_into_one_report_never_mix(rik, tmp_path: Path) -> None:
    """Two concurrent ``rik sysid fit --report rep`` of the same trials: both finish, and the report is whole."""
    import json

    assert rik("sysid", "simulate", "--effect", "soft_close", "--out", str(tmp_path / "a"), "--trials", "3",
               "--duration", "4").code == 0
    fit = ("import sys; sys.argv = ['rik', 'sysid', 'fit', *sorted(__import__('glob').glob({data!r})), '--report', "
           f"{str(tmp_path / 'rep')!r}]\nfrom rik.cli.app import main\nmain()")
    runs = _run_all([fit.format(data=str(tmp_path / "a" / "*.csv"))] * 2, tmp_path)
    assert [r.returncode for r in runs] == [0, 0], [r.stderr for r in runs]
    summary = json.loads((tmp_path / "rep" / "summary.json").read_text())
    assert f"**{summary['cause']}**" in (tmp_path / "rep" / "report.md").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "rep"]  # no staging folder left


def test_asset_tables_keep_a_users_file_and_refuse_before_the_work(rik, tmp_path: Path) -> None:
    """``rik assets stats --out FILE`` and ``rik assets fidelity --out DIR`` write CSV tables: a file of the user's
    at that path (not a table with rik's columns) is refused before any asset is built, and kept."""
    mine = tmp_path / "my.csv"
    mine.write_text("handle,my grip test\nknob/mushroom-30,ok\n")
    (tmp_path / "fidelity.csv").write_bytes(mine.read_bytes())
    before = tree(tmp_path)
    for args in (("stats", "knob/mushroom-30", "--out", str(mine)),
                 ("fidelity", "knob/mushroom-30", "--out", str(tmp_path))):
        res = rik("assets", *args)
        assert res.code == 2 and res.out == "" and "exists and is not a table of rik's" in one_line(res.err), args
    assert tree(tmp_path) == before
