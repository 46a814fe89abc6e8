"""`param list|get|set|describe|dump|load`: the parameters of ROS 2 nodes, llfsm's and rclpy's
alike, as `ros2 param` shows and changes them, through each node's parameter services
(`<node>/list_parameters` ...; llfsm/ros/parameter_service.py serves llfsm's).

The verbs are clients of a hidden node of llfsm's bus on the DDS transport (endpoints.py), as
ros2param's are of rclpy's.  Their output is ros2param's, word for word (`Integer value is: 69`,
`Set parameter successful`); where `ros2 param` prints a failure and still exits 0 (a set
refused, a parameter that is not set), llfsm exits 1, so a script can tell.  A node that does
not answer within the timeout is one line and exit 1; a bad node name, value or file, exit 2.
See docs/parameters.md.
"""

from __future__ import annotations

import re
import time
from typing import Any

from ..msgs.rcl_interfaces.msg import Parameter as ParameterMsg
from ..msgs.rcl_interfaces.msg import ParameterType
from ..msgs.rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from ..ros import FutureReturnCode, spin_until_future_complete
from ..ros.names import InvalidNameError, normalise_namespace, validate_node_name
from ..ros.node import Node
from ..ros.parameter import TYPE_NAMES
from ..ros.parameter_files import ParameterTextError, guess_value, node_pattern, read_params_file
from ..ros.parameter_files import dump as dump_yaml
from ..ros.parameters import Parameter, parameter_value_to_python
from ..ros.transports.dds_graph import Graph
from . import NOT_FOUND, SPIN_TIME, TIMEOUT, CliError
from .discovery import where
from .endpoints import hidden_node

#: `ros2 param get`'s words before a value of each type.
LABELS = {
    ParameterType.PARAMETER_BOOL: "Boolean value is:",
    ParameterType.PARAMETER_INTEGER: "Integer value is:",
    ParameterType.PARAMETER_DOUBLE: "Double value is:",
    ParameterType.PARAMETER_STRING: "String value is:",
    ParameterType.PARAMETER_BYTE_ARRAY: "Byte values are:",
    ParameterType.PARAMETER_BOOL_ARRAY: "Boolean values are:",
    ParameterType.PARAMETER_INTEGER_ARRAY: "Integer values are:",
    ParameterType.PARAMETER_DOUBLE_ARRAY: "Double values are:",
    ParameterType.PARAMETER_STRING_ARRAY: "String values are:",
}


def absolute_node_name(name: str) -> str:
    """`turtlesim` -> `/turtlesim`, checked as ROS checks a node's name and namespace."""
    full = name if name.startswith("/") else "/" + name
    ns, _, base = full.rpartition("/")
    try:
        validate_node_name(base)
        normalise_namespace(ns or "/")
    except InvalidNameError as e:
        raise CliError(f"invalid node name {name!r}: {e}") from None
    return full


class _Session:
    """The hidden node, the graph beside it, and the calls to one node's parameter services."""

    def __init__(self, node: Node, graph: Graph, timeout: float) -> None:
        self.node, self.graph, self.timeout = node, graph, timeout

    def wait_for_node(self, full_name: str) -> None:
        def found() -> bool:
            return any(n.full_name == full_name for n in self.graph.nodes(include_hidden=True))

        if not self.graph.spin(self.timeout, until=found):
            raise CliError(f"Node not found: {full_name} ({where()})", NOT_FOUND)

    def call(self, full_name: str, srv: Any, request: Any, wait: float | None = None) -> Any:
        """The response, or a CliError when the node serves no such service in time."""
        name = f"{full_name.rstrip('/')}/{_SERVICE[srv]}"
        client = self.node.create_client(srv, name)
        bus = self.node._bus
        deadline = time.monotonic() + (self.timeout if wait is None else wait)
        while not client.service_is_ready():
            if time.monotonic() >= deadline:
                raise CliError(
                    f"Wait for service timed out waiting for parameter services for node {full_name}", NOT_FOUND
                )
            bus.spin_once(50_000_000)
        future = client.call_async(request)
        code = spin_until_future_complete(self.node, future, timeout_sec=self.timeout)
        if code is not FutureReturnCode.SUCCESS or future.result() is None:
            raise CliError(f"Exception while calling service of node '{full_name}': no answer", NOT_FOUND)
        return future.result()


