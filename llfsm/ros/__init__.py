"""`from llfsm import ros`: an rclpy look-alike over llfsm's in-process bus.

    ros.init()                              # any machine may call it; the first call initialises
    node = ros.Node("ros_ping_pong")
    pub = node.create_publisher(String, "pingpong", 10)
    pub.publish(msg)
    reader = node.create_subscription(Pose, "/turtle1/pose", None, 10)   # PULL: reader.latest
    client = node.create_client(TurtlePosition, "turtle_pose_service")
    code = ros.spin_until_future_complete(node, client.call_async(TurtlePosition.Request()))
    ros.ok()                                # false after Ctrl-C: machines take their END transitions

Deterministic under `--clock sim`; see docs/bus.md.  This module is the public door: each
entity lives in a module of its own, as in rclpy (node, publisher, subscription, service,
client, timer, qos, parameters, logging, clock, task, executor; actions in action/), on top of
the bus (bus.py) and its transports (transports/).
"""

from __future__ import annotations

from typing import Any

from .action import (
    ActionClient,
    ActionServer,
    CancelResponse,
    ClientGoalHandle,
    GoalResponse,
    ServerGoalHandle,
    qos_profile_action_status_default,
)
from .bus import Bus, bus_of
from .client import Client
from .clock import Time
from .executor import FutureReturnCode, spin, spin_once, spin_until_future_complete
from .logging import Logger, LoggingSeverity
from .names import InvalidNameError, Remap
from .node import Node
from .parameters import Parameter
from .publisher import Publisher
from .qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSDurabilityPolicy,
    QoSHistoryPolicy,
    QoSProfile,
    QoSReliabilityPolicy,
    ReliabilityPolicy,
    qos_profile_parameter_events,
    qos_profile_parameters,
    qos_profile_rosout_default,
    qos_profile_sensor_data,
    qos_profile_services_default,
    qos_profile_system_default,
)
from .service import Service, ServiceServer
from .subscription import Subscription
from .task import Future
from .timer import Timer

__all__ = [
    "ActionClient",
    "ActionServer",
    "Bus",
    "CancelResponse",
    "Client",
    "ClientGoalHandle",
    "DurabilityPolicy",
    "Future",
    "FutureReturnCode",
    "GoalResponse",
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
    "ServerGoalHandle",
    "Service",
    "ServiceServer",
    "Subscription",
    "Time",
    "Timer",
    "init",
    "ok",
    "qos_profile_action_status_default",
    "qos_profile_parameter_events",
    "qos_profile_parameters",
    "qos_profile_rosout_default",
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
