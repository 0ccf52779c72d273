"""Robots when they are used: what the catalog cannot check when it loads (it stays as fast as a plain pydantic
program, and a robot nobody uses may name a package this machine lacks), checked once a command asks for a robot.

An arm's model comes from an installed Python package (never downloaded). Such a package that is missing, or
that lacks the entry's files, or whose files lead out of it (a symbolic link; the schema already refuses absolute
paths and ``..``), is a one-line :class:`rik.errors.CatalogError` naming the catalog file and line, the entry and
the field (``model.package``, ``model.files.N``), as the loader's own errors do.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING

from rik.errors import CatalogError
from rik.registry.sources import BUILTIN_DIR, NOUNS, display_path, read_file

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.schemas.robots import Robot


def installed_package_dir(name: str) -> Path | None:
    """The folder of the installed package importable as ``name``, found without importing it (the packages'
    own code pulls in dependencies rik does not install); None when it is not installed."""
    if not name.isidentifier():  # a dotted name imports its parent package (its code runs) to look inside it
        return None
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):  # a dotted name whose parent is missing; an empty or relative name
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def outside_package(folder: Path, file: str) -> Path | None:
    """Where ``folder / file`` leads (symbolic links followed) when that is outside ``folder``; None when it
    stays inside. A catalog's model file must be its package's own."""
    real = (folder / file).resolve()
    return None if real.is_relative_to(folder.resolve()) else real


def entry_error(catalog: Catalog, section: str, entry_id: str, field: str | None, problem: str) -> CatalogError:
    """A :class:`CatalogError` for an entry of a loaded catalog, naming its file, line, entry and field (the file
    is read again to find them: only done when reporting)."""
    origin = catalog.origins.get((section, entry_id))
    if origin is None:
        return CatalogError("(catalog)", f"{NOUNS[section]} '{entry_id}'", field, problem)
    try:
        entries = read_file(Path(origin.file), origin.builtin)
    except CatalogError:  # the file changed since it was loaded
        entries = []
    for entry in entries:
        if entry.section == section and isinstance(entry.data, dict) and entry.data.get("id") == entry_id:
            return entry.error(field, problem)
    return CatalogError(display_path(Path(origin.file)), f"{NOUNS[section]} '{entry_id}'", field, problem)


def usable_robot(catalog: Catalog, robot_id: str) -> Robot:
    """The robot ``robot_id`` (:class:`rik.errors.UnknownIdError` with suggestions when absent), its model's
    package installed and holding the model's files."""
    robot = catalog.robot(robot_id)
    name = robot.model.package
    if name is None:
        return robot
    folder = installed_package_dir(name)
    builtin = catalog.origins[("robots", robot.id)].builtin if ("robots", robot.id) in catalog.origins else True
    if folder is None:
        remedy = "run scripts/setup.sh, or uv sync" if builtin else "install the distribution that ships it"
        raise entry_error(catalog, "robots", robot.id, "model.package",
                          f"the Python package '{name}' that ships the model is not installed ({remedy})")
    for i, file in enumerate(robot.model.files):
        if (real := outside_package(folder, file)) is not None:
            raise entry_error(catalog, "robots", robot.id, f"model.files.{i}",
                              f"'{file}' leads to {real}, outside the installed package '{name}' ({folder}): a "
                              "model file must be the package's own")
        if not (folder / file).is_file():
            raise entry_error(catalog, "robots", robot.id, f"model.files.{i}",
                              f"'{file}' is not in the installed package '{name}' ({folder})")
    return robot


@functools.cache
def builtin_robot(robot_id: str) -> Robot:
    """A robot of the built-in catalog, read from its own file (``rik/registry/data/robots.yaml``) and validated
    alone: what code that needs one robot's figures reads (the Hand-E's live only there)."""
    from rik.registry.entries import parse_entry
    from rik.schemas.robots import Robot

    for entry in read_file(BUILTIN_DIR / "robots.yaml", builtin=True):
        if entry.section == "robots" and isinstance(entry.data, dict) and entry.data.get("id") == robot_id:
            robot = parse_entry(entry)
            assert isinstance(robot, Robot)
            return robot
    raise CatalogError("rik/registry/data/robots.yaml", f"robots '{robot_id}'", None, "no such built-in robot")
