"""`llfsm bag`: rosbag2 bags, as `ros2 bag` has them (`info`; `record` and `play` speak DDS)."""

from __future__ import annotations

import sys
import time

import click

from ..bag.errors import BagError
from ._group import EXIT_ERRORS, cli, fail


@cli.group()
def bag() -> None:
    """Inspect, record and play rosbag2 bags (MCAP or sqlite3)."""


@bag.command()
@click.argument("bag_path", metavar="DIR")
def info(bag_path: str) -> None:
    """Print what the bag holds: duration, start and end, messages, topics with types and counts."""
    from ..bag.info import format_info  # deferred: start-up (pydantic reads the bag's metadata)

    try:
        text = format_info(bag_path)
    except BagError as e:
        fail(str(e), 1)
    click.echo(text, nl=False)


@bag.command()
@click.argument("topics", nargs=-1, metavar="[TOPIC]...")
@click.option("-a", "--all", "all_topics", is_flag=True, help="Record every topic on the graph (hidden ones aside).")
@click.option("-o", "--output", metavar="DIR", help="The bag folder to create (default: rosbag2_YYYY_MM_DD-HH_MM_SS).")
@click.option("-s", "--storage", type=click.Choice(["mcap", "sqlite3"]), default="mcap", show_default=True)
@click.option("--duration", type=float, metavar="SECONDS", help="Stop after this long (default: at Ctrl-C).")
def record(topics: tuple[str, ...], all_topics: bool, output: str | None, storage: str, duration: float | None) -> None:
    """Record topics from the DDS graph (llfsm runs on --transport dds, ROS 2 nodes) into a bag."""
    if not topics and not all_topics:
        fail("bag record: name the topics to record, or -a for all of them")
    if topics and all_topics:
        fail("bag record: -a records every topic; give topics or -a, not both")
    out = output or time.strftime("rosbag2_%Y_%m_%d-%H_%M_%S")
    from ..bag.dds import record as record_dds  # deferred: start-up (recording needs the bus)
    from ..progress import Status

    status = Status()  # on a terminal: what is recorded, and how much

    def report(text: str) -> None:
        status.print(f"llfsm: {text}")

    try:
        error = record_dds(out, topics, all_topics, storage, report=report, duration=duration, status=status)
    except BagError as e:
        status.clear()
        fail(f"bag record: {e}")
    if error is not None:
        sys.exit(EXIT_ERRORS)


class _SpreadTopics(click.Command):
    """`--topics A B C`, as `ros2 bag play` takes it (argparse's nargs='+'): every name after
    the option, up to the next option or `--`, is a topic.  `--topics A --topics B` works too."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        spread = spread_option(args, "--topics")
        try:
            return super().parse_args(ctx, spread)
        except click.MissingParameter as e:
            if "--topics" in args and e.param is not None and e.param.name == "bag_path":
                raise click.UsageError(
                    "missing DIR: --topics takes every name after it, so give DIR before it "
                    "(`llfsm bag play DIR --topics A B`) or end the names with `--`",
                    ctx,
                ) from None
            raise


def spread_option(args: list[str], option: str) -> list[str]:
    """`OPTION A B` as `OPTION A OPTION B`: the values after OPTION up to the next `-...` or `--`."""
    out: list[str] = []
    i = 0
    while i < len(args):
        arg = args[i]
        out.append(arg)
        i += 1
        if arg == "--":
            out += args[i:]
            break
        if arg == option and i < len(args):
            out.append(args[i])  # the first value may be anything, as click takes it
            i += 1
            while i < len(args) and not args[i].startswith("-"):
                out += [option, args[i]]
                i += 1
    return out


@bag.command(cls=_SpreadTopics)
@click.argument("bag_path", metavar="DIR")
@click.option("-r", "--rate", type=float, default=1.0, show_default=True, help="Time scale (2 = twice as fast).")
@click.option("-l", "--loop", is_flag=True, help="Start over at the end, until Ctrl-C.")
@click.option("--topics", "topics", multiple=True, metavar="TOPIC...", help="Play only these topics (--topics A B).")
@click.option("-d", "--delay", type=float, default=0.0, show_default=True, help="Wait this many seconds first.")
def play(bag_path: str, rate: float, loop: bool, topics: tuple[str, ...], delay: float) -> None:
    """Publish a bag's messages to the DDS graph at their recorded pace."""
    from ..bag.dds import play as play_dds  # deferred: start-up (playing needs the bus)
    from ..progress import Status

    status = Status()  # on a terminal: how far the bag has been played
    try:
        play_dds(bag_path, rate, loop, topics, delay, status=status)
    except BagError as e:
        status.clear()
        fail(f"bag play: {e}")


@bag.command()
@click.argument("bag_path", metavar="BAG")
@click.argument("verify_file", metavar="[FILE.verify.yaml]", required=False)
@click.option(
    "--property",
    "properties",
    multiple=True,
    metavar="KIND:TEXT",
    help="A property over state(m) and published(topic), e.g. 'never: state(p) == \"CRIT\"' (repeatable).",
)
def check(bag_path: str, verify_file: str | None, properties: tuple[str, ...]) -> None:
    """Judge properties over a recorded bag: each machine's state from /llfsm/M/state, and what was
    published.  Exit status 1 when a property is violated or what it waits for is not seen."""
    # deferred: start-up (the property language, only for bag check)
    from pathlib import Path

    from ..monitor import MonitorError, property_source
    from ..monitor.bag import check_bag
    from ..props.file import FileError, read_verify_file

    try:
        sources = read_verify_file(Path(verify_file)).properties if verify_file else []
        sources += [property_source(t, "--property") for t in properties]
        found = check_bag(bag_path, sources, lambda line: click.echo(line, err=True))
    except (BagError, MonitorError, FileError) as e:
        fail(f"bag check: {e}")
    for line in found.notes:
        click.echo(f"llfsm: bag check: {line}", err=True)
    for line in found.lines():
        click.echo(line)
    if found.failed:
        sys.exit(1)
