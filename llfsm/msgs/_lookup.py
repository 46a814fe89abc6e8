"""Interface types by name: `pkg/msg/Name` (or `pkg/Name`, as `ros2` accepts) to llfsm's message,
service and action classes, with a "did you mean" for near misses (docs/cli.md, "The ros2-style
verbs": TYPE).

Every layer that takes a TYPE from a user reads it here: the ros2-style verbs
(llfsm/ros2cli/interface.py turns a `TypeNameError` into their one-line usage error) and the
web view's publish and call forms.  Built-in packages are the generated modules beside this
file, named by their definitions in _interfaces/; a user's packages are found on the interface
search path (llfsm/interface_path.py), as `llfsm run` finds them.
"""

from __future__ import annotations

import difflib
import importlib
import os
import re
from pathlib import Path

from ..interface_path import INTERFACE_KINDS, search_path
from ._message import Action, Message, Service

MSGS_DIR = Path(__file__).resolve().parent
DEFINITIONS = MSGS_DIR / "_interfaces"
_PACKAGE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*$")
KINDS = ("msg", "srv", "action")
_WHAT = {"msg": "message", "srv": "service", "action": "action"}
_EXAMPLES = {
    "msg": "geometry_msgs/msg/Twist",
    "srv": "turtlesim/srv/Spawn",
    "action": "turtlesim/action/RotateAbsolute",
}


class TypeNameError(ValueError):
    """A TYPE that is malformed or names nothing llfsm can import, said in one line."""


def split_type(text: str, kind: str) -> tuple[str, str, str]:
    """("turtlesim", "srv", "Spawn") from "turtlesim/srv/Spawn" or "turtlesim/Spawn"; `kind`
    is what a two-part name means.  Anything else is a TypeNameError (with the close type, if
    one is: `std_msgs/msg/string`)."""
    parts = text.split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3 or parts[1] not in KINDS or not _PACKAGE.match(parts[0]) or not _NAME.match(parts[2]):
        close = _closest(parts[0], parts[-1], kind) if len(parts) == 3 and parts[1] in KINDS else None
        hint = f" (did you mean '{close}'?)" if close else ""
        raise TypeNameError(f"invalid type '{text}': expected pkg/{kind}/Name (e.g. {_EXAMPLES[kind]}){hint}")
    return parts[0], parts[1], parts[2]


def builtin_packages() -> list[str]:
    """The shipped packages: those with generated modules beside this file."""
    return sorted(
        d.name
        for d in MSGS_DIR.iterdir()
        if not d.name.startswith("_") and any((d / k / "__init__.py").is_file() for k in INTERFACE_KINDS)
    )


def _user_packages() -> dict[str, Path]:
    found: dict[str, Path] = {}
    for root in search_path():
        try:
            entries = sorted(root.iterdir())
        except OSError:
            continue
        for d in entries:
            if _PACKAGE.match(d.name) and d.name not in found and any((d / k).is_dir() for k in INTERFACE_KINDS):
                found[d.name] = d
    return found


def packages() -> dict[str, Path]:
    """Every interface package llfsm can import, by name, with the folder of its definitions:
    its own, then the user's from the search path (a user's package of a shipped package's
    name is never imported, so never listed)."""
    out = {pkg: DEFINITIONS / pkg for pkg in builtin_packages()}
    for pkg, d in _user_packages().items():
        out.setdefault(pkg, d)
    return out


def types_of(folder: Path, kind: str) -> list[str]:
    """The names of the types of one kind a package's folder defines, sorted."""
    d = folder / kind
    if not d.is_dir():
        return []
    return sorted(p.stem for p in d.glob(f"*.{kind}") if _NAME.match(p.stem))


def known_types(kind: str) -> list[str]:
    """Every `pkg/kind/Name` llfsm can import: built-in packages, then the user's."""
    return [f"{pkg}/{kind}/{name}" for pkg, d in packages().items() for name in types_of(d, kind)]


#: How alike two names must be to be offered as "did you mean" (difflib's ratio): a package or
#: a type name each on its own, so that what two names share by convention (`_msgs/msg/`) never
#: makes `test_msgs/msg/BasicTypes` look like `std_msgs/msg/Byte`.
CLOSE = 0.75


def _similar(a: str, b: str) -> float:
    return difflib.SequenceMatcher(None, a.lower(), b.lower()).ratio()


def _closest(pkg: str, name: str, kind: str) -> str | None:
    """The known type closest to pkg/kind/name, when one is close: a close name (or one it
    begins: Odom -> Odometry) in the same or a close package.  A type of the same name in an
    unrelated package is not offered: example_interfaces/msg/Int64 is not std_msgs/msg/Int64
    on the wire."""
    best: tuple[float, str] | None = None
    for candidate in known_types(kind):
        cpkg, _, cname = candidate.split("/")
        p = _similar(pkg, cpkg)
        if p < CLOSE:
            continue
        n = _similar(name, cname)
        if n >= CLOSE:
            score = p + n
        elif len(name) >= 3 and cname.lower().startswith(name.lower()):
            score = p + len(name) / len(cname)
        else:
            continue
        if best is None or score > best[0]:
            best = (score, candidate)
    return best[1] if best else None


