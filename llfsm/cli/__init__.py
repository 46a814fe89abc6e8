"""The `llfsm` command, one module per verb group (as the `ros2` command has one package per
verb group): `check`, `build`, `run`, `new`, `graph`.  Each command imports what it needs when
it runs: `llfsm run` must start fast and never load the compiler's libraries when its cached
modules are fresh.  Every failure the user can cause ends in a one-line-per-problem message and
an exit status (1 or 2), never a traceback.

This package itself imports nothing heavy: `main` runs a plain `llfsm run ...` without click
(a third of the start-up time), parsing its arguments with llfsm.cli.run_args, which is built
from the same table of options as the click command; anything that parser does not fully
understand (--help, a mistake, another verb) goes to click.  `cli`, the click group, is
imported on first use (`from llfsm.cli import cli`).
"""

from __future__ import annotations

import sys

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any

    from click import Group

    from ..session import RunOptions

    cli: Group

__all__ = ["cli", "main"]


def main() -> None:
    """Entry point of the `llfsm` command (after llfsm.__main__ has checked the streams)."""
    args = sys.argv[1:]
    try:
        options = _fast_run_options(args)
        launching = _fast_launch(args) if options is None else None
        # deferred: start-up (a run or a launch on the fast path never imports click; other verbs
        # never the run)
        if options is not None:
            from ._exits import run_guarded
            from ._run import run
        elif launching is not None:
            from ._exits import run_guarded
            from ._launch import launch
        else:
            from ._commands import main as click_main
    except KeyboardInterrupt:  # while importing: as llfsm.__main__ does
        sys.exit(130)
    if options is not None:
        run_guarded(lambda: run(options))
    elif launching is not None:
        run_guarded(lambda: launch(*launching))
    else:
        click_main()


def _fast_run_options(args: list[str]) -> RunOptions | None:
    """The run's options when `args` is a run the fast path can take, else None."""
    if not args or args[0] != "run":
        return None
    from .run_args import run_options  # deferred: start-up (only `llfsm run` reads the table of options)

    return run_options(args[1:])


def _fast_launch(args: list[str]) -> tuple[str, list[str]] | None:
    """(FILE, NAME:=VALUE words) when `args` is `launch FILE [NAME:=VALUE]...` with no option."""
    if not args or args[0] != "launch":
        return None
    from ._launch import fast_launch_arguments  # deferred: start-up (only `llfsm launch` reads launch files)

    return fast_launch_arguments(args)


def __getattr__(name: str) -> Any:
    if name == "cli":
        from ._commands import cli  # deferred: start-up (click on first use)

        return cli
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
