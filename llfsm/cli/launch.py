"""`llfsm launch`: start the processes of a ROS 2 launch file (XML or YAML), as `ros2 launch`."""

from __future__ import annotations

import os
import sys

import click

from ._base import EXIT_OK, fail
from ._common import cli


@cli.command(context_settings={"ignore_unknown_options": False})
@click.argument("file", type=click.Path(dir_okay=False))
@click.argument("arguments", nargs=-1, metavar="[NAME:=VALUE]...")
@click.option("-s", "--show-args", "--show-arguments", is_flag=True, help="Show the file's arguments and exit.")
@click.option(
    "-p", "--print", "print_only", is_flag=True, help="Print the processes it would start, one a line, and exit."
)
@click.option(
    "-a",
    "--show-all-subprocesses-output",
    "show_all",
    is_flag=True,
    help="Show every process's output on the screen, whatever its `output` says (OVERRIDE_LAUNCH_PROCESS_OUTPUT).",
)
def launch(file: str, arguments: tuple[str, ...], show_args: bool, print_only: bool, show_all: bool) -> None:
    """Start the nodes, machines and commands of a launch file (*.launch.xml, *.launch.yaml).

    Each process runs on the DDS transport with the launch's discovery settings (ROS_DOMAIN_ID and
    friends, from the environment and set_env); its lines are prefixed [NAME-N].  Ctrl-C stops
    them all: SIGINT, then SIGTERM and SIGKILL for what is left.  Exit status: 0 every process
    ended well, 1 one failed, 2 a launch file that cannot be launched (nothing is started).
    """
    # deferred: start-up (every command module is imported when `llfsm` starts)
    from .. import launch as launching

    given = _arguments(arguments)
    if not os.path.exists(file):
        fail(f"{file}: no such launch file")
    try:
        if show_args:
            _show_arguments(launching.declared_arguments(file, given, os.environ))
            sys.exit(EXIT_OK)
        specs = launching.plan(file, given, os.environ)
    except launching.LaunchError as e:
        fail(str(e))
    if print_only:
        for s in specs:
            click.echo(f"[{s.label}] {s.shown}")
        sys.exit(EXIT_OK)
    override = "screen" if show_all else os.environ.get("OVERRIDE_LAUNCH_PROCESS_OUTPUT")
    if override:
        if override not in launching.OUTPUTS:
            fail(f"OVERRIDE_LAUNCH_PROCESS_OUTPUT={override!r}: expected one of {', '.join(launching.OUTPUTS)}")
        for s in specs:
            s.output = override
    sys.exit(launching.supervise(specs, os.environ))


def _arguments(arguments: tuple[str, ...]) -> dict[str, str]:
    """`NAME:=VALUE` words, as ros2 launch takes them (the last of a name wins)."""
    out: dict[str, str] = {}
    for a in arguments:
        name, sep, value = a.partition(":=")
        if not sep or not name:
            fail(f"malformed launch argument {a!r}, expected format '<name>:=<value>'")
        out[name] = value
    return out


def _show_arguments(args: list) -> None:
    """As `ros2 launch --show-args` prints them."""
    lines = ["Arguments (pass arguments as '<name>:=<value>'):"]
    for a in args:
        lines.append(f"\n    '{a.name}':\n        {a.description or 'no description given'}")
        if a.default is not None:
            lines.append(f"        (default: '{a.default}')")
    if not args:
        lines.append("\n  No arguments.")
    click.echo("\n".join(lines))
