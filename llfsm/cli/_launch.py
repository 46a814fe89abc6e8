"""What `llfsm launch` does once its arguments are parsed (docs/launch.md).

Free of click, so that the start-up fast path (llfsm.cli.main) starts a launch file's processes
without importing it: every hundredth of a second the launcher spends starting up delays every
process it starts.  The click command (llfsm.cli.launch) calls `launch` too, for the forms with
options.
"""

from __future__ import annotations

import os
import sys

from ._exits import EXIT_OK, echo, fail

TYPE_CHECKING = False  # not typing's own: the launcher's start-up delays every process
if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import NoReturn

    from ..launch import ArgumentInfo


def launch(
    file: str, arguments: Sequence[str], *, show_args: bool = False, print_only: bool = False, show_all: bool = False
) -> NoReturn:
    """Plan the launch file and start its processes (or only show its arguments or its
    processes); ends the process with the launch's exit status."""
    from .. import launch as launching  # deferred: start-up (the other verbs never read launch files)

    given = arguments_given(arguments)
    if not os.path.exists(file):
        fail(f"{file}: no such launch file")
    try:
        if show_args:
            _show_arguments(launching.declared_arguments(file, given, os.environ))
            sys.exit(EXIT_OK)
        specs = launching.plan(file, given, os.environ)
    except launching.LaunchError as e:
        fail(str(e))
    if print_only:
        echo("".join(f"[{s.label}] {s.shown}\n" for s in specs), nl=False, err=False)
        sys.exit(EXIT_OK)
    override = "screen" if show_all else os.environ.get("OVERRIDE_LAUNCH_PROCESS_OUTPUT")
    if override:
        if override not in launching.OUTPUTS:
            fail(f"OVERRIDE_LAUNCH_PROCESS_OUTPUT={override!r}: expected one of {', '.join(launching.OUTPUTS)}")
        for s in specs:
            s.output = override
    sys.exit(launching.supervise(specs, os.environ))


def arguments_given(arguments: Sequence[str]) -> dict[str, str]:
    """`NAME:=VALUE` words, as ros2 launch takes them (the last of a name wins)."""
    out: dict[str, str] = {}
    for a in arguments:
        name, sep, value = a.partition(":=")
        if not sep or not name:
            fail(f"malformed launch argument {a!r}, expected format '<name>:=<value>'")
        out[name] = value
    return out


def fast_launch_arguments(args: Sequence[str]) -> tuple[str, list[str]] | None:
    """(FILE, NAME:=VALUE words) of `launch FILE [NAME:=VALUE]...` with no option, a form the
    fast path takes as click would; None for anything else (options, help, a folder)."""
    if len(args) < 2 or args[0] != "launch" or any(a.startswith("-") for a in args[1:]):
        return None
    if "_LLFSM_COMPLETE" in os.environ or os.path.isdir(args[1]):
        return None
    return args[1], list(args[2:])


def _show_arguments(args: list[ArgumentInfo]) -> None:
    """As `ros2 launch --show-args` prints them."""
    lines = ["Arguments (pass arguments as '<name>:=<value>'):"]
    for a in args:
        lines.append(f"\n    '{a.name}':\n        {a.described}")
        if a.default is not None:
            lines.append(f"        (default: '{a.default}')")
    if not args:
        lines.append("\n  No arguments.")
    echo("\n".join(lines), err=False)
