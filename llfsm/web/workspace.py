"""What `llfsm edit` has open (docs/edit.md): the folders and machines, each machine's files as
last read, its `check` diagnostics and its diagram, and the undo and redo of every change.

The files on disk are the truth.  Every write goes through llfsm.edit (a planned Change,
applied atomically over the files it touches); this module never builds a path from what a
page sends: a machine is named by its key (a name this module gave it), a file by a name that
llfsm.edit.write_file validates against the machine format, a new machine by a name that
llfsm.edit.new_machine validates, inside a folder that was opened.  Symlinked files are not
read (nor their folders' machines: llfsm.machinedir.refused_link, as everywhere).

Nothing here imports or runs machine code: diagnostics are `llfsm check`'s (text and `ast`),
diagrams llfsm.diagram.svg's.  Everything is plain data a page can be sent as JSON; the
server (llfsm.web.edit_server) calls it from one worker thread, so no two changes overlap.
"""

from __future__ import annotations

import hashlib
import os
import stat
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import edit
from ..diagram import svg as diagram
from ..diagram.description import of_machine
from ..lang.check import check_machine
from ..lang.diagnostics import Severity
from ..lang.discover import find_machines, is_machine_dir
from ..lang.files import expression, is_machine_file
from ..lang.layout_file import Placement, placement
from ..lang.model import Machine
from ..machinedir import machine_name_of, refused_link

#: A file larger than this is not read into the page (a machine's files are a few kilobytes).
MAX_FILE = 1 << 20
#: Files shown in the page: what a machine directory holds (llfsm.edit.write_file decides what
#: may be written).
SHOWN_SUFFIXES = (".py", ".expr", ".yaml")
#: Changes kept for undo.
UNDO_DEPTH = 200
#: Saves of one file closer together than this (seconds) are one undo step (typing).
TYPING_PAUSE = 2.0
#: A write that does not say which version it was edited from (the CLI's, a test's).
UNCHECKED = object()


class WorkspaceError(Exception):
    """A request the workspace refuses; str(e) is the one line the page shows."""


def digest(text: str) -> str:
    """The page names the version of a file it edited from by this (a conflict is a disk that
    no longer holds it)."""
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:16]


@dataclass
class Opened:
    """One machine directory open in the editor."""

    key: str
    path: Path
    #: relative file name -> text, as last read or written
    files: dict[str, str] = field(default_factory=dict)
    #: relative file name -> (mtime_ns, size), to notice another program's writes
    stamps: dict[str, tuple[int, int]] = field(default_factory=dict)
    diagnostics: list[dict[str, Any]] = field(default_factory=list)
    structure: dict[str, Any] | None = None
    svg: str = ""
    #: the structure and diagram are the last ones that read (machine.yaml does not, now)
    stale: bool = False
    checked: bool = False


