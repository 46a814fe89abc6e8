"""`llfsm interface show|list|package`: interface definitions and types as `ros2 interface`
prints them.  Offline: it reads the .msg/.srv files llfsm ships and the user's interface packages."""

from __future__ import annotations

import sys

import click

from ..ros2cli import CliError
from ._group import cli
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
    from ..ros2cli.lookup import use_working_directory

    if all_comments and no_comments:
        raise CliError("--all-comments and --no-comments exclude each other")
    if type_name == "-":
        type_name = sys.stdin.readline().strip()
        if not type_name:
            raise CliError("no TYPE on standard input")
    use_working_directory()
    comments = "all" if all_comments else "none" if no_comments else "top"
    click.echo(show_text(type_name, comments=comments), nl=False)


def _kinds(only_msgs: bool, only_srvs: bool, only_actions: bool) -> tuple[str, ...]:
    return tuple(k for k, on in (("msg", only_msgs), ("srv", only_srvs), ("action", only_actions)) if on)


_only_msgs = click.option("-m", "--only-msgs", is_flag=True, help="Print out only the message types.")
_only_srvs = click.option("-s", "--only-srvs", is_flag=True, help="Print out only the service types.")
_only_actions = click.option("-a", "--only-actions", is_flag=True, help="Print out only the action types.")


@interface.command("list")
@_only_msgs
@_only_srvs
@_only_actions
@verb
def list_(only_msgs: bool, only_srvs: bool, only_actions: bool) -> None:
    """List all interface types available."""
    # deferred: start-up (the verb lists the packages)
    from ..ros2cli.interface import list_ as list_text
    from ..ros2cli.lookup import use_working_directory

    use_working_directory()
    click.echo(list_text(kinds=_kinds(only_msgs, only_srvs, only_actions)), nl=False)


@interface.command()
@click.argument("package_name", metavar="PACKAGE")
@_only_msgs
@_only_srvs
@_only_actions
@verb
def package(package_name: str, only_msgs: bool, only_srvs: bool, only_actions: bool) -> None:
    """Output a list of available interface types within one package."""
    # deferred: start-up (the verb lists the packages)
    from ..ros2cli.interface import package as package_text
    from ..ros2cli.lookup import use_working_directory

    use_working_directory()
    click.echo(package_text(package_name, kinds=_kinds(only_msgs, only_srvs, only_actions)), nl=False)
