"""`interface show`, `list` and `package`: the definitions of the interface types llfsm can
import.  A TYPE string to its class, for every verb group, is llfsm.ros2cli.lookup.

Built-in packages are the generated modules under llfsm/msgs/; their definitions are the files
in llfsm/msgs/_interfaces/ they are generated from (ROS 2's own, with their comments).  A user's
packages are found as `llfsm run` finds them: the interface search path of llfsm.msgs, to which
the commands add the working directory and its parents (where a machine's packages sit:
`lookup.use_working_directory`).
"""

from __future__ import annotations

import difflib
from pathlib import Path

from ..interface_path import INTERFACE_KINDS
from ..msgs import _lookup, find_package
from ..msgs._lookup import CLOSE, KINDS, builtin_packages, known_types, packages, types_of
from ..msgs._lookup import DEFINITIONS as _DEFINITIONS
from . import NOT_FOUND, CliError
from .lookup import split_type

__all__ = ["KINDS", "definition_file", "known_types", "list_", "package", "show"]

# -- ros2 interface list, package -----------------------------------------------------------------

_HEADINGS = {"msg": "Messages:", "srv": "Services:", "action": "Actions:"}


def list_(*, kinds: tuple[str, ...] = ()) -> str:
    """`ros2 interface list`: each kind under its heading (all three when `kinds` is empty),
    every type of every package llfsm can import, indented by four spaces."""
    out = []
    for kind in [k for k in _HEADINGS if not kinds or k in kinds]:
        out.append(_HEADINGS[kind] + "\n")
        out += [f"    {t}\n" for t in known_types(kind)]
    return "".join(out)


def package(name: str, *, kinds: tuple[str, ...] = ()) -> str:
    """`ros2 interface package NAME`: the package's types, one a line (ros2 prints them in no
    particular order; llfsm sorts them).  An unknown package is status 1, as in ros2."""
    known = packages()
    folder = known.get(name)
    if folder is None:
        close = difflib.get_close_matches(name, list(known), n=1, cutoff=CLOSE)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise CliError(f"Unknown package '{name}'{hint}", NOT_FOUND)
    found = [f"{name}/{k}/{t}" for k in INTERFACE_KINDS if not kinds or k in kinds for t in types_of(folder, k)]
    return "".join(f"{t}\n" for t in sorted(found))


# -- ros2 interface show -------------------------------------------------------------------------


def definition_file(pkg: str, kind: str, name: str) -> Path | None:
    """The .msg/.srv/.action file that defines the type, or None."""
    if pkg in builtin_packages():
        folders = [_DEFINITIONS / pkg / kind]
    else:
        d = find_package(pkg)
        folders = [] if d is None else [d / kind]
    for folder in folders:
        p = folder / f"{name}.{kind}"
        if p.is_file():
            return p
    return None


def _nested_types(path: Path, pkg: str, kind: str, name: str, text: str) -> dict[int, str]:
    """Line number -> the message type its field holds, for the lines that hold a message."""
    # deferred: start-up (only `interface show` parses; resolving a TYPE never does)
    from ..idl.parser import parse_action, parse_message, parse_service
    from ..idl.spec import InterfaceError

    local = {p.stem for p in (path.parent.parent / "msg").glob("*.msg")}
    try:
        if kind == "msg":
            halves = [parse_message(text, f"{pkg}/msg/{name}", str(path), local=local)]
        elif kind == "srv":
            halves = list(parse_service(text, f"{pkg}/srv/{name}", str(path), local=local).parts)
        else:
            halves = list(parse_action(text, f"{pkg}/action/{name}", str(path), local=local).parts)
    except InterfaceError as e:
        raise CliError(str(e)) from None
    return {f.line: f.type.base for h in halves for f in h.fields if f.type.is_message and f.line is not None}


def _content(line: str) -> str:
    """The line without its comment, stripped ('' for a blank or comment-only line)."""
    from ..idl.parser import strip_comment  # deferred: start-up, as in _nested_types

    return strip_comment(line).strip()


def show(text: str, *, comments: str = "top") -> str:
    """`ros2 interface show TYPE`: the definition as written, each field that holds a message
    followed by that message's definition one tab deeper.  `comments`: "top" keeps the comments
    and blank lines of the type itself (ros2's default), "all" of nested ones too, "none" of none."""
    kind = text.split("/")[1] if text.count("/") == 2 else None
    if kind is None:  # pkg/Name: a message if there is one, else a service, else an action
        pkg, _, name = split_type(text, "msg")
        kind = next((k for k in KINDS if definition_file(pkg, k, name)), "msg")
    pkg, kind, name = split_type(text, kind)
    out: list[str] = []
    _show(pkg, kind, name, text, comments != "none", comments == "all", 0, out, ())
    return "".join(out)


def _show(
    pkg: str,
    kind: str,
    name: str,
    text: str,
    keep_comments: bool,
    nested_comments: bool,
    level: int,
    out: list[str],
    seen: tuple[str, ...],
) -> None:
    path = definition_file(pkg, kind, name)
    if path is None:
        raise CliError(str(_lookup.unknown(text, kind)))
    try:
        source = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise CliError(f"{path}: cannot read: {e}") from None
    nested = _nested_types(path, pkg, kind, name, source)
    indent = "\t" * level
    for number, raw in enumerate(source.splitlines(), start=1):
        line = raw.rstrip()
        if not keep_comments:
            line = _content(line)
            if not line:
                continue
        out.append(f"{indent}{line}\n" if line else "\n")
        inner = nested.get(number)
        if inner is not None:
            if inner in seen:  # a recursive definition: ROS forbids it, but never loop on one
                raise CliError(f"{path}:{number}: {inner} contains itself")
            ipkg, _, iname = inner.split("/")
            _show(ipkg, "msg", iname, inner, nested_comments, nested_comments, level + 1, out, (*seen, inner))
