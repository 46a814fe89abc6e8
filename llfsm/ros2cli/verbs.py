"""`topic echo`, `topic pub`, `topic hz` and `service call` over DDS, printing what `ros2` prints.

Each joins the ROS domain with one participant (the transport's discovery settings) and waits
at most `timeout` seconds for what it needs.  echo and hz read with a DataReader of their own,
of the message's DDS form (llfsm/msgs/_dds.py), because they choose QoS as `ros2` does (best
effort unless every publisher is reliable, transient local when every publisher is); the graph
reader on the same participant tells the type and QoS of what is there.  pub and service call
are a hidden node of llfsm's own bus on the DDS transport, as `ros2` makes a node of rclpy: the
transport's publisher and client (request header, client id, readiness) serve them unchanged,
and the node is announced on the graph.  Input mistakes (a TYPE, VALUES, a field, a name) are
found before the domain is joined, so they cost nothing and exit 2; what is not there exits 1.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, TextIO

from . import CliError
from .graph import NEEDS_CYCLONEDDS, NOT_FOUND, open_graph, where
from .interfaces import message_class, service_class, use_working_directory

if TYPE_CHECKING:
    from ..msgs import Message
    from ..ros.node import Node
    from ..ros.transports.dds_graph import Endpoint, Graph

#: rclpy's default QoS depth for `ros2 topic pub` ("default" profile) and `echo` ("sensor_data").
PUB_DEPTH, ECHO_DEPTH = 10, 5
#: How long echo looks for the topic's publishers (to match their QoS) when TYPE is given.
QOS_LOOKUP = 1.0


def full_name(name: str, what: str = "topic") -> str:
    """The fully qualified name, as a node in the root namespace expands it."""
    from ..ros.names import InvalidNameError, expand

    try:
        return expand(name, "_llfsm_cli", "/", what)
    except InvalidNameError as e:
        raise CliError(str(e)) from None


def wait_for_topic_types(graph: Graph, name: str, timeout: float) -> list[str]:
    """The topic's types once discovery shows it; exit 1 when it does not within `timeout`."""
    if not graph.spin(timeout, until=lambda: name in graph.topics(include_hidden=True)):
        raise CliError(f"topic '{name}' not found within {timeout:g} s ({where()})", NOT_FOUND)
    return graph.topics(include_hidden=True)[name]


def _class_of_topic(name: str, types: list[str]) -> type[Message]:
    if len(types) > 1:
        raise CliError(f"topic '{name}' has more than one type: [{', '.join(types)}]; give TYPE", NOT_FOUND)
    try:
        return message_class(types[0])
    except CliError as e:
        raise CliError(f"topic '{name}' has type {types[0]}, which llfsm cannot read: {e.message}") from None


def _check_types(graph: Graph, name: str, cls: type[Message], endpoints: list[Endpoint]) -> None:
    """A topic whose endpoints have another type never matches ours: say so instead of waiting."""
    from ..ros.transports.dds_graph import message_type

    others = sorted({message_type(e.type_name) for e in endpoints} - {cls._TYPE})
    if others:
        what = "types" if len(others) > 1 else "type"
        raise CliError(f"topic '{name}' has {what} {', '.join(others)}, not {cls._TYPE}", NOT_FOUND)


# -- DDS: the transport's types and participant ------------------------------------------------


def _types() -> Any:
    """The DDS forms of llfsm's messages (llfsm/msgs/_dds.py: `dds_type`, `from_dds`)."""
    try:
        import cyclonedds  # noqa: F401

        from ..msgs import _dds
    except ImportError as e:
        raise CliError(NEEDS_CYCLONEDDS.format(e)) from None
    return _dds


