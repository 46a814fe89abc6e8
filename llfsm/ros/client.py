"""Service clients, as `rclpy.client`: `node.create_client(S, name)`.

A server of this process answers in the executor's turn; with a remote transport a server of
another process may answer instead.  `call` is the synchronous form (runtime/errors.py names a
service called again from its own callback by this module's `call` frames).  See docs/bus.md
(Services, clients and futures).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .executor import FutureReturnCode
from .names import type_name
from .task import Future

if TYPE_CHECKING:
    from ..msgs._message import Message
    from ..msgs._message import Service as ServiceType
    from .bus import Bus
    from .transports.base import NodeView


class Client:
    def __init__(self, bus: Bus, node: NodeView, srv_type: type[ServiceType], srv_name: str) -> None:
        """`srv_name` is resolved (the node expanded and remapped it)."""
        self._bus = bus
        self.node = node
        self.srv_name = srv_name
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
            bus.nobody_here(f"{self.srv_name} has no server")
            return False
        deadline = bus.clock.now + round(timeout_sec * 1e9)
        while bus.clock.now < deadline:
            if self._remote is not None and not bus.ok():
                return False  # Ctrl-C while waiting for another process, as rclpy after shutdown
            bus.spin_once(deadline - bus.clock.now)
            if self.service_is_ready():
                return True
        bus.nobody_here(f"{self.srv_name} has no server")
        return False

    def call_async(self, request: Message) -> Future:
        if type(request) is not self.srv_type.Request:
            raise TypeError(
                f"call_async() on {self.srv_name}: expected a {self.srv_type.Request._TYPE}, got {type_name(request)}"
            )
        if self._remote is not None and self.srv_name not in self._bus.services:
            future = Future(self.srv_name, self._remote)
            self._remote.send(request, future)
            return future
        return self._bus.call(self.srv_name, request._copy())

    def call(self, request: Message, timeout_sec: float | None = None) -> Any:
        """Synchronous call: spins until the response; raises TimeoutError if none can come."""
        future = self.call_async(request)
        code = self._bus.spin_until(future, None if timeout_sec is None else round(timeout_sec * 1e9))
        if code is not FutureReturnCode.SUCCESS:
            raise TimeoutError(f"no response from {self.srv_name} ({code.name})")
        return future.result()

    def destroy(self) -> None:
        if self._remote is not None:
            self._remote.close()
            self._remote = None
