"""`llfsm interface show TYPE`: a message or service definition as `ros2 interface show` prints it.
Offline: it reads the .msg/.srv files llfsm ships and the user's interface packages."""

from __future__ import annotations

import sys

import click

from ..ros2cli import CliError
from ._common import cli
from ._ros2 import verb


@cli.group()
def interface() -> None:
    """Show interface definitions (as `ros2 interface`)."""


@interface.command()
@click.argument("type_name", metavar="TYPE")
@click.option("--all-comments", is_flag=True, help="Show all comments, including for nested interface definitions.")
@click.option("--no-comments", is_flag=True, help="Show no comments or whitespace.")
@verb
def show(type_name: str, all_comments: bool, no_comments: bool) -> None:
    """Output the definition of TYPE (e.g. geometry_msgs/msg/Twist, turtlesim/srv/Spawn); '-'
    reads TYPE from standard input."""
    # deferred: start-up (the verb loads the messages)
    from ..ros2cli.interface import show as show_text
    from ..ros2cli.interface import use_working_directory

    if all_comments and no_comments:
        raise CliError("--all-comments and --no-comments exclude each other")
    if type_name == "-":
        type_name = sys.stdin.readline().strip()
        if not type_name:
            raise CliError("no TYPE on standard input")
    use_working_directory()
    comments = "all" if all_comments else "none" if no_comments else "top"
    click.echo(show_text(type_name, comments=comments), nl=False)
