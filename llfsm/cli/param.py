"""`llfsm param list|get|set|describe|dump|load`: `ros2 param` over DDS, for llfsm runs and ROS 2
nodes alike (llfsm/ros2cli/param.py; docs/parameters.md)."""

from __future__ import annotations

import click

from ._group import cli
from ._ros2 import positive, spin_time_option, verb

#: ros2param waits 1 s for the node to show up; llfsm waits as its other verbs do.
timeout_option = click.option(
    "--timeout",
    type=float,
    default=5.0,
    show_default=True,
    callback=positive,
    help="Seconds to wait for the node and its parameter services.",
)


@cli.group()
def param() -> None:
    """Parameters of ROS 2 nodes (as `ros2 param`)."""


@param.command("list")
@click.argument("node_name", metavar="[NODE]", required=False)
@click.option("--filter", "regex", help="Only parameters matching this regular expression.")
@click.option("--include-hidden-nodes", is_flag=True, help="Consider hidden nodes as well.")
@click.option("--param-prefixes", multiple=True, help="Only parameters with this prefix (repeatable).")
@click.option("--param-type", is_flag=True, help="Print parameter types with parameter names.")
@spin_time_option
@timeout_option
@verb
def list_(
    node_name: str | None,
    regex: str | None,
    include_hidden_nodes: bool,
    param_prefixes: tuple[str, ...],
    param_type: bool,
    spin_time: float,
    timeout: float,
) -> None:
    """Output a list of available parameters."""
    from ..ros2cli.param import list_ as run  # deferred: start-up (the verb loads the bus)

    text = run(
        node_name,
        param_type=param_type,
        prefixes=param_prefixes,
        regex=regex,
        include_hidden=include_hidden_nodes,
        spin_time=spin_time,
        timeout=timeout,
    )
    click.echo(text, nl=False)


@param.command()
@click.argument("node_name", metavar="NODE")
@click.argument("parameter_name", metavar="NAME")
@click.option("--hide-type", is_flag=True, help="Hide the type information.")
@timeout_option
@verb
def get(node_name: str, parameter_name: str, hide_type: bool, timeout: float) -> None:
    """Get parameter."""
    from ..ros2cli.param import get as run  # deferred: start-up (the verb loads the bus)

    click.echo(run(node_name, parameter_name, hide_type=hide_type, timeout=timeout), nl=False)


@param.command("set")
@click.argument("node_name", metavar="NODE")
@click.argument("parameter_name", metavar="NAME")
@click.argument("value", metavar="VALUE")
@timeout_option
@verb
def set_(node_name: str, parameter_name: str, value: str, timeout: float) -> None:
    """Set parameter.  VALUE is typed as ros2 types it: 2 an integer, 2.0 a double, true a boolean."""
    from ..ros2cli.param import set_ as run  # deferred: start-up (the verb loads the bus)

    click.echo(run(node_name, parameter_name, value, timeout=timeout), nl=False)


@param.command()
@click.argument("node_name", metavar="NODE")
@click.argument("parameter_names", metavar="NAME...", nargs=-1, required=True)
@timeout_option
@verb
def describe(node_name: str, parameter_names: tuple[str, ...], timeout: float) -> None:
    """Show descriptive information about declared parameters."""
    from ..ros2cli.param import describe as run  # deferred: start-up (the verb loads the bus)

    click.echo(run(node_name, parameter_names, timeout=timeout), nl=False)


@param.command()
@click.argument("node_name", metavar="NODE")
@timeout_option
@verb
def dump(node_name: str, timeout: float) -> None:
    """Show all of the parameters of a node in a YAML file format (loadable by --params-file)."""
    from ..ros2cli.param import dump as run  # deferred: start-up (the verb loads the bus)

    click.echo(run(node_name, timeout=timeout), nl=False)


@param.command()
@click.argument("node_name", metavar="NODE")
@click.argument("parameter_file", metavar="FILE")
@click.option("--no-use-wildcard", is_flag=True, help="Do not load parameters in the '/**' namespace into the node.")
@timeout_option
@verb
def load(node_name: str, parameter_file: str, no_use_wildcard: bool, timeout: float) -> None:
    """Load parameter file for a node."""
    from ..ros2cli import NOT_FOUND, CliError
    from ..ros2cli.param import load as run  # deferred: start-up (the verb loads the bus)

    out, err = run(node_name, parameter_file, use_wildcard=not no_use_wildcard, timeout=timeout)
    click.echo(out, nl=False)
    if err:
        click.echo(err, nl=False, err=True)
        raise CliError("some parameters were not set", NOT_FOUND)