def _qos(reliable: bool, transient_local: bool, depth: int) -> Any:
    """A reader's QoS: rclpy's profile as rmw_cyclonedds sets it (XCDR1), reliability and
    durability as asked."""
    from cyclonedds.core import Policy, Qos

    return Qos(
        Policy.Reliability.Reliable(max_blocking_time=100_000_000) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if transient_local else Policy.Durability.Volatile,
        Policy.History.KeepLast(depth),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def _reader(graph: Graph, dds_topic: str, wire_type: type, qos: Any) -> Any:
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    return DataReader(graph.participant, Topic(graph.participant, dds_topic, wire_type), qos=qos)


@contextmanager
def _node(name: str) -> Iterator[tuple[Node, Graph]]:
    """A hidden ROS node of llfsm's own bus on the DDS transport (announced on the graph as
    `ros2`'s own `_ros2cli_...` nodes are), and a graph reader on the same participant."""
    from ..ros import bus_of
    from ..ros.node import Node
    from ..ros.transports.dds_config import DiscoveryError
    from ..ros.transports.dds_graph import Graph
    from ..runtime.clock import WallClock
    from ..runtime.context import RunContext, activate

    _types()
    from ..ros.transports.dds import DdsTransport

    ctx = RunContext(WallClock())
    try:
        transport = DdsTransport()
    except DiscoveryError as e:
        raise CliError(str(e)) from None
    ctx.transport = transport
    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        bus.initialised = True
        node = Node(name, start_parameter_services=False)
        yield node, Graph(transport.dp)
    finally:
        transport.close()
        activate(prev)


def _samples(reader: Any, name: str, cls: type[Message]) -> Any:
    """The decoded messages of a verb's reader, on llfsm's one decoding path
    (llfsm/ros/transports/dds_read.py): a sample that is not a `cls` (a string that is not
    UTF-8) is dropped with one warning on stderr per peer, and the verb goes on."""
    from ..ros.transports.dds_read import Samples

    decode = _types().from_cdr
    return Samples(reader, lambda data: decode(data, cls), name, f"a {cls._TYPE}")


class _Waiter:
    """Blocks until one of the readers has data, at most a given time (a wait set: no polling)."""

    def __init__(self, graph: Graph, *readers: Any) -> None:
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet

        self.waitset = WaitSet(graph.participant)
        self.conditions = [ReadCondition(r, SampleState.NotRead | ViewState.Any | InstanceState.Any) for r in readers]
        for c in self.conditions:
            self.waitset.attach(c)

    def wait(self, seconds: float) -> bool:
        return self.waitset.wait(max(0, int(seconds * 1e9))) > 0


# -- echo ----------------------------------------------------------------------------------------


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
            import importlib

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
    from ..msgs import Message, to_yaml

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


def echo(
    topic: str,
    type_text: str | None = None,
    *,
    once: bool = False,
    field: str | None = None,
    truncate_length: int | None = 128,
    no_arr: bool = False,
    no_str: bool = False,
    timeout: float = 5.0,
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
            cls = _class_of_topic(name, wait_for_topic_types(graph, name, timeout))
            path = _field_path(cls, field)
            graph.spin(0.1)  # the topic's other publishers, discovered with the first
        else:
            graph.spin(min(QOS_LOOKUP, timeout), until=lambda: bool(graph.topic_endpoints(name, "publisher")))
        publishers = graph.topic_endpoints(name, "publisher")
        _check_types(graph, name, cls, publishers)
        # as ros2 echo: reliable / transient local only when every publisher offers it
        reliable = bool(publishers) and all(p.reliable for p in publishers)
        transient = bool(publishers) and all(p.transient_local for p in publishers)
        types = _types()
        reader = _reader(graph, f"rt{name}", types.dds_type(cls), _qos(reliable, transient, ECHO_DEPTH))
        samples = _samples(reader, name, cls)
        waiter = _Waiter(graph, reader)
        patient = False  # a message was printed, or (streaming) a publisher is there: wait on
        while True:
            if not patient and not once and reader.get_subscription_matched_status().current_count:
                patient = True  # as ros2: a topic that is there may publish rarely
            left = 1.0 if patient else timeout - (time.monotonic() - started)
            if left <= 0:
                raise CliError(f"no message on '{name}' within {timeout:g} s ({where()})", NOT_FOUND)
            if not waiter.wait(left):
                continue
            for msg, _info in samples.take(64):
                out.write(format_message(msg, path or [], truncate_length, no_arr, no_str))
                out.flush()
                patient = True
                if once:
                    return
    finally:
        graph.close()


# -- pub -----------------------------------------------------------------------------------------


def publish(
    topic: str,
    type_text: str,
    values: str = "{}",
    *,
    period: float = 1.0,
    print_nth: int = 1,
    times: int = 0,
    wait_matching: int = 0,
    keep_alive: float = 0.1,
    timeout: float = 5.0,
    out: TextIO | None = None,
) -> None:
    """`ros2 topic pub`: publish the message every `period` seconds, `times` times (0: until
    interrupted), after `wait_matching` subscriptions have matched (at most `timeout` s)."""
    from ..msgs._yaml import ValuesError, from_yaml

    out = out or sys.stdout
    name = full_name(topic)
    use_working_directory()
    cls = message_class(type_text)
    try:
        msg, stamps = from_yaml(cls, values)
    except ValuesError as e:
        raise CliError(f"invalid VALUES: {e}") from None
    with _node(f"_llfsm_cli_{os.getpid()}") as (node, graph):
        pub = node.create_publisher(cls, name, PUB_DEPTH)
        if wait_matching:
            _wait_for_subscriptions(graph, pub, name, cls, wait_matching, timeout, out)
        out.write("publisher: beginning loop\n")
        count = 0
        next_at = time.monotonic()
        while True:
            now_ns = time.time_ns()
            for set_stamp in stamps:
                set_stamp(now_ns // 1_000_000_000, now_ns % 1_000_000_000)
            count += 1
            if print_nth and count % print_nth == 0:
                out.write(f"publishing #{count}: {msg!r}\n\n")
                out.flush()
            pub.publish(msg)
            if times and count >= times:
                break
            next_at += period
            while (left := next_at - time.monotonic()) > 0:
                node._bus.spin_once(int(left * 1e9))  # answers discovery meanwhile
        _linger(node, pub, keep_alive)


def _linger(node: Node, pub: Any, keep_alive: float) -> None:
    """Stay `keep_alive` seconds (as ros2 does) and until what was sent is acknowledged, at most
    a second more: a reliable message must reach the wire before the participant goes."""
    from cyclonedds.util import duration

    for writer in getattr(pub._remote, "writers", ()):
        writer.wait_for_acks(duration(seconds=1))
    end = time.monotonic() + keep_alive
    while (left := end - time.monotonic()) > 0:
        node._bus.spin_once(int(left * 1e9))


def _wait_for_subscriptions(
    graph: Graph, pub: Any, name: str, cls: type[Message], n: int, timeout: float, out: TextIO
) -> None:
    deadline = time.monotonic() + timeout
    said = False
    while pub.get_subscription_count() < n:
        pub.node._bus.spin_once(0)
        graph.update()
        _check_types(graph, name, cls, graph.topic_endpoints(name, "subscription"))
        if time.monotonic() >= deadline:
            found = pub.get_subscription_count()
            raise CliError(
                f"Timed out waiting for subscribers: expected {n} matching subscription(s) on '{name}' "
                f"within {timeout:g} s, found {found} ({where()})",
                NOT_FOUND,
            )
        if not said:
            out.write(f"Waiting for at least {n} matching subscription(s)...\n")
            out.flush()
            said = True
        time.sleep(0.05)


# -- hz ------------------------------------------------------------------------------------------


class RateMeter:
    """ros2 topic hz's statistics over the gaps between the last `window` messages."""

    def __init__(self, window: int = 10000) -> None:
        self.window = window
        self.last_ns: int | None = None
        self.gaps: list[int] = []
        self._printed_at: int | None = None

    def tick(self, now_ns: int) -> None:
        if self.last_ns is not None and now_ns >= self.last_ns:
            self.gaps.append(now_ns - self.last_ns)
            if len(self.gaps) > self.window:
                del self.gaps[0]
        self.last_ns = now_ns

    def stats(self) -> tuple[float, float, float, float, int] | None:
        """(rate in Hz, min, max and standard deviation of the gaps in s, window), or None when
        there is nothing new since the last call."""
        if not self.gaps or self.last_ns == self._printed_at:
            return None
        self._printed_at = self.last_ns
        n = len(self.gaps)
        mean = sum(self.gaps) / n
        rate = 1e9 / mean if mean > 0 else 0.0
        std = math.sqrt(sum((g - mean) ** 2 for g in self.gaps) / n)
        return rate, min(self.gaps) * 1e-9, max(self.gaps) * 1e-9, std * 1e-9, n

    def report(self) -> str | None:
        """The text ros2 prints each second for one topic, or None with nothing new to say."""
        s = self.stats()
        if s is None:
            return None
        rate, lo, hi, std, n = s
        return f"average rate: {rate:.3f}\n\tmin: {lo:.3f}s max: {hi:.3f}s std dev: {std:.5f}s window: {n}\n"


def rate_table(meters: dict[str, RateMeter]) -> str | None:
    """What ros2 topic hz prints each second for several topics: a table, one row per topic
    with something new, or None."""
    header = ["topic", "rate", "min_delta", "max_delta", "std_dev", "window"]
    rows = []
    for topic, meter in meters.items():
        s = meter.stats()
        if s is not None:
            rate, lo, hi, std, n = s
            rows.append([topic, f"{rate:.3f}", f"{lo:.3f}", f"{hi:.3f}", f"{std:.5f}", str(n)])
    if not rows:
        return None
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    head = "   ".join(h.center(w) for h, w in zip(header, widths, strict=True))
    line = "=" * (sum(widths) + 3 * (len(header) - 1))
    body = "\n".join("   ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows)
    return f"{head}\n{line}\n{body}\n\n"


def hz(
    topics: str | list[str],
    *,
    window: int = 10000,
    duration: float | None = None,
    timeout: float = 5.0,
    out: TextIO | None = None,
) -> None:
    """`ros2 topic hz`: the publishing rate every second (a table for several topics), until
    interrupted or `duration` ends."""
    out = out or sys.stdout
    names = list(dict.fromkeys(full_name(t) for t in ([topics] if isinstance(topics, str) else topics)))
    use_working_directory()
    graph = open_graph()
    try:
        started = time.monotonic()
        readers = {}
        samples = {}
        for name in names:
            left = max(0.0, timeout - (time.monotonic() - started))
            cls = _class_of_topic(name, wait_for_topic_types(graph, name, left))
            reader = _reader(graph, f"rt{name}", _types().dds_type(cls), _qos(False, False, ECHO_DEPTH))
            readers[name] = reader
            samples[name] = _samples(reader, name, cls)
            if len(names) > 1:
                out.write(f"Subscribed to [{name}]\n")
        waiter = _Waiter(graph, *readers.values())
        meters = {name: RateMeter(window) for name in names}
        next_print = time.monotonic() + 1.0
        end = started + duration if duration else math.inf
        while True:
            now = time.monotonic()
            if now >= end:
                return
            if now - started >= timeout:
                for name, reader in readers.items():
                    if meters[name].last_ns is None and not reader.get_subscription_matched_status().current_count:
                        raise CliError(f"no publisher of '{name}' matched within {timeout:g} s ({where()})", NOT_FOUND)
            if waiter.wait(min(next_print, end) - now):
                for name, taken in samples.items():
                    for _msg, _info in taken.take():  # decoded: what ros2 could not read is not counted
                        meters[name].tick(time.monotonic_ns())
            if time.monotonic() >= next_print:
                text = meters[names[0]].report() if len(names) == 1 else rate_table(meters)
                if text:
                    out.write(text)
                    out.flush()
                next_print += 1.0
    finally:
        graph.close()


# -- service call --------------------------------------------------------------------------------


def call(
    service: str,
    type_text: str,
    values: str = "{}",
    *,
    period: float | None = None,
    timeout: float = 5.0,
    out: TextIO | None = None,
) -> None:
    """`ros2 service call`: send the request (every `period` seconds when given) and print the
    response.  No server within `timeout`, or no answer within `timeout`: exit status 1."""
    from ..msgs._yaml import ValuesError, from_yaml

    out = out or sys.stdout
    name = full_name(service, "service")
    use_working_directory()
    srv = service_class(type_text)
    try:
        request, stamps = from_yaml(srv.Request, values)
    except ValuesError as e:
        raise CliError(f"invalid VALUES: {e}") from None
    pkg, _, srv_name = srv._TYPE.split("/")
    with _node(f"_llfsm_cli_requester_{pkg}_{srv_name}") as (node, graph):
        from ..ros import FutureReturnCode, spin_until_future_complete

        client = node.create_client(srv, name)
        if not client.service_is_ready():
            out.write("waiting for service to become available...\n")
            out.flush()
            if not _wait_for_service(graph, client, name, srv, timeout):
                raise CliError(f"service '{name}' not available within {timeout:g} s ({where()})", NOT_FOUND)
        while True:
            now_ns = time.time_ns()
            for set_stamp in stamps:
                set_stamp(now_ns // 1_000_000_000, now_ns % 1_000_000_000)
            out.write(f"requester: making request: {request!r}\n\n")
            out.flush()
            last = time.monotonic()
            future = client.call_async(request)
            code = spin_until_future_complete(node, future, timeout_sec=timeout)
            if code is not FutureReturnCode.SUCCESS or future.result() is None:
                if client.service_is_ready():
                    raise CliError(f"no response from service '{name}' within {timeout:g} s", NOT_FOUND)
                raise CliError(f"service '{name}' went away before it answered", NOT_FOUND)
            out.write(f"response:\n{future.result()!r}\n\n")
            out.flush()
            if period is None:
                return
            while (left := last + period - time.monotonic()) > 0:
                node._bus.spin_once(int(left * 1e9))


def _wait_for_service(graph: Graph, client: Any, name: str, srv: Any, timeout: float) -> bool:
    """True once the client sees a server; a server of another type is said at once."""
    deadline = time.monotonic() + timeout
    while not client.service_is_ready():
        client.node._bus.spin_once(50_000_000)
        graph.update()
        types = graph.services(include_hidden=True).get(name)
        if types and srv._TYPE not in types:
            raise CliError(f"service '{name}' has type {', '.join(types)}, not {srv._TYPE}", NOT_FOUND)
        if time.monotonic() >= deadline:
            return False
    return True
