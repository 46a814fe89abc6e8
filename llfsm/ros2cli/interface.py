"""`interface show`, and interface types by name: `pkg/msg/Name` (or `pkg/Name`, as `ros2`
accepts) to llfsm's message, service and action classes, which every verb that takes a TYPE
(and the web view) reads it through.

Built-in packages are the generated modules under llfsm/msgs/; their definitions are the files
in llfsm/msgs/_interfaces/ they are generated from (ROS 2's own, with their comments).  A user's
packages are found as `llfsm run` finds them: the interface search path of llfsm.msgs, to which
the commands add the working directory and its parents (where a machine's packages sit).
"""

from __future__ import annotations

import difflib
import importlib
import os
import re
from pathlib import Path

from ..msgs import Message, Service, add_search_path, find_package, search_path
from ..msgs._message import Action
from . import CliError

_MSGS_DIR = Path(__file__).resolve().parent.parent / "msgs"
_DEFINITIONS = _MSGS_DIR / "_interfaces"
_PACKAGE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*$")
KINDS = ("msg", "srv", "action")
_WHAT = {"msg": "message", "srv": "service", "action": "action"}
_EXAMPLES = {
    "msg": "geometry_msgs/msg/Twist",
    "srv": "turtlesim/srv/Spawn",
    "action": "turtlesim/action/RotateAbsolute",
}


def use_working_directory(cwd: str | os.PathLike[str] | None = None) -> None:
    """Search the working directory and its three parents for interface packages, as `llfsm
    run` searches the folders above its machines."""
    here = Path(os.path.realpath(cwd or os.getcwd()))
    for folder in [here, *list(here.parents)[:3]]:
        add_search_path(folder)


def split_type(text: str, kind: str) -> tuple[str, str, str]:
    """("turtlesim", "srv", "Spawn") from "turtlesim/srv/Spawn" or "turtlesim/Spawn"; `kind`
    is what a two-part name means.  Anything else is a usage error."""
    parts = text.split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3 or parts[1] not in KINDS or not _PACKAGE.match(parts[0]) or not _NAME.match(parts[2]):
        raise CliError(f"invalid type '{text}': expected pkg/{kind}/Name (e.g. {_EXAMPLES[kind]})")
    return parts[0], parts[1], parts[2]


def _builtin_packages() -> list[str]:
    return sorted(
        d.name
        for d in _MSGS_DIR.iterdir()
        if not d.name.startswith("_") and any((d / k / "__init__.py").is_file() for k in KINDS)
    )


def _user_packages() -> dict[str, Path]:
    found: dict[str, Path] = {}
    for root in search_path():
        try:
            entries = sorted(root.iterdir())
        except OSError:
            continue
        for d in entries:
            if _PACKAGE.match(d.name) and d.name not in found and any((d / k).is_dir() for k in KINDS):
                found[d.name] = d
    return found


def known_types(kind: str) -> list[str]:
    """Every `pkg/kind/Name` llfsm can import: built-in packages, then the user's."""
    out = []
    builtin = _builtin_packages()
    for pkg in builtin:
        folder = _DEFINITIONS / pkg / kind
        if folder.is_dir():
            out += [f"{pkg}/{kind}/{p.stem}" for p in sorted(folder.glob(f"*.{kind}"))]
    for pkg, d in _user_packages().items():
        if pkg not in builtin and (d / kind).is_dir():
            out += [f"{pkg}/{kind}/{p.stem}" for p in sorted((d / kind).glob(f"*.{kind}")) if _NAME.match(p.stem)]
    return out


def _unknown(text: str, kind: str) -> CliError:
    name = _WHAT[kind]
    parts = text.split("/")
    for other in KINDS:
        twin = f"{parts[0]}/{other}/{parts[-1]}"
        if other != kind and len(parts) in (2, 3) and twin in known_types(other):  # std_srvs/msg/Trigger
            what = "an action" if other == "action" else f"a {_WHAT[other]}"
            return CliError(f"unknown {name} type '{text}' ('{twin}' is {what} type)")
    candidates = known_types(kind)
    close = difflib.get_close_matches(text, candidates, n=1, cutoff=0.6)
    if not close:  # "Twist", "geometry_msgs/twist": match on the name alone
        last = text.rsplit("/", 1)[-1].lower()
        close = [t for t in candidates if t.rsplit("/", 1)[1].lower() == last][:1]
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return CliError(f"unknown {name} type '{text}'{hint}")


def _import(pkg: str, kind: str, name: str, text: str) -> object:
    try:  # llfsm.msgs, imported above, has installed the import hook for user packages
        module = importlib.import_module(f"llfsm.msgs.{pkg}.{kind}")
    except ModuleNotFoundError as e:
        if e.name is not None and e.name.startswith(f"llfsm.msgs.{pkg}"):  # no such package, or no msg/srv in it
            raise _unknown(text, kind) from None
        raise CliError(f"{text}: {e}") from None
    except ImportError as e:  # a user's definition that does not compile: file and line
        raise CliError(str(e)) from None
    cls = getattr(module, name, None)
    if cls is None or getattr(cls, "_TYPE", None) != f"{pkg}/{kind}/{name}":
        raise _unknown(text, kind)
    return cls


def message_class(text: str) -> type[Message]:
    """The message class that TYPE names (`std_msgs/msg/String`, `std_msgs/String`)."""
    pkg, kind, name = split_type(text, "msg")
    if kind != "msg":
        raise CliError(f"'{text}' is {_a(kind)} type; a topic carries a message type (pkg/msg/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/msg/name


def service_class(text: str) -> type[Service]:
    """The service class that TYPE names (`turtlesim/srv/Spawn`, `turtlesim/Spawn`)."""
    pkg, kind, name = split_type(text, "srv")
    if kind != "srv":
        raise CliError(f"'{text}' is {_a(kind)} type; a service has a service type (pkg/srv/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/srv/name


def action_class(text: str) -> type[Action]:
    """The action class that TYPE names (`turtlesim/action/RotateAbsolute`, `turtlesim/RotateAbsolute`)."""
    pkg, kind, name = split_type(text, "action")
    if kind != "action":
        raise CliError(f"'{text}' is {_a(kind)} type; an action has an action type (pkg/action/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/action/name


def _a(kind: str) -> str:
    return "an action" if kind == "action" else f"a {_WHAT[kind]}"


# -- ros2 interface show -------------------------------------------------------------------------


def definition_file(pkg: str, kind: str, name: str) -> Path | None:
    """The .msg/.srv file that defines the type, or None."""
    if pkg in _builtin_packages():
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
        raise _unknown(text, kind)
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
