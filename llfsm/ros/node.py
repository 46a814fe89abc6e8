"""Nodes and what they create: publishers, subscriptions (PUSH and PULL), services, clients,
timers, loggers and parameters, with rclpy's names and signatures."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from ..msgs._message import Message, Service, is_message_class, is_service_class
from .bus import Bus, Future, bus_of
from .names import expand, normalise_namespace, remap_name, remap_node, validate_node_name


class ReliabilityPolicy(IntEnum):
    """rclpy's reliability policies (same names and values).  Over DDS a RELIABLE writer
    resends what a reader missed; a BEST_EFFORT one never does (sensor drivers publish so).  A
    RELIABLE reader never matches a BEST_EFFORT writer, as in ROS 2; in process nothing is ever
    lost, so the policy changes nothing there.  SYSTEM_DEFAULT leaves Cyclone's default, as
    rmw_cyclonedds_cpp does: a writer is reliable, a reader best effort."""

    SYSTEM_DEFAULT = 0
    RELIABLE = 1
    BEST_EFFORT = 2


class HistoryPolicy(IntEnum):
    """rclpy's history policies.  KEEP_LAST keeps the newest `depth` messages per queue;
    KEEP_ALL keeps every message not yet handed on (depth is then ignored); SYSTEM_DEFAULT is
    KEEP_LAST (of 1 when the depth is 0, Cyclone's default)."""

    SYSTEM_DEFAULT = 0
    KEEP_LAST = 1
    KEEP_ALL = 2


class DurabilityPolicy(IntEnum):
    """rclpy's durability policies.  TRANSIENT_LOCAL: a publisher keeps its last `depth`
    messages and hands them to subscriptions that join later (and ask for TRANSIENT_LOCAL too),
    as a latched topic does; VOLATILE (the default): a late subscription gets only new messages.
    SYSTEM_DEFAULT is VOLATILE (DDS's default)."""

    SYSTEM_DEFAULT = 0
    TRANSIENT_LOCAL = 1
    VOLATILE = 2


# rclpy's older names
QoSReliabilityPolicy = ReliabilityPolicy
QoSHistoryPolicy = HistoryPolicy
QoSDurabilityPolicy = DurabilityPolicy


def _policy(enum: type[IntEnum], value: Any, keyword: str) -> Any:
    """`value` as a member of `enum`, or a ValueError naming the keyword and the choices."""
    try:
        return enum(value)
    except (ValueError, TypeError):
        choices = ", ".join(f"{enum.__name__}.{m.name}" for m in enum)
        raise ValueError(f"QoSProfile(): {keyword} must be one of {choices}, not {value!r}") from None


class QoSProfile:
    """rclpy's QoSProfile: history and depth, reliability and durability.  Depth and durability
    matter in process too; reliability matters only over DDS (see ReliabilityPolicy).  Other
    policies (deadline, lifespan, liveliness...) are accepted where rclpy takes them and ignored.
    Unlike rclpy, `depth` defaults to 10 (rclpy demands history or depth)."""

    _FIELDS = ("history", "depth", "reliability", "durability")

    def __init__(
        self,
        depth: int = 10,
        *,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
        durability: DurabilityPolicy = DurabilityPolicy.VOLATILE,
        history: HistoryPolicy = HistoryPolicy.KEEP_LAST,
        **_ignored: Any,
    ) -> None:
        self.depth = depth
        self.reliability: ReliabilityPolicy = _policy(ReliabilityPolicy, reliability, "reliability")
        self.durability: DurabilityPolicy = _policy(DurabilityPolicy, durability, "durability")
        self.history: HistoryPolicy = _policy(HistoryPolicy, history, "history")

    def _key(self) -> tuple[Any, ...]:
        return tuple(getattr(self, k) for k in self._FIELDS)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, QoSProfile):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return (
            f"QoSProfile(history={self.history.name}, depth={self.depth}, "
            f"reliability={self.reliability.name}, durability={self.durability.name})"
        )


