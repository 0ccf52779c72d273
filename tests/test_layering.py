"""rik's architecture as data: its packages on floors, each importing only from floors below it, read from the source
(ast) of ``rik/`` and of the distributions in ``packages/`` (the LeRobot plugin ``lerobot_env_rik``, the top floor).
Every import counts: at module level, inside functions and in ``if TYPE_CHECKING:`` blocks. The table
(:data:`FLOORS`) is also what ``docs/architecture.md`` is generated from (``python tests/test_layering.py``), and a
test keeps that page equal to it."""

from __future__ import annotations

import ast
import functools
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

import rik

PACKAGE = Path(rik.__file__).parent
ROOT = PACKAGE.parent
DOC = ROOT / "docs" / "architecture.md"
PLUGIN_ROOTS = tuple(sorted(init.parent.parent for init in (ROOT / "packages").glob("*/*/__init__.py")))
"""The import roots of the distributions in ``packages/`` (``packages/lerobot_env_rik``)."""

FLOORS: tuple[tuple[tuple[str, str], ...], ...] = (
    (("rik", "The root: rik's version and the catalog format's; imports nothing."),),
    (("rik.errors", "`RikError` and its kinds: the one-line messages every command ends with."),),
    (("rik.paths", "Paths: the cache folder, paths kept inside their folder, bounded JSON reads."),
     ("rik.locks", "Cross-process file locks (content-addressed caches, shared folders)."),
     ("rik.scheduling", "Threads kept at normal scheduling where a library raises them to real time (SVT-AV1)."),
     ("rik.schemas", "pydantic models of everything rik reads: catalog entries, episodes, dataset specs, "
                     "measured trajectories. SI units.")),
    (("rik.joints", "Joint mechanisms and resistance laws: MJCF for MuJoCo's own, runtime effects for the rest."),
     ("rik.outputs", "The output contract: every file and folder rik writes, replaces or removes goes through it "
                     "(exclusive names, only what rik made is replaced, checked before the work).")),
    (("rik.registry", "The catalog: YAML files loaded, validated and indexed; ids, splits, the fit test, "
                      "CATALOG.md."),),
    (("rik.workers", "The process pool every batch command runs on: workers that load the catalog once and die "
                     "with their parent."),),
    (("rik.assets", "Meshes of handles and base units, CoACD collision (cached), the collision-fidelity metric."),
     ("rik.sysid", "Model discovery from measured trajectories: trials, fits, effects, reports, presets; "
                   "synthetic measurements.")),
    (("rik.combinator", "Variants: base unit x handle x preset placed, checked by name and written as MJCF."),),
    (("rik.sim", "The simulated scene (scene, build, pose, grasp, probe, observation, outcome), the quasi-static "
                 "pull through a handle (pull) and the robots (sim/robots: gripper, arm, ik, drive, reach, checks, "
                 "layout)."),),
    (("rik.episodes", "Episodes: scripted strategies, the recorder, the format on disk, exact replay, the seeded "
                      "draw."),),
    (("rik.tables", "The outcome tables `rik bench` and `rik eval` both write (Table 3, Wilson intervals, CSV)."),),
    (("rik.render", "Images of episodes: MuJoCo and Mitsuba streams, alignment, visual-gap metrics."),
     ("rik.teleop", "Teleoperation: sessions, the keymap, the desktop viewer, the browser station."),
     ("rik.benchmark", "The paper's resistance benchmark (`rik bench`): F/P/S per handle type, strategy, "
                       "preset.")),
    (("rik.lerobot", "rik's contract with LeRobot: feature keys and layouts, the `PolicyIO` a dataset, a policy "
                     "folder and an evaluation share (written, carried, read; guessed only for older policies), "
                     "what a policy folder may hold, the `--env.type=rik` config, the training hook."),),
    (("rik.envs", "The gymnasium environment rik/OpenFront-v0 that LeRobot and `rik eval` run policies in."),
     ("rik.exporters", "LeRobot v3.0 export: frames, features, the card, the check of a finished export."),
     ("rik.web", "The web app (`rik serve`): the catalog pages (with a 3D view), the teleop station and the page "
                 "of episodes and datasets, behind a launch-token gate.")),
    (("rik.evaluation", "Policies on the benchmark (`rik eval`): a saved LeRobot policy checked, loaded and run."),),
    (("rik.dataset", "`rik dataset build`: a spec planned into units, run locally or on Ray, merged, verified."),
     ("rik.demo", "`rik demo`'s stages, each doing its work and returning what it made (the CLI prints it).")),
    (("rik.cli", "The `rik` command (typer + rich): parses and prints, the library does the work."),),
    (("rik.__main__", "`python -m rik`."),),
    (("lerobot_env_rik", "The LeRobot plugin: a shim that LeRobot imports at start-up; it registers rik's env "
                         "config, its environment and the training hook."),),
)
"""rik's packages from the bottom floor up, each with its job. A module may import its own package and the packages
of lower floors, never a package of its own floor or of one above."""

