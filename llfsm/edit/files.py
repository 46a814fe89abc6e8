"""Planners for whole files: a file of the machine written as text (the editor's code editors),
a new machine, and layout.yaml's positions.

`write_file` takes only the names a machine directory holds (docs/machine-format.md: machine.yaml,
layout.yaml, Includes.py, Variables.py, State_S_<section>.py, State_S_Transition_N.expr), and
does not need machine.yaml to be valid: the editor writes machine.yaml as the user types it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from ruamel.yaml.comments import CommentedMap

from ..lang.files import GUARD_RE, header, header_target, is_machine_file
from ..lang.layout_file import MAX_COORD
from ..lang.reader import MAX_FILE_BYTES
from ..machinedir import LAYOUT_FILE, MACHINE_SUFFIX
from ..scaffold import ScaffoldError, machine_files
from .change import Change, EditError, check_relpath, check_root, read_plain
from .plan import MACHINE_YAML, Plan, check_name, target_of


def write_file(machine: Path, relpath: str, text: str) -> Change:
    """`relpath` of the machine holds `text` (UTF-8).  A new guard file starts with
    `# -> TARGET` when machine.yaml says which transition it is."""
    root = Path(machine)
    check_root(root)
    parts = check_relpath(relpath)
    if len(parts) != 1 or not is_machine_file(relpath):
        raise EditError(
            f"refused file name {relpath!r}: not a file of a machine directory (machine.yaml, layout.yaml, "
            "Includes.py, Variables.py, State_S_<section>.py, State_S_Transition_N.expr)"
        )
    if not isinstance(text, str) or "\0" in text:
        raise EditError(f"{relpath}: refused text (not a string, or it holds a NUL byte)")
    data = text.encode("utf-8", "surrogatepass")
    if len(data) > MAX_FILE_BYTES:
        raise EditError(f"{relpath}: larger than {MAX_FILE_BYTES // 1024} KiB; refused")
    before = read_plain(root, relpath)
    guard = GUARD_RE.match(relpath)
    if before is None and guard is not None and header_target(text) is None:
        target = _target(root, guard["state"], int(guard["n"]))
        if target is not None:
            data = (header(target) + text).encode("utf-8", "surrogatepass")
    writes = {relpath: data} if data != before else {}
    return Change(root, writes, {relpath: before} if writes else {}, f"wrote {relpath}")


def _target(root: Path, state: str, n: int) -> str | None:
    """The target of transition n of `state`, if machine.yaml can be read and says."""
    try:
        p = Plan(root)
        st = p.by_name.get(state)
        entries = list(st.get("transitions") or []) if st is not None else []
    except EditError:
        return None
    return target_of(entries[n]) if n < len(entries) else None


def new_machine(
    folder: Path, name: str, states: Sequence[str] | None = None, *, description: str | None = None
) -> Change:
    """A new machine NAME.machine in `folder`: `states` in a chain (default INITIAL -> END),
    as `llfsm new machine --states` writes it.  The Change's root is `folder`."""
    check_name(name, "machine name")
    try:
        files = machine_files(name, description, states)
    except ScaffoldError as e:
        raise EditError(str(e)) from None
    target = Path(folder) / (name + MACHINE_SUFFIX)
    if target.exists() or target.is_symlink():
        raise EditError(f"{target} already exists")
    n = len(states) if states is not None else 2
    change = write_machine(folder, name, files)
    return Change(change.root, change.writes, change.before, f"created machine {name} ({n} states)")


class MachineExists(EditError):
    """`write_machine` without `replace` found the machine directory there already (the caller
    says how to replace it: `llfsm import --force`)."""

    def __init__(self, target: Path) -> None:
        super().__init__(f"{target} exists")
        self.target = target