# rclpy's preset profiles (rmw's qos_profiles.h)
qos_profile_sensor_data = QoSProfile(5, reliability=ReliabilityPolicy.BEST_EFFORT)
qos_profile_system_default = QoSProfile(
    0,
    reliability=ReliabilityPolicy.SYSTEM_DEFAULT,
    durability=DurabilityPolicy.SYSTEM_DEFAULT,
    history=HistoryPolicy.SYSTEM_DEFAULT,
)
qos_profile_services_default = QoSProfile(10)
qos_profile_parameters = QoSProfile(1000)
qos_profile_parameter_events = QoSProfile(1000)


@dataclass(frozen=True, slots=True)
class _Qos:
    """A profile (or a bare depth) as an endpoint uses it: `depth` None keeps all."""

    depth: int | None
    reliability: ReliabilityPolicy
    transient_local: bool


def _resolve(qos: int | QoSProfile, where: str) -> _Qos:
    if not isinstance(qos, QoSProfile):
        return _Qos(_depth(qos, where), ReliabilityPolicy.RELIABLE, False)
    transient_local = qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
    if qos.history == HistoryPolicy.KEEP_ALL:
        return _Qos(None, qos.reliability, transient_local)
    depth = qos.depth
    if qos.history == HistoryPolicy.SYSTEM_DEFAULT and depth == 0:
        depth = 1
    return _Qos(_depth(depth, where), qos.reliability, transient_local)


def _depth(depth: Any, where: str) -> int:
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise ValueError(f"{where}: the QoS depth must be an integer >= 1, not {depth!r}")
    return depth


def _type_name(obj: object) -> str:
    t = obj if isinstance(obj, type) else type(obj)
    return getattr(t, "_TYPE", "") or t.__name__


# -- publishers and subscriptions -----------------------------------------------------------------


