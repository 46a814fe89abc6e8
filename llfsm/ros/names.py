"""ROS 2 names: validation, expansion and remapping, as rcl does them.

Rules (design.ros2.org "Topic and Service name mapping"): names use letters, digits, `_`, `/`,
`~` and `{substitutions}`; a name must not be empty or end with `/`; no token may start with a
digit; `~` may only start a name, followed by `/` or nothing.  A name starting with `/` is
absolute; `~/x` is private (`<namespace>/<node>/x`); anything else is relative to the node's
namespace.  Remapping rules `from:=to` (or `node:from:=to`, for one node) compare fully
expanded names, as `--ros-args --remap` does.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_TOKEN = r"[A-Za-z_][A-Za-z0-9_]*"
_NODE_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_NAMESPACE_RE = re.compile(rf"/(?:{_TOKEN}(?:/{_TOKEN})*)?\Z")
_SUBST_RE = re.compile(r"\{([^{}]*)\}")
_FULL_RE = re.compile(rf"/{_TOKEN}(?:/{_TOKEN})*\Z")
MAX_NAME = 255


class InvalidNameError(ValueError):
    """An invalid node name, namespace, topic or service name (a clear message, never silent)."""


def validate_node_name(name: str) -> str:
    if not isinstance(name, str) or not name:
        raise InvalidNameError("node name must be a non-empty string")
    if not _NODE_RE.match(name):
        raise InvalidNameError(
            f"invalid node name {name!r}: use letters, digits and underscores, not starting with a digit"
        )
    if len(name) > MAX_NAME:
        raise InvalidNameError(f"invalid node name {name[:20]!r}...: longer than {MAX_NAME} characters")
    return name


def normalise_namespace(ns: str) -> str:
    """ "" and "/" are the root; "robot" means "/robot"; a trailing "/" is dropped."""
    if not isinstance(ns, str):
        raise InvalidNameError("namespace must be a string")
    if ns in ("", "/"):
        return "/"
    full = ns if ns.startswith("/") else "/" + ns
    full = full.rstrip("/") if len(full) > 1 and full.endswith("/") and not full.endswith("//") else full
    if not _NAMESPACE_RE.match(full):
        raise InvalidNameError(
            f"invalid namespace {ns!r}: tokens of letters, digits and underscores separated by '/', "
            "none starting with a digit"
        )
    return full


def validate_name(name: str, what: str = "topic") -> None:
    """The checks that apply before expansion (rcl_validate_topic_name)."""
    if not isinstance(name, str) or not name:
        raise InvalidNameError(f"{what} name must be a non-empty string")
    if name.endswith("/"):
        raise InvalidNameError(f"invalid {what} name {name!r}: must not end with '/'")
    if "~" in name[1:]:
        raise InvalidNameError(f"invalid {what} name {name!r}: '~' may only start a name")
    if name.startswith("~") and len(name) > 1 and name[1] != "/":
        raise InvalidNameError(f"invalid {what} name {name!r}: '~' must be followed by '/'")
    stripped = _SUBST_RE.sub("x", name)
    if "{" in stripped or "}" in stripped:
        raise InvalidNameError(f"invalid {what} name {name!r}: unmatched curly brace")
    bad = re.search(r"[^A-Za-z0-9_/~]", stripped)
    if bad:
        raise InvalidNameError(f"invalid {what} name {name!r}: character {bad.group()!r} is not allowed")
    for token in stripped.lstrip("~").split("/"):
        if token and token[0].isdigit():
            raise InvalidNameError(f"invalid {what} name {name!r}: token {token!r} starts with a digit")


def expand(name: str, node: str, namespace: str, what: str = "topic") -> str:
    """The fully qualified name of `name` used by node `node` in `namespace`."""
    validate_name(name, what)
    ns = normalise_namespace(namespace)
    node_fqn = f"{ns.rstrip('/')}/{node}"

    def subst(m: re.Match[str]) -> str:
        key = m.group(1)
        if key == "node":
            return node
        if key in ("ns", "namespace"):
            return ns  # with its leading slash, as rcl substitutes it: `{ns}/x` is absolute
        raise InvalidNameError(f"invalid {what} name {name!r}: unknown substitution {{{key}}}")

    out = _SUBST_RE.sub(subst, name)
    if out.startswith("//"):
        out = out[1:]  # `{ns}/x` in the root namespace
    if out == "~":
        out = node_fqn
    elif out.startswith("~/"):
        out = node_fqn + out[1:]
    elif not out.startswith("/"):
        out = f"{ns.rstrip('/')}/{out}"
    if len(out) > MAX_NAME or not _FULL_RE.match(out):
        raise InvalidNameError(f"invalid {what} name {name!r}: expands to {out!r}, which is not a valid name")
    return out


@dataclass(frozen=True)
class Remap:
    """One `--remap` rule; `node` limits it to one node (`node:from:=to`)."""

    source: str
    target: str
    node: str | None = None

    @classmethod
    def parse(cls, rule: str) -> Remap:
        if ":=" not in rule:
            raise InvalidNameError(f"--remap {rule!r}: expected FROM:=TO or NODE:FROM:=TO")
        left, target = rule.split(":=", 1)
        node = None
        if ":" in left:
            node, left = left.split(":", 1)
            validate_node_name(node)
        if not left or not target:
            raise InvalidNameError(f"--remap {rule!r}: expected FROM:=TO or NODE:FROM:=TO")
        if left not in ("__node", "__ns", "__name"):
            validate_name(left, "remapped")
            validate_name(target, "remapped")
        return cls(left, target, node)

    def applies_to(self, node: str) -> bool:
        return self.node is None or self.node == node


def remap_name(full: str, node: str, namespace: str, rules: list[Remap], what: str = "topic") -> str:
    """Apply the first matching rule to an expanded name (rcl applies the first match only)."""
    for r in rules:
        if r.source in ("__node", "__ns", "__name") or not r.applies_to(node):
            continue
        if expand(r.source, node, namespace, what) == full:
            return expand(r.target, node, namespace, what)
    return full


def remap_node(node: str, namespace: str, rules: list[Remap]) -> tuple[str, str]:
    """`__node:=name` / `__ns:=/ns` rules rename a node or move it to another namespace."""
    for r in rules:
        if r.applies_to(node):
            if r.source in ("__node", "__name"):
                node = validate_node_name(r.target)
            elif r.source == "__ns":
                namespace = normalise_namespace(r.target)
    return node, namespace


def type_name(obj: object) -> str:
    """The ROS type name of a message or service (class or instance), or Python's name for
    anything else: what the errors of publish() and call_async() say was given instead."""
    t = obj if isinstance(obj, type) else type(obj)
    return getattr(t, "_TYPE", "") or t.__name__
