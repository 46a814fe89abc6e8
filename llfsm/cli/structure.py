"""`llfsm state add|rename|remove` and `llfsm transition add|move|retarget|remove` (SPEC 13):
the structure operations of llfsm.edit, which the editor's page calls too, from the command
line.  Each plans the whole change, then writes every file it touches or none; a refused
request is one line on stderr and exit 1, with nothing changed."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import click

from ._group import EXIT_ERRORS, cli, fail

if TYPE_CHECKING:
    from ..edit import Change

MACHINE = click.argument("machine", metavar="M.machine", type=click.Path(file_okay=False))


def _do(plan: Callable[[], Change]) -> None:
    """Plan, apply, say what was done (or why nothing was)."""
    from ..edit import EditError, apply  # deferred: start-up (ruamel.yaml)

    try:
        change = plan()
        apply(change)
    except EditError as e:
        fail(str(e), EXIT_ERRORS)
    click.echo(change.summary if change.writes else f"{change.summary} (nothing to change)")


@cli.group()
def state() -> None:
    """Add, rename or remove a state of a machine (every file it touches, or none)."""


@state.command("add")
@MACHINE
@click.argument("name")
@click.option("--after", metavar="STATE", help="Put it after STATE in machine.yaml (default: last).")
def state_add(machine: str, name: str, after: str | None) -> None:
    """A new state NAME with no transitions (accepting until it has some)."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.state_add(Path(machine), name, after=after))


@state.command("rename")
@MACHINE
@click.argument("name")
@click.argument("new")
def state_rename(machine: str, name: str, new: str) -> None:
    """NAME becomes NEW: its files, every transition to it, initial/suspended, layout.yaml and
    `state_name() == "NAME"` comparisons in the machine's code."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.state_rename(Path(machine), name, new))


@state.command("remove")
@MACHINE
@click.argument("name")
def state_remove(machine: str, name: str) -> None:
    """NAME, its files and the transitions into it (refused for the initial state)."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.state_remove(Path(machine), name))


@cli.group()
def transition() -> None:
    """Add, move, retarget or remove a transition; its guard goes with it."""


@transition.command("add")
@MACHINE
@click.argument("source")
@click.argument("target")
@click.option("--guard", metavar="EXPR", help="The guard, one Python expression (default: True).")
@click.option("--priority", type=click.IntRange(min=0), help="Its place among SOURCE's transitions (default: last).")
@click.option(
    "--inline/--file",
    "inline",
    default=None,
    help="Write the guard in machine.yaml ({to: TARGET, guard: EXPR}) or in its .expr file "
    "(default: the form SOURCE's guards, else the machine's, are written in; files if none).",
)
def transition_add(
    machine: str, source: str, target: str, guard: str | None, priority: int | None, inline: bool | None
) -> None:
    """A transition from SOURCE to TARGET."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.transition_add(Path(machine), source, target, guard=guard, priority=priority, inline=inline))


@transition.command("move")
@MACHINE
@click.argument("source")
@click.argument("n", type=int)
@click.option("--to-priority", "to", type=click.IntRange(min=0), required=True, metavar="K")
def transition_move(machine: str, source: str, n: int, to: int) -> None:
    """Transition N of SOURCE to priority K (0 is tested first); every guard stays with its transition."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.transition_move(Path(machine), source, n, to))


@transition.command("retarget")
@MACHINE
@click.argument("source")
@click.argument("n", type=int)
@click.argument("target")
def transition_retarget(machine: str, source: str, n: int, target: str) -> None:
    """Transition N of SOURCE goes to TARGET instead (its guard stays)."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.transition_retarget(Path(machine), source, n, target))


@transition.command("remove")
@MACHINE
@click.argument("source")
@click.argument("n", type=int)
def transition_remove(machine: str, source: str, n: int) -> None:
    """Transition N of SOURCE and its guard; the later ones move up with theirs."""
    from .. import edit  # deferred: start-up (ruamel.yaml)

    _do(lambda: edit.transition_remove(Path(machine), source, n))
