"""What the translator knows of a C++ value's type: a *kind*, and the imports kinds need.

The translator is typed because C++ is: `ss << x` appends to a string when `ss` is a
`std::stringstream` and shifts when it is an int; `x->publish(m)` is llfsm's `x.publish(m)`
only when `x` is a publisher; `cout << flag` prints `1`, not `True`, when `flag` is a bool.
A kind is a short string:

| kind | C++ | Python |
|---|---|---|
| `int`, `float`, `bool`, `str` | `int`, `double`, `bool`, `std::string`, `const char *` | the same |
| `stream` | `std::stringstream` | a `str` that `<<` appends to |
| `list:K` | `T x[N]` | a list of K |
| `msg:Cls` | `geometry_msgs::msg::Twist`, `...::srv::T::Request` | the message class `Cls` |
| `srv:Cls` | `turtle_sensor_interface::srv::TurtlePosition` | the service type |
| `ros:Node`, `ros:Publisher`, ... | `rclcpp::Node::SharedPtr`, `rclcpp::Publisher<T>::SharedPtr` | `ros.Node`, ... |
| `any` | a message field, whose type the translator does not look up | whatever it is |

A type the translator does not know has no kind (None): a variable of that type is declared
with a placeholder and a marked line, and code that uses it is left for a person.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..lang.cpp import C_TYPES

#: ROS handle types: the C++ class (any spelling of a shared pointer to it) -> llfsm's name.
_ROS_CLASSES = {
    "Node": "ros:Node",
    "Publisher": "ros:Publisher",
    "Subscription": "ros:Subscription",
    "Client": "ros:Client",
    "Service": "ros:Service",
    "TimerBase": "ros:Timer",
    "WallTimer": "ros:Timer",
    "Logger": "ros:Logger",
    "FutureReturnCode": "ros:FutureReturnCode",
}

#: Scalar types (spaces taken out: `unsigned int` is `unsignedint`) -> kind.  A lone `char` is
#: taken for a one-character string, as `'c'` is written "c".
_SCALARS = {
    **{t: a for t, a in C_TYPES.items() if a},
    "ssize_t": "int",
    "unsignedint": "int",
    "longint": "int",
    "longlong": "int",
    "unsignedlong": "int",
    "unsignedlonglong": "int",
    "unsignedshort": "int",
    "longlongint": "int",
    "longdouble": "float",
    "std::stringstream": "stream",
    "stringstream": "stream",
    "std::ostringstream": "stream",
    "ostringstream": "stream",
}
_FIXED_INT = re.compile(r"u?int(?:8|16|32|64)_t\Z")
_MSG = re.compile(
    r"(?:::)?(?P<pkg>[a-z][a-z0-9_]*)::(?P<sub>msg|srv)::(?P<name>[A-Z][A-Za-z0-9]*)(?:::(?P<part>Request|Response))?\Z"
)
_SHARED = re.compile(r"(?:std::)?shared_ptr<(?P<inner>.+)>\Z")
_HANDLE = re.compile(
    r"rclcpp::(?P<cls>[A-Za-z]+)(?:<.*>)?(?:::(?:SharedPtr|SharedFuture|SharedPtrConst|ConstSharedPtr))?\Z"
)
_FUTURE = re.compile(
    r"rclcpp::Client<.*>::(?:SharedFuture|FutureAndRequestId|SharedFutureAndRequestId)\Z|std::shared_future<.*>\Z"
)

#: Python annotation and default initialiser (None: no initialiser, the variable starts None).
_ANNOTATIONS = {"int": "int", "float": "float", "bool": "bool", "str": "str", "stream": "str", "any": "object"}
_DEFAULTS = {"int": "0", "float": "0.0", "bool": "False", "str": '""', "stream": '""'}


@dataclass
class Imports:
    """The Python imports the translated code needs, gathered while translating: a message
    type per package, and standard modules (math, sys, os, time, contextlib)."""

    modules: set[str] = field(default_factory=set)
    ros: bool = False
    #: (package, msg|srv, Name) -> the name the code uses (an alias when two packages share a Name)
    types: dict[tuple[str, str, str], str] = field(default_factory=dict)

    def message(self, pkg: str, sub: str, name: str) -> str:
        key = (pkg, sub, name)
        if key not in self.types:
            taken = set(self.types.values())
            self.types[key] = name if name not in taken else f"{pkg}_{name}"
        return self.types[key]

    def lines(self) -> list[str]:
        out = [f"import {m}" for m in sorted(self.modules)]
        if self.ros:
            out.append("from llfsm import ros")
        for (pkg, sub, name), alias in sorted(self.types.items()):
            tail = name if alias == name else f"{name} as {alias}"
            out.append(f"from llfsm.msgs.{pkg}.{sub} import {tail}")
        return out


def normalise(type_text: str) -> str:
    """A C++ type as one comparable spelling: no qualifiers, no spaces."""
    t = re.sub(r"\b(?:const|volatile|struct|class|enum|typename|mutable|static|inline|constexpr)\b", " ", type_text)
    return re.sub(r"\s+", "", t)


def kind_of(type_text: str, pointer: bool, imports: Imports) -> str | None:
    """The kind of a declared type (`pointer`: declared with `*`), or None when unknown."""
    t = normalise(type_text)
    if pointer:
        return "str" if t == "char" else None
    if t in _SCALARS:
        return _SCALARS[t]
    if _FIXED_INT.match(t):
        return "int"
    if t == "auto":
        return "any"
    shared = _SHARED.match(t)
    if shared:
        t = shared["inner"]
    m = _MSG.match(t)
    if m:
        cls = imports.message(m["pkg"], m["sub"], m["name"])
        if m["part"]:
            return f"msg:{cls}.{m['part']}"
        return ("msg:" if m["sub"] == "msg" else "srv:") + cls
    if m is None and "::srv::" in t and t.endswith(("::Request::SharedPtr", "::Response::SharedPtr")):
        return kind_of(t.rsplit("::", 1)[0], False, imports)
    if _FUTURE.match(t):
        imports.ros = True
        return "ros:Future"
    handle = _HANDLE.match(t)
    if handle and handle["cls"] in _ROS_CLASSES:
        imports.ros = True
        return _ROS_CLASSES[handle["cls"]]
    return None


def annotation(kind: str) -> str:
    """The annotation of a variable of `kind` in Variables.py."""
    if kind in _ANNOTATIONS:
        return _ANNOTATIONS[kind]
    if kind.startswith("list:"):
        return "list"
    if kind.startswith(("msg:", "srv:")):
        return kind[4:]
    if kind.startswith("ros:"):
        return "ros." + kind[4:]
    return "object"


def default(kind: str) -> str | None:
    """What a variable of `kind` declared without an initialiser starts as in C++ (a message
    and a std::string are default-constructed; a handle starts empty: None; the caller gives
    None for a pointer, `const char *` included)."""
    if kind in _DEFAULTS:
        return _DEFAULTS[kind]
    if kind.startswith("msg:"):
        return kind[4:] + "()"
    return None


def numeric(kind: str | None) -> bool:
    return kind in ("int", "float", "bool")