class Workspace:
    """The folders and machines `llfsm edit PATH...` was opened on."""

    def __init__(self, paths: list[Path]) -> None:
        self.folders: list[Path] = []  # where new machines may be made
        self.machines: dict[str, Opened] = {}
        self.undo_stack: list[tuple[str, edit.Change]] = []
        self.redo_stack: list[tuple[str, edit.Change]] = []
        self._typing: float | None = None  # when the last save of typed text was
        self.ended = False  # set by the server when it stops (the view's sources have it too)
        for p in paths:
            self._open(p)

    # -- what is open --------------------------------------------------------------------------------
    def _open(self, path: Path) -> None:
        if path.name.endswith(".verify.yaml") and path.is_file():
            # deferred: start-up (the verification file's reader is verify's; only this form needs it)
            from ..verify.load import VerifyError, read_verify_file

            try:
                vf = read_verify_file(path)
            except VerifyError as e:
                raise WorkspaceError(str(e)) from None
            for listed in vf.machines:
                self._open(Path(listed))
            return
        if not path.exists():
            raise WorkspaceError(f"{path}: no such machine directory or folder")
        if not path.is_dir():
            raise WorkspaceError(f"{path}: not a machine directory, a folder or a NAME.verify.yaml")
        why = refused_link(path)
        if why is not None:
            raise WorkspaceError(why)
        if not (is_machine_dir(path) or (path / "machine.yaml").exists()):
            self.folders.append(path.resolve())
        for m in find_machines(path):
            if refused_link(m) is None:
                self._add(m.resolve())

    def _add(self, path: Path) -> Opened:
        for o in self.machines.values():
            if o.path == path:
                return o
        name = machine_name_of(path)
        key, n = name, 1
        while key in self.machines:
            n += 1
            key = f"{name}~{n}"
        opened = Opened(key, path)
        self.machines[key] = opened
        self._read(opened)
        return opened

    def rescan(self) -> bool:
        """New machine directories in the opened folders (made by another program); True if any."""
        found = False
        for folder in self.folders:
            for m in find_machines(folder):
                if refused_link(m) is None and all(o.path != m.resolve() for o in self.machines.values()):
                    self._add(m.resolve())
                    found = True
        return found

    def machine(self, key: object) -> Opened:
        if not isinstance(key, str) or key not in self.machines:
            raise WorkspaceError(f"no machine {str(key)[:80]!r} is open")
        return self.machines[key]

    def summary(self) -> list[dict[str, Any]]:
        """What the page lists before it opens one machine: names and problem counts."""
        return [
            {
                "key": o.key,
                "name": machine_name_of(o.path),
                "folder": str(o.path.parent),
                "errors": sum(d["severity"] == "error" for d in o.diagnostics),
                "warnings": sum(d["severity"] == "warning" for d in o.diagnostics),
                "checked": o.checked,
            }
            for o in self.machines.values()
        ]

    def full(self, key: object) -> dict[str, Any]:
        """One machine as the page edits it (checked and drawn first if it was not yet)."""
        o = self.machine(key)
        if not o.checked:
            self.refresh(o)
        return {
            "key": o.key,
            "name": machine_name_of(o.path),
            "folder": str(o.path.parent),
            "files": o.files,
            "versions": {name: digest(text) for name, text in o.files.items()},
            "diagnostics": o.diagnostics,
            "structure": o.structure,
            "svg": o.svg,
            "stale": o.stale,
        }

    # -- reading, checking, drawing ----------------------------------------------------------------
    def _read(self, o: Opened) -> set[str]:
        """Read the machine's files; the names whose text changed since last read."""
        files: dict[str, str] = {}
        stamps: dict[str, tuple[int, int]] = {}
        try:
            with os.scandir(o.path) as it:
                entries = sorted(it, key=lambda e: e.name)
        except OSError:
            entries = []
        for e in entries:
            if not e.name.endswith(SHOWN_SUFFIXES) or e.is_symlink():
                continue
            try:
                st = e.stat(follow_symlinks=False)
                if not e.is_file(follow_symlinks=False) or st.st_size > MAX_FILE:
                    continue
                data = Path(e.path).read_bytes()
            except OSError:
                continue
            files[e.name] = data.decode("utf-8", "replace")
            stamps[e.name] = (st.st_mtime_ns, st.st_size)
        changed = {n for n in files.keys() | o.files.keys() if files.get(n) != o.files.get(n)}
        o.files, o.stamps = files, stamps
        return changed

    def refresh(self, o: Opened) -> None:
        """Check the machine as `llfsm check` does and draw it (the last good drawing is kept
        while machine.yaml does not read)."""
        result = check_machine(o.path)
        o.diagnostics = [_relative(d.as_dict(), o.path) for d in result.diagnostics]
        o.checked = True
        m = result.machine
        if m is None:
            o.stale = o.structure is not None
            return
        o.structure = structure(m)
        o.stale = False
        placed = placement(result.read)[0] or Placement()
        try:
            o.svg = diagram.svg(of_machine(m), positions=placed.states, labels=placed.labels)
        except Exception as e:  # a bug of ours must not take the editor down: said in Problems
            o.diagnostics.append(_note(f"the diagram could not be drawn: {type(e).__name__}: {e}"))

    def poll(self) -> dict[str, list[str]]:
        """What another program changed on disk since the last look: machine key -> changed
        file names (each such machine reread, checked and drawn again)."""
        out: dict[str, list[str]] = {}
        for o in list(self.machines.values()):
            if _stamps(o.path) == o.stamps:
                continue
            changed = self._read(o)
            if changed:
                self.refresh(o)
                out[o.key] = sorted(changed)
        return out

    # -- changing -----------------------------------------------------------------------------------------
    def operate(self, key: object, op: str, args: dict[str, Any]) -> tuple[str, list[str]]:
        """One structure operation of llfsm.edit by name; (its summary, the files it changed)."""
        o = self.machine(key)
        plan = OPERATIONS.get(op)
        if plan is None:
            raise WorkspaceError(f"unknown operation {op[:40]!r}")
        try:
            change = plan(o.path, args)
        except edit.EditError as e:
            raise WorkspaceError(str(e)) from None
        except (KeyError, TypeError, ValueError) as e:
            raise WorkspaceError(f"{op}: a bad request ({type(e).__name__}: {e})") from None
        return self._apply(o, change)

    def write(self, key: object, name: object, text: object, base: object = UNCHECKED) -> tuple[str, list[str]]:
        """Write one file's text; refused as a conflict (WriteConflict, with the disk's text) when
        the disk no longer holds the version the page edited from (`base`: a digest, or None
        for a file that did not exist)."""
        o = self.machine(key)
        if not isinstance(name, str) or not isinstance(text, str):
            raise WorkspaceError("a write names a file and gives its text")
        # that file alone, as it is now (the others' changes are for poll() to report)
        now = _disk_text(o.path, name)
        if base is not UNCHECKED and (digest(now) if now is not None else None) != base:
            raise WriteConflict(name, now)
        if now == text:
            return "", []
        try:
            change = edit.write_file(o.path, name, text)
        except edit.EditError as e:
            raise WorkspaceError(str(e)) from None
        return self._apply(o, change)

    def new_machine(self, name: object, folder: object = 0, states: object = None) -> str:
        """Make a machine in an opened folder (`folder`: its index); its key."""
        if not self.folders:
            raise WorkspaceError("open a folder (llfsm edit FOLDER) to make machines in it")
        if not isinstance(folder, int) or not 0 <= folder < len(self.folders):
            raise WorkspaceError("no such folder is open")
        if not isinstance(name, str):
            raise WorkspaceError("a machine's name is text")
        if states is not None and not (isinstance(states, list) and all(isinstance(s, str) for s in states)):
            raise WorkspaceError("states are a list of names")
        try:
            change = edit.new_machine(self.folders[folder], name, states)
            edit.apply(change)
        except edit.EditError as e:
            raise WorkspaceError(str(e)) from None
        path = self._made_dir(change)
        o = self._add(path)
        self._push_undo(o.key, change)
        self.refresh(o)
        return o.key

    def undo(self) -> tuple[str, str, list[str]]:
        return self._step(self.undo_stack, self.redo_stack, "undo")

    def redo(self) -> tuple[str, str, list[str]]:
        return self._step(self.redo_stack, self.undo_stack, "redo")

    def _step(
        self, source: list[tuple[str, edit.Change]], target: list[tuple[str, edit.Change]], verb: str
    ) -> tuple[str, str, list[str]]:
        if not source:
            raise WorkspaceError(f"nothing to {verb}")
        key, change = source[-1]
        back = edit.invert(change)
        try:
            edit.apply(back)
        except edit.EditError as e:
            raise WorkspaceError(f"cannot {verb}: {e}") from None
        source.pop()
        target.append((key, back))
        self._typing = None
        o = self.machines.get(key)
        if o is None:
            return key, f"{verb}: {change.summary}", []
        self._read(o)
        self.refresh(o)
        return key, f"{verb}: {change.summary}", _files_of(o, back)

    def _apply(self, o: Opened, change: edit.Change) -> tuple[str, list[str]]:
        try:
            edit.apply(change)
        except edit.EditError as e:
            raise WorkspaceError(str(e)) from None
        self._push_undo(o.key, change)
        self._read(o)
        self.refresh(o)
        return change.summary, _files_of(o, change)

    def _push_undo(self, key: str, change: edit.Change) -> None:
        """One undo step per change, but the saves of one file while its text is typed (each a
        pause of a fraction of a second) are one step: the first's `before`, the last's text."""
        now = time.monotonic()
        if self.undo_stack and self._typing is not None:
            last_key, last = self.undo_stack[-1]
            if (
                last_key == key
                and now - self._typing < TYPING_PAUSE
                and len(change.writes) == 1
                and last.writes.keys() == change.writes.keys()
                and last.summary == change.summary
            ):
                self.undo_stack[-1] = (key, edit.Change(last.root, change.writes, last.before, last.summary))
                self._typing = now
                self.redo_stack.clear()
                return
        self._typing = now if change.summary.startswith("wrote ") and len(change.writes) == 1 else None
        self.undo_stack.append((key, change))
        del self.undo_stack[:-UNDO_DEPTH]
        self.redo_stack.clear()

    def _made_dir(self, change: edit.Change) -> Path:
        for rel in change.writes:
            first = Path(rel).parts[0]
            if first.endswith(".machine"):
                return (change.root / first).resolve()
        return change.root.resolve()


