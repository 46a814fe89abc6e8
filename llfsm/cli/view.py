"""`llfsm view`: the live page (SPEC §10) for every llfsm machine found over DDS (SPEC §8)."""

from __future__ import annotations

import sys

import click

from ._common import DURATION, cli


@cli.command()
@click.option(
    "--web",
    "web",
    default="8080",
    show_default=True,
    metavar="[HOST:]PORT",
    help="Where to serve the page (127.0.0.1 unless HOST is given; 0: a free port).",
)
@click.option("--duration", type=DURATION, help="Stop after this much time (default: until Ctrl-C).")
def view(web: str, duration: int | None) -> None:
    """Watch and steer every llfsm machine on the DDS graph in a web page.

    Machines are found by their /llfsm/M/description topics (any `llfsm run --transport dds`);
    their diagrams, current states (/llfsm/M/state), topics and services are shown live, and
    Suspend / Resume / Restart call /llfsm/M/suspend|resume|restart.  Discovery follows
    ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS and CYCLONEDDS_URI.
    """
    from ..runtime import Arrangement, RunContext, WallClock, signals_handled
    from ..runtime.context import activate
    from ._run import _open_transport, _serve_web, _web_address

    address = _web_address(web)
    ctx = RunContext(WallClock(10_000_000, None))
    ctx.extras["transport"] = _open_transport("dds")
    from ..ros.bus import bus_of
    from ..web.machines import GraphSource

    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        bus.init()
        source = GraphSource(bus)
    finally:
        activate(prev)
    arr = Arrangement([], context=ctx)
    arr.serve_forever = True  # no machines of its own: it runs until Ctrl-C or --duration
    server = _serve_web(source, address)
    try:
        with signals_handled(arr):
            result = arr.run(duration, 0)
    finally:
        server.stop()
    sys.exit(result.status)
