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

Node names may hold wildcards as rcl takes them: `/**` for any namespaces, `*` for part of a
name.  Entries a node matches apply in file order, so a later one wins; then `-p NAME:=VALUE`,
then `-p NODE:NAME:=VALUE`, as `--ros-args -p` wins over files.  Values are typed as rcl types
them: an unquoted scalar is a bool (`true`, `yes`, `on`...), an integer (`0x1F` too), a double
(`1e3`, `.inf`) or else a string; a quoted one is a string; a list holds one type.  Anything
else (a list of mixed types, a node without `ros__parameters`, text that is not YAML) is one
error naming the file and line: a run refuses it before any node or machine starts.

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
#: A params file larger than this is not a params file (and would take a run long to read), nor
#: one nested deeper (namespaces, nodes and nested names: a handful of levels).
MAX_FILE_BYTES = 16 * 1024 * 1024
MAX_DEPTH = 64
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


# -- values ---------------------------------------------------------------------------------------
def scalar(text: str, quoted: bool) -> Any:
    """An rcl-typed scalar: a bool, an int, a float, else a string (always a string if quoted)."""
    if quoted:
        return text
    if text in TRUE:
        return True
    if text in FALSE:
        return False
    body = text.replace("_", "") if re.fullmatch(r"[-+]?[0-9][0-9_]*", text) else text
    try:
        return int(body, 0)
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
        return scalar(node.value, bool(node.style))
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


def value_from_text(text: str) -> Any:
    """A value as `-p NAME:=VALUE` writes it (rcl's rules, YAML flow lists included)."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return text
    if node is None:
        return text
    return _typed(node, "-p", "value") if not isinstance(node, yaml.MappingNode) else text


def guess_value(text: str) -> Any:
    """A value as `ros2 param set` guesses it (rclpy's get_parameter_value): YAML's bool, int,
    float or list of one type, else the text itself as a string."""
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return text
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
        value = value_from_text(raw)
    except ParameterTextError as e:
        raise ParameterTextError(f"-p {text!r}: {str(e).removeprefix('-p: ')}") from None
    return (node or None), name, value


# -- params files -------------------------------------------------------------------------------------
def node_pattern(key: str) -> re.Pattern[str]:
    """A node key of a params file as a pattern over fully qualified names (rcl's wildcards)."""
    full = key if key.startswith("/") else "/" + key
    out = []
    i = 0
    while i < len(full):
        if full.startswith("/**", i):
            out.append("(?:/[^/]+)*")
            i += 3
        elif full[i] == "*":
            out.append("[^/]*")
            i += 1
        else:
            out.append(re.escape(full[i]))
            i += 1
    return re.compile("".join(out))


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
    as nested mappings), which `--params-file` and `param load` read back."""
    tree: dict[str, Any] = {}
    for name, value in values.items():
        parts = name.split(".")
        d = tree
        for p in parts[:-1]:
            d = d.setdefault(p, {})
        d[parts[-1]] = value
    return yaml.dump({full_name: {PARAMS_KEY: tree}}, default_flow_style=False) + "\n"