class WriteConflict(WorkspaceError):
    """The disk no longer holds the version the page edited from: both are kept (the page
    shows the two, the disk is not written)."""

    def __init__(self, name: str, disk: str | None) -> None:
        super().__init__(f"{name} was changed on disk while you edited it")
        self.name = name
        self.disk = disk


def structure(m: Machine) -> dict[str, Any]:
    """The machine as the page's forms edit it: states, transitions (target, guard text, where
    the guard is written), initial and suspend state."""
    states = []
    for s in m.states:
        if s.implicit:
            continue
        states.append(
            {
                "name": s.name,
                "transitions": [
                    {
                        "index": t.index,
                        "target": t.target,
                        "guard": expression(t.guard.text) if t.guard is not None else "",
                        "file": t.guard.file if t.guard is not None and not t.guard.inline else None,
                    }
                    for t in s.transitions
                ],
            }
        )
    explicit = {s["name"] for s in states}
    return {
        "name": m.name,
        "description": m.description or "",
        "initial": m.initial,
        "suspend": m.suspended if m.suspended in explicit else None,
        "states": states,
    }


def _disk_text(machine: Path, name: str) -> str | None:
    """A file of the machine as it is on disk now (None: no such file, or not one the page may
    see).  The name is checked against the machine format before any path is built."""
    if not is_machine_file(name):
        return None
    path = machine / name
    try:
        st = path.lstat()
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_FILE:
            return None
        return path.read_bytes().decode("utf-8", "replace")
    except OSError:
        return None