class Publisher:
    __slots__ = (
        "_bus",
        "_destroyed",
        "_remote",
        "_topic",
        "_type",
        "depth",
        "msg_type",
        "node",
        "reliability",
        "topic_name",
    )

    #: TRANSIENT_LOCAL (see _LatchingPublisher): a transport gives its writer that durability.
    transient_local = False

    def __init__(
        self,
        node: Node,
        msg_type: type[Message],
        topic: str,
        depth: int | None = 10,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        self._bus = node._bus
        self.node = node
        self.topic_name = node.resolve_topic_name(topic)
        self._topic = node._bus.topic(self.topic_name, msg_type, "publish on")
        self._topic.publishers += 1
        self._type = self.msg_type = msg_type
        self.depth = depth  # None: KEEP_ALL
        self.reliability = reliability  # the transport's writer offers it; in process nothing is lost
        self._destroyed = False
        self._remote = node._bus.transport.publisher(self)  # None unless the transport has one

    def publish(self, msg: Message) -> None:
        if type(msg) is not self._type:
            raise TypeError(
                f"publish() on {self.topic_name}: expected a {self._type._TYPE} message, got {_type_name(msg)}"
            )
        topic = self._topic
        topic.published += 1
        for reader in topic.readers:
            reader._deliver(msg._copy())
        if topic.taps:
            for tap in topic.taps:
                tap(msg)
        if self._remote is not None:
            self._remote.write(msg)

    def get_subscription_count(self) -> int:
        remote = self._remote.subscription_count() if self._remote is not None else 0
        return len(self._topic.readers) + len(self._topic.taps) + remote

    def destroy(self) -> None:
        if not self._destroyed:
            self._destroyed = True
            self._topic.publishers -= 1
            self._topic.latched.pop(self, None)
            if self._remote is not None:
                self._remote.close()


class _LatchingPublisher(Publisher):
    """A TRANSIENT_LOCAL publisher: also keeps its last `depth` messages on the topic, for
    subscriptions that join later (a DDS transport gives its writer the same durability).
    A subclass, so volatile publishers pay nothing for it."""

    __slots__ = ()
    transient_local = True

    def __init__(
        self,
        node: Node,
        msg_type: type[Message],
        topic: str,
        depth: int | None,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        super().__init__(node, msg_type, topic, depth, reliability)
        self._topic.latched[self] = deque(maxlen=depth)

    def publish(self, msg: Message) -> None:
        super().publish(msg)
        kept = self._topic.latched.get(self)
        if kept is not None:
            kept.append(msg._copy())


class Subscription:
    """A reader of a topic.  PUSH (with a callback): messages queue up to the QoS depth and the
    callback runs when the executor spins.  PULL (callback None, clfsm's preferred style):
    `latest` is the newest message, `take()` the newest one not taken yet, `count` how many came."""

    __slots__ = (
        "_bus",
        "_destroyed",
        "_fresh",
        "_queue",
        "_remote",
        "_scheduled",
        "_topic",
        "callback",
        "count",
        "depth",
        "latest",
        "msg_type",
        "node",
        "reliability",
        "topic_name",
        "transient_local",
    )

    def __init__(
        self,
        node: Node,
        msg_type: type[Message],
        topic: str,
        callback: Callable[[Any], Any] | None,
        depth: int | None,
        transient_local: bool = False,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        self._bus = node._bus
        self.topic_name = node.resolve_topic_name(topic)
        self._topic = node._bus.topic(self.topic_name, msg_type, "subscribe to")
        self.msg_type = msg_type
        self.callback = callback
        self.count = 0
        self.latest: Any = None
        self._fresh = False
        self._queue: deque[Any] = deque(maxlen=depth)
        self._scheduled = False
        self._destroyed = False
        topic = self._topic
        for fn in topic.on_readers:  # before joining: a latched value can still be brought up to date
            fn(topic, True)
        topic.readers.append(self)
        if transient_local:  # a late joiner gets what TRANSIENT_LOCAL publishers kept, oldest first
            for kept in list(topic.latched.values()):
                for msg in kept:
                    self._deliver(msg._copy())
        self.node = node
        self.depth = depth  # None: KEEP_ALL
        self.transient_local = transient_local
        self.reliability = reliability  # what the transport's reader asks for
        self._remote = node._bus.transport.subscription(self)  # brings in other processes' messages

    def _deliver(self, msg: Any) -> None:
        self.latest = msg
        self.count += 1
        if self.callback is None:
            self._fresh = True
            return
        self._queue.append(msg)  # a full queue drops its oldest message
        if not self._scheduled:
            self._scheduled = True
            self._bus.queue(self)

    def _run(self) -> None:
        """Executor work: hand the messages queued so far to the callback, oldest first.  What
        callbacks publish meanwhile waits for the next spin, so a callback that publishes on
        its own topic cannot loop forever."""
        queue = self._queue
        self._scheduled = False
        for _ in range(len(queue)):
            if self._destroyed:
                return
            self.callback(queue.popleft())  # type: ignore[misc]

    def take(self) -> Any:
        """The newest message not taken yet, or None (PULL readers)."""
        if self._fresh:
            self._fresh = False
            return self.latest
        return None

    def destroy(self) -> None:
        if not self._destroyed:
            self._destroyed = True
            topic = self._topic
            topic.readers.remove(self)
            for fn in topic.on_readers:
                fn(topic, False)
            if self._remote is not None:
                self._remote.close()


# -- services --------------------------------------------------------------------------------------


class ServiceServer:
    def __init__(self, node: Node, srv_type: type[Service], name: str, callback: Callable[[Any, Any], Any]) -> None:
        self._bus = node._bus
        self.srv_name = node.resolve_service_name(name)
        if self.srv_name in self._bus.services:
            raise ValueError(f"create_service(): {self.srv_name} already has a server; a service has exactly one")
        self.type = srv_type
        self.callback = callback
        self.node = node
        self._bus.services[self.srv_name] = self
        self._remote = self._bus.transport.service(self)  # answers other processes' clients

    def _answer(self, request: Message) -> Message:
        response = self.callback(request, self.type.Response())
        if type(response) is not self.type.Response:
            raise TypeError(
                f"the callback of service {self.srv_name} must return the {self.type.Response._TYPE} it was "
                f"given (filled in), not {_type_name(response)}"
            )
        return response

    def _serve(self, request: Message, future: Future) -> None:
        future.set_result(self._answer(request)._copy())

    def destroy(self) -> None:
        if self._bus.services.get(self.srv_name) is self:
            del self._bus.services[self.srv_name]
        if self._remote is not None:
            self._remote.close()
            self._remote = None


class Client:
    def __init__(self, node: Node, srv_type: type[Service], name: str) -> None:
        self._bus = node._bus
        self.node = node
        self.srv_name = node.resolve_service_name(name)
        self.srv_type = srv_type
        self._remote = self._bus.transport.client(self)  # reaches servers of other processes

    def service_is_ready(self) -> bool:
        """A server in this process, or (DDS) one in another process matched both ways."""
        if self.srv_name in self._bus.services:
            return True
        return self._remote is not None and self._remote.ready()

    def wait_for_service(self, timeout_sec: float | None = None) -> bool:
        """True once a server exists.  Waits (the sim clock jumps) at most timeout_sec, running due
        timers meanwhile; with no timeout it does not block in process (nothing else in this
        process could create the server while this machine waits) and waits for one as rclpy
        does with a remote transport (until Ctrl-C or the run's --duration)."""
        if self.service_is_ready():
            return True
        bus = self._bus
        if timeout_sec is None and self._remote is not None:
            while bus.ok() and (bus.ctx.deadline is None or bus.clock.now < bus.ctx.deadline):
                bus.spin_once(100_000_000)
                if self.service_is_ready():
                    return True
            return False
        if timeout_sec is None or timeout_sec <= 0:
            return False
        deadline = bus.clock.now + round(timeout_sec * 1e9)
        while bus.clock.now < deadline:
            if self._remote is not None and not bus.ok():
                return False  # Ctrl-C while waiting for another process, as rclpy after shutdown
            bus.spin_once(deadline - bus.clock.now)
            if self.service_is_ready():
                return True
        return False

    def call_async(self, request: Message) -> Future:
        if type(request) is not self.srv_type.Request:
            raise TypeError(
                f"call_async() on {self.srv_name}: expected a {self.srv_type.Request._TYPE}, got {_type_name(request)}"
            )
        if self._remote is not None and self.srv_name not in self._bus.services:
            future = Future(self.srv_name, self._remote)
            self._remote.send(request, future)
            return future
        return self._bus.call(self.srv_name, request._copy())

    def call(self, request: Message, timeout_sec: float | None = None) -> Any:
        """Synchronous call: spins until the response; raises TimeoutError if none can come."""
        from .bus import FutureReturnCode

        future = self.call_async(request)
        code = self._bus.spin_until(future, None if timeout_sec is None else round(timeout_sec * 1e9))
        if code is not FutureReturnCode.SUCCESS:
            raise TimeoutError(f"no response from {self.srv_name} ({code.name})")
        return future.result()

    def destroy(self) -> None:
        if self._remote is not None:
            self._remote.close()
            self._remote = None


# -- timers ------------------------------------------------------------------------------------------


class Timer:
    """Calls back every period of run time; the first call is one period after creation."""

    __slots__ = ("_bus", "_cancelled", "_due", "callback", "period_ns")

    def __init__(self, bus: Bus, period_sec: float, callback: Callable[[], Any]) -> None:
        if isinstance(period_sec, bool) or not isinstance(period_sec, int | float) or not period_sec > 0:
            raise ValueError(f"create_timer(): the period must be a number of seconds > 0, not {period_sec!r}")
        self._bus = bus
        self.period_ns = max(1, round(period_sec * 1e9))
        self.callback = callback
        self._cancelled = False
        self._due = bus.clock.now + self.period_ns
        bus.add_timer(self, self._due)

    def _call(self) -> None:
        self.callback()

    @property
    def timer_period_ns(self) -> int:
        return self.period_ns

    def cancel(self) -> None:
        self._cancelled = True

    def is_canceled(self) -> bool:
        return self._cancelled

    def reset(self) -> None:
        self._cancelled = False
        self._due = self._bus.clock.now + self.period_ns
        self._bus.add_timer(self, self._due)

    def time_until_next_call(self) -> int:
        return max(0, self._due - self._bus.clock.now)

    def destroy(self) -> None:
        self.cancel()


# -- logging -----------------------------------------------------------------------------------------


class LoggingSeverity(IntEnum):
    UNSET = 0
    DEBUG = 10
    INFO = 20
    WARN = 30
    ERROR = 40
    FATAL = 50


class Logger:
    """rclpy's logger: `[INFO] [seconds.nanoseconds] [name]: message`, on stderr as ROS 2 Humble
    does (RCUTILS_LOGGING_USE_STDOUT=1 sends it to stdout).  Under the sim clock the stamp is run
    time, so logs are reproducible too."""

    def __init__(self, bus: Bus, name: str) -> None:
        self._bus = bus
        self.name = name
        self.level = LoggingSeverity.INFO
        self._once: set[tuple[str, str]] = set()
        self._last: dict[tuple[str, str], int] = {}

    def get_name(self) -> str:
        return self.name

    def set_level(self, level: LoggingSeverity | int) -> None:
        self.level = LoggingSeverity(level)

    def get_child(self, name: str) -> Logger:
        child = Logger(self._bus, f"{self.name}.{name}")
        child.level = self.level
        return child

    def log(
        self,
        message: object,
        severity: LoggingSeverity,
        *,
        once: bool = False,
        throttle_duration_sec: float | None = None,
        skip_first: bool = False,
    ) -> bool:
        if severity < self.level:
            return False
        text = str(message)
        key = (severity.name, text)
        if once:
            if key in self._once:
                return False
            self._once.add(key)
        if skip_first and key not in self._last:
            self._last[key] = self._bus.clock.now
            return False
        if throttle_duration_sec is not None:
            last = self._last.get(key)
            if last is not None and self._bus.clock.now - last < throttle_duration_sec * 1e9:
                return False
            self._last[key] = self._bus.clock.now
        sec, nsec = self._bus.stamp()
        stream = self._bus.log_output()
        stream.write(f"[{severity.name}] [{sec}.{nsec:09d}] [{self.name}]: {text}\n")
        stream.flush()
        return True

    def debug(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.DEBUG, **kw)

    def info(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.INFO, **kw)

    def warning(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.WARN, **kw)

    warn = warning

    def error(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.ERROR, **kw)

    def fatal(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.FATAL, **kw)


# -- parameters and time --------------------------------------------------------------------------------


@dataclass
class Parameter:
    name: str
    value: Any = None

    def get_parameter_value(self) -> Any:
        return self.value


@dataclass(frozen=True)
class Time:
    nanoseconds: int

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, 1_000_000_000)


class RunClock:
    """`node.get_clock()`: the run clock (virtual under --clock sim)."""

    def __init__(self, bus: Bus) -> None:
        self._bus = bus

    def now(self) -> Time:
        return Time(self._bus.clock.now)


# -- the node ------------------------------------------------------------------------------------------


class Node:
    """A participant on the bus, as `rclpy.node.Node`.  Names follow ROS 2 rules: relative names
    take the node's namespace, `~/x` is private to the node, and `--remap` rules apply."""

    def __init__(
        self, node_name: str, namespace: str = "", *, start_parameter_services: bool = True, **_ignored: Any
    ) -> None:
        bus = bus_of()
        if not bus.initialised:
            raise RuntimeError("call ros.init() before creating a node")
        name, ns = remap_node(validate_node_name(node_name), normalise_namespace(namespace), bus.remaps)
        self._bus = bus
        self._name = name
        self._ns = ns
        self._destroyed = False
        self._entities: list[Any] = []
        self._params: dict[str, Parameter] = {}
        logger_name = ".".join([*ns.strip("/").split("/"), name]) if ns != "/" else name
        self._logger = Logger(bus, logger_name)
        bus.nodes.append(self)
        bus.transport.node_changed(self)

    # names
    def get_name(self) -> str:
        return self._name

    def get_namespace(self) -> str:
        return self._ns

    def get_fully_qualified_name(self) -> str:
        return f"{self._ns.rstrip('/')}/{self._name}"

    def resolve_topic_name(self, topic: str) -> str:
        full = expand(topic, self._name, self._ns, "topic")
        return remap_name(full, self._name, self._ns, self._bus.remaps, "topic")

    def resolve_service_name(self, service: str) -> str:
        full = expand(service, self._name, self._ns, "service")
        return remap_name(full, self._name, self._ns, self._bus.remaps, "service")

    # entities
    def _check(self) -> None:
        if self._destroyed:
            raise RuntimeError(f"node {self.get_fully_qualified_name()} has been destroyed")

    def create_publisher(
        self, msg_type: type[Message], topic: str, qos_profile: int | QoSProfile = 10, **_ignored: Any
    ) -> Publisher:
        self._check()
        if not is_message_class(msg_type):
            raise TypeError(f"create_publisher(): msg_type must be a message class such as Twist, not {msg_type!r}")
        qos = _resolve(qos_profile, "create_publisher()")
        if qos.transient_local:
            pub: Publisher = _LatchingPublisher(self, msg_type, topic, qos.depth, qos.reliability)
        else:
            pub = Publisher(self, msg_type, topic, qos.depth, qos.reliability)
        self._entities.append(pub)
        self._bus.transport.node_changed(self)
        return pub

    def create_subscription(
        self,
        msg_type: type[Message],
        topic: str,
        callback: Callable[[Any], Any] | None,
        qos_profile: int | QoSProfile = 10,
        **_ignored: Any,
    ) -> Subscription:
        self._check()
        if not is_message_class(msg_type):
            raise TypeError(f"create_subscription(): msg_type must be a message class such as Twist, not {msg_type!r}")
        if callback is not None and not callable(callback):
            raise TypeError("create_subscription(): callback must be callable, or None for a PULL reader")
        qos = _resolve(qos_profile, "create_subscription()")
        sub = Subscription(self, msg_type, topic, callback, qos.depth, qos.transient_local, qos.reliability)
        self._entities.append(sub)
        self._bus.transport.node_changed(self)
        return sub

    def create_service(
        self, srv_type: type[Service], srv_name: str, callback: Callable[[Any, Any], Any], **_ignored: Any
    ) -> ServiceServer:
        self._check()
        if not is_service_class(srv_type):
            raise TypeError(f"create_service(): srv_type must be a service class such as Spawn, not {srv_type!r}")
        if not callable(callback):
            raise TypeError("create_service(): callback must be callable as callback(request, response)")
        srv = ServiceServer(self, srv_type, srv_name, callback)
        self._entities.append(srv)
        self._bus.transport.node_changed(self)
        return srv

    def create_client(self, srv_type: type[Service], srv_name: str, **_ignored: Any) -> Client:
        self._check()
        if not is_service_class(srv_type):
            raise TypeError(f"create_client(): srv_type must be a service class such as Spawn, not {srv_type!r}")
        cli = Client(self, srv_type, srv_name)
        self._entities.append(cli)
        self._bus.transport.node_changed(self)
        return cli

    def create_timer(self, timer_period_sec: float, callback: Callable[[], Any], **_ignored: Any) -> Timer:
        self._check()
        timer = Timer(self._bus, timer_period_sec, callback)
        self._entities.append(timer)
        return timer

    def destroy_publisher(self, p: Publisher) -> None:
        p.destroy()

    def destroy_subscription(self, s: Subscription) -> None:
        s.destroy()

    def destroy_service(self, s: ServiceServer) -> None:
        s.destroy()

    def destroy_timer(self, t: Timer) -> None:
        t.destroy()

    def destroy_client(self, c: Client) -> None:
        c.destroy()

    def destroy_node(self) -> None:
        for e in self._entities:
            e.destroy()
        self._entities.clear()
        self._destroyed = True
        self._bus.transport.node_changed(self)

    # logging, time, parameters
    def get_logger(self) -> Logger:
        return self._logger

    def get_clock(self) -> RunClock:
        return RunClock(self._bus)

    def declare_parameter(self, name: str, value: Any = None, *_args: Any, **_kw: Any) -> Parameter:
        overrides = self._bus.parameters
        for key in ((self._name, name), (None, name)):
            if key in overrides:
                value = overrides[key]
                break
        p = self._params[name] = Parameter(name, value)
        return p

    def has_parameter(self, name: str) -> bool:
        return name in self._params

    def get_parameter(self, name: str) -> Parameter:
        if name not in self._params:
            raise KeyError(f"parameter {name!r} of node {self._name} is not declared")
        return self._params[name]

    def set_parameters(self, parameters: list[Parameter]) -> list[bool]:
        for p in parameters:
            self._params[p.name] = Parameter(p.name, p.value)
        return [True] * len(parameters)
