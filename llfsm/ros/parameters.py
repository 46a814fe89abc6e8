"""A node's parameters, as the parameter half of `rclpy.node.Node`: what a node declares, how a
set is checked, and the events it publishes.

    node.declare_parameter("gain", 1.5, ParameterDescriptor(description="P gain"))
    node.get_parameter("gain").value                      # 1.5, or what -p / --params-file said
    node.set_parameters([Parameter("gain", value=2.0)])   # [SetParametersResult(successful=True)]
    node.set_parameters([Parameter("gain", value=2)])     # refused: Wrong parameter type, ...
    node.add_on_set_parameters_callback(fn)               # fn(params) -> SetParametersResult

Typed as rclpy types them: a parameter declared with a value takes that value's type for good
(unless its descriptor says `dynamic_typing`), and a set of another type, of a read-only
parameter or out of the descriptor's range is refused with rclpy's reason text, so what a user
reads in `llfsm param set` is what `ros2 param set` prints for an rclpy node.  The overrides of
the run (`llfsm run -p`, `--params-file`; llfsm/ros/parameter_files.py) are read at declare
time, as rclpy reads its overrides.

`Parameter` and the exceptions are llfsm/ros/parameter.py (rclpy.parameter, rclpy.exceptions),
also importable from here, where they were first.  `ParameterHost` holds a node's parameters and
is a base of `llfsm.ros.node.Node`, so this module keeps the whole behaviour in one place; the
services that serve it to other processes (`ros2 param`, `llfsm param`) are
llfsm/ros/parameter_service.py.  See docs/parameters.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from ..msgs.builtin_interfaces.msg import Time as TimeMsg
from ..msgs.rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ListParametersResult,
    ParameterDescriptor,
    ParameterEvent,
    ParameterType,
    ParameterValue,
    SetParametersResult,
)
from ..msgs.rcl_interfaces.msg import Parameter as ParameterMsg
from .parameter import (
    DEPTH_RECURSIVE,
    PARAMETER_SEPARATOR_STRING,
    InvalidParameterException,
    InvalidParameterTypeException,
    InvalidParameterValueException,
    Parameter,
    ParameterAlreadyDeclaredException,
    ParameterException,
    ParameterImmutableException,
    ParameterNotDeclaredException,
    ParameterUninitializedException,
    parameter_value_to_python,
    validate_parameter_name,
)

if TYPE_CHECKING:
    from .bus import Bus
    from .publisher import Publisher

__all__ = [
    "PARAMETER_SEPARATOR_STRING",
    "FloatingPointRange",
    "IntegerRange",
    "InvalidParameterException",
    "InvalidParameterTypeException",
    "InvalidParameterValueException",
    "Parameter",
    "ParameterAlreadyDeclaredException",
    "ParameterDescriptor",
    "ParameterException",
    "ParameterHost",
    "ParameterImmutableException",
    "ParameterNotDeclaredException",
    "ParameterUninitializedException",
    "ParameterValue",
    "SetParametersResult",
    "parameter_value_to_python",
]


# -- a node's parameters ----------------------------------------------------------------------------
def overrides_for(bus: Bus, name: str, full_name: str) -> dict[str, tuple[Any, str]]:
    """The run's overrides for the node `name` (fully qualified `full_name`), each with where it
    was written: the params files' entries that match it in file order, then `-p NAME:=VALUE`,
    then `-p NODE:NAME:=VALUE` (NODE its name or its fully qualified name), later ones winning."""
    out: dict[str, tuple[Any, str]] = {}
    for pattern, values in bus.parameter_files:
        if pattern.fullmatch(full_name):
            out.update(values)
    origins = bus.parameter_origins
    for specific in (False, True):
        for key, value in bus.parameters.items():
            node = key[0]
            if (node is not None) == specific and (node is None or node in (name, full_name)):
                out[key[1]] = (value, origins.get(key, f"-p {key[1]}"))
    return out


PreSetCallback = Callable[[list[Parameter]], list[Parameter]]
OnSetCallback = Callable[[list[Parameter]], SetParametersResult]
PostSetCallback = Callable[[list[Parameter]], None]


class ParameterHost:
    """The parameter methods of `rclpy.node.Node`, over a node's own table.  A base of
    llfsm.ros.node.Node, which calls `_init_parameters` from its constructor."""

    #: rclpy's tolerance for a double at the edge of its range or on a step.
    PARAM_REL_TOL = 1e-6

    _bus: Bus

    def get_name(self) -> str:
        raise NotImplementedError

    def get_fully_qualified_name(self) -> str:
        raise NotImplementedError

    def _init_parameters(
        self,
        overrides: dict[str, tuple[Any, str]],
        parameter_overrides: Sequence[Parameter] | None,
        allow_undeclared_parameters: bool,
        event_publisher: Publisher | None,
    ) -> None:
        """`overrides`: the run's, name -> (value, where it was written); then the node's own
        `parameter_overrides`, which win (as rclpy's constructor argument wins over files)."""
        self._parameters: dict[str, Parameter] = {}
        self._descriptors: dict[str, ParameterDescriptor] = {}
        self._pre_set_parameters_callbacks: list[PreSetCallback] = []
        self._on_set_parameters_callbacks: list[OnSetCallback] = []
        self._post_set_parameters_callbacks: list[PostSetCallback] = []
        self._allow_undeclared_parameters = allow_undeclared_parameters
        self._parameter_overrides: dict[str, Parameter] = {}
        self._override_origins: dict[str, str] = {}
        #: Where a value being declared came from, while it is checked (for the error).
        self._declared_from: dict[str, str] = {}
        for name, (value, origin) in overrides.items():
            try:
                self._parameter_overrides[name] = Parameter(name, value=value)
            except (TypeError, ValueError):
                continue  # parameter_files.py only hands over values a parameter can hold
            self._override_origins[name] = origin
        for p in parameter_overrides or ():
            self._parameter_overrides[p.name] = p
            self._override_origins.pop(p.name, None)
        self._parameter_event_publisher = event_publisher
        #: Called before the parameters are read (llfsm.ros.control: a machine's variables
        #: changed by its own code show in `param get`).
        self._refresh_parameters: Callable[[], None] | None = None

    # -- declaring -------------------------------------------------------------------------------
    def declare_parameter(
        self,
        name: str,
        value: Any = None,
        descriptor: ParameterDescriptor | None = None,
        ignore_override: bool = False,
    ) -> Parameter:
        """Declare and initialise a parameter: its value is the run's override when there is
        one, else `value`.  `value` may be a `Parameter.Type` (declared, not yet set)."""
        if value is None and descriptor is None:
            args: tuple[Any, ...] = (name,)
        else:
            args = (name, value, ParameterDescriptor() if descriptor is None else descriptor)
        return self.declare_parameters("", [args], ignore_override)[0]

    def declare_parameters(
        self,
        namespace: str,
        parameters: Sequence[tuple[Any, ...]],
        ignore_override: bool = False,
    ) -> list[Parameter]:
        """Declare each `(name[, value[, descriptor]])` as `namespace.name`."""
        parameter_list: list[Parameter] = []
        descriptors: dict[str, ParameterDescriptor] = {}
        for index, entry in enumerate(parameters):
            if not isinstance(entry, tuple | list) or not 1 <= len(entry) <= 3:
                raise TypeError(
                    f"Invalid parameter tuple length at index {index} in parameters list: {entry}; "
                    "expecting length between 1 and 3"
                )
            name = entry[0]
            if not isinstance(name, str):
                raise TypeError(f"First element {name} at index {index} in parameters list is not a str.")
            if namespace:
                name = f"{namespace}.{name}"
            validate_parameter_name(name)
            second = entry[1] if len(entry) > 1 else None
            descriptor = entry[2] if len(entry) > 2 else ParameterDescriptor()
            if not isinstance(descriptor, ParameterDescriptor):
                raise TypeError(
                    f"Third element {descriptor} at index {index} in parameters list is not a ParameterDescriptor."
                )
            descriptor = descriptor._copy()  # the node keeps its own: the caller's stays theirs
            if len(entry) == 1:
                descriptor.dynamic_typing = True  # rclpy: deprecated, and dynamically typed
            value: Any = None
            if isinstance(second, Parameter.Type):
                if second is Parameter.Type.NOT_SET:
                    raise ValueError(f"Cannot declare parameter {{{name}}} as statically typed of type NOT_SET")
                if descriptor.dynamic_typing:
                    raise ValueError(
                        f"When declaring parameter {{{name}}} passing a descriptor with`dynamic_typing=True` "
                        "is not allowed when the parameter type is provided"
                    )
                descriptor.type = int(second)
            else:
                value = second
                if not descriptor.dynamic_typing:
                    descriptor.type = int(Parameter.Type.from_parameter_value(value))
                    if descriptor.type == ParameterType.PARAMETER_NOT_SET:
                        raise ValueError(
                            "Cannot declare a statically typed parameter with default value of type PARAMETER_NOT_SET"
                        )
            origin = None
            if not ignore_override and name in self._parameter_overrides:
                value = self._parameter_overrides[name].value
                origin = self._override_origins.get(name)
            try:
                parameter = Parameter(name, value=value)
            except (TypeError, ValueError) as e:
                raise TypeError(f"parameter {name}: {e}") from None
            if origin is not None:
                self._declared_from[name] = origin
            parameter_list.append(parameter)
            descriptors[name] = descriptor
        already = [p.name for p in parameter_list if p.name in self._parameters]
        if already:
            raise ParameterAlreadyDeclaredException(already)
        for param in parameter_list:
            result = self._set_atomically([param], descriptors, allow_not_set_type=True)
            if not result.successful:
                error: ParameterException
                if result.reason.startswith("Wrong parameter type"):
                    error = InvalidParameterTypeException(param, Parameter.Type(descriptors[param.name].type).name)
                else:
                    error = InvalidParameterValueException(param.name, param.value, result.reason)
                error.origin = self._declared_from.pop(param.name, None)
                error.node = self.get_fully_qualified_name()
                raise error
            self._declared_from.pop(param.name, None)
        return [self._parameters[p.name] for p in parameter_list]

    def undeclare_parameter(self, name: str) -> None:
        if not self.has_parameter(name):
            raise ParameterNotDeclaredException(name)
        if self._descriptors[name].read_only:
            raise ParameterImmutableException(name)
        del self._parameters[name]
        del self._descriptors[name]

    # -- reading -----------------------------------------------------------------------------------
    def has_parameter(self, name: str) -> bool:
        return name in self._parameters

    def get_parameter(self, name: str) -> Parameter:
        if self._refresh_parameters is not None:
            self._refresh_parameters()
        if name in self._parameters:
            parameter = self._parameters[name]
            if parameter.type_ is not Parameter.Type.NOT_SET or self._descriptors[name].dynamic_typing:
                return parameter
            raise ParameterUninitializedException(name)
        if self._allow_undeclared_parameters:
            return Parameter(name, Parameter.Type.NOT_SET, None)
        raise ParameterNotDeclaredException(name)

    def get_parameters(self, names: list[str]) -> list[Parameter]:
        if not all(isinstance(n, str) for n in names):
            raise TypeError("All names must be instances of type str")
        return [self.get_parameter(n) for n in names]

    def get_parameter_or(self, name: str, alternative_value: Parameter | None = None) -> Parameter:
        if alternative_value is None:
            alternative_value = Parameter(name, Parameter.Type.NOT_SET)
        if name not in self._parameters or self._parameters[name].type_ is Parameter.Type.NOT_SET:
            return alternative_value
        return self.get_parameter(name)

    def get_parameters_by_prefix(self, prefix: str) -> dict[str, Parameter]:
        if prefix:
            prefix += PARAMETER_SEPARATOR_STRING
        if self._refresh_parameters is not None:
            self._refresh_parameters()
        return {n[len(prefix) :]: p for n, p in self._parameters.items() if n.startswith(prefix)}

    def get_parameter_type(self, name: str) -> Parameter.Type:
        if name in self._parameters:
            return self._parameters[name].type_
        if self._allow_undeclared_parameters:
            return Parameter.Type.NOT_SET
        raise ParameterNotDeclaredException(name)

    def get_parameter_types(self, names: list[str]) -> list[Parameter.Type]:
        if not all(isinstance(n, str) for n in names):
            raise TypeError("All names must be instances of type str")
        return [self.get_parameter_type(n) for n in names]

    def describe_parameter(self, name: str) -> ParameterDescriptor:
        try:
            return self._descriptors[name]
        except KeyError:
            if self._allow_undeclared_parameters:
                return ParameterDescriptor()
            raise ParameterNotDeclaredException(name) from None

    def describe_parameters(self, names: list[str]) -> list[ParameterDescriptor]:
        return [self.describe_parameter(n) for n in names]

    def list_parameters(self, prefixes: list[str], depth: int) -> ListParametersResult:
        """The names (and their prefixes) under `prefixes`, at most `depth` parts below them
        (0: any depth), as rclpy lists them for `ros2 param list`."""
        if not isinstance(prefixes, list) or not all(isinstance(p, str) for p in prefixes):
            raise TypeError("The prefixes argument must be a list of str")
        if not isinstance(depth, int) or depth < 0:
            raise ValueError("The depth must be greater than or equal to zero")
        result = ListParametersResult()
        sep = PARAMETER_SEPARATOR_STRING

        def shallow(s: str) -> bool:
            return s.count(sep) < depth

        recursive = not prefixes and depth == DEPTH_RECURSIVE

        def wanted(name: str) -> bool:
            if recursive or (not prefixes and shallow(name)):
                return True
            return any(
                name == prefix
                or (name.startswith(prefix + sep) and (depth == DEPTH_RECURSIVE or shallow(name[len(prefix) + 1 :])))
                for prefix in prefixes
            )

        for name in self._parameters:
            if not wanted(name):
                continue
            result.names.append(name)
            last = name.rfind(sep)
            if last != -1 and name[:last] not in result.prefixes:
                result.prefixes.append(name[:last])
        return result

    # -- setting ---------------------------------------------------------------------------------------
    def set_parameters(self, parameter_list: list[Parameter]) -> list[SetParametersResult]:
        """Set each parameter on its own: one result each, a refused one changes nothing."""
        return [self._set_parameters_atomically([p]) for p in parameter_list]

    def set_parameters_atomically(self, parameter_list: list[Parameter]) -> SetParametersResult:
        """Set them all or none: one result."""
        return self._set_parameters_atomically(parameter_list)

    def _set_parameters_atomically(self, parameter_list: list[Parameter]) -> SetParametersResult:
        if self._pre_set_parameters_callbacks:
            modified: list[Parameter] = []
            for callback in self._pre_set_parameters_callbacks:
                modified.extend(callback(parameter_list))
            parameter_list = modified
            if not parameter_list:
                return SetParametersResult(
                    successful=False,
                    reason="parameter list cannot be empty, this might be due to pre_set_parameters_callback "
                    "modifying the original parameters list.",
                )
        if not all(isinstance(p, Parameter) for p in parameter_list):
            raise TypeError(f"parameter must be instance of type '{Parameter!r}'")
        undeclared = [p.name for p in parameter_list if p.name not in self._parameters]
        if undeclared and not self._allow_undeclared_parameters:
            raise ParameterNotDeclaredException(undeclared)
        return self._set_atomically(parameter_list)

    def _set_atomically(
        self,
        parameter_list: list[Parameter],
        descriptors: dict[str, ParameterDescriptor] | None = None,
        allow_not_set_type: bool = False,
    ) -> SetParametersResult:
        """Check against the descriptors (new ones when declaring), ask the on-set callbacks,
        store, publish one ParameterEvent, tell the post-set callbacks."""
        if descriptors is not None:
            result = self._apply_descriptors(parameter_list, descriptors, check_read_only=False)
        else:
            result = self._apply_descriptors(parameter_list, self._descriptors, check_read_only=True)
        if not result.successful:
            return result
        for callback in self._on_set_parameters_callbacks:
            result = callback(parameter_list)
            if not isinstance(result, SetParametersResult):
                return SetParametersResult(successful=False, reason="Callback returned an invalid type")
            if not result.successful:
                return result
        event = ParameterEvent(node=self.get_fully_qualified_name())
        for param in parameter_list:
            if not allow_not_set_type and param.type_ is Parameter.Type.NOT_SET:
                event.deleted_parameters.append(param.to_parameter_msg())
                self._parameters.pop(param.name, None)
                self._descriptors.pop(param.name, None)
                continue
            if descriptors is not None:
                self._descriptors[param.name] = descriptors[param.name]
            elif param.name not in self._descriptors:
                self._descriptors[param.name] = ParameterDescriptor(name=param.name, dynamic_typing=True)
            old = self._parameters.get(param.name)
            if old is None or old.type_ is Parameter.Type.NOT_SET:
                event.new_parameters.append(param.to_parameter_msg())
            else:
                event.changed_parameters.append(param.to_parameter_msg())
            self._parameters[param.name] = param
        self._publish_event(event)
        for post in self._post_set_parameters_callbacks:
            post(parameter_list)
        return SetParametersResult(successful=True)

    def _publish_event(self, event: ParameterEvent) -> None:
        pub = self._parameter_event_publisher
        if pub is None:
            return
        sec, nsec = divmod(self._bus.clock.now, 1_000_000_000)  # run time: reproducible under --clock sim
        event.stamp = TimeMsg(sec=sec, nanosec=nsec)
        pub.publish(event)

    # -- descriptors ------------------------------------------------------------------------------------
    def _apply_descriptors(
        self,
        parameter_list: list[Parameter],
        descriptors: dict[str, ParameterDescriptor],
        check_read_only: bool = True,
    ) -> SetParametersResult:
        for param in parameter_list:
            if param.name in descriptors:
                result = self._apply_descriptor(param, descriptors[param.name], check_read_only)
                if not result.successful:
                    return result
        return SetParametersResult(successful=True)

    def _apply_descriptor(
        self, parameter: Parameter, descriptor: ParameterDescriptor, check_read_only: bool = True
    ) -> SetParametersResult:
        """rclpy's checks, with its reasons: read-only, type, range, step."""
        descriptor.name = parameter.name
        if check_read_only and descriptor.read_only:
            return SetParametersResult(
                successful=False, reason=f"Trying to set a read-only parameter: {parameter.name}."
            )
        if descriptor.dynamic_typing:
            descriptor.type = int(parameter.type_)
        elif parameter.name in self._parameters and parameter.type_ is Parameter.Type.NOT_SET:
            return SetParametersResult(successful=False, reason="Static parameter cannot be undeclared")
        elif parameter.type_ is not Parameter.Type.NOT_SET and int(parameter.type_) != descriptor.type:
            return SetParametersResult(
                successful=False,
                reason=f"Wrong parameter type, expected '{_type_text(descriptor.type)}' got '{parameter.type_}'",
            )
        if parameter.type_ is Parameter.Type.INTEGER and descriptor.integer_range:
            return _integer_range(parameter, descriptor.integer_range[0])
        if parameter.type_ is Parameter.Type.DOUBLE and descriptor.floating_point_range:
            return _floating_point_range(parameter, descriptor.floating_point_range[0], self.PARAM_REL_TOL)
        return SetParametersResult(successful=True)

    def set_descriptor(
        self, name: str, descriptor: ParameterDescriptor, alternative_value: ParameterValue | None = None
    ) -> ParameterValue:
        """A new descriptor for a declared parameter; the value must fit it (or the alternative)."""
        if not self.has_parameter(name):
            if not self._allow_undeclared_parameters:
                raise ParameterNotDeclaredException(name)
            return self.get_parameter(name).get_parameter_value()
        if self.describe_parameter(name).read_only:
            raise ParameterImmutableException(name)
        current = self.get_parameter(name)
        alternative = (
            current
            if alternative_value is None
            else Parameter.from_parameter_msg(ParameterMsg(name=name, value=alternative_value))
        )
        if not self._apply_descriptor(current, descriptor, False).successful:
            result = self._apply_descriptor(alternative, descriptor, False)
            if not result.successful:
                raise InvalidParameterValueException(name, alternative.value, result.reason)
            self._parameters[name] = alternative
        self._descriptors[name] = descriptor
        return self.get_parameter(name).get_parameter_value()

    # -- callbacks ----------------------------------------------------------------------------------------
    def add_pre_set_parameters_callback(self, callback: PreSetCallback) -> None:
        """`callback(params) -> params`: may change what is about to be set."""
        self._pre_set_parameters_callbacks.insert(0, _callable(callback))

    def add_on_set_parameters_callback(self, callback: OnSetCallback) -> None:
        """`callback(params) -> SetParametersResult`: refuses the set with a reason, or lets it
        through.  The last one added is asked first, as in rclpy."""
        self._on_set_parameters_callbacks.insert(0, _callable(callback))

    def add_post_set_parameters_callback(self, callback: PostSetCallback) -> None:
        """`callback(params)`: told after a set succeeded (turtlesim repaints from it)."""
        self._post_set_parameters_callbacks.insert(0, _callable(callback))

    def remove_pre_set_parameters_callback(self, callback: PreSetCallback) -> None:
        self._pre_set_parameters_callbacks.remove(callback)

    def remove_on_set_parameters_callback(self, callback: OnSetCallback) -> None:
        self._on_set_parameters_callbacks.remove(callback)

    def remove_post_set_parameters_callback(self, callback: PostSetCallback) -> None:
        self._post_set_parameters_callbacks.remove(callback)


def _callable(callback: Any) -> Any:
    if not callable(callback):
        raise TypeError(f"Callback must be callable, got {type(callback)}")
    return callback


def _type_text(type_number: int) -> str:
    try:
        return str(Parameter.Type(type_number))
    except ValueError:
        return str(type_number)


def _integer_range(parameter: Parameter, r: IntegerRange) -> SetParametersResult:
    lo, hi = min(r.from_value, r.to_value), max(r.from_value, r.to_value)
    value = parameter.value
    if value in (lo, hi):
        return SetParametersResult(successful=True)
    if not lo < value < hi:
        return SetParametersResult(
            successful=False,
            reason=f"Parameter {parameter.name} out of range. Min: {lo}, Max: {hi}, value: {value}",
        )
    if r.step != 0 and (value - lo) % r.step != 0:
        return SetParametersResult(
            successful=False,
            reason=f"The parameter value for {parameter.name} is not a valid step. "
            f"Min: {lo}, max: {hi}, value: {value}, step: {r.step}",
        )
    return SetParametersResult(successful=True)


def _floating_point_range(parameter: Parameter, r: FloatingPointRange, tol: float) -> SetParametersResult:
    lo, hi = min(r.from_value, r.to_value), max(r.from_value, r.to_value)
    value = parameter.value
    if math.isclose(value, lo, rel_tol=tol) or math.isclose(value, hi, rel_tol=tol):
        return SetParametersResult(successful=True)
    if not lo < value < hi:
        return SetParametersResult(
            successful=False,
            reason=f"Parameter {parameter.name} out of range Min: {lo}, Max: {hi}, value: {value}",
        )
    if r.step != 0.0:
        steps = round((value - lo) / r.step)
        if not math.isclose(lo + steps * r.step, value, rel_tol=tol):
            return SetParametersResult(
                successful=False,
                reason=f"The parameter value for {parameter.name} is not close enough to a valid step. "
                f"Min: {lo}, max: {hi}, value: {value}, step: {r.step}",
            )
    return SetParametersResult(successful=True)
