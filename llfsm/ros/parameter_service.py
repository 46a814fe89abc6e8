"""The parameter services every node serves, as `rclpy.parameter_service`: `~/list_parameters`,
`~/get_parameters`, `~/set_parameters`, `~/set_parameters_atomically`, `~/describe_parameters`
and `~/get_parameter_types` (rcl_interfaces types), so `ros2 param` and `llfsm param` reach an
llfsm node as they reach an rclpy one, on either transport.

They answer as rclpy's do, including where rclpy answers oddly: a get of several names of
which one is undeclared gives an empty list, not the others.  A request from another process
is data, not trust: a value of a type number no parameter has is refused with a reason, never
an exception in the run.  See docs/parameters.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..msgs.rcl_interfaces.msg import ListParametersResult, SetParametersResult
from ..msgs.rcl_interfaces.srv import (
    DescribeParameters,
    GetParameters,
    GetParameterTypes,
    ListParameters,
    SetParameters,
    SetParametersAtomically,
)
from .parameters import (
    Parameter,
    ParameterException,
    ParameterNotDeclaredException,
    ParameterUninitializedException,
)

if TYPE_CHECKING:
    from .node import Node


class ParameterService:
    """The six services of one node."""

    def __init__(self, node: Node) -> None:
        self._node = node
        for srv, name, callback in (
            (DescribeParameters, "describe_parameters", self._describe),
            (GetParameters, "get_parameters", self._get),
            (GetParameterTypes, "get_parameter_types", self._get_types),
            (ListParameters, "list_parameters", self._list),
            (SetParameters, "set_parameters", self._set),
            (SetParametersAtomically, "set_parameters_atomically", self._set_atomically),
        ):
            node.create_service(srv, f"~/{name}", callback)

    def _describe(self, request: Any, response: Any) -> Any:
        try:
            response.descriptors = [d._copy() for d in self._node.describe_parameters(list(request.names))]
        except ParameterNotDeclaredException:
            response.descriptors = []
        return response

    def _get(self, request: Any, response: Any) -> Any:
        try:
            response.values = [p.get_parameter_value() for p in self._node.get_parameters(list(request.names))]
        except (ParameterNotDeclaredException, ParameterUninitializedException):
            response.values = []
        return response

    def _get_types(self, request: Any, response: Any) -> Any:
        try:
            response.types = [int(t) for t in self._node.get_parameter_types(list(request.names))]
        except ParameterNotDeclaredException:
            response.types = []
        return response

    def _list(self, request: Any, response: Any) -> Any:
        try:
            response.result = self._node.list_parameters(list(request.prefixes), request.depth)
        except (TypeError, ValueError):
            response.result = ListParametersResult()
        return response

    def _set(self, request: Any, response: Any) -> Any:
        response.results = [self._set_one([p]) for p in request.parameters]
        return response

    def _set_atomically(self, request: Any, response: Any) -> Any:
        response.result = self._set_one(list(request.parameters))
        return response

    def _set_one(self, messages: list[Any]) -> SetParametersResult:
        try:
            params = [Parameter.from_parameter_msg(m) for m in messages]
        except ValueError as e:
            return SetParametersResult(successful=False, reason=str(e))
        try:
            return self._node.set_parameters_atomically(params)
        except ParameterException as e:
            return SetParametersResult(successful=False, reason=str(e))
