"""Every command of `llfsm` registered on the click group (llfsm.cli._group), and click's entry
point, which turns what escapes the commands into a message and a status, not a traceback.
A new verb group is imported here."""

from __future__ import annotations

import sys

import click

from . import (  # noqa: F401  (each registers its commands)
    action,
    bag,
    build,
    check,
    edit,
    graph,
    import_,
    interface,
    launch,
    new,
    node,
    param,
    replay,
    run,
    service,
    structure,
    topic,
    verify,
    view,
)
from ._exits import EXIT_USAGE, run_guarded
from ._group import cli

__all__ = ["cli", "main"]


def main() -> None:
    """Entry point: click's own outcomes become a status here; whatever else escapes the
    commands (a closed pipe, Ctrl-C, an llfsm bug) is handled as on the fast path of `llfsm
    run`, by run_guarded: a message and a status, not a traceback."""

    def invoke() -> None:
        try:
            cli.main(prog_name="llfsm", standalone_mode=False)
        except click.exceptions.Exit as e:
            sys.exit(e.exit_code)
        except click.ClickException as e:
            e.show()
            sys.exit(EXIT_USAGE)
        except click.exceptions.Abort:
            sys.exit(130)

    run_guarded(invoke)
