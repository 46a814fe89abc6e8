"""What the user types after a verb, checked before the domain is joined: a topic or service
name, and VALUES (YAML as `ros2 topic pub` takes it).  TYPE is llfsm/ros2cli/interface.py's.

A mistake here costs nothing (no participant yet) and is one line with exit status 2
(docs/cli.md).
"""

from __future__ import annotations

import time

from ..msgs import Message
from ..msgs._yaml import StampSetter, ValuesError, from_yaml
from ..ros.names import InvalidNameError, expand
from . import CliError


def full_name(name: str, what: str = "topic") -> str:
    """The fully qualified name, as a node in the root namespace expands it."""
    try:
        return expand(name, "_llfsm_cli", "/", what)
    except InvalidNameError as e:
        raise CliError(str(e)) from None


def parse_values(cls: type[Message], values: str) -> tuple[Message, list[StampSetter]]:
    """The message VALUES fill, and the setters of the stamps it asked to be `now` (`auto`)."""
    try:
        return from_yaml(cls, values)
    except ValuesError as e:
        raise CliError(f"invalid VALUES: {e}") from None


def stamp(stamps: list[StampSetter]) -> None:
    """Set the `auto` stamps to now, as each send does."""
    now_ns = time.time_ns()
    for set_stamp in stamps:
        set_stamp(now_ns // 1_000_000_000, now_ns % 1_000_000_000)
