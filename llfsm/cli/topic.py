"""`llfsm topic list|info|type|find|echo|pub|hz`: `ros2 topic` over DDS, for llfsm runs and ROS 2
nodes alike.  Syntax and output follow `ros2 topic`; docs/cli.md lists what differs."""

from __future__ import annotations

import click

from ..ros2cli import CliError
from ._group import cli
from ._ros2 import positive, spin_time_option, timeout_option, verb


@cli.group()
def topic() -> None:
    """Topics of the ROS 2 graph (as `ros2 topic`)."""


@topic.command("list")
@click.option("-t", "--show-types", is_flag=True, help="Additionally show the topic type.")
@click.option("-c", "--count-topics", is_flag=True, help="Only display the number of topics discovered.")
@click.option("--include-hidden-topics", is_flag=True, help="Consider hidden topics as well.")
@click.option("-v", "--verbose", is_flag=True, help="List full details about each topic.")
@spin_time_option
@verb
def list_(show_types: bool, count_topics: bool, include_hidden_topics: bool, verbose: bool, spin_time: float) -> None:
    """Output a list of available topics."""
    from ..ros2cli.topic.list import list_ as run_list  # deferred: start-up (the verb loads the bus)

    text = run_list(
        show_types=show_types,
        count=count_topics,
        include_hidden=include_hidden_topics,
        verbose=verbose,
        spin_time=spin_time,
    )
    click.echo(text, nl=False)


@topic.command()
@click.argument("topic_name", metavar="TOPIC")
@click.option("-v", "--verbose", is_flag=True, help="Each endpoint's node, GID and QoS profile.")
@timeout_option
@verb
def info(topic_name: str, verbose: bool, timeout: float) -> None:
    """Print information about a topic."""
    from ..ros2cli.topic.info import info as run_info  # deferred: start-up (the verb loads the bus)

    click.echo(run_info(topic_name, verbose=verbose, timeout=timeout), nl=False)


@topic.command("type")
@click.argument("topic_name", metavar="TOPIC")
@timeout_option
@verb
def type_(topic_name: str, timeout: float) -> None:
    """Print a topic's type."""
    from ..ros2cli.topic.type import type_ as run_type  # deferred: start-up (the verb loads the bus)

    click.echo(run_type(topic_name, timeout=timeout), nl=False)


@topic.command()
@click.argument("topic_type", metavar="TYPE")
@click.option("-c", "--count-topics", is_flag=True, help="Only display the number of topics discovered.")
@click.option("--include-hidden-topics", is_flag=True, help="Consider hidden topics as well.")
@spin_time_option
@verb
def find(topic_type: str, count_topics: bool, include_hidden_topics: bool, spin_time: float) -> None:
    """Output a list of available topics of a given type."""
    from ..ros2cli.topic.find import find as run_find  # deferred: start-up (the verb loads the bus)

    click.echo(
        run_find(topic_type, count=count_topics, include_hidden=include_hidden_topics, spin_time=spin_time), nl=False
    )


@topic.command()
@click.argument("topic_name", metavar="TOPIC")
@click.argument("message_type", metavar="[TYPE]", required=False)
@click.option("--once", is_flag=True, help="Print the first message received and then exit.")
@click.option("--field", help="Echo a selected field of a message; '.' selects sub-fields (e.g. pose.position).")
@click.option("-f", "--full-length", is_flag=True, help="Output all elements of arrays, bytes and strings.")
@click.option(
    "-l",
    "--truncate-length",
    type=click.IntRange(min=0),
    default=128,
    show_default=True,
    help="Cut arrays, bytes and strings there.",
)
@click.option("--no-arr", is_flag=True, help="Don't print array fields of messages.")
@click.option("--no-str", is_flag=True, help="Don't print string fields of messages.")
@timeout_option
@verb
def echo(
    topic_name: str,
    message_type: str | None,
    once: bool,
    field: str | None,
    full_length: bool,
    truncate_length: int,
    no_arr: bool,
    no_str: bool,
    timeout: float,
) -> None:
    """Output messages from a topic as YAML, '---' after each.  TYPE (e.g. std_msgs/msg/String)
    is read from the graph when left out."""
    from ..ros2cli.topic.echo import echo as run_echo  # deferred: start-up (the verb loads the bus)

    run_echo(
        topic_name,
        message_type,
        once=once,
        field=field,
        truncate_length=None if full_length else truncate_length,
        no_arr=no_arr,
        no_str=no_str,
        timeout=timeout,
    )


@topic.command()
@click.argument("topic_name", metavar="TOPIC")
@click.argument("message_type", metavar="TYPE")
@click.argument("values", metavar="[VALUES]", required=False, default="{}")
@click.option(
    "-r", "--rate", type=float, default=1.0, show_default=True, callback=positive, help="Publishing rate in Hz."
)
@click.option(
    "-p",
    "--print",
    "print_nth",
    type=int,
    default=1,
    show_default=True,
    help="Only print every N-th published message (0: none).",
)
@click.option("-1", "--once", is_flag=True, help="Publish one message and exit.")
@click.option(
    "-t", "--times", type=click.IntRange(min=0), default=0, help="Publish this number of times and then exit."
)
@click.option(
    "-w",
    "--wait-matching-subscriptions",
    type=click.IntRange(min=0),
    help="Wait for this many matching subscriptions first (default 1 with --once/--times, else 0).",
)
@click.option(
    "--keep-alive", type=float, default=0.1, show_default=True, help="Seconds to stay after the last message."
)
@timeout_option
@verb
def pub(
    topic_name: str,
    message_type: str,
    values: str,
    rate: float,
    print_nth: int,
    once: bool,
    times: int,
    wait_matching_subscriptions: int | None,
    keep_alive: float,
    timeout: float,
) -> None:
    """Publish a message to a topic.  VALUES fill the message, in YAML (e.g. "{linear: {x: 2.0}}")."""
    from ..ros2cli.topic.pub import pub as run_pub  # deferred: start-up (the verb loads the bus)

    if once and times:
        raise CliError("--once and --times exclude each other")
    times = 1 if once else times
    run_pub(
        topic_name,
        message_type,
        values,
        period=1.0 / rate,
        print_nth=print_nth,
        times=times,
        wait_matching=wait_matching_subscriptions if wait_matching_subscriptions is not None else int(times != 0),
        keep_alive=keep_alive,
        timeout=timeout,
    )


@topic.command()
@click.argument("topic_names", metavar="TOPIC...", nargs=-1, required=True)
@click.option(
    "-w", "--window", type=click.IntRange(min=1), default=10000, show_default=True, help="Messages to average over."
)
@click.option("--duration", type=float, callback=positive, help="Stop after this many seconds (default: until Ctrl-C).")
@timeout_option
@verb
def hz(topic_names: tuple[str, ...], window: int, duration: float | None, timeout: float) -> None:
    """Print the average publishing rate of topics every second (a table for several)."""
    from ..ros2cli.topic.hz import hz as run_hz  # deferred: start-up (the verb loads the bus)

    run_hz(list(topic_names), window=window, duration=duration, timeout=timeout)
