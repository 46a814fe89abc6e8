"""The `llfsm` click group, and what its commands share on click's side: the DURATION parameter
type, `write_output`, `progress`, and the names of llfsm.cli._exits (exit statuses, `fail`) that
the click-free fast path of `llfsm run` shares with them.

Each command imports what it needs when it runs: `llfsm run` must start fast and never load
the compiler's libraries when its cached modules are fresh.  Every failure the user can cause
ends in a one-line-per-problem message and an exit status (1 or 2), never a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import click

from .. import __version__
from ._exits import (  # noqa: F401  (shared with the click-free fast path of `llfsm run`)
    EXIT_ERRORS,
    EXIT_OK,
    EXIT_USAGE,
    MAX_DURATION_NS,
    _output_failed,
    _quiet_broken_pipe,
    duration_ns,
    fail,
    output_errors,
)

F = TypeVar("F", bound=Callable[..., Any])


class Duration(click.ParamType):
    """Seconds (`0.5`) or a number with a unit (`500ms`, `2s`), as nanoseconds."""

    name = "duration"

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> int:
        if isinstance(value, int):
            return value
        try:
            return duration_ns(str(value))
        except ValueError as e:
            self.fail(str(e), param, ctx)


DURATION = Duration()


def web_option(what: str) -> Callable[[F], F]:
    """`--web [HOST:]PORT` of `llfsm view` and `llfsm edit` (`llfsm run` parses its own)."""
    return click.option(
        "--web",
        "web",
        default="8080",
        show_default=True,
        metavar="[HOST:]PORT",
        help=f"Where to serve {what} (127.0.0.1 unless HOST is given; 0: a free port).",
    )


#: `--duration` of the commands that serve until Ctrl-C (`llfsm view`, `llfsm edit`).
duration_option = click.option("--duration", type=DURATION, help="Stop after this much time (default: until Ctrl-C).")


def write_output(path: str, data: bytes, what: str) -> None:
    """Write a file the user named (`-o FILE`) through llfsm.outputs: atomically, and one clear
    line with exit status 1 if it cannot be written (full disk, /proc, a directory)."""
    # deferred: start-up (every command module imports this one; only a command that writes a file needs it)
    from ..outputs import OutputError, write_file

    try:
        write_file(path, data, what=what, mkdirs=True)
    except OutputError as e:
        fail(f"{e}", EXIT_ERRORS)


def progress(text: str) -> None:
    """A progress line on stderr that cannot stop the work: when its reader has gone
    (`llfsm build 2>&1 | head -1`), later lines go nowhere and the work goes on to its end,
    so the exit status still says whether it succeeded."""
    try:
        click.echo(text, nl=False, err=True)
    except (BrokenPipeError, ValueError):
        from ..progress import abandon  # deferred: start-up (only once stderr's reader has gone)

        abandon(sys.stderr)


def _existing(paths: tuple[str, ...]) -> list[Path]:
    out = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            fail(f"{p}: no such file or directory")
        if not path.is_dir():
            fail(f"{p}: not a machine directory or a folder of machines")
        out.append(path)
    return out


class _Group(click.Group):
    """Handles a closed pipe before click does: click would turn it into exit status 1."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except OSError as e:  # a closed pipe, a full disk under stdout (as the fast path: _exits)
            output_errors(e)
            raise


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="llfsm")
def cli() -> None:
    """Logic-labelled finite-state machines: check, build and run them."""