FORBIDDEN = {
    "rik.sysid.synthetic.foreign": ("rik.joints", "rik.sim", "rik.combinator", "rik.sysid.effects",
                                    "rik.sysid.synthetic.generate"),
    **{p: ("rik.envs",) for p in ("rik.dataset", "rik.evaluation")},
}
"""Rules finer than the floors: the foreign generator of measured data writes its laws independently of rik's, and the
gymnasium environment stays out of the dataset build and ``rik eval`` (they take observations from
:mod:`rik.sim.observation`, so that none of them imports gymnasium's registration of the env)."""

ONLY = {"lerobot_env_rik": ("rik.envs", "rik.lerobot")}
"""Packages that may import only these of rik: the plugin, which LeRobot imports in every one of its commands, reaches
rik's environment and its LeRobot contract, nothing that imports it back (``rik.evaluation`` imports the contract)."""

HEAVY = ("numpy", "scipy", "mujoco", "torch", "lerobot", "mitsuba", "drjit", "coacd", "trimesh", "pyarrow", "pandas",
         "PIL", "cv2", "av", "imageio", "ray", "fastapi", "starlette", "uvicorn", "matplotlib", "gymnasium", "pydantic",
         "yaml", "manifold3d", "skimage", "sklearn", "glfw", "playwright", "huggingface_hub", "datasets")
"""Libraries that take long to import: a module may import a module of its own package inside a function (rather
than at its top) only when that module brings one of these that the importer does not already load."""


def floor_of() -> dict[str, int]:
    """Package -> floor number (0: the bottom)."""
    return {package: i for i, floor in enumerate(FLOORS) for package, _ in floor}


