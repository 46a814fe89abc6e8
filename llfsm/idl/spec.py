"""What a ROS interface definition says, once read: packages, messages, services, their fields
and constants, and the rules a name must follow (docs/bus.md, "Your own interfaces").

The parser (llfsm.idl.parser) makes these, the package builder (llfsm.idl.package) gathers them
by package, and the generators (llfsm.idl.pygen, llfsm.idl.ddsgen) read them.  Nothing here
reads a file or writes code, so every stage can be tested on specs made by hand.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

#: The kinds of definition files, each in a folder of its name (PKG/msg/*.msg, PKG/srv/*.srv),
#: and the sections `---` lines cut one of its files into: each section is a message of its own,
#: `<Name>_<Section>`.  A .msg is one message.  Issue 21's .action joins as ("Goal", "Result",
#: "Feedback"), with the services and messages rclpy derives from them.
SECTIONS: dict[str, tuple[str, ...]] = {"msg": (), "srv": ("Request", "Response")}
KINDS = tuple(SECTIONS)

FLOATS = ("float32", "float64")
INTS = ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char")
STRINGS = ("string", "wstring")
PRIMITIVES = frozenset((*FLOATS, *INTS, *STRINGS, "bool"))

# rosidl's rules for names.  Each ends at \Z, not $ (which also matches before a final newline):
# a name becomes a folder, a module and a class.
PACKAGE_NAME = re.compile(r"^(?!.*__)(?!.*_\Z)[a-z][a-z0-9_]*\Z")
TYPE_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*\Z")
FIELD_NAME = re.compile(r"^(?!.*__)(?!.*_\Z)[a-z][a-z0-9_]*\Z")
CONSTANT_NAME = re.compile(r"^[A-Z](?:[A-Z0-9_]*[A-Z0-9])?\Z")
# Names a field cannot take: they would break the generated class (its __init__ has a `self`
# parameter and its body uses the `property` decorator) or are not valid identifiers.
RESERVED_FIELDS = frozenset(("self", "property"))

#: A value a definition gives (a constant, a default, an element of an array's default), as
#: Python holds it: bool, an integer type, a float type, or a string type.
Scalar = bool | int | float | str
#: A default: a scalar, or a list of them for an array.
Value = Scalar | list[Scalar]


class InterfaceError(ImportError):
    """A definition that cannot be compiled, with the file and line to fix.  An ImportError,
    because the import of a user's package is where it surfaces."""

    def __init__(self, path: str, line: int | None, message: str) -> None:
        where = f"{path}:{line}" if line else path
        super().__init__(f"{where}: {message}")
        self.path = path
        self.line = line
        self.message = message


@dataclass(frozen=True)
class FieldType:
    """One field's ROS type: a primitive or "pkg/msg/Name", maybe bounded, maybe an array."""

    base: str
    string_bound: int | None = None
    array: str | None = None  # None, "fixed" (T[N]), "bounded" (T[<=N]) or "unbounded" (T[])
    size: int | None = None  # N of T[N] and T[<=N]

    @property
    def is_message(self) -> bool:
        return "/" in self.base

    @property
    def element(self) -> str:
        """The ROS spelling of one element: "float64", "string<=10", "geometry_msgs/msg/Point"."""
        return self.base if self.string_bound is None else f"{self.base}<={self.string_bound}"

    @property
    def ros(self) -> str:
        """The ROS spelling of the whole type, as `_FIELDS` of a generated class carries it."""
        if self.array is None:
            return self.element
        if self.array == "fixed":
            return f"{self.element}[{self.size}]"
        if self.array == "bounded":
            return f"{self.element}[<={self.size}]"
        return f"{self.element}[]"


@dataclass
class FieldSpec:
    name: str
    type: FieldType
    default: Value | None = None  # a value given in the definition, or None
    line: int | None = None


@dataclass
class ConstantSpec:
    name: str
    type: FieldType
    value: Scalar
    line: int | None = None


@dataclass
class MessageSpec:
    type_name: str  # "geometry_msgs/msg/Twist", "turtlesim/srv/Spawn_Request"
    fields: list[FieldSpec] = field(default_factory=list)
    constants: list[ConstantSpec] = field(default_factory=list)
    path: str = ""  # where the definition came from, for errors

    @property
    def name(self) -> str:
        return self.type_name.rsplit("/", 1)[1]


@dataclass
class ServiceSpec:
    type_name: str  # "turtlesim/srv/Spawn"
    request: MessageSpec
    response: MessageSpec
    path: str = ""

    @property
    def name(self) -> str:
        return self.type_name.rsplit("/", 1)[1]

    @property
    def parts(self) -> tuple[MessageSpec, ...]:
        """The messages of its sections, in the order of SECTIONS["srv"]."""
        return (self.request, self.response)


@dataclass
class PackageSpec:
    name: str
    messages: list[MessageSpec] = field(default_factory=list)
    services: list[ServiceSpec] = field(default_factory=list)
    source: str = ""  # shown in the header of the generated modules

    def all_messages(self) -> list[MessageSpec]:
        """Every message the package defines: its .msg files, then the sections of the others."""
        return [*self.messages, *(part for s in self.services for part in s.parts)]
