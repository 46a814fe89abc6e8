"""What the ros2-style verb groups (topic, service, node, interface) share: options with
`ros2`'s names and defaults, and the turning of a CliError into its one line and status."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

import click

from ..ros2cli import SPIN_TIME, TIMEOUT, CliError
from ._group import fail

P = ParamSpec("P")
R = TypeVar("R")


def verb(fn: Callable[P, R]) -> Callable[P, R]:
    """Run the command; a CliError ends it with its message and status, Ctrl-C with 130."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return fn(*args, **kwargs)
        except CliError as e:
            fail(e.message, e.status)

    return wrapper


def positive(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    if value is not None and value <= 0:
        raise click.BadParameter("must be greater than 0")
    return value


spin_time_option = click.option(
    "--spin-time",
    type=float,
    default=SPIN_TIME,
    show_default=True,
    callback=positive,
    help="Seconds to wait for discovery.",
)
timeout_option = click.option(
    "--timeout",
    type=float,
    default=TIMEOUT,
    show_default=True,
    callback=positive,
    help="Seconds to wait for what the command needs (a publisher, a service, a message) before giving up.",
)
