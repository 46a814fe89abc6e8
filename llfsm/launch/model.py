"""The launch-file model: one pydantic model per tag, built from either front end's elements.

Every tag and attribute llfsm takes is a field here, so an unknown tag or attribute, a missing
one, a bad value and a malformed substitution are all refused when the file is read, each as
one line with the file and line, before anything starts.  Attribute values that may hold
substitutions are parsed (llfsm.launch.substitutions) into texts, performed later, when the
launch is planned (llfsm.launch.plan).

Internal fields (where an element is, its children) have aliases starting with `@`, which no
attribute name can have, so a file cannot set them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, TypeAlias

from pydantic import BaseModel, ConfigDict, Field, PlainValidator, ValidationError, model_validator

from .frontend import Attr, Element, shown
from .substitutions import Sub, SubstitutionError, Text, literal, parse  # noqa: F401  (Text's Sub, for pydantic)

_NAME_RE = re.compile(r"[A-Za-z][A-Za-z0-9_-]*\Z")


class ModelError(ValueError):
    """A launch file that does not follow the model: the message starts with FILE:LINE."""


@dataclass(frozen=True)
class Where:
    file: str
    line: int

    def __str__(self) -> str:
        return f"{shown(self.file)}:{self.line}"


def _where(v: Any) -> Where:
    if not isinstance(v, Where):
        raise ValueError("not a position")
    return v


def _text(v: Any) -> Text:
    if isinstance(v, tuple):
        return v
    if not isinstance(v, Attr) or v.items is not None:
        raise ValueError("takes text, not a list")
    try:
        return parse(v.text)
    except SubstitutionError as e:
        raise ValueError(str(e)) from None


def _plain(v: Any) -> str:
    if isinstance(v, str):
        return v
    if not isinstance(v, Attr) or v.items is not None:
        raise ValueError("takes text, not a list")
    return v.text


def _flag(v: Any) -> bool:
    if isinstance(v, bool):
        return v
    text = _plain(v).strip().lower()
    if text not in ("true", "false", "1", "0"):
        raise ValueError(f"takes true or false, not {_plain(v)!r}")
    return text in ("true", "1")


@dataclass(frozen=True)
class ParamValue:
    """A parameter's value as written: a text (quoted: a YAML string, never a number), or a
    YAML list of them."""

    text: Text
    quoted: bool = False
    items: tuple[ParamValue, ...] | None = None


def _param_value(v: Any) -> ParamValue:
    if isinstance(v, ParamValue):
        return v
    if not isinstance(v, Attr):
        raise ValueError("not a value")
    if v.items is not None:
        return ParamValue((), items=tuple(_param_value(x) for x in v.items))
    return ParamValue(_text(v), quoted=v.quoted)


#: A parameter's `type`, as launch's get_data_type_from_identifier takes it.
PARAM_TYPES = ("str", "bool", "float", "int", "list_of_str", "list_of_bool", "list_of_float", "list_of_int", "yaml")


def _param_type(v: Any) -> str:
    text = _plain(v)
    if text not in PARAM_TYPES:
        raise ValueError(f"{text!r} is not a type (one of {', '.join(PARAM_TYPES)})")
    return text


SubText: TypeAlias = Annotated[Text, PlainValidator(_text)]
Plain: TypeAlias = Annotated[str, PlainValidator(_plain)]
Flag: TypeAlias = Annotated[bool, PlainValidator(_flag)]
At: TypeAlias = Annotated[Where, PlainValidator(_where)]


class Part(BaseModel):
    """An element: each tag's model says which attributes and children it takes."""

    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True)
    #: child tag -> the field holding those children (entity children: CONTAINS_ENTITIES)
    CHILDREN: ClassVar[dict[str, str]] = {}
    CONTAINS_ENTITIES: ClassVar[bool] = False

    where: At = Field(alias="@where")


class Entity(Part):
    """An action of the launch description; every one may carry `if` or `unless`."""

    if_: SubText | None = Field(None, alias="if")
    unless: SubText | None = None

    @model_validator(mode="after")
    def _one_condition(self) -> Entity:
        if self.if_ is not None and self.unless is not None:
            raise ValueError("`if` and `unless` cannot be used together")
        return self


class Choice(Part):
    value: Plain


