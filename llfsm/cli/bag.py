"""`llfsm bag`: rosbag2 bags, as `ros2 bag` has them (`info`; `record` and `play` speak DDS)."""

from __future__ import annotations

import click

from ._common import cli, fail


@cli.group()
def bag() -> None:
    """Inspect, record and play rosbag2 bags (MCAP or sqlite3)."""


@bag.command()
@click.argument("bag_path", metavar="DIR")
def info(bag_path: str) -> None:
    """Print what the bag holds: duration, start and end, messages, topics with types and counts."""
    from ..bag.errors import BagError
    from ..bag.info import format_info

    try:
        text = format_info(bag_path)
    except BagError as e:
        fail(str(e), 1)
    click.echo(text, nl=False)