def where_interfaces() -> str:
    """Where llfsm looks for interface packages, in words, with what the variables hold."""
    env = {name: os.environ.get(name, "") for name in ("LLFSM_INTERFACE_PATH", "AMENT_PREFIX_PATH")}
    shown = {name: f"({value})" if value else "(not set)" for name, value in env.items()}
    return (
        "llfsm looks among the packages it ships, in the folders above the machines (for a command, "
        f"the current folder and the three above it), in LLFSM_INTERFACE_PATH {shown['LLFSM_INTERFACE_PATH']} "
        f"and in share/ of AMENT_PREFIX_PATH {shown['AMENT_PREFIX_PATH']}"
    )


def unknown(text: str, kind: str) -> TypeNameError:
    """The error for a TYPE that names nothing: the right kind when it is another kind's, the
    closest known type when one is close, and for a package found nowhere, where llfsm looked."""
    name = _WHAT[kind]
    parts = text.split("/")
    pkg, tname = parts[0], parts[-1]
    for other in INTERFACE_KINDS:  # std_srvs/msg/Trigger: the kind is wrong
        twin = f"{pkg}/{other}/{tname}"
        if other != kind and len(parts) in (2, 3) and twin in known_types(other):
            return TypeNameError(f"unknown {name} type '{text}' ('{twin}' is {_a(other)} type)")
    close = _closest(pkg, tname, kind)
    hint = f" (did you mean '{close}'?)" if close else ""
    if pkg not in packages():
        return TypeNameError(f"unknown {name} type '{text}': no interface package '{pkg}'{hint}; {where_interfaces()}")
    return TypeNameError(f"unknown {name} type '{text}': {pkg} has no {name} '{tname}'{hint}")


def _import(pkg: str, kind: str, name: str, text: str) -> object:
    try:  # llfsm.msgs (this module's package) has installed the import hook for user packages
        module = importlib.import_module(f"llfsm.msgs.{pkg}.{kind}")
    except ModuleNotFoundError as e:
        if e.name is not None and e.name.startswith(f"llfsm.msgs.{pkg}"):  # no such package, or not that kind in it
            raise unknown(text, kind) from None
        raise TypeNameError(f"{text}: {e}") from None
    except ImportError as e:  # a user's definition that does not compile: file and line
        raise TypeNameError(str(e)) from None
    cls = getattr(module, name, None)
    if cls is None or getattr(cls, "_TYPE", None) != f"{pkg}/{kind}/{name}":
        raise unknown(text, kind)
    return cls


#: The messages rosidl makes of an action's definition (`turtlesim/action/RotateAbsolute_Goal`):
#: topics carry them, as an action's hidden feedback topic carries `Name_FeedbackMessage`.
ACTION_MESSAGES = ("_Goal", "_Result", "_Feedback", "_FeedbackMessage")


def message_class(text: str) -> type[Message]:
    """The message class that TYPE names (`std_msgs/msg/String`, `std_msgs/String`, and the
    messages of an action: `turtlesim/action/RotateAbsolute_FeedbackMessage`)."""
    parts = text.split("/")
    if len(parts) == 3 and parts[1] == "action" and _PACKAGE.match(parts[0]):
        for suffix in ACTION_MESSAGES:
            if parts[2].endswith(suffix) and _NAME.match(parts[2].removesuffix(suffix)):
                return _import(parts[0], "action", parts[2], text)  # type: ignore[return-value]  # a message
    pkg, kind, name = split_type(text, "msg")
    if kind != "msg":
        raise TypeNameError(f"'{text}' is {_a(kind)} type; a topic carries a message type (pkg/msg/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/msg/name


def service_class(text: str) -> type[Service]:
    """The service class that TYPE names (`turtlesim/srv/Spawn`, `turtlesim/Spawn`)."""
    pkg, kind, name = split_type(text, "srv")
    if kind != "srv":
        raise TypeNameError(f"'{text}' is {_a(kind)} type; a service has a service type (pkg/srv/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/srv/name


def action_class(text: str) -> type[Action]:
    """The action class that TYPE names (`turtlesim/action/RotateAbsolute`, `turtlesim/RotateAbsolute`)."""
    pkg, kind, name = split_type(text, "action")
    if kind != "action":
        raise TypeNameError(f"'{text}' is {_a(kind)} type; an action has an action type (pkg/action/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/action/name


def _a(kind: str) -> str:
    """ "a message", "a service", "an action"."""
    return "an action" if kind == "action" else f"a {_WHAT[kind]}"
