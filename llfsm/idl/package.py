"""The package builder: a folder in ROS layout (PKG/msg/*.msg, PKG/srv/*.srv,
PKG/action/*.action) read into a PackageSpec, checked, and compiled into the cache as an
importable llfsm.msgs.PKG (docs/bus.md, "Your own interfaces").

`build_package` is what the import hook of llfsm.msgs calls, through its one deferred import,
the first time a user's package is imported (or after one of its files changed): the only
way run time reaches the toolchain.  The shipped packages are read with the same
`read_package` (llfsm.idl.shipped).
"""

from __future__ import annotations

import importlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from ..interface_path import find_package
from ..templating import header_lines
from .generate import render_package
from .parser import parse_action, parse_message, parse_service, parse_type
from .spec import KINDS, PACKAGE_NAME, PRIMITIVES, TYPE_NAME, FieldSpec, InterfaceError, MessageSpec, PackageSpec

MSGS_DIR = Path(__file__).resolve().parent.parent / "msgs"


def _definition_files(package_dir: Path, kind: str) -> list[Path]:
    folder = package_dir / kind
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.suffix == f".{kind}" and p.is_file())


def read_package(package_dir: Path, source: str | None = None) -> PackageSpec:
    """Every definition of the package's kinds: each .msg of PKG/msg, each .srv of PKG/srv, each
    .action of PKG/action."""
    name = package_dir.name
    if not PACKAGE_NAME.match(name):
        raise InterfaceError(str(package_dir), None, f"invalid package name {name!r}")
    spec = PackageSpec(name, source=source or str(package_dir))
    files = {kind: _definition_files(package_dir, kind) for kind in KINDS}
    local = {p.stem for p in files["msg"]}
    for kind in KINDS:
        for p in files[kind]:
            if not TYPE_NAME.match(p.stem):
                raise InterfaceError(str(p), None, f"invalid {kind} name {p.stem!r}: names are CamelCase")
            try:
                text = p.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as e:
                raise InterfaceError(str(p), None, f"cannot read: {e}") from None
            type_name = f"{name}/{kind}/{p.stem}"
            if kind == "msg":
                spec.messages.append(parse_message(text, type_name, str(p), local=local))
            elif kind == "srv":
                spec.services.append(parse_service(text, type_name, str(p), local=local))
            else:
                spec.actions.append(parse_action(text, type_name, str(p), local=local))
    return spec


def check_references(package: PackageSpec, exists: Callable[[str, str], bool]) -> None:
    """Every message a field names must exist: `exists(pkg, Name)` answers for other packages."""
    own = {m.name for m in package.messages}
    for msg in package.all_messages():
        for f in msg.fields:
            if not f.type.is_message:
                continue
            pkg, _, name = f.type.base.split("/")
            if (pkg == package.name and name in own) or (pkg != package.name and exists(pkg, name)):
                continue
            hint = f" (did you mean {name.lower()}?)" if name.lower() in PRIMITIVES else ""
            raise InterfaceError(msg.path, f.line, f"field {f.name}: unknown message type {pkg}/msg/{name}{hint}")


def installed_spec(type_name: str) -> MessageSpec:
    """The definition of an importable message class, read back from its `_FIELDS` (how a
    user's package learns the layout of the messages it uses from other packages)."""
    pkg, kind, name = type_name.split("/")
    cls = getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)

    def fail(message: str) -> InterfaceError:
        return InterfaceError(type_name, None, message)

    fields = [FieldSpec(f, parse_type(t, pkg, set(), fail)) for f, t in cls._FIELDS]
    return MessageSpec(type_name, fields, path=type_name)


def _exists_anywhere(pkg: str, name: str) -> bool:
    """A message that a user's package references: shipped, or in the interface search path."""
    if (MSGS_DIR / pkg / "msg" / "__init__.py").exists():
        return hasattr(importlib.import_module(f"llfsm.msgs.{pkg}.msg"), name)
    where = find_package(pkg)
    return where is not None and (where / "msg" / f"{name}.msg").is_file()


def write_atomic(path: Path, text: str) -> None:
    """Write `path` whole or not at all (a reader never sees half a module), world-readable."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would hide committed modules from other users
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def build_package(package_dir: Path, out_dir: Path, fingerprint: str) -> None:
    """Compile a user's interface package into `out_dir` (which must not exist yet): the import
    hook's compiler.  Raises InterfaceError (an ImportError) naming the file and line at fault."""
    package = read_package(package_dir)
    check_references(package, _exists_anywhere)
    # the folder is a user's: never on line 1 or 2 (PEP 263), and escaped onto one line
    header = header_lines(
        "Generated by llfsm from a package's .msg/.srv/.action files: edit the definitions, not this file.",
        Fingerprint=fingerprint,
        Source=package_dir,
    )
    for rel, text in render_package(package, header, installed_spec).items():
        write_atomic(out_dir / rel, text)
