"""Service servers, as `rclpy.service`: `node.create_service(S, name, callback)`.

A request from this process is served in the executor's turn (bus.py queues it); one from
another process arrives through the transport, which calls `_answer` the same way.  See
docs/bus.md (Services, clients and futures).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .names import type_name

if TYPE_CHECKING:
    from ..msgs._message import Message
    from ..msgs._message import Service as ServiceType
    from .bus import Bus
    from .transports.base import NodeView


class ServiceServer:
    def __init__(
        self,
        bus: Bus,
        node: NodeView,
        srv_type: type[ServiceType],
        srv_name: str,
        callback: Callable[[Any, Any], Any],
    ) -> None:
        """`srv_name` is resolved (the node expanded and remapped it)."""
        self._bus = bus
        self.srv_name = srv_name
        old = self._bus.services.get(self.srv_name)
        if old is not None and not _same_node(old.node, node):
            raise ValueError(f"create_service(): {self.srv_name} already has a server; a service has exactly one")
        # A node made again under its old name (a machine restarted re-runs `node = ros.Node(...)`)
        # takes over the old node's services: the old one is destroyed once the machine's
        # variable no longer holds it (lifetimes.py), and its destroy() leaves the new server be.
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
                f"given (filled in), not {type_name(response)}"
            )
        return response

    def destroy(self) -> None:
        if self._bus.services.get(self.srv_name) is self:
            del self._bus.services[self.srv_name]
        if self._remote is not None:
            self._remote.close()
            self._remote = None


def _same_node(a: NodeView, b: NodeView) -> bool:
    """Two nodes of one name, a different object (the server of the same node twice stays refused)."""
    return a is not b and (a.get_namespace(), a.get_name()) == (b.get_namespace(), b.get_name())


Service = ServiceServer  # rclpy calls the server object `Service`
