"""Import rules between rik's packages, read from the source (ast): every import counts, also those inside
functions and ``if TYPE_CHECKING:`` blocks."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import rik

PACKAGE = Path(rik.__file__).parent

FORBIDDEN = {
    "rik.joints": ("rik.sim", "rik.combinator", "rik.sysid"),
    "rik.combinator": ("rik.sim",),
    "rik.sysid.synthetic.foreign": ("rik.joints", "rik.sim", "rik.combinator", "rik.sysid.effects",
                                    "rik.sysid.synthetic.generate"),
    **{m: ("rik.sim.env",) for m in ("rik.exporters", "rik.dataset", "rik.render", "rik.web", "rik.sim.operators",
                                     "rik.sim.record", "rik.sim.episode", "rik.sim.teleop")},
}
"""Package or module → packages and modules it must not import (joint effects sit below the combinator, the
simulator and sysid; the combinator below the simulator; the foreign generator writes its laws independently of
rik's; the gymnasium environment sits above the recorder, the operators, the exporters and the web app: they take
observations from :mod:`rik.sim.observation`, so that none of them imports gymnasium's registration of the env)."""


def _module(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, module: str | None = None) -> set[str]:
    """Absolute names of the rik modules (or names in them) that ``path`` imports, relative imports resolved;
    ``module``: the file's module name (default: from its place in the package)."""
    module = module or _module(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            base = base[:len(base) - node.level + 1] if node.level else []
            name = ".".join([*base, node.module] if node.module else base)
            found.add(name)
            found.update(f"{name}.{a.name}" for a in node.names)  # ``from rik import sim``
    return {n for n in found if n == "rik" or n.startswith("rik.")}


MODULES = {f"rik.{p.stem}" for p in PACKAGE.iterdir() if p.suffix == ".py" or (p / "__init__.py").exists()}
"""rik's top-level modules and packages (``rik.sim``, ``rik.errors``)."""


def _top(name: str) -> str:
    return ".".join(name.split(".")[:2])


def _graph() -> dict[str, set[str]]:
    """Top-level package (``rik.sim``) → the top-level packages its modules import."""
    edges: dict[str, set[str]] = defaultdict(set)
    for path in sorted(PACKAGE.rglob("*.py")):
        source = _top(_module(path))
        edges[source].update(t for t in map(_top, _imports(path)) if t in MODULES and t != source)
    return edges


def _breaches(rules: dict[str, tuple[str, ...]], files: list[tuple[Path, str]] | None = None) -> list[str]:
    """``<module> imports <name>`` for every import that breaks ``rules``, in ``files`` ((path, module) pairs;
    default: all of rik)."""
    out = []
    for path, module in files or [(p, _module(p)) for p in sorted(PACKAGE.rglob("*.py"))]:
        for package, forbidden in rules.items():
            if module == package or module.startswith(package + "."):
                out += [f"{module} imports {n}" for n in sorted(_imports(path, module))
                        if any(n == f or n.startswith(f + ".") for f in forbidden)]
    return out


def _reaches(edges: dict[str, set[str]], start: str) -> set[str]:
    seen: set[str] = set()
    todo = list(edges.get(start, ()))
    while todo:
        node = todo.pop()
        if node not in seen:
            seen.add(node)
            todo += edges.get(node, ())
    return seen


def test_the_import_rules_hold() -> None:
    assert _breaches(FORBIDDEN) == []


def test_joint_effects_are_in_no_package_cycle() -> None:
    edges = _graph()
    assert "rik.joints" in edges  # the package exists and imports something (rik.schemas)
    assert "rik.joints" not in _reaches(edges, "rik.joints")


def test_the_environment_is_in_no_module_cycle_of_the_simulator() -> None:
    """rik.sim.env imports the recorder; nothing the recorder imports may import the env back (the cycle env ->
    record -> operators -> env is cut)."""
    modules = {_module(p): p for p in sorted((PACKAGE / "sim").glob("*.py"))}
    edges = {m: {n for n in _imports(p) if n in modules and n != m} for m, p in modules.items()}
    assert "rik.sim.record" in edges["rik.sim.env"]
    assert "rik.sim.env" not in _reaches(edges, "rik.sim.env")


def test_the_rules_see_imports_in_functions_and_type_checking_blocks(tmp_path: Path) -> None:
    """The checker itself: a lazy import inside a function and one under TYPE_CHECKING both count."""
    source = tmp_path / "probe.py"
    source.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from rik.sim.scene import SimScene\n"
                      "def f():\n    import rik.sysid.fit\n    from rik import combinator\n", encoding="utf-8")
    found = _imports(source, module="rik.joints.probe")
    assert {"rik.sim.scene", "rik.sysid.fit", "rik.combinator"} <= found
    assert _breaches({"rik.joints": ("rik.sim",)}, [(source, "rik.joints.probe")]) == [
        "rik.joints.probe imports rik.sim.scene", "rik.joints.probe imports rik.sim.scene.SimScene"]
