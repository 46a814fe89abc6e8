"""Verification files, `NAME.verify.yaml` (docs/verify.md, "Verification files"), as `llfsm
verify`, `llfsm run --monitor` and `llfsm bag check` read them.

```yaml
machines: [a.machine, b.machine]   # in load order, relative to this file
period: 1ms                        # options: period, interrupt, max_states, max_memory
bounds: {a.count: 5}               # explore no further where a variable passes a bound
environment:                       # what services answer and topics hold (docs/verify.md)
  services:
    /pose: {type: pkg/srv/T, responses: [{x: 1.0}], may_fail: true}
  topics:
    /scan: {type: pkg/msg/T, values: [{data: 0}]}
properties:
  - name: ...                      # optional: the line printed
    leads_to: [A, B]               # one kind (llfsm.props.kinds), then its text
    within: 1s                     # a deadline, for the kinds that take one
```

Everything is read into plain data, every mistake one line with the file and line: a mapping
where a list belongs, an unknown key, a duration that does not parse.  Anchors and aliases are
refused (an alias bomb costs nothing to write), the file is at most 1 MiB, and what the
environment lists is bounded (MAX_VALUES).  Message types and values are checked by their users
(llfsm.verify.environment), which know the messages.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .. import yamlfile
from ..runtime.clock import parse_duration
from .kinds import BY_NAME, KINDS

#: The suffix of a verification file.
VERIFY_SUFFIX = ".verify.yaml"
#: Keys of a verification file besides machines, properties, bounds and environment: defaults
#: for the options of the same names.
FILE_OPTIONS = ("period", "interrupt", "max_states", "max_memory")
#: At most this many responses of one service, values of one topic.
MAX_VALUES = 1_000

#: Largest verification file read, and deepest nesting (a verification file nests five deep).
MAX_FILE_BYTES = 1 << 20
MAX_DEPTH = 64
#: A verification file's words for what llfsm.yamlfile refuses (the rest in its default words).
_WORDS = {"syntax": "{where}:{line}: invalid YAML: {detail}"}


class FileError(ValueError):
    """A verification file that cannot be used: one line naming the file and line."""


@dataclass
class PropertySource:
    kind: str
    text: Any  # str, or a list of two for leads_to
    name: str | None = None
    where: str = "--property"
    within: int | None = None  # ns


@dataclass
class ServiceDecl:
    """A service the environment serves: its type (`pkg/srv/Name`), the responses it may give
    (each a mapping of the response's fields), and whether it may not answer at all."""

    type: str
    responses: list[Any]
    may_fail: bool = False
    where: str = ""


@dataclass
class TopicDecl:
    """A topic the environment publishes on: its type (`pkg/msg/Name`) and the messages it may
    carry (each a mapping of the message's fields)."""

    type: str
    values: list[Any]
    where: str = ""


@dataclass
class Environment:
    services: dict[str, ServiceDecl] = field(default_factory=dict)
    topics: dict[str, TopicDecl] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.services or self.topics)


@dataclass
class VerifyFile:
    path: Path
    machines: list[str]
    properties: list[PropertySource]
    options: dict[str, Any] = field(default_factory=dict)
    environment: Environment = field(default_factory=Environment)
    #: `machine.variable` -> the largest value explored on (docs/verify.md, "Bounded verification")
    bounds: dict[str, float] = field(default_factory=dict)


def _looks_installed(target: str) -> bool:
    return target.count("/") == 1 and not target.endswith((".py", ".machine"))


def read_verify_file(path: Path) -> VerifyFile:
    """The file at `path` (FileError, one line, for anything wrong with it)."""

    def fail(node: yaml.Node | None, message: str) -> FileError:
        line = node.start_mark.line + 1 if node is not None else 1
        return FileError(f"{path}:{line}: {message}")

    try:
        root = yamlfile.load(path, MAX_FILE_BYTES, MAX_DEPTH)
    except yamlfile.Refused as e:
        raise FileError(e.say(str(path), "a verification file", _WORDS)) from None
    if not isinstance(root, yaml.MappingNode):
        raise fail(root, "a verification file is a mapping with `machines:` and `properties:`")
    keys = ("machines", "properties", "bounds", "environment", *FILE_OPTIONS)
    top = _mapping(root, keys, fail, "a verification file")
    mnode = top.get("machines")
    if not isinstance(mnode, yaml.SequenceNode) or not mnode.value:
        raise fail(mnode or root, "`machines:` lists the machines to load, in load order")
    machines = []
    for m in mnode.value:
        if not isinstance(m, yaml.ScalarNode) or not m.value:
            raise fail(m, "each machine is a path (relative to this file) or PKG/NAME")
        p = path.parent / m.value
        machines.append(os.path.normpath(p) if p.exists() or not _looks_installed(m.value) else m.value)
    props: list[PropertySource] = []
    pnode = top.get("properties")
    if pnode is not None and not _null(pnode):
        if not isinstance(pnode, yaml.SequenceNode):
            raise fail(pnode, "`properties:` is a list")
        for item in pnode.value:
            props.append(_property(item, path, fail))
    options: dict[str, Any] = {}
    for key in FILE_OPTIONS:
        node = top.get(key)
        if node is not None:
            if not isinstance(node, yaml.ScalarNode):
                raise fail(node, f"`{key}` is a single value")
            options[key] = node.value if key in ("period", "max_memory") else yaml.safe_load(node.value)
    bounds: dict[str, float] = {}
    bnode = top.get("bounds")
    if bnode is not None and not _null(bnode):
        if not isinstance(bnode, yaml.MappingNode):
            raise fail(bnode, "`bounds:` maps machine.variable to the largest value explored on")
        for k, v in bnode.value:
            value = _construct(v)
            if not isinstance(k, yaml.ScalarNode) or k.value.count(".") != 1:
                raise fail(k, "a bound names machine.variable")
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise fail(v, f"the bound of {k.value} is a number (the largest value explored on)")
            bounds[k.value] = value
    env = Environment()
    enode = top.get("environment")
    if enode is not None and not _null(enode):
        env = _environment(enode, path, fail)
    return VerifyFile(path, machines, props, options, env, bounds)


