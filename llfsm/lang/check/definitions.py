"""Interface definitions as `check` knows them: read as text with llfsm.idl's parser, never
imported (`check` runs on untrusted machines in CI, and must not pay for llfsm.msgs either).

The rules that need a message's fields ask here: an input's binding (LF049), a field written
on a variable of a message type (LF051), the import line a message class used without one
needs (LF040's hint).  A definition is found where `llfsm run` would import it from: the
packages llfsm ships (llfsm/msgs/_interfaces, the files its modules are generated from), then
the folders around the machine and the interface search path (llfsm.interface_path).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ...interface_path import (
    INTERFACE_KINDS,
    SHIPPED_DIR,
    interface_folder,
    interface_names,
    is_package_name,
    search_path,
)

if TYPE_CHECKING:
    from ...idl.spec import MessageSpec

#: A definition larger than this is not read (a hostile file must not make `check` slow).
MAX_DEFINITION = 1 << 20


def message_spec(type_name: str, roots: Sequence[str] = ()) -> MessageSpec | None:
    """The fields of `pkg/msg/Name`, or of one section of a service or an action
    (`pkg/srv/Name_Request`, `pkg/action/Name_Goal`); None when no definition is found.
    InterfaceError when the definition cannot be read or parsed."""
    # deferred: start-up (only a machine whose code uses messages reads their definitions)
    from ...idl.spec import SECTIONS, InterfaceError

    parts = type_name.split("/")
    if len(parts) != 3 or parts[1] not in INTERFACE_KINDS:
        return None
    pkg, kind, name = parts
    section = ""
    if kind != "msg":
        name, _, section = name.rpartition("_")
        if section not in SECTIONS[kind]:
            return None
    found = interface_folder(pkg, roots)
    if found is None:
        return None
    path = os.path.join(found[0], kind, f"{name}.{kind}")
    try:
        st = os.stat(path)
    except OSError:
        return None
    if st.st_size > MAX_DEFINITION:
        raise InterfaceError(path, None, f"larger than {MAX_DEFINITION} bytes")
    specs = _parsed(path, f"{pkg}/{kind}/{name}", kind, st.st_mtime_ns)
    return specs[SECTIONS[kind].index(section)] if section else specs[0]


@functools.lru_cache(maxsize=512)
def _parsed(path: str, type_name: str, kind: str, _mtime: int) -> tuple[MessageSpec, ...]:
    """Parsed once per file while it is unchanged: many machines use the same messages."""
    # deferred: start-up (as in message_spec; the parser also imports llfsm.msgs' base)
    from ...idl.parser import parse_message, parse_sections
    from ...idl.spec import InterfaceError

    try:
        with open(path, encoding="utf-8") as f:
            text = f.read(MAX_DEFINITION + 1)
    except (OSError, UnicodeDecodeError) as e:
        raise InterfaceError(path, None, f"cannot read: {e}") from None
    local = interface_names(os.path.dirname(os.path.dirname(path)), "msg")
    if kind == "msg":
        return (parse_message(text, type_name, path, local=local),)
    return tuple(parse_sections(text, kind, type_name, path, local=local))


def interface_imports(name: str, roots: Sequence[str] = ()) -> list[str]:
    """The import lines that give a message, service or action type called `name` (`Pose`:
    geometry_msgs' and turtlesim's): the packages llfsm ships, then a user's in `roots` and in
    the interface search path (as `llfsm run` would find them).  LF040's hint for a type used
    without its import."""
    found = list(_shipped_types().get(name, ()))
    for root in dict.fromkeys([*roots, *(str(p) for p in search_path())]):
        found += [line for line in _user_types(root).get(name, ()) if line not in found]
    return found[:4]


@functools.cache
def _shipped_types() -> dict[str, tuple[str, ...]]:
    return _types_in(SHIPPED_DIR)


@functools.lru_cache(maxsize=64)
def _user_types(root: str) -> dict[str, tuple[str, ...]]:
    return _types_in(root)


#: A folder with more entries than this is not searched for packages (a home folder, say).
MAX_PACKAGES = 1000


def _types_in(root: str) -> dict[str, tuple[str, ...]]:
    """Type name -> its import lines, for the interface packages in `root` (listings only)."""
    out: dict[str, list[str]] = {}
    try:
        with os.scandir(root) as entries:
            packages = sorted(e.name for _, e in zip(range(MAX_PACKAGES), entries, strict=False))
    except OSError:
        return {}
    for pkg in packages:
        if not is_package_name(pkg):
            continue
        for kind in INTERFACE_KINDS:
            for name in interface_names(os.path.join(root, pkg), kind):
                out.setdefault(name, []).append(f"from llfsm.msgs.{pkg}.{kind} import {name}")
    return {k: tuple(v) for k, v in out.items()}