def _module(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def source_files(root: Path = ROOT) -> list[tuple[Path, str]]:
    """(file, module) of every module of ``rik/`` and of the distributions in ``packages/`` under ``root`` (a
    checkout, or an old tree from ``git archive``)."""
    plugins = sorted(init.parent.parent for init in (root / "packages").glob("*/*/__init__.py"))
    return [(p, _module(p, base)) for base, folder in ((root, root / "rik"), *((d, d) for d in plugins))
            for p in sorted(folder.rglob("*.py"))]


MODULE_FILES = {module: path for path, module in source_files()}
"""Every module of rik and of its plugin -> its file."""
OURS = frozenset(m.split(".")[0] for m in MODULE_FILES)
"""The top-level names of rik's modules: ``rik`` and the plugin's."""


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The parsed source of ``path`` (parsed once per test run)."""
    return ast.parse(path.read_text(encoding="utf-8"))


@functools.cache
def _in_functions(tree: ast.Module) -> frozenset[int]:
    """ids of the nodes inside function bodies (they run when the function is called, not when the module loads)."""
    return frozenset(id(n) for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                     for n in ast.walk(f))


def _type_only(tree: ast.AST) -> set[int]:
    """ids of the nodes inside ``if TYPE_CHECKING:`` blocks."""
    return {id(x) for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
            for sub in node.body for x in ast.walk(sub)}


def _resolve(name: str) -> str:
    """The rik module a dotted name lives in (``rik.sim.scene.SimScene`` -> ``rik.sim.scene``)."""
    while name and name not in MODULE_FILES:
        name = name.rpartition(".")[0]
    return name


def _imports(path: Path, module: str | None = None, *, types: bool = True, where: str = "all") -> set[str]:
    """Absolute names of the rik modules that ``path`` imports, relative imports resolved (``from pkg import sub``
    names ``pkg.sub``); ``module``: the file's module name (default: from its place in the package); ``types``: also
    imports under ``TYPE_CHECKING``; ``where``: ``all``, ``top`` (module level) or ``function`` imports."""
    module = module or _module(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    tree = _tree(path)
    skip = set() if types else _type_only(tree)
    in_functions = _in_functions(tree)
    nodes = [n for n in ast.walk(tree) if where == "all" or (id(n) in in_functions) == (where == "function")]
    found = set()
    for node in nodes:
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            base = base[:len(base) - node.level + 1] if node.level else []
            name = ".".join([*base, node.module] if node.module else base)
            subs = {f"{name}.{a.name}" for a in node.names}
            found.update(subs)
            if not subs <= set(MODULE_FILES):
                found.add(name)
    return {n for n in found if n.split(".")[0] in OURS}


def _top(name: str) -> str:
    """The package of a module on the floors: ``rik.sim.robots.drive`` -> ``rik.sim``, ``rik.errors`` -> itself, a
    plugin's module -> the plugin (``lerobot_env_rik``)."""
    parts = name.split(".")
    return ".".join(parts[:2]) if parts[0] == "rik" else parts[0]


def _breaches(rules: dict[str, tuple[str, ...]], files: list[tuple[Path, str]] | None = None) -> list[str]:
    """``<module> imports <name>`` for every import that breaks ``rules`` (module or package -> what it must not
    import), in ``files`` ((path, module) pairs; default: all of rik)."""
    out = []
    for path, module in files or [(p, m) for m, p in MODULE_FILES.items()]:
        for package, forbidden in rules.items():
            if module == package or module.startswith(package + "."):
                out += [f"{module} imports {n}" for n in sorted(_imports(path, module))
                        if any(n == f or n.startswith(f + ".") for f in forbidden)]
    return out


def floor_breaches(files: list[tuple[Path, str]] | None = None) -> list[str]:
    """``<module> (floor i) imports <name> (floor j)`` for every import of a package on the same floor or above."""
    floors = floor_of()
    out = []
    for path, module in files or [(p, m) for m, p in MODULE_FILES.items()]:
        own = _top(module)
        for name in sorted(_imports(path, module)):
            other = _top(name)
            if other != own and other in floors and own in floors and floors[other] >= floors[own]:
                out.append(f"{module} (floor {floors[own]}) imports {name} (floor {floors[other]})")
    return out


def only_breaches(files: list[tuple[Path, str]] | None = None) -> list[str]:
    """``<module> imports <name>`` for every import of rik by a package of :data:`ONLY` that is not one it may make."""
    out = []
    for path, module in files or [(p, m) for m, p in MODULE_FILES.items()]:
        allowed = ONLY.get(_top(module))
        if allowed is not None:
            out += [f"{module} imports {n}" for n in sorted(_imports(path, module))
                    if _top(n) != _top(module) and _top(n) not in allowed]
    return out


def package_graph(files: list[tuple[Path, str]] | None = None) -> dict[str, set[str]]:
    """Package on the floors -> the others it imports (every import counts)."""
    edges: dict[str, set[str]] = defaultdict(set)
    for path, module in files or [(p, m) for m, p in MODULE_FILES.items()]:
        edges[_top(module)] |= {_top(n) for n in _imports(path, module) if _top(n) != _top(module)}
    return dict(edges)


def module_graph(*, types: bool = True) -> dict[str, set[str]]:
    """Module -> the rik modules it imports (``types``: also under TYPE_CHECKING)."""
    return {m: {r for n in _imports(p, m, types=types) if (r := _resolve(n)) and r != m}
            for m, p in MODULE_FILES.items()}


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def _heavy_at_import(module: str, seen: dict[str, set[str]]) -> set[str]:
    """The heavy libraries (:data:`HEAVY`) that importing ``module`` loads: its own top-level imports and those of
    the rik modules it imports at top level."""
    if module in seen:
        return seen[module]
    seen[module] = set()
    path = MODULE_FILES[module]
    tree = _tree(path)
    skip = _type_only(tree) | _in_functions(tree)
    heavy: set[str] = set()
    for node in tree.body:
        for sub in ast.walk(node):
            if id(sub) in skip:
                continue
            names = ([a.name for a in sub.names] if isinstance(sub, ast.Import) else
                     [sub.module or ""] if isinstance(sub, ast.ImportFrom) and sub.level == 0 else [])
            heavy.update(n.split(".")[0] for n in names if n.split(".")[0] in HEAVY)
    for name in _imports(path, module, types=False, where="top"):
        target = _resolve(name)
        if target and target != module:
            heavy |= _heavy_at_import(target, seen)
    seen[module] = heavy
    return heavy


def lazy_sibling_imports() -> list[str]:
    """``<module> imports <sibling> inside a function`` for each import of a module of the same package inside a
    function where that module loads no heavy library the importer does not already load."""
    seen: dict[str, set[str]] = {}
    out = []
    for module, path in MODULE_FILES.items():
        own = _top(module)
        mine = _heavy_at_import(module, seen)
        for name in sorted(_imports(path, module, types=False, where="function")):
            target = _resolve(name)
            if target and target != module and _top(target) == own and not _heavy_at_import(target, seen) - mine:
                out.append(f"{module} imports {target} inside a function")
    return sorted(set(out))


# ---- the tests ----------------------------------------------------------------------------------------------------
def test_every_package_is_on_one_floor() -> None:
    placed = [package for floor in FLOORS for package, _ in floor]
    assert len(placed) == len(set(placed))
    assert set(placed) == {_top(m) for m in MODULE_FILES}


def test_every_import_runs_down_the_floors() -> None:
    assert floor_breaches() == []


def test_the_finer_rules_hold() -> None:
    assert _breaches(FORBIDDEN) == []


def test_the_plugin_imports_only_the_env_and_the_contract() -> None:
    assert only_breaches() == []


def test_no_package_imports_another_that_imports_it_back() -> None:
    assert circles(package_graph()) == []


def test_no_module_imports_another_that_imports_it_back() -> None:
    """No circle between rik's modules, counting every import (also inside functions and under TYPE_CHECKING)."""
    assert circles(module_graph()) == []


def test_modules_of_one_package_import_each_other_at_the_top() -> None:
    """A function-level import of a module of the same package hides a circle, unless the module loads a heavy
    library (:data:`HEAVY`) that the importer does not."""
    assert lazy_sibling_imports() == []


def test_the_architecture_page_is_the_table() -> None:
    assert DOC.read_text(encoding="utf-8") == architecture_page(), "run: uv run python tests/test_layering.py"


def test_the_readme_layout_names_every_package() -> None:
    """The README's layout table lists every package of the floors (its folder), and no folder that is gone."""
    text = (PACKAGE.parent / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Layout"):]
    section = section[:section.index("\n## ", 4)]
    listed = {f.rstrip("/") for f in re.findall(r"^\| `(rik/[a-z_/]+)` \|", section, re.M)}
    folders = {p.replace(".", "/") for floor in FLOORS for p, _ in floor if (PACKAGE.parent / p.replace(".", "/")).is_dir()}
    assert folders - {"rik"} <= listed
    assert all((PACKAGE.parent / f).is_dir() for f in listed)


# ---- the checker itself -------------------------------------------------------------------------------------------
def test_the_floors_catch_what_main_had_before_the_layering(tmp_path: Path) -> None:
    """The two arrows that ran up the floors before this table existed: the gym env imported the renderer (from
    ``rik.sim``), and the catalog's checks imported the variant-id grammar from the combinator."""
    env = tmp_path / "env.py"
    env.write_text("def make():\n    from rik.render.renderers import make_renderer\n", encoding="utf-8")
    checks = tmp_path / "checks.py"
    checks.write_text("from rik.combinator.ids import variant_id\n", encoding="utf-8")
    found = floor_breaches([(env, "rik.sim.env"), (checks, "rik.registry.checks")])
    floors = floor_of()
    assert f"rik.sim.env (floor {floors['rik.sim']}) imports rik.render.renderers (floor {floors['rik.render']})" in found
    assert (f"rik.registry.checks (floor {floors['rik.registry']}) imports rik.combinator.ids "
            f"(floor {floors['rik.combinator']})") in found


def test_the_rules_see_imports_in_functions_and_type_checking_blocks(tmp_path: Path) -> None:
    """A lazy import inside a function and one under TYPE_CHECKING both count."""
    source = tmp_path / "probe.py"
    source.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from rik.sim.scene import SimScene\n"
                      "def f():\n    import rik.sysid.fit\n    from rik import combinator\n", encoding="utf-8")
    found = _imports(source, module="rik.joints.probe")
    assert {"rik.sim.scene", "rik.sysid.fit", "rik.combinator"} <= found
    assert _breaches({"rik.joints": ("rik.sim",)}, [(source, "rik.joints.probe")]) == [
        "rik.joints.probe imports rik.sim.scene", "rik.joints.probe imports rik.sim.scene.SimScene"]
    assert "rik.sim.scene" not in _imports(source, module="rik.joints.probe", types=False)


def test_a_function_level_import_is_not_an_import_at_load(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The heavy-library check reads only what runs when a module loads: an import inside a function is not."""
    lazy = tmp_path / "lazy.py"
    lazy.write_text("import json\ndef f():\n    import numpy\n", encoding="utf-8")
    eager = tmp_path / "eager.py"
    eager.write_text("import numpy\n", encoding="utf-8")
    monkeypatch.setitem(MODULE_FILES, "rik.probe_lazy", lazy)
    monkeypatch.setitem(MODULE_FILES, "rik.probe_eager", eager)
    assert _heavy_at_import("rik.probe_lazy", {}) == set()
    assert _heavy_at_import("rik.probe_eager", {}) == {"numpy"}


def test_the_scan_catches_the_cycle_between_evaluation_and_the_plugin_of_c210781(tmp_path: Path) -> None:
    """On c210781 ``rik.evaluation.evaluate`` imported the plugin inside a function and the plugin imported
    ``rik.evaluation.load`` inside another: a cycle the scan of ``rik/`` alone could not see. The scan of ``rik/`` and
    ``packages/`` names both arrows and the cycle; run only where git has that commit (a shallow clone may not)."""
    git = subprocess.run(["git", "-C", str(ROOT), "cat-file", "-e", "c210781^{commit}"], capture_output=True)
    if git.returncode != 0:
        pytest.skip("commit c210781 is not in this clone")
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "c210781", "rik", "packages"], capture_output=True,
                             check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp_path)], input=archive, check=True)
    old = source_files(tmp_path)
    floors = floor_of()
    assert (f"rik.evaluation.evaluate (floor {floors['rik.evaluation']}) imports lerobot_env_rik "
            f"(floor {floors['lerobot_env_rik']})") in floor_breaches(old)
    assert "lerobot_env_rik imports rik.evaluation.load" in only_breaches(old)
    assert ["lerobot_env_rik", "rik.evaluation"] in circles(package_graph(old))


def test_the_plugins_arrows_are_found(tmp_path: Path) -> None:
    """The same two arrows without git: the evaluation importing the plugin in a function runs up the floors, and the
    plugin importing anything but the env and the contract is named."""
    evaluate = tmp_path / "evaluate.py"
    evaluate.write_text("def env_config():\n    import lerobot_env_rik\n", encoding="utf-8")
    plugin = tmp_path / "__init__.py"
    plugin.write_text("import rik.envs.open_front\ndef _fit():\n    import rik.evaluation.load\n", encoding="utf-8")
    files = [(evaluate, "rik.evaluation.evaluate"), (plugin, "lerobot_env_rik")]
    floors = floor_of()
    assert floor_breaches(files) == [f"rik.evaluation.evaluate (floor {floors['rik.evaluation']}) imports "
                                     f"lerobot_env_rik (floor {floors['lerobot_env_rik']})"]
    assert only_breaches(files) == ["lerobot_env_rik imports rik.evaluation.load"]
    assert circles(package_graph(files)) == [["lerobot_env_rik", "rik.evaluation"]]


def test_circles_are_found_through_several_modules() -> None:
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert circles(edges) == [["a", "b", "c"]]


# ---- docs/architecture.md -----------------------------------------------------------------------------------------
def architecture_page() -> str:
    """docs/architecture.md, from :data:`FLOORS` and the imports as they are."""
    floors = floor_of()
    uses: dict[str, set[str]] = defaultdict(set)
    for module, path in MODULE_FILES.items():
        for name in _imports(path, module):
            if _top(name) != _top(module) and _top(name) in floors:
                uses[_top(module)].add(_top(name))
    lines = ["# rik's architecture", "",
             "<!-- generated from tests/test_layering.py (FLOORS): `uv run python tests/test_layering.py`; "
             "a test fails when it is stale -->", "",
             "rik's packages stand on floors. A module imports its own package and packages of lower floors only: "
             "never one of its own floor or above, and no module imports another that imports it back (every "
             "import counts, also inside functions and under `TYPE_CHECKING`). `tests/test_layering.py` holds the "
             "table and fails on any import against it.", "",
             "The scan covers `rik/` and the distributions in `packages/`: the LeRobot plugin `lerobot_env_rik` "
             "stands on the top floor and may import only rik's environment and its LeRobot contract "
             "(`rik/envs/`, `rik/lerobot/`).", "",
             "Where to look: robots in `rik/sim/robots/`, episodes in `rik/episodes/`, teleoperation in "
             "`rik/teleop/`, the benchmark in `rik/benchmark/`, rik's contract with LeRobot in `rik/lerobot/`, "
             "evaluation of policies in `rik/evaluation/`.", "",
             "| floor | package | job | imports (today) |", "|---|---|---|---|"]
    for i in reversed(range(len(FLOORS))):
        for package, job in FLOORS[i]:
            used = ", ".join(f"`{u}`" for u in sorted(uses[package], key=lambda u: (-floors[u], u))) or "nothing"
            folder = package.replace(".", "/") + ("" if package == "rik.__main__" else "/")
            shown = folder if (ROOT / folder).is_dir() else package.replace(".", "/") + ".py"
            if package.split(".")[0] not in ("rik",):  # a plugin: its distribution's folder
                shown = MODULE_FILES[package].parent.parent.relative_to(ROOT).as_posix() + "/"
            lines.append(f"| {i} | `{shown}` | {job} | {used} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    DOC.write_text(architecture_page(), encoding="utf-8")
    print(f"wrote {DOC}", file=sys.stderr)
