"""`llfsm edit`: write machines in the browser (SPEC 13, docs/edit.md)."""

from __future__ import annotations

import signal
import threading
from pathlib import Path

import click

from ._exits import echo, fail
from ._group import cli, duration_option, web_option


@cli.command()
@click.argument("paths", nargs=-1, type=click.Path())
@web_option("the editor")
@duration_option
def edit(paths: tuple[str, ...], web: str, duration: int | None) -> None:
    """Edit machines in a web page: diagrams, structure, code, live checks, Run.

    PATH: machine directories, folders holding them (new machines are made there), or a
    NAME.verify.yaml (its machines); the current folder if none.  The files stay the truth:
    every change is written at once, atomically, and another program's changes appear in
    the page.
    """
    # deferred: start-up (every command module is imported when `llfsm` starts; the editor's
    # libraries are optional: the web extra)
    from ..session import UsageError
    from ._web import web_address

    try:
        address = web_address(web)
    except UsageError as e:
        fail(str(e))
    from ..web.edit_server import EditServer  # deferred: optional dependency (checked by web_address)
    from ..web.server import AddressError
    from ..web.workspace import Workspace, WorkspaceError

    try:
        workspace = Workspace([Path(p) for p in paths] or [Path(".")])
    except WorkspaceError as e:
        fail(str(e))
    server = EditServer(workspace, *address)
    try:
        url = server.start()
    except AddressError as e:
        fail(str(e))
    echo(f"llfsm: editor at {url}")
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    try:
        done.wait(None if duration is None else duration / 1e9)
    finally:
        server.stop()
