"""Nodes, as `rclpy.node.Node`: a participant on the bus, and what creates its publishers,
subscriptions, services, clients and timers (each entity in its own module, as in rclpy).

Names follow ROS 2 rules (names.py); see docs/bus.md (Nodes and names).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..msgs._message import Message, Service, is_message_class, is_service_class
from ..msgs.rcl_interfaces.msg import Log, ParameterEvent
from .bus import bus_of
from .client import Client
from .clock import RunClock
from .logging import Logger
from .names import expand, normalise_namespace, remap_name, remap_node, validate_node_name
from .parameter_service import ParameterService
from .parameters import Parameter, ParameterHost, overrides_for
from .publisher import LatchingPublisher, Publisher
from .qos import QoSProfile, qos_profile_parameter_events, qos_profile_rosout_default
from .qos import resolve as resolve_qos
from .service import ServiceServer
from .subscription import Subscription
from .timer import Timer


class Node(ParameterHost):
    """A participant on the bus, as `rclpy.node.Node`.  Names follow ROS 2 rules: relative names
    take the node's namespace, `~/x` is private to the node, and `--remap` rules apply.  Its
    parameters (ParameterHost, parameters.py) are rclpy's, served to other processes unless
    `start_parameter_services=False` (the hidden nodes of `llfsm topic pub` and the like).  Its
    logger's lines are published on /rosout unless `enable_rosout=False`, as in rclpy."""

    def __init__(
        self,
        node_name: str,
        namespace: str = "",
        *,
        start_parameter_services: bool = True,
        enable_rosout: bool = True,
        rosout_qos_profile: int | QoSProfile = qos_profile_rosout_default,
        parameter_overrides: list[Parameter] | None = None,
        allow_undeclared_parameters: bool = False,
        automatically_declare_parameters_from_overrides: bool = False,
        **_ignored: Any,
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
        logger_name = ".".join([*ns.strip("/").split("/"), name]) if ns != "/" else name
        bus.nodes.append(self)
        bus.transport.node_changed(self)
        bus.lifetimes.created()
        rosout = self.create_publisher(Log, "/rosout", rosout_qos_profile) if enable_rosout else None
        self._logger = Logger(bus, logger_name, rosout)
        events = (
            self.create_publisher(ParameterEvent, "/parameter_events", qos_profile_parameter_events)
            if start_parameter_services
            else None
        )
        self._init_parameters(
            overrides_for(bus, name, self.get_fully_qualified_name()),
            parameter_overrides,
            allow_undeclared_parameters,
            events,
        )
        if automatically_declare_parameters_from_overrides:
            self.declare_parameters("", [(n, p.value) for n, p in self._parameter_overrides.items()])
        if start_parameter_services:
            ParameterService(self)

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
        qos = resolve_qos(qos_profile, "create_publisher()")
        kind = LatchingPublisher if qos.transient_local else Publisher
        pub = kind(self._bus, self, msg_type, self.resolve_topic_name(topic), qos.depth, qos.reliability)
        self._entities.append(pub)
        self._bus.transport.node_changed(self)
        self._bus.lifetimes.created()
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
        qos = resolve_qos(qos_profile, "create_subscription()")
        name = self.resolve_topic_name(topic)
        sub = Subscription(self._bus, self, msg_type, name, callback, qos.depth, qos.transient_local, qos.reliability)
        self._entities.append(sub)
        self._bus.transport.node_changed(self)
        self._bus.lifetimes.created()
        return sub

    def create_service(
        self, srv_type: type[Service], srv_name: str, callback: Callable[[Any, Any], Any], **_ignored: Any
    ) -> ServiceServer:
        self._check()
        if not is_service_class(srv_type):
            raise TypeError(f"create_service(): srv_type must be a service class such as Spawn, not {srv_type!r}")
        if not callable(callback):
            raise TypeError("create_service(): callback must be callable as callback(request, response)")
        srv = ServiceServer(self._bus, self, srv_type, self.resolve_service_name(srv_name), callback)
        self._entities.append(srv)
        self._bus.transport.node_changed(self)
        self._bus.lifetimes.created()
        return srv

    def create_client(self, srv_type: type[Service], srv_name: str, **_ignored: Any) -> Client:
        self._check()
        if not is_service_class(srv_type):
            raise TypeError(f"create_client(): srv_type must be a service class such as Spawn, not {srv_type!r}")
        cli = Client(self._bus, self, srv_type, self.resolve_service_name(srv_name))
        self._entities.append(cli)
        self._bus.transport.node_changed(self)
        self._bus.lifetimes.created()
        return cli

    def create_timer(self, timer_period_sec: float, callback: Callable[[], Any], **_ignored: Any) -> Timer:
        self._check()
        timer = Timer(self._bus, timer_period_sec, callback)
        self._entities.append(timer)
        self._bus.lifetimes.created()
        return timer

    def _destroy_entity(self, e: Any) -> None:
        """Destroy one of this node's entities and take it out of the graph (rclpy's
        destroy_publisher and the like; llfsm.ros.lifetimes when machine code dropped it)."""
        e.destroy()
        if e in self._entities:
            self._entities.remove(e)
            self._bus.transport.node_changed(self)

    def destroy_publisher(self, p: Publisher) -> None:
        self._destroy_entity(p)

    def destroy_subscription(self, s: Subscription) -> None:
        self._destroy_entity(s)

    def destroy_service(self, s: ServiceServer) -> None:
        self._destroy_entity(s)

    def destroy_timer(self, t: Timer) -> None:
        self._destroy_entity(t)

    def destroy_client(self, c: Client) -> None:
        self._destroy_entity(c)

    def destroy_node(self) -> None:
        """Destroy the node's entities and leave the graph (`node list` no longer shows it)."""
        if self._destroyed:
            return
        for e in self._entities:
            e.destroy()
        self._entities.clear()
        self._destroyed = True
        self._bus.transport.node_changed(self)
        if self in self._bus.nodes:
            self._bus.nodes.remove(self)

    # logging, time (parameters: ParameterHost)
    def get_logger(self) -> Logger:
        return self._logger

    def get_clock(self) -> RunClock:
        return RunClock(self._bus)
