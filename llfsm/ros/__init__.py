"""`from llfsm import ros`: an rclpy look-alike over llfsm's in-process bus.

    ros.init()                              # any machine may call it; the first call initialises
    node = ros.Node("ros_ping_pong")
    pub = node.create_publisher(String, "pingpong", 10)
    pub.publish(msg)
    reader = node.create_subscription(Pose, "/turtle1/pose", None, 10)   # PULL: reader.latest
    client = node.create_client(TurtlePosition, "turtle_pose_service")
    code = ros.spin_until_future_complete(node, client.call_async(TurtlePosition.Request()))
    ros.ok()                                # false after Ctrl-C: machines take their END transitions

Deterministic under `--clock sim`; see docs/bus.md.
"""

from __future__ import annotations

from typing import Any

from .bus import Bus, Future, FutureReturnCode, bus_of
from .names import InvalidNameError, Remap
from .node import (
    Client,
    DurabilityPolicy,
    HistoryPolicy,
    Logger,
    LoggingSeverity,
    Node,
    Parameter,
    Publisher,
    QoSDurabilityPolicy,
    QoSHistoryPolicy,
    QoSProfile,
    QoSReliabilityPolicy,
    ReliabilityPolicy,
    ServiceServer,
    Subscription,
    Time,
    Timer,
    qos_profile_parameter_events,
    qos_profile_parameters,
    qos_profile_sensor_data,
    qos_profile_services_default,
    qos_profile_system_default,
)

Service = ServiceServer  # rclpy calls the server object `Service`

__all__ = [
    "Bus",
    "Client",
    "DurabilityPolicy",
    "Future",
    "FutureReturnCode",
    "HistoryPolicy",
    "InvalidNameError",
    "Logger",
    "LoggingSeverity",
    "Node",
    "Parameter",
    "Publisher",
    "QoSDurabilityPolicy",
    "QoSHistoryPolicy",
    "QoSProfile",
    "QoSReliabilityPolicy",
    "ReliabilityPolicy",
    "Remap",
    "Service",
    "ServiceServer",
    "Subscription",
    "Time",
    "Timer",
    "init",
    "ok",
    "qos_profile_parameter_events",
    "qos_profile_parameters",
    "qos_profile_sensor_data",
    "qos_profile_services_default",
    "qos_profile_system_default",
    "shutdown",
    "spin",
    "spin_once",
    "spin_until_future_complete",
]


def init(args: list[str] | None = None, **_ignored: Any) -> None:
    """Initialise the bus of this run.  Every machine may call it; later calls do nothing."""
    bus_of().init()


def ok() -> bool:
    """True between `init()` and `shutdown()`, until Ctrl-C / SIGTERM interrupts the run."""
    return bus_of().ok()


def shutdown(**_ignored: Any) -> None:
    """Every machine then sees `ok()` false and can take its transition to END."""
    bus_of().shut = True


def _ns(timeout_sec: float | None) -> int | None:
    if timeout_sec is None:
        return None
    if isinstance(timeout_sec, bool) or not isinstance(timeout_sec, int | float) or timeout_sec < 0:
        raise ValueError(f"timeout_sec must be a number of seconds >= 0 or None, not {timeout_sec!r}")
    return round(timeout_sec * 1e9)


def spin_once(node: Node, *, timeout_sec: float | None = 0) -> None:
    """Run one callback, timer or service request if one is ready; else wait up to timeout_sec
    for the next timer (the sim clock jumps there, the wall clock sleeps)."""
    bus = node._bus
    timeout = _ns(timeout_sec)
    if timeout is None:
        timeout = (bus.ctx.deadline - bus.clock.now) if bus.ctx.deadline is not None else 0
    bus.spin_once(timeout)


def spin_until_future_complete(node: Node, future: Future, timeout_sec: float | None = None) -> FutureReturnCode:
    """Spin until the future is done (SUCCESS), ok() turns false (INTERRUPTED), or the timeout
    passes (TIMEOUT).  A request to a service that has no server is TIMEOUT at once: nothing in
    this process could ever answer it, so it never hangs."""
    if not isinstance(future, Future):
        raise TypeError(f"spin_until_future_complete(): expected a Future, not {type(future).__name__}")
    return node._bus.spin_until(future, _ns(timeout_sec))


def spin(node: Node) -> None:
    """Spin until ok() turns false or the run's --duration; inside a machine prefer spin_once."""
    bus = node._bus
    while bus.ok():
        if bus.ctx.deadline is not None and bus.clock.now >= bus.ctx.deadline:
            return
        if bus.transport.remote:  # other processes can always bring something: wait for it
            bus.spin_once(100_000_000)
            continue
        if not bus.spin_once(0) and bus.next_timer_due() is None:
            return  # nothing can ever happen: do not hang
        if not bus.ready:
            due = bus.next_timer_due()
            if due is not None and due > bus.clock.now:
                bus.clock.sleep_until(due)


def parse_param(text: str) -> tuple[str | None, str, Any]:
    """`--param [node:]name:=value` -> (node or None, name, value); the value is read as a
    YAML-like scalar: true/false, an int, a float, else a string."""
    if ":=" not in text:
        raise ValueError(f"--param {text!r}: expected [NODE:]NAME:=VALUE")
    left, raw = text.split(":=", 1)
    node, _, name = left.rpartition(":")
    if not name:
        raise ValueError(f"--param {text!r}: expected [NODE:]NAME:=VALUE")
    value: Any
    low = raw.strip().lower()
    if low in ("true", "false"):
        value = low == "true"
    else:
        try:
            value = int(raw)
        except ValueError:
            try:
                value = float(raw)
            except ValueError:
                value = raw
    return (node or None), name, value
