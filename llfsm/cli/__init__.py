"""The `llfsm` command, one module per verb group (as the `ros2` command has one package per
verb group): `check`, `build`, `run`, `new`, `graph`.  Each command imports what it needs when
it runs: `llfsm run` must start fast and never load the compiler's libraries when its cached
modules are fresh.  Every failure the user can cause ends in a one-line-per-problem message and
an exit status (1 or 2), never a traceback.
"""

from __future__ import annotations

import os
import sys

import click

from . import (  # noqa: F401  (each registers its commands)
    bag,
    build,
    check,
    graph,
    interface,
    new,
    node,
    run,
    service,
    topic,
    view,
)
from ._common import EXIT_USAGE, _quiet_broken_pipe, cli

__all__ = ["cli", "main"]


def main() -> None:
    """Entry point: turns what escapes the commands into a message and a status, not a traceback."""
    try:
        cli.main(prog_name="llfsm", standalone_mode=False)
    except click.exceptions.Exit as e:
        sys.exit(e.exit_code)
    except click.ClickException as e:
        e.show()
        sys.exit(EXIT_USAGE)
    except click.exceptions.Abort:
        sys.exit(130)
    except BrokenPipeError:
        _quiet_broken_pipe()
    except KeyboardInterrupt:
        sys.exit(130)
    except SystemExit:
        raise
    except Exception as exc:  # an llfsm bug: say so plainly
        if os.environ.get("LLFSM_DEBUG"):
            raise
        click.echo(f"llfsm: internal error: {type(exc).__name__}: {exc} (set LLFSM_DEBUG=1 for a traceback)", err=True)
        sys.exit(70)


if __name__ == "__main__":
    main()
