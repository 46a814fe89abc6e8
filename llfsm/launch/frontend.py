"""The XML and YAML front ends: a launch file as a tree of elements, each with its line.

Both syntaxes come down to the same tree (`Element`: a tag, attributes, children), as launch's
`Entity` does for its two parsers, so one model (llfsm.launch.model) validates either:
- XML (`*.launch.xml`): elements and attributes; `<param>`, `<remap>`, `<env>`, `<arg>` inside
  a node or include are children.  Read with the standard library's expat, which gives each
  element its line; a DOCTYPE or entity declaration is refused (no entity expansion, no
  external files), as is text between elements.
- YAML (`*.launch.yaml`): `launch:` holds a list of one-key mappings (`- node: {...}`); a key
  whose value is a list of mappings (`param:`, `remap:`, `arg:`...) holds children of that tag,
  and `children:` (or a group's list itself) holds entities.  Anchors and aliases are refused
  (as verification and parameter files refuse them) before any tree is built.

Files are bounded (1 MiB, nesting 64 deep): reading one costs linear time and bounded memory.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from xml.parsers import expat

import yaml

from .. import yamlfile

#: Largest launch file read, in bytes, and deepest nesting of elements.
MAX_FILE_BYTES = 1 << 20
MAX_DEPTH = 64
#: What a launch file says of what llfsm.yamlfile refuses (the rest in its default words).
_WORDS = {"large": "{where}: larger than {mib} MiB: not a launch file"}


class FrontEndError(ValueError):
    """A file that is not a launch file: the message starts with FILE:LINE."""


@dataclass
class Attr:
    """An attribute's value as written: its text, or (YAML) a list of scalars."""

    text: str
    line: int
    quoted: bool = False  # YAML: a quoted scalar ('255' is a string, 255 a number)
    items: list[Attr] | None = None  # YAML: a list of scalars (a parameter's value)


@dataclass
class Element:
    tag: str
    file: str
    line: int
    attrs: dict[str, Attr] = field(default_factory=dict)
    children: list[Element] = field(default_factory=list)


def shown(path: str) -> str:
    """A path as messages show it: relative to the current folder when inside it."""
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return path
    return rel if not rel.startswith("..") else os.path.abspath(path)


def read(path: str) -> Element:
    """The root `launch` element of an XML or YAML launch file (by its name's ending, else by
    its first character); FrontEndError naming the file and line of what is wrong."""
    where = shown(path)
    try:
        text = yamlfile.read_text(path, MAX_FILE_BYTES)
    except yamlfile.Refused as e:
        raise FrontEndError(e.say(where, "a launch file", _WORDS)) from None
    name = path.lower()
    if name.endswith(".xml"):
        return _xml(text, path)
    if name.endswith((".yaml", ".yml")):
        return _yaml(text, path)
    return _xml(text, path) if text.lstrip().startswith("<") else _yaml(text, path)


# -- XML ----------------------------------------------------------------------------------------------
def _xml(text: str, path: str) -> Element:
    where = shown(path)
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def fail(message: str) -> FrontEndError:
        return FrontEndError(f"{where}:{parser.CurrentLineNumber}: {message}")

    def start(tag: str, attrs: dict[str, str]) -> None:
        if len(stack) >= MAX_DEPTH:
            raise fail(f"elements nested deeper than {MAX_DEPTH}")
        line = parser.CurrentLineNumber
        el = Element(tag, path, line, {k: Attr(v, line) for k, v in attrs.items()})
        (stack[-1].children if stack else roots).append(el)
        stack.append(el)

    def end(tag: str) -> None:
        stack.pop()

    def chars(data: str) -> None:
        if data.strip():
            raise fail(f"unexpected text {data.strip()[:40]!r} (a launch file's content is in its attributes)")

    def doctype(*_: object) -> None:
        raise fail("a DOCTYPE is not allowed in a launch file")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    parser.EntityDeclHandler = doctype
    try:
        parser.Parse(text, True)
    except expat.ExpatError as e:
        raise FrontEndError(f"{where}:{e.lineno}: not XML: {expat.errors.messages.get(e.code, str(e))}") from None
    if not roots:
        raise FrontEndError(f"{where}:1: no <launch> element")
    return _root(roots[0], where)


