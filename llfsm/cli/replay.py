"""`llfsm replay FILE`: the page over a recorded run (docs/debug.md, "Replay")."""

from __future__ import annotations

import time

import click

from ._exits import echo, fail
from ._group import cli, duration_option, web_option


@cli.command()
@click.argument("file", metavar="FILE")
@web_option("the page")
@duration_option
def replay(file: str, web: str, duration: int | None) -> None:
    """Step through a recorded run on its machines' diagrams, in a web page.

    FILE is a `llfsm run --trace FILE.jsonl`, or a folder written by `llfsm verify
    --counterexample DIR`.  The page's History slider moves through its ringlets: each
    machine's state and variables at any of them.  A FILE that is neither is one line, exit 2.
    """
    # deferred: start-up (the other verbs never load the page)
    from ..session import UsageError
    from ._web import serve, web_address

    try:
        address = web_address(web)
    except UsageError as e:
        fail(e.message)
    from ..web.debugging import ReplaySource  # deferred: optional dependency (checked above)
    from ..web.replay import ReplayError, read

    try:
        recorded = read(file)
    except ReplayError as e:
        fail(str(e))
    try:
        server = serve(ReplaySource(recorded), address)
    except UsageError as e:
        fail(e.message)
    echo(f"llfsm: replay of the {recorded.summary()}")
    end = None if duration is None else time.monotonic() + duration / 1e9
    try:
        while end is None or time.monotonic() < end:
            time.sleep(0.2 if end is None else max(0.0, min(0.2, end - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
