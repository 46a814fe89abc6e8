"""Node parameters, as `rclpy.parameter` and the parameter half of `rclpy.node.Node`.

Today: `node.declare_parameter(name, default)` (a `--param [node:]name:=value` given to
`llfsm run` overrides the default), `has_parameter`, `get_parameter`, `set_parameters`.  A
node keeps its parameters in a `NodeParameters` and forwards those calls to it, so rclpy's full
parameter API (types, descriptors, callbacks, the parameter services; SPEC section 12) grows
here.  See docs/bus.md (Parameters: `--param`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .bus import Bus


@dataclass
class Parameter:
    name: str
    value: Any = None

    def get_parameter_value(self) -> Any:
        return self.value


class NodeParameters:
    """The parameters of one node.  The run's overrides (`Bus.parameters`, keyed by node name or
    None for every node) are read when a parameter is declared, as rclpy reads its overrides."""

    def __init__(self, bus: Bus, node_name: str) -> None:
        self._bus = bus
        self._node = node_name
        self._params: dict[str, Parameter] = {}

    def declare(self, name: str, value: Any = None) -> Parameter:
        overrides = self._bus.parameters
        for key in ((self._node, name), (None, name)):
            if key in overrides:
                value = overrides[key]
                break
        p = self._params[name] = Parameter(name, value)
        return p

    def has(self, name: str) -> bool:
        return name in self._params

    def get(self, name: str) -> Parameter:
        if name not in self._params:
            raise KeyError(f"parameter {name!r} of node {self._node} is not declared")
        return self._params[name]

    def set(self, parameters: list[Parameter]) -> list[bool]:
        for p in parameters:
            self._params[p.name] = Parameter(p.name, p.value)
        return [True] * len(parameters)


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
