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
    from ..ros2cli.graph import discovered, duplicate_nodes, node_list

    with discovered(spin_time) as graph:
        graph.settle()  # the nodes of participants already seen
        text = node_list(graph, include_hidden=all_, count=count_nodes, spin_time=spin_time)
        duplicates = duplicate_nodes(graph)
    if duplicates and not count_nodes:
        click.echo(
            "WARNING: Be aware that there are nodes in the graph that share an exact name, "
            "which can have unintended side effects.",
            err=True,
        )
    click.echo(text, nl=False)
