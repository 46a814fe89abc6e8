"""`llfsm node list|info`: the ROS 2 nodes of the graph (as `ros2 node`), llfsm's and ROS 2's."""

from __future__ import annotations

import click

from ._group import cli
from ._ros2 import spin_time_option, timeout_option, verb


@cli.group()
def node() -> None:
    """Nodes of the ROS 2 graph (as `ros2 node`)."""


@node.command("list")
@click.option("-a", "--all", "all_", is_flag=True, help="Display all nodes, even hidden ones.")
@click.option("-c", "--count-nodes", is_flag=True, help="Only display the number of nodes discovered.")
@spin_time_option
@verb
def list_(all_: bool, count_nodes: bool, spin_time: float) -> None:
    """Output a list of available nodes."""
    from ..ros2cli.node import list_ as run_list  # deferred: start-up (the verb loads the bus)

    text, warning = run_list(include_hidden=all_, count=count_nodes, spin_time=spin_time)
    if warning is not None:
        click.echo(warning, err=True)
    click.echo(text, nl=False)


@node.command()
@click.argument("node_name", metavar="NODE")
@click.option("--include-hidden", is_flag=True, help="Display hidden topics, services, and actions as well.")
@spin_time_option
@timeout_option
@verb
def info(node_name: str, include_hidden: bool, spin_time: float, timeout: float) -> None:
    """Output information about a node (e.g. /turtlesim)."""
    from ..ros2cli.node import info as run_info  # deferred: start-up (the verb loads the bus)

    text, warning = run_info(node_name, include_hidden=include_hidden, spin_time=spin_time, timeout=timeout)
    if warning is not None:
        click.echo(warning, err=True)
    click.echo(text, nl=False)
