"""Builds: validation first, an incremental skip when nothing changed (a content fingerprint in
the module header), and atomic writes, so an interrupted build never leaves half a module."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from ..discover import machine_name_of
from ..fingerprint import machine_fingerprint, module_fingerprint

if TYPE_CHECKING:
    from ..diagnostics import Diagnostic

# -- builds ------------------------------------------------------------------------------------


@dataclass
class BuildOutcome:
    path: Path  # machine directory
    module: Path | None
    status: str  # compiled | unchanged | failed
    diagnostics: list[Diagnostic] = field(default_factory=list)
    name: str = ""


def write_atomic_bytes(target: Path, data: bytes) -> None:
    """Write via a temporary file in the same folder and rename: readers see old or new, never half."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def write_atomic(target: Path, text: str) -> None:
    write_atomic_bytes(target, text.encode("utf-8"))


def build_machine(path: Path, out_dir: Path, force: bool = False) -> BuildOutcome:
    """Compile one machine into out_dir/NAME.py unless the module there is already up to date."""
    name = machine_name_of(path)
    target = out_dir / f"{name}.py"
    try:
        fp = machine_fingerprint(path)
    except OSError:
        fp = ""
    if not force and fp and module_fingerprint(target) == fp:
        return BuildOutcome(path, target, "unchanged", name=name)
    # only now the checker and the code generator (pydantic, yaml, jinja2): warm builds skip them
    from ..check import check_machine
    from .generate import CompileError, compile_machine

    checked = check_machine(path)
    if not checked.ok:
        return BuildOutcome(path, None, "failed", checked.diagnostics, name=name)
    try:
        source = compile_machine(checked, fp)
    except CompileError as e:
        return BuildOutcome(path, None, "failed", checked.diagnostics + e.diagnostics, name=name)
    write_atomic(target, source)
    return BuildOutcome(path, target, "compiled", checked.diagnostics, name=name)