def _root(root: Element, where: str) -> Element:
    if root.tag != "launch":
        raise FrontEndError(f"{where}:{root.line}: the root is <{root.tag}>, not <launch>")
    return root


# -- YAML ---------------------------------------------------------------------------------------------
def _yaml(text: str, path: str) -> Element:
    where = shown(path)
    try:
        root = yamlfile.compose(text, MAX_DEPTH)
    except yamlfile.Refused as e:
        raise FrontEndError(e.say(where, "a launch file", _WORDS)) from None
    if not isinstance(root, yaml.MappingNode) or len(root.value) != 1:
        line = root.start_mark.line + 1 if root is not None else 1
        raise FrontEndError(f"{where}:{line}: a YAML launch file is one mapping, `launch:`, holding a list")
    key, value = root.value[0]
    return _root(_yaml_entity(_key(key, path), key.start_mark.line + 1, value, path), where)


def _yaml_entity(tag: str, line: int, value: yaml.Node, path: str) -> Element:
    """`TAG: {attributes and children}` or `TAG: [entities]` as one element."""
    el = Element(tag, path, line)
    if isinstance(value, yaml.SequenceNode):
        el.children = _yaml_entities(value, path)
    elif isinstance(value, yaml.MappingNode):
        for k, v in value.value:
            name = _key(k, path)
            if name in el.attrs:
                raise _yaml_fail(k, path, f"{name!r} is given twice")
            if name == "children":
                if not isinstance(v, yaml.SequenceNode):
                    raise _yaml_fail(v, path, "`children:` is a list of entities")
                el.children.extend(_yaml_entities(v, path))
            elif isinstance(v, yaml.SequenceNode) and v.value and isinstance(v.value[0], yaml.MappingNode):
                el.children.extend(_yaml_child(name, item, path) for item in v.value)
            else:
                el.attrs[name] = _yaml_attr(v, path, name)
    elif not (isinstance(value, yaml.ScalarNode) and value.value in ("", "~", "null")):
        raise _yaml_fail(value, path, f"`{tag}:` holds its attributes as a mapping")
    return el


def _yaml_entities(seq: yaml.SequenceNode, path: str) -> list[Element]:
    out = []
    for item in seq.value:
        if not isinstance(item, yaml.MappingNode) or len(item.value) != 1:
            raise _yaml_fail(item, path, "each entity is a mapping of one tag (`- node: {...}`)")
        key, value = item.value[0]
        out.append(_yaml_entity(_key(key, path), key.start_mark.line + 1, value, path))
    return out


def _yaml_child(tag: str, item: yaml.Node, path: str) -> Element:
    """One item of `param:`, `remap:`, `arg:`...: a mapping of attributes (and children)."""
    if not isinstance(item, yaml.MappingNode):
        raise _yaml_fail(item, path, f"each item of `{tag}:` is a mapping")
    return _yaml_entity(tag, item.start_mark.line + 1, item, path)


def _yaml_attr(node: yaml.Node, path: str, name: str) -> Attr:
    line = node.start_mark.line + 1
    if isinstance(node, yaml.ScalarNode):
        text = "" if not node.style and node.value in ("~", "null", "Null", "NULL") else node.value
        return Attr(text, line, quoted=bool(node.style))
    if isinstance(node, yaml.SequenceNode) and all(isinstance(x, yaml.ScalarNode) for x in node.value):
        return Attr("", line, items=[_yaml_attr(x, path, name) for x in node.value])
    raise _yaml_fail(node, path, f"`{name}:` holds a value, not a mapping")


def _key(node: yaml.Node, path: str) -> str:
    if not isinstance(node, yaml.ScalarNode) or not node.value:
        raise _yaml_fail(node, path, "a key is a name")
    return str(node.value)


def _yaml_fail(node: yaml.Node, path: str, message: str) -> FrontEndError:
    return FrontEndError(f"{shown(path)}:{node.start_mark.line + 1}: {message}")
