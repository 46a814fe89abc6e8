"""The live view (docs/view.md): `llfsm run ... --web [HOST:]PORT` and `llfsm view`.

One page, live over a WebSocket: each machine's diagram with its current state, commands,
topics, a form to publish and one to call a service, and the turtle world.  Every script, style
and font ships in this package (static/); diagrams are laid out by llfsm.diagram, so the page
works with no network at all.

The server stack (aiohttp) is the optional extra `llfsm[web]`; importing this package does not
need it, so that `--web` without it can say what to install.
"""

from __future__ import annotations

from typing import Any

INSTALL_HINT = "the web view needs aiohttp: pip install 'llfsm[web]'"


class WebUnavailable(Exception):
    """The optional server stack is not installed."""


def server_class() -> Any:
    """llfsm.web.server.WebServer, or WebUnavailable naming what to install."""
    # deferred: optional dependency (aiohttp, the web extra), and start-up: a run without --web never imports the server
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        raise WebUnavailable(INSTALL_HINT) from None
    from .server import WebServer  # deferred: start-up, as aiohttp above

    return WebServer
