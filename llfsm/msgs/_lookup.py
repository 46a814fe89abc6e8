"""Interface types by name: `pkg/msg/Name` (or `pkg/Name`, as `ros2` accepts) to llfsm's message
and service classes, with a "did you mean" for near misses (docs/cli.md, "The ros2-style verbs": TYPE).

Every layer that takes a TYPE from a user reads it here: the ros2-style verbs
(llfsm/ros2cli/interface.py turns a `TypeNameError` into their one-line usage error) and the
web view's publish and call forms.  Built-in packages are the generated modules beside this
file, named by their definitions in _interfaces/; a user's packages are found on the interface
search path (llfsm/interface_path.py), as `llfsm run` finds them.
"""

from __future__ import annotations

import difflib
import importlib
import re
from pathlib import Path

from ..interface_path import search_path
from ._message import Message, Service

MSGS_DIR = Path(__file__).resolve().parent
DEFINITIONS = MSGS_DIR / "_interfaces"
_PACKAGE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*$")
KINDS = ("msg", "srv")


class TypeNameError(ValueError):
    """A TYPE that is malformed or names nothing llfsm can import, said in one line."""


def split_type(text: str, kind: str) -> tuple[str, str, str]:
    """("turtlesim", "srv", "Spawn") from "turtlesim/srv/Spawn" or "turtlesim/Spawn"; `kind`
    is what a two-part name means.  Anything else is a TypeNameError."""
    parts = text.split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3 or parts[1] not in KINDS or not _PACKAGE.match(parts[0]) or not _NAME.match(parts[2]):
        example = "geometry_msgs/msg/Twist" if kind == "msg" else "turtlesim/srv/Spawn"
        raise TypeNameError(f"invalid type '{text}': expected pkg/{kind}/Name (e.g. {example})")
    return parts[0], parts[1], parts[2]


def builtin_packages() -> list[str]:
    """The shipped packages: those with generated modules beside this file."""
    return sorted(
        d.name
        for d in MSGS_DIR.iterdir()
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
    builtin = builtin_packages()
    for pkg in builtin:
        folder = DEFINITIONS / pkg / kind
        if folder.is_dir():
            out += [f"{pkg}/{kind}/{p.stem}" for p in sorted(folder.glob(f"*.{kind}"))]
    for pkg, d in _user_packages().items():
        if pkg not in builtin and (d / kind).is_dir():
            out += [f"{pkg}/{kind}/{p.stem}" for p in sorted((d / kind).glob(f"*.{kind}")) if _NAME.match(p.stem)]
    return out


def unknown(text: str, kind: str) -> TypeNameError:
    """The error for a TYPE that names nothing, with the closest known type as a hint."""
    name = "message" if kind == "msg" else "service"
    parts = text.split("/")
    other = "srv" if kind == "msg" else "msg"
    twin = f"{parts[0]}/{other}/{parts[-1]}"
    if len(parts) in (2, 3) and twin in known_types(other):  # std_srvs/msg/Trigger: the kind is wrong
        what = "a service" if other == "srv" else "a message"
        return TypeNameError(f"unknown {name} type '{text}' ('{twin}' is {what} type)")
    candidates = known_types(kind)
    close = difflib.get_close_matches(text, candidates, n=1, cutoff=0.6)
    if not close:  # "Twist", "geometry_msgs/twist": match on the name alone
        last = text.rsplit("/", 1)[-1].lower()
        close = [t for t in candidates if t.rsplit("/", 1)[1].lower() == last][:1]
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return TypeNameError(f"unknown {name} type '{text}'{hint}")


def _import(pkg: str, kind: str, name: str, text: str) -> object:
    try:  # llfsm.msgs (this module's package) has installed the import hook for user packages
        module = importlib.import_module(f"llfsm.msgs.{pkg}.{kind}")
    except ModuleNotFoundError as e:
        if e.name is not None and e.name.startswith(f"llfsm.msgs.{pkg}"):  # no such package, or no msg/srv in it
            raise unknown(text, kind) from None
        raise TypeNameError(f"{text}: {e}") from None
    except ImportError as e:  # a user's definition that does not compile: file and line
        raise TypeNameError(str(e)) from None
    cls = getattr(module, name, None)
    if cls is None or getattr(cls, "_TYPE", None) != f"{pkg}/{kind}/{name}":
        raise unknown(text, kind)
    return cls


def message_class(text: str) -> type[Message]:
    """The message class that TYPE names (`std_msgs/msg/String`, `std_msgs/String`)."""
    pkg, kind, name = split_type(text, "msg")
    if kind != "msg":
        raise TypeNameError(f"'{text}' is a service type; a topic carries a message type (pkg/msg/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/msg/name


def service_class(text: str) -> type[Service]:
    """The service class that TYPE names (`turtlesim/srv/Spawn`, `turtlesim/Spawn`)."""
    pkg, kind, name = split_type(text, "srv")
    if kind != "srv":
        raise TypeNameError(f"'{text}' is a message type; a service has a service type (pkg/srv/Name)")
    return _import(pkg, kind, name, text)  # type: ignore[return-value]  # its _TYPE is pkg/srv/name
