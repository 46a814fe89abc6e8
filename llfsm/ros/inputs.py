"""Inputs bound to topics (SPEC 11): for each input a machine binds to a field of a topic's
messages, a PULL reader on the machine's node (`/llfsm/M`, llfsm.ros.control) that hands the
field of each message it receives to the machine's inputs (llfsm.runtime.inputs), where the
machine's next ringlet takes it as its snapshot.

The run session binds them before the first round (`bind`), on either transport: a message from
this process is handed over as it is published, one from another process when the executor
takes it in.  Inputs of one machine on one topic share a reader.  A type the bus cannot carry on
that topic (the run already has it with another type) is a `BindError` naming the machine's
machine.yaml; a message whose field is missing cannot happen, since the field was checked
against the message's definition when the machine was built.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..msgs._message import is_message_class
from ..runtime.inputs import FIELD, MSG, NAME, TOPIC, TYPE, Inputs
from .subscription import Subscription

if TYPE_CHECKING:
    from ..runtime.machine import Machine
    from ..runtime.scheduler import Arrangement
    from .bus import Bus
    from .node import Node

#: How a field's value becomes an input's (an int field read by a float input is a float).
_CONVERT: dict[str, Callable[[Any], Any]] = {"bool": bool, "int": int, "float": float, "str": str}


class BindError(Exception):
    """An input that cannot be bound: the message says which machine.yaml and why."""


class InputReader(Subscription):
    """A PULL reader (keeps `latest`) that also hands each message's fields to the inputs."""

    __slots__ = ("_inputs", "_targets")

    def __init__(self, node: Node, msg_type: type[Any], topic: str, inputs: Inputs) -> None:
        self._inputs = inputs
        #: (input index, field path, conversion) for each input this reader feeds
        self._targets: list[tuple[int, tuple[str, ...], Callable[[Any], Any]]] = []
        super().__init__(node._bus, node, msg_type, topic, None, 1)
        node._entities.append(self)
        node._bus.transport.node_changed(node)

    def _deliver(self, msg: Any) -> None:
        super()._deliver(msg)
        for index, path, convert in self._targets:
            value = msg
            for name in path:
                value = getattr(value, name)
            self._inputs.set(index, convert(value))


def message_class(type_name: str) -> type[Any]:
    """llfsm's class for `pkg/msg/Name` (a shipped one, or a user's from the search path)."""
    pkg, _, name = type_name.split("/")
    try:
        module = importlib.import_module(f"llfsm.msgs.{pkg}.msg")
    except ImportError as e:
        raise LookupError(f"no message package {pkg} ({e})") from None
    cls: type[Any] | None = getattr(module, name, None)
    if cls is None or not is_message_class(cls):
        raise LookupError(f"{pkg} has no message {name}")
    return cls


def bind(arr: Arrangement, bus: Bus, where: Callable[[Machine], str] | None = None) -> list[InputReader]:
    """A reader for each topic a machine of `arr` binds inputs to, on the machine's node.
    `where(m)`: how to name the machine's machine.yaml in an error (default: its name)."""
    # deferred: start-up (control imports the messages it publishes; a run binds inputs rarely)
    from .control import attach  # the machines' nodes (/llfsm/M): made here if not yet

    graph = attach(arr, bus)
    readers: list[InputReader] = []
    for m, node in zip(arr.machines, graph.nodes, strict=True):
        inputs = m._inputs
        if inputs is None:
            continue
        by_topic: dict[str, InputReader] = {}
        for index, entry in enumerate(m.INPUTS):
            topic = entry[TOPIC]
            if topic is None:
                continue
            place = where(m) if where is not None else f"machine {m.NAME}"
            try:
                cls = message_class(entry[MSG])
                # a relative name is taken from the root, as for a node of the machine's own
                # (the machine's node lives in /llfsm)
                name = node.resolve_topic_name(topic if topic.startswith(("/", "~")) else "/" + topic)
                reader = by_topic.get(name)
                if reader is None:
                    reader = by_topic[name] = InputReader(node, cls, name, inputs)
                    readers.append(reader)
                elif reader.msg_type is not cls:
                    raise TypeError(f"{name} is bound with two message types, {reader.msg_type._TYPE} and {entry[MSG]}")
            except (LookupError, TypeError, ValueError) as e:
                raise BindError(f"{place}: input {entry[NAME]} (topic {topic}): {e}") from None
            reader._targets.append((index, tuple(entry[FIELD].split(".")), _CONVERT[entry[TYPE]]))
    return readers
