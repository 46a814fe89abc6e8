"""`llfsm service list|type|find|call`: `ros2 service` over DDS, for llfsm runs and ROS 2 nodes alike."""

from __future__ import annotations

import click

from ._group import cli
from ._ros2 import positive, spin_time_option, timeout_option, verb


@cli.group()
def service() -> None:
    """Services of the ROS 2 graph (as `ros2 service`)."""


@service.command("list")
@click.option("-t", "--show-types", is_flag=True, help="Additionally show the service type.")
@click.option("-c", "--count-services", is_flag=True, help="Only display the number of services discovered.")
@click.option("--include-hidden-services", is_flag=True, help="Consider hidden services as well.")
@spin_time_option
@verb
def list_(show_types: bool, count_services: bool, include_hidden_services: bool, spin_time: float) -> None:
    """Output a list of available services."""
    from ..ros2cli.service import list_ as run_list  # deferred: start-up (the verb loads the bus)

    text = run_list(
        show_types=show_types,
        count=count_services,
        include_hidden=include_hidden_services,
        spin_time=spin_time,
    )
    click.echo(text, nl=False)


@service.command("type")
@click.argument("service_name", metavar="SERVICE")
@click.option("--include-hidden-services", is_flag=True, help="Consider hidden services as well.")
@timeout_option
@verb
def type_(service_name: str, include_hidden_services: bool, timeout: float) -> None:
    """Output a service's type."""
    from ..ros2cli.service import type_ as run_type  # deferred: start-up (the verb loads the bus)

    click.echo(run_type(service_name, include_hidden=include_hidden_services, timeout=timeout), nl=False)


@service.command()
@click.argument("service_type", metavar="TYPE")
@click.option("-c", "--count-services", is_flag=True, help="Only display the number of services discovered.")
@click.option("--include-hidden-services", is_flag=True, help="Consider hidden services as well.")
@spin_time_option
@verb
def find(service_type: str, count_services: bool, include_hidden_services: bool, spin_time: float) -> None:
    """Output a list of available services of a given type."""
    from ..ros2cli.service import find as run_find  # deferred: start-up (the verb loads the bus)

    text = run_find(service_type, count=count_services, include_hidden=include_hidden_services, spin_time=spin_time)
    click.echo(text, nl=False)


@service.command()
@click.argument("service_name", metavar="SERVICE")
@click.argument("service_type", metavar="TYPE")
@click.argument("values", metavar="[VALUES]", required=False, default="{}")
@click.option("-r", "--rate", type=float, callback=positive, help="Repeat the call at this rate in Hz.")
@timeout_option
@verb
def call(service_name: str, service_type: str, values: str, rate: float | None, timeout: float) -> None:
    """Call a service.  VALUES fill the request, in YAML (e.g. "{x: 2.0, y: 2.0}")."""
    from ..ros2cli.service import call as run_call  # deferred: start-up (the verb loads the bus)

    run_call(service_name, service_type, values, period=1.0 / rate if rate else None, timeout=timeout)
