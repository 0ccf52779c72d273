"""The ``rik`` command: one typer app; each command group lives in its own module."""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from rik.cli import assets, catalog, dataset, export, policy, render, rerender, serve, sim, sysid, variants
from rik.cli.common import CatalogOption, finite_floats, overlays, usage_line
from rik.errors import RikError, os_error_text


def _print_version(value: bool) -> None:
    """``--version``: print and exit while the options are parsed (eagerly), before a command is required."""
    if value:
        from rik import __version__

        print(f"rik {__version__}")
        raise typer.Exit()


def _root(version: bool = typer.Option(False, "--version", help="Print rik's version and exit.", is_eager=True,
                                       callback=_print_version)) -> None:
    """rik (Real-IKEA kit): articulated furniture for contact-rich robot manipulation."""


def _new_app() -> typer.Typer:
    """The root ``rik`` app with its own options and no command yet."""
    root = typer.Typer(
        name="rik",
        help="rik (Real-IKEA kit): articulated furniture for contact-rich robot manipulation.",
        no_args_is_help=True,
        pretty_exceptions_enable=False,
        add_completion=False,
    )
    root.callback()(_root)
    return root


app = _new_app()
app.add_typer(catalog.app, name="catalog")
app.add_typer(assets.app, name="assets")
app.add_typer(variants.app, name="variants")
app.add_typer(sysid.app, name="sysid")
app.add_typer(dataset.app, name="dataset")
for _command in (sim.record, sim.teleop, sim.replay, sim.bench, rerender.render, rerender.rerender,
                 render.visual_gap, export.export_lerobot):
    app.command()(_command)
app.command("eval")(policy.eval_policy)
app.command("robot-check")(sim.robot_check)
app.command("serve")(serve.serve)


@app.command()
def demo(res: Annotated[int, typer.Option("--res", min=25, max=1024, help="Image size of the rendered streams "
                                           "and the dataset's videos, px (square; 25 at least, the narrowest frame "
                                           "the dataset's AV1 encoder takes). 64 takes about half the time.")]
         = rerender.DEMO_RES,
         episodes: Annotated[int, typer.Option("--episodes", min=1, max=100, help="Scripted episodes to record, "
                                               "render and export (seeds 0, 1, ...).")] = 2,
         catalog_paths: CatalogOption = None) -> None:
    """The main job on built-in defaults: validate the catalog and print its summary, then build a sample of
    assets (one handle of each type and a chest of drawers), measure their collision fidelity and run the finger
    test on the two-point handle, then build and check three MuJoCo variants into variants/, record two (or
    ``--episodes``) scripted contact-rich episodes of the first into episodes/ (checked to replay exactly), render
    them into renders/ (the MuJoCo stream and its Mitsuba re-render, checked to align, side by side in a picture),
    export them to a LeRobot v3.0 dataset in datasets/rik-demo and load it back with LeRobotDataset; finally find the
    hidden effect in simulated measurements of a drawer (sysid-data/, report in sysid-report/) and make the fitted
    joint a preset (sysid-catalog/)."""
    from rik.registry.index import catalog_index
    from rik.registry.stats import catalog_stats

    catalog.print_summary(catalog_stats(catalog_index(overlays(catalog_paths))))
    assets.print_demo_assets(overlays(catalog_paths))
    variants.print_demo_variants(overlays(catalog_paths))
    recorded = variants.print_demo_episode(overlays(catalog_paths), episodes=episodes)
    rerender.print_demo_renders(overlays(catalog_paths), recorded, res=res)
    export.print_demo_export(overlays(catalog_paths), recorded, res=res)
    sysid.print_demo_sysid(overlays(catalog_paths))


def _app_for(args: list[str]) -> typer.Typer:
    """The app that runs ``args``. When the first argument names a command group or a command, a root app that
    holds only that one: typer builds the parameters of every registered command (evaluating each signature's
    annotations) before it parses anything, ~25 ms for all of rik's commands against ~4 ms for one group, which
    was most of ``rik catalog``'s own start-up. Anything else (no argument, ``--help``, ``--version``, a typo)
    runs the full app, so help, suggestions and errors are unchanged."""
    from typer.main import get_command_name

    if not args:
        return app
    groups = [g for g in app.registered_groups if g.name == args[0]]
    commands = [c for c in app.registered_commands
                if (c.name or (c.callback and get_command_name(c.callback.__name__))) == args[0]]
    if not groups and not commands:
        return app
    only = _new_app()
    only.registered_groups, only.registered_commands = groups, commands
    return only


def _run(args: list[str]) -> None:
    """Run ``rik ARGS``: typer's command, whose floats are finite (:func:`finite_floats`), with click's usage and
    parameter errors (an option out of its range, an unknown command) as one line, exit 2 (click's own code), in
    place of typer's box of five; help, ``--version``, ``typer.Exit`` and Ctrl-C end as they did."""
    from typer._click.exceptions import ClickException, NoArgsIsHelpError
    from typer.main import get_command

    command = finite_floats(get_command(_app_for(args)))
    try:
        code = command.main(args, prog_name="rik", standalone_mode=False)  # also under `python -m`
    except NoArgsIsHelpError as exc:  # ``rik`` or a group alone: its help (rich printed it already), exit 2
        if exc.format_message().strip():
            exc.show()
        sys.exit(exc.exit_code)
    except ClickException as exc:
        print(f"rik: error: {usage_line(exc)}", file=sys.stderr)
        sys.exit(exc.exit_code)
    except typer.Abort:
        print("rik: error: aborted", file=sys.stderr)
        sys.exit(1)
    sys.exit(code if isinstance(code, int) else 0)  # a typer.Exit's code (commands return None)


def main() -> None:
    """Entry point: bad input becomes one line on stderr and exit code 2, never a traceback."""
    import os

    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("MUJOCO_GL", "egl")  # headless machines render through EGL
    try:
        _run(sys.argv[1:])
    except RikError as exc:
        print(f"rik: error: {exc}", file=sys.stderr)
        sys.exit(2)
    except OSError as exc:  # the machine's fault, not the input's: one line and exit 1, never a traceback
        import errno

        if exc.errno in (errno.ENOTDIR, errno.EISDIR, errno.EEXIST, errno.ENAMETOOLONG):
            # a path the user gave: a file where a folder belongs (or the reverse), or a name too long to be one
            print(f"rik: error: {os_error_text(exc)}; give a path that is a folder where a folder is expected, a file "
                  "where a file is", file=sys.stderr)
            sys.exit(2)
        if exc.errno not in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS):
            raise
        print(f"rik: error: {os_error_text(exc)}; files being written were removed, finished ones kept",
              file=sys.stderr)
        sys.exit(1)
