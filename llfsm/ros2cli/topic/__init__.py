"""`topic list|info|type|echo|pub|hz`: a module per verb, as ros2topic has a file per verb.

What more than one verb needs to know of a topic's type is here: which class reads a
discovered topic, and whether the endpoints already there have another type (which never
matches ours, so the verb says so instead of waiting).
"""

from __future__ import annotations

from ...msgs import Message
from ...ros.transports.dds_graph import Endpoint, message_type
from .. import NOT_FOUND, CliError
from ..lookup import message_class


def class_of_topic(name: str, types: list[str]) -> type[Message]:
    """The class of a discovered topic's one type; a topic of several types needs TYPE."""
    if len(types) > 1:
        raise CliError(f"topic '{name}' has more than one type: [{', '.join(types)}]; give TYPE", NOT_FOUND)
    try:
        return message_class(types[0])
    except CliError as e:
        raise CliError(f"topic '{name}' has type {types[0]}, which llfsm cannot read: {e.message}") from None


def check_types(name: str, cls: type[Message], endpoints: list[Endpoint]) -> None:
    """A topic whose endpoints have another type never matches ours: say so instead of waiting."""
    others = sorted({message_type(e.type_name) for e in endpoints} - {cls._TYPE})
    if others:
        what = "types" if len(others) > 1 else "type"
        raise CliError(f"topic '{name}' has {what} {', '.join(others)}, not {cls._TYPE}", NOT_FOUND)