_SERVICE = {
    ListParameters: "list_parameters",
    GetParameters: "get_parameters",
    SetParameters: "set_parameters",
    DescribeParameters: "describe_parameters",
}


def list_(
    node_name: str | None = None,
    *,
    param_type: bool = False,
    prefixes: tuple[str, ...] = (),
    regex: str | None = None,
    include_hidden: bool = False,
    spin_time: float = SPIN_TIME,
    timeout: float = TIMEOUT,
) -> str:
    """What `ros2 param list [NODE]` prints: each node's parameter names, sorted (under a
    `/node:` line when no NODE is given), with `(type: double)` when asked."""
    full = absolute_node_name(node_name) if node_name else None
    try:
        pattern = re.compile(regex) if regex is not None else None
    except re.error as e:
        raise CliError(f"--filter {regex!r}: not a regular expression: {e}") from None
    out: list[str] = []
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        if full is not None:
            s.wait_for_node(full)
            names = [full]
        else:
            graph.spin(spin_time)
            graph.settle()
            names = sorted({n.full_name for n in graph.nodes(include_hidden=include_hidden)})
            if not names:
                raise CliError(f"no nodes found within {spin_time:g} s ({where()})", NOT_FOUND)
        for fqn in names:
            try:
                request = ListParameters.Request(prefixes=list(prefixes))
                response = s.call(fqn, ListParameters, request, wait=None if full else spin_time)
            except CliError as e:
                if full is not None:
                    raise
                out.append(f"{e.message}\n")
                continue
            found = sorted(response.result.names)
            if pattern is not None:
                found = [n for n in found if pattern.match(n)]
            if full is None and found:
                out.append(f"{fqn}:\n")
            types: dict[str, str] = {}
            if param_type and found:
                described = s.call(fqn, DescribeParameters, DescribeParameters.Request(names=found))
                types = {d.name: TYPE_NAMES.get(d.type, str(d.type)) for d in described.descriptors}
            for n in found:
                out.append(f"  {n} (type: {types.get(n, 'not set')})\n" if param_type else f"  {n}\n")
    return "".join(out)


def get(node_name: str, parameter: str, *, hide_type: bool = False, timeout: float = TIMEOUT) -> str:
    """What `ros2 param get NODE NAME` prints (`Integer value is: 69`)."""
    full = absolute_node_name(node_name)
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        s.wait_for_node(full)
        response = s.call(full, GetParameters, GetParameters.Request(names=[parameter]))
    if not response.values:
        raise CliError("Parameter not set", NOT_FOUND)
    pv = response.values[0]
    if pv.type == ParameterType.PARAMETER_NOT_SET:
        return "None\n" if hide_type else "Parameter not set.\n"
    if pv.type not in LABELS:
        raise CliError(f"Unknown parameter type '{pv.type}'", NOT_FOUND)
    value = parameter_value_to_python(pv)
    if pv.type == ParameterType.PARAMETER_BYTE_ARRAY:
        value = [bytes((b,)) for b in value]
    return f"{value}\n" if hide_type else f"{LABELS[pv.type]} {value}\n"


def set_(node_name: str, parameter: str, value: str, *, timeout: float = TIMEOUT) -> str:
    """`ros2 param set NODE NAME VALUE`: the value typed as ros2 guesses it (`2` an integer,
    `2.0` a double, `true` a boolean, `[1, 2]` an integer array, else a string).  Returns
    `Set parameter successful`; a refusal is a CliError with rclpy's reason (exit 1)."""
    full = absolute_node_name(node_name)
    try:
        guessed = guess_value(value)
    except ParameterTextError as e:
        raise CliError(f"param set {parameter} VALUE: {e}") from None
    msg = ParameterMsg(name=parameter, value=Parameter(parameter, value=guessed).get_parameter_value())
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        s.wait_for_node(full)
        response = s.call(full, SetParameters, SetParameters.Request(parameters=[msg]))
    if len(response.results) != 1:
        raise CliError(f"node {full} answered {len(response.results)} results for one parameter", NOT_FOUND)
    result = response.results[0]
    if not result.successful:
        raise CliError("Setting parameter failed" + (f": {result.reason}" if result.reason else ""), NOT_FOUND)
    return "Set parameter successful" + (f": {result.reason}" if result.reason else "") + "\n"