def write_machine(folder: Path, name: str, files: Mapping[str, str], *, replace: bool = False) -> Change:
    """NAME.machine in `folder` holding exactly `files` (file name -> text; names of the machine
    format only, as `write_file` takes): a new machine, or with `replace` an llfsm machine that
    is there already, its files that `files` does not name removed.  `apply` then writes the
    whole directory or none of it (a full disk midway leaves the old machine as it was).

    A machine directory holding anything but plain files (a folder, a symlink) is not replaced:
    llfsm writes files, and removes nothing it did not write.  The Change's root is `folder` and
    its paths NAME.machine/FILE, as `new_machine`'s."""
    root = Path(folder)
    check_root(root)
    check_name(name, "machine name")
    for rel in files:
        if not isinstance(rel, str) or "/" in rel or not is_machine_file(rel):
            raise EditError(f"refused file name {rel!r} for machine {name}: not a file of a machine directory")
    dirname = name + MACHINE_SUFFIX
    target = root / dirname
    before: dict[str, bytes | None] = {}
    if target.is_symlink():
        raise EditError(f"{target} is a symlink: not replaced")
    if target.exists():
        if not target.is_dir() or not (target / MACHINE_YAML).is_file():
            raise EditError(f"{target} exists and is not an llfsm machine: not replaced")
        if not replace:
            raise MachineExists(target)
        for rel in _plain_files(target):
            before[f"{dirname}/{rel}"] = read_plain(root, f"{dirname}/{rel}")
    writes: dict[str, bytes | None] = dict.fromkeys(before)
    for rel, text in files.items():
        data = text.encode("utf-8", "surrogatepass")
        if len(data) > MAX_FILE_BYTES:
            raise EditError(f"{target / rel}: larger than {MAX_FILE_BYTES // 1024} KiB; refused")
        writes[f"{dirname}/{rel}"] = data
    for rel in writes:
        check_relpath(rel)
        before.setdefault(rel, None)
    changed = {rel: data for rel, data in writes.items() if data != before[rel]}
    summary = f"{'replaced' if replace and target.exists() else 'created'} machine {name} ({len(files)} files)"
    return Change(root, changed, {rel: before[rel] for rel in changed}, summary)


def _plain_files(machine: Path) -> list[str]:
    """The names of the files in `machine`; EditError if it holds anything else."""
    try:
        with os.scandir(machine) as it:
            entries = list(it)
    except OSError as e:
        raise EditError(f"{machine}: cannot be listed: {e.strerror or e}") from None
    for entry in entries:
        if entry.is_symlink() or not entry.is_file(follow_symlinks=False):
            raise EditError(f"{machine / entry.name}: not a plain file; {machine} not replaced")
    return sorted(entry.name for entry in entries)


def set_layout(
    machine: Path,
    positions: Mapping[str, tuple[float, float]],
    *,
    labels: Mapping[tuple[str, int], tuple[float, float]] | None = None,
) -> Change:
    """Where states (centres) and transition labels (top-left corners) are drawn, merged into
    layout.yaml (created if need be; its comments and the places of others kept)."""
    p = Plan(machine)
    states = p.layout_section("states", create=True)
    assert states is not None
    for name, point in positions.items():
        p.state(name)
        states[name] = _point(point, f"position of {name}")
    for (name, index), point in (labels or {}).items():
        p.state(name)
        p.index(name, index)
        section = p.layout_section("labels", create=True)
        assert section is not None
        mine = section.get(name)
        if not isinstance(mine, CommentedMap):
            mine = section[name] = CommentedMap()
        mine[index] = _point(point, f"label of transition {index} of {name}")
    p.layout_changed = True
    placed = len(positions) + len(labels or {})
    return p.change(f"placed {placed} item{'s' if placed != 1 else ''} in {LAYOUT_FILE}")


def _point(point: object, what: str) -> CommentedMap:
    try:
        if not isinstance(point, tuple | list) or len(point) != 2:
            raise TypeError
        x, y = float(point[0]), float(point[1])
    except (TypeError, ValueError):
        raise EditError(f"{what}: two numbers (x, y)") from None
    if not all(math.isfinite(v) and abs(v) <= MAX_COORD for v in (x, y)):
        raise EditError(f"{what}: finite numbers within ±{MAX_COORD:g}")
    m = CommentedMap([("x", _number(x)), ("y", _number(y))])
    m.fa.set_flow_style()
    return m


def _number(v: float) -> float | int:
    r = round(v, 1)
    return int(r) if r == int(r) else r
