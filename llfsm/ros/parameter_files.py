"""Parameter values written as text: `llfsm run -p [NODE:]NAME:=VALUE`, `--params-file FILE` (ROS
2's YAML, read as rcl_yaml_param_parser reads it) and `llfsm param dump` (YAML that
`--params-file` loads back).

A params file names nodes, and under each its parameters:

    /**:                      # every node
      ros__parameters:
        use_sim_time: false
    turtlesim:                # the node turtlesim in the root namespace (same as /turtlesim)
      ros__parameters:
        background_r: 200
    /llfsm/turtle_follower:   # a machine's node: its variables listed under `parameters:`
      ros__parameters:
        k_angular: 6.0
    robots:                   # a namespace: the node /robots/driver
      driver:
        ros__parameters:
          pid: {kp: 1.0}      # nested names: pid.kp

Node names may hold wildcards as rcl takes them: a part `**` for any number of namespaces, `*`
for any part of one name (`/**/driver_*`).  They are matched part by part, never by a regular
expression that could backtrack: a key costs at most (its parts x the name's parts) comparisons
of one part each, each in one pass over the part.  Entries a node matches apply in file order,
so a later one wins; then `-p NAME:=VALUE`, then `-p NODE:NAME:=VALUE`, as `--ros-args -p` wins
over files.  Values are typed as rcl types them: an unquoted scalar is a bool (`true`, `yes`,
`on`...), an integer (`0x1F` too), a double (`1e3`, `.inf`) or else a string; a quoted one is a
string; a list holds one type.  Anything
else (a list of mixed types, a node without `ros__parameters`, text that is not YAML, an integer
outside int64, a YAML anchor or alias) is one error naming the file and line: a run refuses it
before any node or machine starts.

The overrides this produces are what llfsm.ros.parameters reads at declare time (Bus fields
`parameters` and `parameter_files`).  See docs/parameters.md.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import yaml

from .. import yamlfile

#: The key under a node that holds its parameters.
PARAMS_KEY = "ros__parameters"
#: rcl_yaml_param_parser's words for true and false.
TRUE = frozenset({"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON", "y", "Y"})
FALSE = frozenset({"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF", "n", "N"})
#: A params file larger than this is not a params file (and would take a run long to read).
MAX_FILE_BYTES = 16 * 1024 * 1024
#: Mappings and lists nested deeper than this in a params file: far more than namespaces, a
#: node, `ros__parameters` and parameter names of many parts ever need.
MAX_DEPTH = 64
#: Parts of a parameter name `param dump` nests at most (then the rest is one key): what it
#: writes is read back under MAX_DEPTH.
DUMP_NESTING = MAX_DEPTH - 8

#: The integers a parameter holds (rcl_interfaces' int64).
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
#: A text that YAML and rcl read as a decimal integer: one longer than this is outside int64
#: (and Python would refuse to convert one of more than 4300 digits).
_DECIMAL = re.compile(r"[-+]?[0-9][0-9_]*")
_MAX_DECIMAL = 24
#: A params file's words for what llfsm.yamlfile refuses (the rest in its default words; anchors
#: and aliases are refused as rcl_yaml_param_parser refuses them).
_WORDS = {
    "unreadable": "--params-file {where}: cannot read: {detail}",
    "large": "{where}: larger than {mib} MB: not a params file",
}

#: An override: the value, and where it was written (`params.yaml:3`, `-p gain:=2`).
Override = tuple[Any, str]


class ParameterTextError(ValueError):
    """A value, `-p` or params file that cannot be read: the message names the file and line."""


class OutsideInt64(ParameterTextError):
    """An integer no parameter can hold; the message says so, the caller says where."""

    def __init__(self, text: str) -> None:
        shown = text if len(text) <= 40 else f"{text[:20]}...{text[-8:]} ({len(text)} characters)"
        super().__init__(f"{shown} is outside the 64-bit integers a parameter holds ({INT64_MIN} to {INT64_MAX})")


def int64(text: str) -> int:
    """An integer written as rcl and YAML write one (`0x1F`, `1_000`), in int64 or OutsideInt64;
    ValueError when it is no integer."""
    body = text.replace("_", "") if _DECIMAL.fullmatch(text) else text
    if len(body.lstrip("+-")) > _MAX_DECIMAL and _DECIMAL.fullmatch(text):
        raise OutsideInt64(text)
    value = int(body, 0)
    if not INT64_MIN <= value <= INT64_MAX:
        raise OutsideInt64(text)
    return value


# -- values ---------------------------------------------------------------------------------------
def scalar(text: str, quoted: bool) -> Any:
    """An rcl-typed scalar: a bool, an int, a float, else a string (always a string if quoted);
    OutsideInt64 for an integer no parameter can hold."""
    if quoted:
        return text
    if text in TRUE:
        return True
    if text in FALSE:
        return False
    try:
        return int64(text)
    except OutsideInt64:
        raise
    except ValueError:
        pass
    special = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}
    if text.lower() in special:
        return special[text.lower()]
    try:
        return float(text)
    except ValueError:
        return text


def _typed(node: yaml.Node, where: str, name: str) -> Any:
    """The value of a YAML node as rcl types it; ParameterTextError when no parameter can hold it."""
    if isinstance(node, yaml.ScalarNode):
        if not node.style and node.value in ("", "~", "null", "Null", "NULL"):
            raise ParameterTextError(f"{where}: parameter {name} has no value")
        try:
            return scalar(node.value, bool(node.style))
        except OutsideInt64 as e:
            raise ParameterTextError(f"{where}: parameter {name}: {e}") from None
    if isinstance(node, yaml.SequenceNode):
        items = []
        for item in node.value:
            if not isinstance(item, yaml.ScalarNode):
                raise ParameterTextError(f"{where}: parameter {name}: a list may hold only plain values, not lists")
            items.append(_typed(item, where, name))
        if not items:
            raise ParameterTextError(f"{where}: parameter {name}: an empty list has no type a parameter can take")
        kinds = {_kind(v) for v in items}
        if len(kinds) > 1:
            raise ParameterTextError(
                f"{where}: parameter {name}: a list must hold values of one type, not {' and '.join(sorted(kinds))}"
            )
        return items
    raise ParameterTextError(f"{where}: parameter {name}: not a value")


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "booleans"
    if isinstance(value, int):
        return "integers"
    if isinstance(value, float):
        return "doubles"
    return "strings"


def value_from_text(text: str, name: str = "value") -> Any:
    """A value as `-p NAME:=VALUE` writes it (rcl's rules, YAML flow lists included)."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return text
    if node is None:
        return text
    return _typed(node, "-p", name) if not isinstance(node, yaml.MappingNode) else text


def guess_value(text: str) -> Any:
    """A value as `ros2 param set` guesses it (rclpy's get_parameter_value): YAML's bool, int,
    float or list of one type, else the text itself as a string.  OutsideInt64 for an integer
    (alone or in the list) that no parameter can hold."""
    if _DECIMAL.fullmatch(text.strip()):
        return int64(text.strip())
    try:
        value = yaml.load(text, Loader=yamlfile.LOADER)
    except yaml.YAMLError:
        return text
    except ValueError:  # an integer of more than 4300 digits, a date that is none
        if re.search(rf"[0-9]{{{_MAX_DECIMAL}}}", text):
            raise OutsideInt64(text) from None
        return text
    for item in value if isinstance(value, list) else (value,):
        if isinstance(item, int) and not isinstance(item, bool) and not INT64_MIN <= item <= INT64_MAX:
            raise OutsideInt64(str(item))
    if isinstance(value, bool | int | float):
        return value
    if isinstance(value, list) and value:
        for kind in (bool, int, float, str):
            if all(isinstance(v, kind) and (kind is bool or not isinstance(v, bool)) for v in value):
                return value
        return text
    if isinstance(value, list):
        return text
    return value if isinstance(value, str) else text


# -- -p ---------------------------------------------------------------------------------------------
def parse_param(text: str) -> tuple[str | None, str, Any]:
    """`-p [NODE:]NAME:=VALUE` -> (node or None, name, value).  NODE is a node's name or its
    fully qualified name (`/llfsm/M:gain:=2.0`)."""
    if ":=" not in text:
        raise ParameterTextError(f"-p {text!r}: expected [NODE:]NAME:=VALUE")
    left, raw = text.split(":=", 1)
    node, _, name = left.rpartition(":")
    if not name or not raw.strip():
        raise ParameterTextError(f"-p {text!r}: expected [NODE:]NAME:=VALUE")
    try:
        value = value_from_text(raw, name)
    except ParameterTextError as e:
        shown = text if len(text) <= 80 else f"{left}:=..."
        raise ParameterTextError(f"-p {shown!r}: {str(e).removeprefix('-p: ')}") from None
    return (node or None), name, value


# -- params files -------------------------------------------------------------------------------------
class NodeKey:
    """A node key of a params file, as rcl matches it against fully qualified node names: part
    by part (the parts between slashes), where a part `**` matches any number of parts and a
    `*` in a part any text within it.  `fullmatch(name)` is True when the key names the node."""

    __slots__ = ("key", "parts")

    def __init__(self, key: str) -> None:
        self.key = key
        full = key if key.startswith("/") else "/" + key
        #: Each part: None for `**`, else its text split at `*` (one piece: no wildcard).
        self.parts: list[list[str] | None] = []
        for part in full[1:].split("/"):
            if part == "**":
                if not self.parts or self.parts[-1] is not None:  # `**/**` is `**`
                    self.parts.append(None)
            else:
                self.parts.append(part.split("*"))

    def __repr__(self) -> str:
        return f"NodeKey({self.key!r})"

    def fullmatch(self, name: str) -> bool:
        """Whether the key names the node `name` (fully qualified: `/ns/node`).  The classic
        matching of one wildcard with a single point to go back to: at most (parts of the key x
        parts of the name) comparisons of one part, each by `_part`, in one pass over it."""
        parts, names = self.parts, name[1:].split("/") if name.startswith("/") else name.split("/")
        p = n = 0
        star, mark = -1, 0
        while n < len(names):
            if p < len(parts) and parts[p] is None:
                star, mark = p, n
                p += 1
            elif p < len(parts) and _part(parts[p], names[n]):  # type: ignore[arg-type]  # not None here
                p += 1
                n += 1
            elif star != -1:
                p, mark = star + 1, mark + 1
                n = mark
            else:
                return False
        return all(part is None for part in parts[p:])


def _part(pieces: list[str], text: str) -> bool:
    """Whether one part of a node name matches one part of a key, split at its `*`s: the first
    piece leads it, the last ends it, the others are found in order, each at its first place
    (for `*` alone, the first place is always right), so one pass over the text decides."""
    if len(pieces) == 1:
        return pieces[0] == text
    head, *middle, tail = pieces
    if len(text) < len(head) + len(tail) or not text.startswith(head) or not text.endswith(tail):
        return False
    at, end = len(head), len(text) - len(tail)
    for piece in middle:
        found = text.find(piece, at, end)
        if found == -1:
            return False
        at = found + len(piece)
    return True


def node_pattern(key: str) -> NodeKey:
    """A node key of a params file, ready to match fully qualified node names (NodeKey)."""
    return NodeKey(key)


def read_params_file(path: str | Path) -> list[tuple[str, dict[str, Override]]]:
    """The entries of a params file in file order: (node key, {name: (value, "FILE:LINE")})."""
    shown = str(path)
    try:
        root = yamlfile.load(path, MAX_FILE_BYTES, MAX_DEPTH)
    except yamlfile.Refused as e:
        raise ParameterTextError(e.say(shown, "a params file", _WORDS)) from None
    if root is None:
        raise ParameterTextError(f"{shown}:1: the file holds no parameters")
    entries: list[tuple[str, dict[str, Override]]] = []
    _nodes(root, "", shown, entries)
    if not entries:
        raise ParameterTextError(f"{shown}:1: the file holds no node with `{PARAMS_KEY}`")
    return entries


def _line(node: yaml.Node) -> int:
    return node.start_mark.line + 1


def _mapping(node: yaml.Node, shown: str, what: str) -> list[tuple[str, yaml.Node, yaml.Node]]:
    if not isinstance(node, yaml.MappingNode):
        raise ParameterTextError(f"{shown}:{_line(node)}: {what} must be a mapping")
    out = []
    for k, v in node.value:
        if not isinstance(k, yaml.ScalarNode) or not k.value:
            raise ParameterTextError(f"{shown}:{_line(k)}: keys must be names")
        out.append((k.value, k, v))
    return out


def _nodes(node: yaml.Node, prefix: str, shown: str, entries: list[tuple[str, dict[str, Override]]]) -> None:
    what = f"the entry of {prefix}" if prefix else "a params file"
    for key, knode, value in _mapping(node, shown, what):
        if key == PARAMS_KEY:
            if not prefix:
                raise ParameterTextError(f"{shown}:{_line(knode)}: `{PARAMS_KEY}` must be under a node name")
            params: dict[str, Override] = {}
            _parameters(value, "", shown, params)
            entries.append((prefix, params))
            continue
        name = f"{prefix.rstrip('/')}/{key.lstrip('/')}" if prefix else key
        if not isinstance(value, yaml.MappingNode):
            raise ParameterTextError(
                f"{shown}:{_line(knode)}: {key}: expected a node's `{PARAMS_KEY}:` (or a namespace holding nodes)"
            )
        _nodes(value, name, shown, entries)


def _parameters(node: yaml.Node, prefix: str, shown: str, out: dict[str, Override]) -> None:
    for key, knode, value in _mapping(node, shown, f"`{PARAMS_KEY}`"):
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, yaml.MappingNode):
            _parameters(value, name, shown, out)
            continue
        where = f"{shown}:{_line(knode)}"
        out[name] = (_typed(value, where, name), where)


def dump(full_name: str, values: dict[str, Any]) -> str:
    """What `ros2 param dump NODE` prints: the node's parameters as a params file (nested names
    as nested mappings), which `--params-file` and `param load` read back.  Whatever names a
    node answers are written: where a name cannot nest (`a` beside `a.b`, an empty part, more
    than DUMP_NESTING parts) the rest of it is one key with its dots, which a params file reads
    as the same name."""
    return yaml.dump({full_name: {PARAMS_KEY: _tree(values, 0)}}, default_flow_style=False) + "\n"


def _tree(values: dict[str, Any], depth: int) -> dict[str, Any]:
    """`values` (names relative to this level) as nested mappings (dump's docstring)."""
    tree: dict[str, Any] = {}
    groups: dict[str, dict[str, Any]] = {}
    for name, value in values.items():
        head, dot, rest = name.partition(".")
        if dot and head and rest and depth < DUMP_NESTING:
            groups.setdefault(head, {})[rest] = value
        else:
            tree[name] = value
    for head, below in groups.items():
        if head in tree:  # `a` has a value of its own: the names below it stay whole
            tree.update({f"{head}.{rest}": value for rest, value in below.items()})
        else:
            tree[head] = _tree(below, depth + 1)
    return tree