class Arg(Entity):
    """`arg`: a launch argument (`NAME:=VALUE` on the command line), with its default."""

    CHILDREN = {"choice": "choices"}
    name: Plain
    default: SubText | None = None
    description: Plain | None = None
    choices: tuple[Choice, ...] = Field((), alias="@choices")


class Let(Entity):
    """`let`: sets a launch configuration in the current scope."""

    name: SubText
    value: SubText


class NameValue(Part):
    """`<arg>` of an include, `<keep>` of a group, `<env>` of a process."""

    name: SubText
    value: SubText


class Include(Entity):
    """`include`: another launch file, its `arg`s set as launch configurations first."""

    CHILDREN = {"arg": "args"}
    file: SubText
    args: tuple[NameValue, ...] = Field((), alias="@args")


class Group(Entity):
    """`group`: its entities in a scope of their own (unless `scoped="false"`)."""

    CHILDREN = {"keep": "keeps"}
    CONTAINS_ENTITIES = True
    scoped: Flag = True
    forwarding: Flag = True
    keeps: tuple[NameValue, ...] = Field((), alias="@keeps")
    children: tuple[AnyEntity, ...] = Field((), alias="@children")


class PushRosNamespace(Entity):
    namespace: SubText


class SetEnv(Entity):
    name: SubText
    value: SubText


class UnsetEnv(Entity):
    name: SubText


class Param(Part):
    """`param`: `name` and `value` (or nested params, names joined by dots), or `from` a
    params file."""

    CHILDREN = {"param": "params"}
    name: SubText | None = None
    value: Annotated[ParamValue, PlainValidator(_param_value)] | None = None
    from_: SubText | None = Field(None, alias="from")
    value_sep: Plain | None = Field(None, alias="value-sep")
    type: Annotated[str, PlainValidator(_param_type)] | None = None
    params: tuple[Param, ...] = Field((), alias="@params")

    @model_validator(mode="after")
    def _shape(self) -> Param:
        if self.from_ is not None:
            if self.name is not None or self.value is not None or self.params or self.type is not None:
                raise ValueError("`from` (a params file) goes alone, without name, value or nested params")
        elif self.name is None:
            raise ValueError("needs `name` (with `value` or nested params) or `from`")
        elif (self.value is None) == (not self.params):
            raise ValueError("needs either `value` or nested params")
        elif self.params and self.type is not None:
            raise ValueError("`type` goes with a `value`, not with nested params")
        return self


class Remap(Part):
    from_: SubText = Field(alias="from")
    to: SubText


def _on_exit(v: Any) -> str:
    text = _plain(v)
    if text != "shutdown":
        raise ValueError(f'takes only "shutdown" (the one on_exit action of launch\'s front ends), not {text!r}')
    return text


OnExit: TypeAlias = Annotated[str, PlainValidator(_on_exit)]


class Process(Entity):
    """What `node` and `executable` share (launch's ExecuteProcess attributes)."""

    CHILDREN = {"env": "env"}
    name: SubText | None = None
    args: SubText | None = None
    cwd: SubText | None = None
    output: SubText | None = None
    respawn: SubText | None = None
    respawn_delay: SubText | None = None
    respawn_max_retries: SubText | None = None
    sigterm_timeout: SubText | None = None
    sigkill_timeout: SubText | None = None
    launch_prefix: SubText | None = Field(None, alias="launch-prefix")
    on_exit: OnExit | None = None
    env: tuple[NameValue, ...] = Field((), alias="@env")

    @model_validator(mode="after")
    def _numbers(self) -> Process:
        for key in ("respawn_delay", "sigterm_timeout", "sigkill_timeout"):
            text = getattr(self, key)
            value = literal(text) if text is not None else None
            if value is not None:
                seconds(value, key)
        return self


class Node(Process):
    """`node`: a ROS node by package and executable (llfsm.launch.executables maps them)."""

    CHILDREN = {"env": "env", "param": "params", "remap": "remaps"}
    pkg: SubText | None = None
    exec_: SubText = Field(alias="exec")
    namespace: SubText | None = None
    exec_name: SubText | None = None
    ros_args: SubText | None = None
    params: tuple[Param, ...] = Field((), alias="@params")
    remaps: tuple[Remap, ...] = Field((), alias="@remaps")


class Executable(Process):
    """`executable`: any command (`cmd`), with `args` after it."""

    cmd: SubText
    shell: Flag = False


