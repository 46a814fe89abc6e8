"""`llfsm action list|info|send_goal`: `ros2 action` over DDS, for llfsm runs and ROS 2 nodes alike."""

from __future__ import annotations

import click

from ._group import cli
from ._ros2 import spin_time_option, timeout_option, verb


@cli.group()
def action() -> None:
    """Actions of the ROS 2 graph (as `ros2 action`)."""


@action.command("list")
@click.option("-t", "--show-types", is_flag=True, help="Additionally show the action type.")
@click.option("-c", "--count-actions", is_flag=True, help="Only display the number of actions discovered.")
@spin_time_option
@verb
def list_(show_types: bool, count_actions: bool, spin_time: float) -> None:
    """Output a list of action names."""
    from ..ros2cli.action import list_ as run_list  # deferred: start-up (the verb loads the bus)

    click.echo(run_list(show_types=show_types, count=count_actions, spin_time=spin_time), nl=False)


@action.command()
@click.argument("action_name", metavar="ACTION")
@click.option("-t", "--show-types", is_flag=True, help="Additionally show the action type.")
@click.option("-c", "--count", is_flag=True, help="Only display the number of action clients and action servers.")
@spin_time_option
@verb
def info(action_name: str, show_types: bool, count: bool, spin_time: float) -> None:
    """Print information about an action.

    ACTION is its name, e.g. /turtle1/rotate_absolute."""
    from ..ros2cli.action import info as run_info  # deferred: start-up (the verb loads the bus)

    click.echo(run_info(action_name, show_types=show_types, count=count, spin_time=spin_time), nl=False)


@action.command("send_goal")
@click.argument("action_name", metavar="ACTION")
@click.argument("action_type", metavar="TYPE")
@click.argument("goal", metavar="[GOAL]", required=False, default="{}")
@click.option("-f", "--feedback", is_flag=True, help="Echo feedback messages for the goal.")
@timeout_option
@verb
def send_goal(action_name: str, action_type: str, goal: str, feedback: bool, timeout: float) -> None:
    """Send an action goal.  GOAL holds its values, in YAML (e.g. "{theta: 1.57}"); Ctrl-C
    cancels the goal."""
    from ..ros2cli.action import send_goal as run_send_goal  # deferred: start-up (the verb loads the bus)

    run_send_goal(action_name, action_type, goal, feedback=feedback, timeout=timeout)
