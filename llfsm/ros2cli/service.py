"""`service list|type|find|call`: services of the ROS graph as `ros2 service` lists, types, finds
and calls them.

`call` is a client of a hidden node of llfsm's own bus on the DDS transport
(llfsm/ros2cli/endpoints.py): the transport's request header, client id and readiness serve
it unchanged, as rclpy's serve `ros2 service call`.
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

from ..ros import FutureReturnCode, spin_until_future_complete
from ..ros.transports.dds_graph import Graph
from ..suggest import did_you_mean
from . import NOT_FOUND, SPIN_TIME, TIMEOUT, CliError
from .arguments import full_name, parse_values, stamp
from .discovery import discovered, open_graph, where
from .endpoints import hidden_node
from .lookup import service_class, split_type, use_working_directory


def list_(
    *, show_types: bool = False, count: bool = False, include_hidden: bool = False, spin_time: float = SPIN_TIME
) -> str:
    """What `ros2 service list` prints after `spin_time` seconds of discovery."""
    with discovered(spin_time) as graph:
        services = graph.services(include_hidden=include_hidden)
    if count:
        return f"{len(services)}\n"
    if not services:
        raise CliError(f"no services found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{name} [{', '.join(types)}]\n" if show_types else f"{name}\n" for name, types in services.items())


def type_(service: str, *, include_hidden: bool = False, timeout: float = TIMEOUT) -> str:
    """What `ros2 service type SERVICE` prints: its type (one a line, if servers differ), once
    discovery shows the service; not within `timeout` is status 1, with the close names there are."""
    name = full_name(service, "service")
    graph = open_graph()
    try:
        found = graph.spin(timeout, until=lambda: name in graph.services(include_hidden=True))
        services = graph.services(include_hidden=True)
    finally:
        graph.close()
    if not found:
        hint = did_you_mean(name, services)
        raise CliError(f"service '{name}' not found within {timeout:g} s ({where()}){hint}", NOT_FOUND)
    return "".join(f"{t}\n" for t in services[name])


def find(type_text: str, *, count: bool = False, include_hidden: bool = False, spin_time: float = SPIN_TIME) -> str:
    """What `ros2 service find TYPE` prints: the services of that type, one a line (with `count`,
    their number).  None found is status 1 (ros2 prints nothing)."""
    pkg, kind, srv_name = split_type(type_text, "srv")
    wanted = f"{pkg}/{kind}/{srv_name}"
    with discovered(spin_time) as graph:
        services = [s for s, types in graph.services(include_hidden=include_hidden).items() if wanted in types]
    if count:
        return f"{len(services)}\n"
    if not services:
        raise CliError(f"no services of type {wanted} found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{s}\n" for s in services)


def call(
    service: str,
    type_text: str,
    values: str = "{}",
    *,
    period: float | None = None,
    timeout: float = TIMEOUT,
    out: TextIO | None = None,
) -> None:
    """`ros2 service call`: send the request (every `period` seconds when given) and print the
    response.  No server within `timeout`, or no answer within `timeout`: exit status 1."""
    out = out or sys.stdout
    name = full_name(service, "service")
    use_working_directory()
    srv = service_class(type_text)
    request, stamps = parse_values(srv.Request, values)
    pkg, _, srv_name = srv._TYPE.split("/")
    with hidden_node(f"_llfsm_cli_requester_{pkg}_{srv_name}") as (node, graph):
        client = node.create_client(srv, name)
        if not client.service_is_ready():
            out.write("waiting for service to become available...\n")
            out.flush()
            if not _wait_for_service(graph, client, name, srv, timeout):
                hint = did_you_mean(name, graph.services(include_hidden=True))
                raise CliError(f"service '{name}' not available within {timeout:g} s ({where()}){hint}", NOT_FOUND)
        while True:
            stamp(stamps)
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