def _null(node: yaml.Node) -> bool:
    return isinstance(node, yaml.ScalarNode) and node.tag.endswith("null")


def _mapping(node: yaml.Node, keys: tuple[str, ...], fail: Any, what: str) -> dict[str, yaml.Node]:
    if not isinstance(node, yaml.MappingNode):
        raise fail(node, f"{what} is a mapping ({', '.join(keys)})")
    out: dict[str, yaml.Node] = {}
    for k, v in node.value:
        key = k.value if isinstance(k, yaml.ScalarNode) else None
        if key not in keys:
            raise fail(k, f"unknown key {key!r} in {what} ({', '.join(keys)})")
        out[key] = v
    return out


def _construct(node: yaml.Node) -> Any:
    """A node's plain value (mappings, lists, scalars as YAML reads them)."""
    return yamlfile.LOADER("").construct_object(node, deep=True)


def _property(item: yaml.Node, path: Path, fail: Any) -> PropertySource:
    if not isinstance(item, yaml.MappingNode):
        raise fail(item, f"a property is a mapping of one kind ({', '.join(KINDS)}) to its text")
    name = None
    within: int | None = None
    found: tuple[str, Any] | None = None
    for k, v in item.value:
        key = k.value if isinstance(k, yaml.ScalarNode) else None
        if key == "name":
            name = v.value if isinstance(v, yaml.ScalarNode) else None
            if not name:
                raise fail(v, "a property's name is text")
        elif key == "within":
            if not isinstance(v, yaml.ScalarNode):
                raise fail(v, "`within:` is a duration (500ms, 2s)")
            try:
                within = parse_duration(v.value)
            except ValueError as e:
                raise fail(v, f"within: {e}") from None
            if within <= 0:
                raise fail(v, "within: a deadline greater than 0")
        elif key in BY_NAME:
            if found is not None:
                raise fail(k, f"a property has one kind; this one has {found[0]} and {key}")
            if isinstance(v, yaml.ScalarNode):
                found = (key, v.value)
            elif isinstance(v, yaml.SequenceNode) and BY_NAME[key].form == "pair":
                found = (key, [x.value if isinstance(x, yaml.ScalarNode) else None for x in v.value])
            else:
                raise fail(v, f"the text of a {key} property")
        else:
            raise fail(k, f"unknown key {key!r} in a property (name, within, or one of {', '.join(KINDS)})")
    if found is None:
        raise fail(item, f"a property needs one of {', '.join(KINDS)}")
    return PropertySource(found[0], found[1], name, f"{path}:{item.start_mark.line + 1}", within)


def _environment(node: yaml.Node, path: Path, fail: Any) -> Environment:
    top = _mapping(node, ("services", "topics"), fail, "`environment:`")
    env = Environment()
    for section in ("services", "topics"):
        snode = top.get(section)
        if snode is None or _null(snode):
            continue
        if not isinstance(snode, yaml.MappingNode):
            raise fail(snode, f"`{section}:` maps each name to what it declares")
        for k, v in snode.value:
            if not isinstance(k, yaml.ScalarNode) or not k.value.strip():
                raise fail(k, f"each of `{section}:` is named")
            name = k.value if k.value.startswith("/") else "/" + k.value
            where = f"{path}:{k.start_mark.line + 1}"
            if section == "services":
                fields = _mapping(v, ("type", "responses", "may_fail"), fail, f"service {name}")
                responses = _list(fields, "responses", name, v, fail)
                may_fail = _construct(fields["may_fail"]) if "may_fail" in fields else False
                if not isinstance(may_fail, bool):
                    raise fail(fields["may_fail"], f"service {name}: `may_fail:` is true or false")
                if not responses and not may_fail:
                    raise fail(v, f"service {name}: list its `responses:` (or say `may_fail: true`)")
                env.services[name] = ServiceDecl(_type(fields, name, v, fail), responses, may_fail, where)
            else:
                fields = _mapping(v, ("type", "values"), fail, f"topic {name}")
                values = _list(fields, "values", name, v, fail)
                if not values:
                    raise fail(v, f"topic {name}: list the `values:` its messages may have")
                env.topics[name] = TopicDecl(_type(fields, name, v, fail), values, where)
    return env


def _type(fields: dict[str, yaml.Node], name: str, node: yaml.Node, fail: Any) -> str:
    t = fields.get("type")
    if not isinstance(t, yaml.ScalarNode) or t.value.count("/") != 2:
        raise fail(t or node, f"{name}: `type:` is pkg/msg/Name or pkg/srv/Name")
    return str(t.value)


def _list(fields: dict[str, yaml.Node], key: str, name: str, node: yaml.Node, fail: Any) -> list[Any]:
    v = fields.get(key)
    if v is None or _null(v):
        return []
    if not isinstance(v, yaml.SequenceNode):
        raise fail(v, f"{name}: `{key}:` is a list")
    if len(v.value) > MAX_VALUES:
        raise fail(v, f"{name}: more than {MAX_VALUES:,} {key}")
    out = []
    for x in v.value:
        value = _construct(x)
        if value is None:
            value = {}
        if not isinstance(value, dict):
            raise fail(x, f"{name}: each of `{key}:` is a mapping of fields ({{x: 1.0}}; {{}} for the defaults)")
        out.append(value)
    return out
