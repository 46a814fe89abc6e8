"""`llfsm launch`: start the processes of a ROS 2 launch file (XML or YAML), as `ros2 launch`;
what it does is llfsm.cli._launch.launch, which the start-up fast path (llfsm.cli.main) calls too."""

from __future__ import annotations

import click

from ._group import cli


@cli.command()
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
    from ._launch import (
        launch as run_launch,
    )  # deferred: start-up (every command module is imported when `llfsm` starts)

    run_launch(file, arguments, show_args=show_args, print_only=print_only, show_all=show_all)
