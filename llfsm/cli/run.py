"""`llfsm run`: the click command, built from the table of options in llfsm.cli.run_args; what
it does is llfsm.cli._run.run with the options as one llfsm.session.RunOptions, which the
start-up fast path (llfsm.cli.main) builds too."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from ..rosargs import RosArgsError, without_ros_args
from ._group import DURATION, cli
from .run_args import CHOICE, COUNT, FILE, FLAG, FLOAT, RUN_OPTIONS, TARGETS, RunOption
from .run_args import DURATION as DURATION_KIND

_TYPES: dict[str, Callable[[RunOption], Any]] = {
    FILE: lambda o: click.Path(dir_okay=False),
    CHOICE: lambda o: click.Choice(list(o.choices)),
    DURATION_KIND: lambda o: DURATION,
    FLOAT: lambda o: float,
    COUNT: lambda o: click.IntRange(min=1),
}


def _click_option(o: RunOption) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    kwargs: dict[str, Any] = {"help": o.help}
    if o.kind == FLAG:
        kwargs["is_flag"] = True
    elif o.kind in _TYPES:
        kwargs["type"] = _TYPES[o.kind](o)
    for key in ("default", "metavar", "envvar"):
        if getattr(o, key) is not None:
            kwargs[key] = getattr(o, key)
    if o.multiple:
        kwargs["multiple"] = True
    if o.show_default:
        kwargs["show_default"] = True
    return click.option(*o.flags, o.dest, **kwargs)


class _RunCommand(click.Command):
    """`llfsm run`, which also takes ROS arguments as `ros2 run` does (`--ros-args -r a:=b --`)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        try:
            args = without_ros_args(args)
        except RosArgsError as e:
            raise click.UsageError(str(e), ctx) from None
        return super().parse_args(ctx, args)


def _command(f: Callable[..., Any]) -> click.Command:
    for o in reversed(RUN_OPTIONS):
        f = _click_option(o)(f)
    f = click.argument(TARGETS, nargs=-1, required=False)(f)
    return cli.command(name="run", cls=_RunCommand)(f)


@_command
def run(**options: Any) -> None:
    """Run an arrangement of machines, round-robin, in command-line order.

    A TARGET is a NAME.machine directory (compiled into a cache), a built module, or PKG/NAME
    of an installed package.  ROS 2 arguments are taken as `ros2 run` takes them, after
    --ros-args (docs/cli.md).  With --node (or --echo) and no TARGET the nodes run on their own
    until Ctrl-C or --duration, as `ros2 run` does.  Exit status: 0 normal end, 1 an exception
    in machine code, 2 bad arguments or a machine that fails validation.
    """
    # deferred: start-up (the other verbs never load the run's session)
    from ..session import RunOptions
    from ._run import run as run_machines

    run_machines(RunOptions(**options))
