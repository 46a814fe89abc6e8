"""The web view (docs/view.md) as the run's session takes it: `llfsm run --web` serves the run's
own machines, `llfsm view` the machines found over DDS.  The session (llfsm.session) sits a
layer below llfsm.web, so the page is handed to it from here (llfsm.session.WebPage).

Free of click, as the fast path of `llfsm run` is; llfsm.web is imported only when a page is
asked for (it is optional: `pip install 'llfsm[web]'`).
"""

from __future__ import annotations

from ..session import UsageError
from ._exits import echo

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from ..session import Session
    from ..web.server import WebServer


def web_address(text: str) -> tuple[str, int]:
    """`[HOST:]PORT` as (host, port); UsageError without the web extra or for a bad address."""
    from ..web import INSTALL_HINT, WebUnavailable, server_class  # deferred: optional dependency

    try:
        server_class()
    except WebUnavailable:
        raise UsageError(f"--web: {INSTALL_HINT}") from None
    from ..web.server import AddressError, parse_address  # deferred: optional dependency (checked above)

    try:
        return parse_address(text)
    except AddressError as e:
        raise UsageError(str(e)) from None


def serve(source: object, address: tuple[str, int]) -> WebServer:
    """Start the page's server for a source and print its address: one line holding `http://`
    (docs/view.md)."""
    from ..web.server import AddressError, WebServer  # deferred: optional dependency

    server = WebServer(source, *address)
    try:
        url = server.start()
    except AddressError as e:
        raise UsageError(str(e)) from None
    echo(f"llfsm: web view at {url}")
    return server


class _Page:
    runs_alone = False

    def __init__(self, text: str) -> None:
        self.text = text
        self.address: tuple[str, int] | None = None

    def check(self) -> None:
        self.address = web_address(self.text)

    def serve(self, source: object) -> WebServer:
        assert self.address is not None, "check() first"
        return serve(source, self.address)


class RunPage(_Page):
    """`llfsm run --web [HOST:]PORT`: the run's machines, topics, services and turtle world."""

    def source(self, session: Session) -> object:
        from ..web.source import RunSource  # deferred: optional dependency

        assert session.arrangement is not None and session.bus is not None
        source = RunSource(session.arrangement, session.bus, world=session.world)
        if session.debugger is not None:
            from ..web.debugging import RunDebug  # deferred: optional dependency, as above

            source.debug = RunDebug(session.debugger)
        return source


class GraphPage(_Page):
    """`llfsm view`: every llfsm machine on the DDS graph; a run of its own, with no machine."""

    runs_alone = True

    def source(self, session: Session) -> object:
        from ..web.debugging import GraphDebug  # deferred: optional dependency
        from ..web.machines import GraphSource

        assert session.bus is not None
        source = GraphSource(session.bus)
        source.debug = GraphDebug(source)
        return source