class Launch(Part):
    """The root: `<launch>` or `launch:`."""

    CONTAINS_ENTITIES = True
    version: Plain | None = None
    children: tuple[AnyEntity, ...] = Field((), alias="@children")


AnyEntity: TypeAlias = Arg | Let | Include | Group | PushRosNamespace | SetEnv | UnsetEnv | Node | Executable

#: Tag -> model, as launch and launch_ros expose them (push-ros-namespace is launch_ros's alias).
ENTITIES: dict[str, type[Entity]] = {
    "arg": Arg,
    "let": Let,
    "include": Include,
    "group": Group,
    "push_ros_namespace": PushRosNamespace,
    "push-ros-namespace": PushRosNamespace,
    "set_env": SetEnv,
    "unset_env": UnsetEnv,
    "node": Node,
    "executable": Executable,
}
#: What each child tag is, by its parent's field.
_CHILD_TYPES: dict[str, type[Part]] = {
    "choices": Choice,
    "args": NameValue,
    "keeps": NameValue,
    "env": NameValue,
    "params": Param,
    "remaps": Remap,
}
Group.model_rebuild()
Launch.model_rebuild()


def seconds(text: str, what: str) -> float:
    """A non-negative number of seconds; ValueError naming the attribute otherwise."""
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"`{what}` takes a number of seconds, not {text!r}") from None
    if not value >= 0 or value == float("inf"):
        raise ValueError(f"`{what}` takes a number of seconds (0 or more), not {text!r}")
    return value


def build(root: Element) -> Launch:
    """The model of a launch file's root element; ModelError with FILE:LINE for the first
    thing that is not as the model says."""
    launch = _build(Launch, root)
    assert isinstance(launch, Launch)
    return launch


def _build(cls: type[Part], el: Element) -> Part:
    data: dict[str, Any] = {"@where": Where(el.file, el.line)}
    for name, attr in el.attrs.items():
        if not _NAME_RE.match(name):
            raise ModelError(f"{Where(el.file, attr.line)}: <{el.tag}> has no attribute {name!r}{_takes(cls)}")
        data[name] = attr
    for child in el.children:
        field = cls.CHILDREN.get(child.tag)
        if field is not None:
            data.setdefault(f"@{field}", []).append(_build(_CHILD_TYPES[field], child))
        elif cls.CONTAINS_ENTITIES and child.tag in ENTITIES:
            data.setdefault("@children", []).append(_build(ENTITIES[child.tag], child))
        else:
            raise ModelError(f"{Where(child.file, child.line)}: {_unknown_child(el.tag, child.tag, cls)}")
    try:
        return cls.model_validate(data)
    except ValidationError as e:
        raise ModelError(_message(e, el, cls)) from None


def _unknown_child(parent: str, tag: str, cls: type[Part]) -> str:
    if cls.CONTAINS_ENTITIES:
        known = sorted({t for t in ENTITIES if t != "push-ros-namespace"} | set(cls.CHILDREN))
        return f"unknown tag <{tag}> (llfsm launch knows {', '.join(known)})"
    if cls.CHILDREN:
        return f"<{parent}> cannot hold <{tag}> (it holds {', '.join(cls.CHILDREN)})"
    return f"<{parent}> holds nothing, not <{tag}>"


def _attributes(cls: type[Part]) -> list[str]:
    names = (f.alias or n for n, f in cls.model_fields.items())
    return [n for n in names if not n.startswith("@")]


def _takes(cls: type[Part]) -> str:
    return f" (it takes {', '.join(_attributes(cls))})"


def _message(e: ValidationError, el: Element, cls: type[Part]) -> str:
    err = e.errors(include_url=False)[0]
    name = str(err["loc"][0]) if err["loc"] else ""
    attr = el.attrs.get(name)
    where = Where(el.file, attr.line if attr is not None else el.line)
    kind = err["type"]
    if kind == "extra_forbidden":
        return f"{where}: <{el.tag}> has no attribute {name!r}{_takes(cls)}"
    if kind == "missing":
        return f"{where}: <{el.tag}> needs the attribute {name!r}"
    cause = err.get("ctx", {}).get("error")
    text = str(cause) if cause is not None else err["msg"]
    return f"{where}: <{el.tag}>{f' {name}' if name and attr is not None else ''}: {text}"
