"""`topic echo`: each message of a topic as YAML, `---` after each, as `ros2 topic echo`
prints it.

It reads with a DataReader of its own (llfsm/ros2cli/endpoints.py) whose QoS follows the
publishers already there, as ros2's does: reliable only when every publisher is, transient
local only when every publisher is.
"""

from __future__ import annotations

import importlib
import sys
import time
from typing import Any, TextIO

from ...msgs import Message, to_yaml
from ...progress import Status, seconds
from ...suggest import did_you_mean
from .. import NOT_FOUND, TIMEOUT, CliError
from ..arguments import full_name
from ..discovery import open_graph, wait_for_topic_types, where
from ..endpoints import Waiter, samples, topic_reader
from ..lookup import message_class, use_working_directory
from . import check_types, class_of_topic

#: How long echo looks for the topic's publishers (to match their QoS) when TYPE is given.
QOS_LOOKUP = 1.0


def echo(
    topic: str,
    type_text: str | None = None,
    *,
    once: bool = False,
    field: str | None = None,
    truncate_length: int | None = 128,
    no_arr: bool = False,
    no_str: bool = False,
    timeout: float = TIMEOUT,
    out: TextIO | None = None,
) -> None:
    """`ros2 topic echo`: print each message; with `once`, the first one only.  Exit status 1
    when nothing is there within `timeout` seconds: no such topic (without TYPE), no message
    (with `once`), or neither a publisher nor a message (streaming: a topic whose publisher is
    there may publish rarely, and echo then waits as ros2 does)."""
    out = out or sys.stdout
    name = full_name(topic)
    use_working_directory()
    cls = message_class(type_text) if type_text else None
    path = _field_path(cls, field) if cls is not None else None
    graph = open_graph()
    try:
        started = time.monotonic()
        if cls is None:
            cls = class_of_topic(name, wait_for_topic_types(graph, name, timeout))
            path = _field_path(cls, field)
            graph.spin(0.1)  # the topic's other publishers, discovered with the first
        else:
            graph.spin(min(QOS_LOOKUP, timeout), until=lambda: bool(graph.topic_endpoints(name, "publisher")))
        publishers = graph.topic_endpoints(name, "publisher")
        check_types(name, cls, publishers)
        # as ros2 echo: reliable / transient local only when every publisher offers it
        reliable = bool(publishers) and all(p.reliable for p in publishers)
        transient = bool(publishers) and all(p.transient_local for p in publishers)
        reader = topic_reader(graph, name, cls, reliable=reliable, transient_local=transient)
        taken = samples(reader, name, cls)
        waiter = Waiter(graph, reader)
        patient = False  # a message was printed, or (streaming) a publisher is there: wait on
        status = Status()  # on a terminal: what echo waits for, until the first message comes
        printed = False
        while True:
            if not patient and not once and reader.get_subscription_matched_status().current_count:
                patient = True  # as ros2: a topic that is there may publish rarely
            left = 1.0 if patient else timeout - (time.monotonic() - started)
            if left <= 0:
                status.clear()
                hint = "" if publishers else did_you_mean(name, graph.topics(include_hidden=True))
                raise CliError(f"no message on '{name}' within {timeout:g} s ({where()}){hint}", NOT_FOUND)
            if status.enabled and not printed:
                waited = time.monotonic() - started
                if waited >= 0.5:
                    status.show(f"waiting for a message on '{name}'... {seconds(waited)}")
                left = min(left, 0.25)  # the line keeps counting while nothing comes
            if not waiter.wait(left):
                continue
            for msg, _info in taken.take(64):
                if not printed:
                    status.clear()
                    printed = True
                out.write(format_message(msg, path or [], truncate_length, no_arr, no_str))
                out.flush()
                patient = True
                if once:
                    return
    finally:
        graph.close()


def _field_path(cls: type[Message], field: str | None) -> list[str]:
    """`--field pose.position` as names, checked against the type now rather than at the first
    message."""
    if field is None:
        return []
    parts = [p for p in field.split(".") if p]
    if not parts:
        raise CliError(f"Invalid field value '{field}'")
    current: Any = cls
    for i, part in enumerate(parts):
        fields = dict(current._FIELDS) if current is not None else {}
        if part not in fields:
            owner = current._TYPE if current is not None else "a field that is not a message"
            raise CliError(f"Invalid field '{field}': {owner} has no field '{part}'")
        ftype = fields[part]
        if "/" in ftype and not ftype.endswith("]") and i + 1 < len(parts):
            pkg, kind, name = ftype.split("/")
            current = getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)
        else:
            current = None
    return parts


def _plain_filtered(value: Any, no_arr: bool, no_str: bool) -> Any:
    if isinstance(value, dict):
        return {
            k: _plain_filtered(v, no_arr, no_str)
            for k, v in value.items()
            if not (no_arr and isinstance(v, list | tuple)) and not (no_str and isinstance(v, str))
        }
    return value


def format_message(
    msg: Any, field: list[str], truncate_length: int | None, no_arr: bool = False, no_str: bool = False
) -> str:
    """One message as `ros2 topic echo` prints it, its `---` line included."""
    value = msg
    for part in field:
        value = getattr(value, part)
    if not isinstance(value, Message):  # a primitive field: ros2 prints the Python value
        if isinstance(value, list | tuple) and value and isinstance(value[0], Message):
            value = [v.to_dict() for v in value]
        return f"{value}\n---\n"
    data = value.to_dict()
    if no_arr or no_str:
        data = _plain_filtered(data, no_arr, no_str)
    return to_yaml(data, truncate_length=truncate_length) + "---\n"
