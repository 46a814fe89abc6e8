"""`llfsm view`: the live page (docs/view.md) for every llfsm machine found over DDS."""

from __future__ import annotations

from ._exits import echo
from ._group import cli, duration_option, web_option


@cli.command()
@web_option("the page")
@duration_option
def view(web: str, duration: int | None) -> None:
    """Watch and steer every llfsm machine on the DDS graph in a web page.

    Machines are found by their /llfsm/M/description topics (any `llfsm run --transport dds`);
    their diagrams, current states (/llfsm/M/state), topics and services are shown live, and
    Suspend / Resume / Restart call /llfsm/M/suspend|resume|restart.  Discovery follows
    ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS and CYCLONEDDS_URI.
    """
    # deferred: start-up (the other verbs never load the run's session)
    from ..session import RunOptions, Session, SessionError
    from ._run import exit_with, finish
    from ._web import GraphPage

    # a run of its own with no machine: the DDS transport, its bus, and the page of the graph
    options = RunOptions(transport="dds", duration=duration, web=web)
    try:
        outcome = Session(options, web=GraphPage(web), say=echo).run()
    except SessionError as e:
        exit_with(e)
    finish(outcome)
