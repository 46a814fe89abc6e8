"""What a ROS interface definition says, once read: packages, messages, services, actions, their
fields and constants, and the rules a name must follow (docs/bus.md, "Your own interfaces";
docs/actions.md for actions).

The parser (llfsm.idl.parser) makes these, the package builder (llfsm.idl.package) gathers them
by package, and the generators (llfsm.idl.pygen, llfsm.idl.ddsgen) read them.  Nothing here
reads a file or writes code, so every stage can be tested on specs made by hand.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

#: The kinds of definition files, each in a folder of its name (PKG/msg/*.msg, PKG/srv/*.srv,
#: PKG/action/*.action), and the sections `---` lines cut one of its files into: each section is
#: a message of its own, `<Name>_<Section>`.  A .msg is one message.  An .action also gets the
#: services and the message rosidl derives from its sections (ActionSpec).
SECTIONS: dict[str, tuple[str, ...]] = {
    "msg": (),
    "srv": ("Request", "Response"),
    "action": ("Goal", "Result", "Feedback"),
}
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


#: The messages every action's derived types refer to (rosidl's implicit includes).
UUID_TYPE = "unique_identifier_msgs/msg/UUID"
TIME_TYPE = "builtin_interfaces/msg/Time"


@dataclass
class ActionSpec:
    """An .action: the three sections a user writes (Goal, Result, Feedback) and what rosidl
    derives from them, which is what travels on the wire: the services `<Name>_SendGoal` (goal
    id and goal -> accepted and stamp) and `<Name>_GetResult` (goal id -> status and result), and
    the message `<Name>_FeedbackMessage` (goal id and feedback), fields in rosidl's order."""

    type_name: str  # "turtlesim/action/RotateAbsolute"
    goal: MessageSpec
    result: MessageSpec
    feedback: MessageSpec
    path: str = ""

    @property
    def name(self) -> str:
        return self.type_name.rsplit("/", 1)[1]

    @property
    def parts(self) -> tuple[MessageSpec, ...]:
        """The messages of its sections, in the order of SECTIONS["action"]."""
        return (self.goal, self.result, self.feedback)

    def _derived(self, suffix: str, *members: tuple[str, str]) -> MessageSpec:
        fields = [FieldSpec(name, FieldType(base)) for name, base in members]
        return MessageSpec(f"{self.type_name}_{suffix}", fields, path=self.path)

    @property
    def send_goal(self) -> ServiceSpec:
        request = self._derived("SendGoal_Request", ("goal_id", UUID_TYPE), ("goal", self.goal.type_name))
        response = self._derived("SendGoal_Response", ("accepted", "bool"), ("stamp", TIME_TYPE))
        return ServiceSpec(f"{self.type_name}_SendGoal", request, response, self.path)

    @property
    def get_result(self) -> ServiceSpec:
        request = self._derived("GetResult_Request", ("goal_id", UUID_TYPE))
        response = self._derived("GetResult_Response", ("status", "int8"), ("result", self.result.type_name))
        return ServiceSpec(f"{self.type_name}_GetResult", request, response, self.path)

    @property
    def feedback_message(self) -> MessageSpec:
        return self._derived("FeedbackMessage", ("goal_id", UUID_TYPE), ("feedback", self.feedback.type_name))

    @property
    def services(self) -> tuple[ServiceSpec, ServiceSpec]:
        return (self.send_goal, self.get_result)

    @property
    def messages(self) -> list[MessageSpec]:
        """Every message of the action, in the order rosidl lists them: its sections, the two
        services' requests and responses, the feedback message."""
        return [*self.parts, *(m for s in self.services for m in s.parts), self.feedback_message]


@dataclass
class PackageSpec:
    name: str
    messages: list[MessageSpec] = field(default_factory=list)
    services: list[ServiceSpec] = field(default_factory=list)
    actions: list[ActionSpec] = field(default_factory=list)
    source: str = ""  # shown in the header of the generated modules

    def all_messages(self) -> list[MessageSpec]:
        """Every message the package's files define: its .msg files, then the sections of the
        others (what a user wrote, whose references `check_references` checks)."""
        return [
            *self.messages,
            *(part for s in self.services for part in s.parts),
            *(part for a in self.actions for part in a.parts),
        ]
