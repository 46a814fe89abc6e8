"""`llfsm node list`: the ROS 2 nodes of the graph (as `ros2 node list`), llfsm's and ROS 2's."""

from __future__ import annotations

import click

from ._common import cli
from ._ros2 import spin_time_option, verb


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
