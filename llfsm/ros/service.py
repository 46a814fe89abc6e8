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
                f"given (filled in), not {type_name(response)}"
            )
        return response

    def destroy(self) -> None:
        if self._bus.services.get(self.srv_name) is self:
            del self._bus.services[self.srv_name]
        if self._remote is not None:
            self._remote.close()
            self._remote = None


Service = ServiceServer  # rclpy calls the server object `Service`