def _stamps(path: Path) -> dict[str, tuple[int, int]]:
    out: dict[str, tuple[int, int]] = {}
    try:
        with os.scandir(path) as it:
            for e in it:
                if e.name.endswith(SHOWN_SUFFIXES) and not e.is_symlink():
                    try:
                        st = e.stat(follow_symlinks=False)
                    except OSError:
                        continue
                    if st.st_size <= MAX_FILE:
                        out[e.name] = (st.st_mtime_ns, st.st_size)
    except OSError:
        pass
    return out


def _files_of(o: Opened, change: edit.Change) -> list[str]:
    """The files of `o` a change wrote (names inside the machine directory)."""
    out = []
    for rel in change.writes:
        p = (change.root / rel).resolve()
        if p.parent == o.path:
            out.append(p.name)
    return sorted(out)


def _relative(d: dict[str, Any], machine: Path) -> dict[str, Any]:
    """A diagnostic with its file named inside the machine directory (the page's file names)."""
    f = Path(str(d["file"]))
    if f.parent.resolve() == machine or f.parent == machine:
        d["file"] = f.name
    elif f.name == machine.name or f.resolve() == machine:
        d["file"] = ""
    return d


def _note(message: str) -> dict[str, Any]:
    return {"code": "", "severity": str(Severity.WARNING), "file": "", "line": 1, "column": 1, "message": message}