def describe(node_name: str, parameters: tuple[str, ...], *, timeout: float = TIMEOUT) -> str:
    """What `ros2 param describe NODE NAME...` prints: type, description, constraints."""
    full = absolute_node_name(node_name)
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        s.wait_for_node(full)
        response = s.call(full, DescribeParameters, DescribeParameters.Request(names=list(parameters)))
    if not response.descriptors:
        raise CliError(f"Parameter not declared: {', '.join(parameters)}", NOT_FOUND)
    out: list[str] = []
    for d in response.descriptors:
        out.append(f"Parameter name: {d.name}\n")
        out.append(f"  Type: {TYPE_NAMES.get(d.type, str(d.type))}\n")
        if d.description:
            out.append(f"  Description: {d.description}\n")
        out.append("  Constraints:\n")
        if d.read_only:
            out.append("    Read only: true\n")
        ranges = [*d.floating_point_range, *d.integer_range]
        if ranges:
            r = ranges[0]
            out.append(f"    Min value: {r.from_value}\n    Max value: {r.to_value}\n")
            if r.step:
                out.append(f"    Step: {r.step}\n")
        if d.additional_constraints:
            out.append(f"    Additional constraints: {d.additional_constraints}\n")
    return "".join(out)


def dump(node_name: str, *, timeout: float = TIMEOUT) -> str:
    """What `ros2 param dump NODE` prints: the node's parameters as a params file."""
    full = absolute_node_name(node_name)
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        s.wait_for_node(full)
        names = sorted(s.call(full, ListParameters, ListParameters.Request()).result.names)
        values = s.call(full, GetParameters, GetParameters.Request(names=names)).values if names else []
    if len(values) != len(names):
        raise CliError(f"node {full} did not give the values of its own parameters", NOT_FOUND)
    return dump_yaml(full, {n: parameter_value_to_python(v) for n, v in zip(names, values, strict=True)})


def load(node_name: str, path: str, *, use_wildcard: bool = True, timeout: float = TIMEOUT) -> tuple[str, str]:
    """`ros2 param load NODE FILE`: set what the file says for NODE (and for `/**` unless
    `use_wildcard` is false).  (stdout, stderr): `Set parameter NAME successful` for each,
    `Set parameter NAME failed: reason` on stderr; a CliError (exit 1) if any failed."""
    full = absolute_node_name(node_name)
    try:
        entries = read_params_file(path)
    except ParameterTextError as e:
        raise CliError(str(e)) from None
    chosen: dict[str, Any] = {}
    for key, values in entries:
        if ("*" in key and not use_wildcard) or not node_pattern(key).fullmatch(full):
            continue
        chosen.update({name: value for name, (value, _where) in values.items()})
    if not chosen:
        raise CliError(f"{path}: Param file does not contain any valid parameters for {full}")
    messages = [ParameterMsg(name=n, value=Parameter(n, value=v).get_parameter_value()) for n, v in chosen.items()]
    with hidden_node("_llfsm_cli_param") as (node, graph):
        s = _Session(node, graph, timeout)
        s.wait_for_node(full)
        response = s.call(full, SetParameters, SetParameters.Request(parameters=messages))
    out: list[str] = []
    err: list[str] = []
    for name, result in zip(chosen, response.results, strict=False):
        said = f": {result.reason}" if result.reason else ""
        (out if result.successful else err).append(
            f"Set parameter {name} {'successful' if result.successful else 'failed'}{said}\n"
        )
    if len(response.results) != len(chosen):
        err.append(f"node {full} answered {len(response.results)} results for {len(chosen)} parameters\n")
    return "".join(out), "".join(err)