def _int(args: dict[str, Any], key: str) -> int:
    v = args[key]
    if not isinstance(v, int) or isinstance(v, bool):
        raise TypeError(f"{key} must be an integer")
    return v


def _str(args: dict[str, Any], key: str) -> str:
    v = args[key]
    if not isinstance(v, str):
        raise TypeError(f"{key} must be text")
    return v


def _opt_str(args: dict[str, Any], key: str) -> str | None:
    v = args.get(key)
    if v is not None and not isinstance(v, str):
        raise TypeError(f"{key} must be text")
    return v or None


def _layout(path: Path, args: dict[str, Any]) -> edit.Change:
    """States' centres ({name: [x, y]}) and labels' corners ([{source, index, x, y}])."""
    raw = args.get("positions", {})
    if not isinstance(raw, dict):
        raise TypeError("positions map states to [x, y]")
    positions: dict[str, tuple[float, float]] = {}
    for name, xy in raw.items():
        if not (isinstance(xy, list) and len(xy) == 2 and all(_number(v) for v in xy)):
            raise TypeError("positions map states to [x, y]")
        positions[str(name)] = (float(xy[0]), float(xy[1]))
    labels: dict[tuple[str, int], tuple[float, float]] = {}
    for item in args.get("labels", []):
        if not isinstance(item, dict) or not all(_number(item.get(k)) for k in ("x", "y")):
            raise TypeError("labels are [{source, index, x, y}]")
        labels[(_str(item, "source"), _int(item, "index"))] = (float(item["x"]), float(item["y"]))
    return edit.set_layout(path, positions, labels=labels or None)


def _number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _transition_add(path: Path, a: dict[str, Any]) -> edit.Change:
    priority = a.get("priority")
    if priority is not None:
        priority = _int(a, "priority")
    return edit.transition_add(
        path, _str(a, "source"), _str(a, "target"), guard=_opt_str(a, "guard"), priority=priority
    )


#: The structure operations a page may ask for, by name: each validates its arguments' types
#: here and their meaning in llfsm.edit.
OPERATIONS: dict[str, Any] = {
    "state_add": lambda p, a: edit.state_add(p, _str(a, "name"), after=_opt_str(a, "after")),
    "state_rename": lambda p, a: edit.state_rename(p, _str(a, "old"), _str(a, "new")),
    "state_remove": lambda p, a: edit.state_remove(p, _str(a, "name")),
    "transition_add": _transition_add,
    "transition_move": lambda p, a: edit.transition_move(p, _str(a, "source"), _int(a, "index"), _int(a, "to")),
    "transition_retarget": lambda p, a: edit.transition_retarget(
        p, _str(a, "source"), _int(a, "index"), _str(a, "target")
    ),
    "transition_remove": lambda p, a: edit.transition_remove(p, _str(a, "source"), _int(a, "index")),
    "set_guard": lambda p, a: edit.set_guard(p, _str(a, "source"), _int(a, "index"), _str(a, "guard")),
    "set_initial": lambda p, a: edit.set_initial(p, _str(a, "state")),
    "set_suspend": lambda p, a: edit.set_suspend(p, _opt_str(a, "state")),
    "set_description": lambda p, a: edit.set_description(p, _opt_str(a, "text")),
    "set_layout": _layout,
}
