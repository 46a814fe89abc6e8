"""Reading a clfsm (MiEditLLFSM) machine directory: which file carries what.

| what | where |
|---|---|
| the states, in index order | `States`: one name a line (a missing final newline is fine) |
| transition n of S and its target | `State_<S>.h`: `Transition_<n>(int toState = <idx>)` (n is the priority) |
| its guard | `State_<S>_Transition_<n>.expr` |
| initial and suspend state | `<M>.mm`: `setInitialState(_states[N])`, `setSuspendState(_states[K])` |
| the five sections | `State_<S>_OnEntry.mm`, `_OnExit.mm`, `_Internal.mm`, `_OnSuspend.mm`, `_OnResume.mm` (1) |
| variables | `<M>_Variables.h`, `State_<S>_Variables.h` |
| includes | `<M>_Includes.h`, `State_<S>_Includes.h` |
| functions | `<M>_Methods.h`, `State_<S>_Methods.h` |
| where the editor drew the states | `Layout.plist` |

(1) A missing one is empty: machines older than suspension have no OnSuspend and OnResume.

Everything else is generated glue (`*_VarRefs.mm`, `*_FuncRefs.mm`, `<M>.h`, `State_<S>.mm`,
`WindowLayout.plist`), build settings (`IncludePath`, `Language`) or AppleDouble `._*` files,
and is ignored.

The directory is untrusted: nothing is ever executed, no symlink is followed, a file is read
only up to a size limit and only as UTF-8 text, and a state name is used in a file name only
once it is known to name no other place.
"""

from __future__ import annotations

import os
import plistlib
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..machinedir import FileTooLarge, NotRegularFile, machine_name_of, read_regular, refused_link

#: A hand-written file of a machine comes nowhere near this; Layout.plist of a big machine may
#: (SLAM's is about 300 KiB).
MAX_FILE_BYTES = 1 << 20
MAX_PLIST_BYTES = 8 << 20
#: More entries than this in one machine directory is not a machine (SLAM has 277 files).
MAX_ENTRIES = 50_000
MAX_STATES = 10_000

SECTIONS = ("OnEntry", "OnExit", "Internal", "OnSuspend", "OnResume")
_TRANSITION = re.compile(r"\bTransition_(\d+)\s*\(\s*int\s+toState\s*=\s*(\d+)\s*\)")
_INITIAL = re.compile(r"setInitialState\s*\(\s*_states\s*\[\s*(\d+)\s*\]\s*\)")
_SUSPEND = re.compile(r"setSuspendState\s*\(\s*_states\s*\[\s*(\d+)\s*\]\s*\)")
#: Files of a machine that carry nothing to import (generated, or settings of clfsm's build).
_IGNORED = re.compile(
    r"(?:.*_(?:VarRefs|FuncRefs)\.mm|WindowLayout\.plist|IncludePath|LibPath|Language|Makefile|"
    r"package\.xml|\.gitignore|\.DS_Store|CMakeLists\.txt|.*\.(?:o|so|dylib|a))\Z"
)


class ReadError(Exception):
    """The directory cannot be imported; str(e) is one line naming the file."""


@dataclass(frozen=True)
class Source:
    """One file of the clfsm machine, as text."""

    name: str
    text: str


@dataclass
class ClfsmTransition:
    index: int
    target: int
    guard: Source | None  # None when the .expr file is missing


@dataclass
class ClfsmState:
    name: str
    transitions: list[ClfsmTransition] = field(default_factory=list)
    sections: dict[str, Source] = field(default_factory=dict)
    variables: Source | None = None
    includes: Source | None = None
    methods: Source | None = None


@dataclass
class ClfsmMachine:
    path: Path
    name: str
    states: list[ClfsmState]
    initial: int
    suspended: int | None
    includes: Source | None = None
    variables: Source | None = None
    methods: Source | None = None
    #: state name -> (x, y) of its box in MiEditLLFSM
    layout: dict[str, tuple[float, float]] = field(default_factory=dict)
    #: what the report says about the directory (files skipped, defaults taken)
    notes: list[str] = field(default_factory=list)


def is_clfsm_machine(path: Path) -> bool:
    return path.name.endswith(".machine") and (path / "States").is_file() and not (path / "machine.yaml").exists()


class _Dir:
    """The entries of one directory, listed once, and files read from it safely."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            with os.scandir(path) as it:
                self.entries: dict[str, os.DirEntry[str]] = {}
                for e in it:
                    if len(self.entries) >= MAX_ENTRIES:
                        raise ReadError(f"{path}: more than {MAX_ENTRIES} files: not a machine directory")
                    self.entries[e.name] = e
        except NotADirectoryError:
            raise ReadError(f"{path}: not a directory") from None
        except OSError as e:
            raise ReadError(f"{path}: cannot be listed ({e.strerror})") from None

    def read(self, name: str, limit: int = MAX_FILE_BYTES) -> str | None:
        """The text of `name`, or None if it is missing; a file that cannot be imported safely
        (a symlink, not a regular file, too big, binary, not UTF-8) is a ReadError."""
        raw = self.read_bytes(name, limit)
        if raw is None:
            return None
        if b"\0" in raw:
            raise ReadError(f"{self.path / name}: a binary file, not text")
        try:
            return raw.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")
        except UnicodeDecodeError as e:
            raise ReadError(f"{self.path / name}: not UTF-8 text (byte {e.start + 1})") from None

    def read_bytes(self, name: str, limit: int) -> bytes | None:
        entry = self.entries.get(name)
        if entry is None:
            return None
        where = self.path / name
        if entry.is_symlink():
            raise ReadError(f"{where}: a symlink; llfsm import follows none")
        try:
            return read_regular(where, limit)
        except NotRegularFile:
            raise ReadError(f"{where}: not a regular file") from None
        except FileTooLarge as e:
            if e.size is None:
                raise ReadError(f"{where}: more than the {limit} bytes a machine file may have") from None
            raise ReadError(f"{where}: {e.size} bytes, more than the {limit} a machine file may have") from None
        except OSError as e:
            raise ReadError(f"{where}: cannot be read ({e.strerror})") from None

    def source(self, name: str) -> Source | None:
        text = self.read(name)
        return None if text is None else Source(name, text)


def _state_names(d: _Dir) -> list[str]:
    text = d.read("States")
    if text is None:
        raise ReadError(f"{d.path}: no States file: not a clfsm machine directory")
    names = [line.strip() for line in text.split("\n")]
    names = [n for n in names if n]
    if not names:
        raise ReadError(f"{d.path / 'States'}: names no state")
    if len(names) > MAX_STATES:
        raise ReadError(f"{d.path / 'States'}: more than {MAX_STATES} states")
    seen: set[str] = set()
    for i, n in enumerate(names, 1):
        if "/" in n or "\\" in n or n in (".", "..") or not n.isprintable():
            raise ReadError(f"{d.path / 'States'}:{i}: the state name {n!r} cannot name a file")
        if n in seen:
            raise ReadError(f"{d.path / 'States'}:{i}: the state {n} is listed twice")
        seen.add(n)
    return names


def _transitions(d: _Dir, state: str, count: int) -> list[ClfsmTransition]:
    header_name = f"State_{state}.h"
    header = d.read(header_name)
    if header is None:
        if f"State_{state}_Transition_0.expr" in d.entries:
            raise ReadError(f"{d.path / header_name}: missing, so the targets of {state}'s transitions are unknown")
        return []
    targets: dict[int, int] = {}
    for m in _TRANSITION.finditer(header):
        n, target = int(m[1]), int(m[2])
        line = header.count("\n", 0, m.start()) + 1
        if target >= count:
            raise ReadError(f"{d.path / header_name}:{line}: Transition_{n} targets state {target}; there are {count}")
        if n in targets and targets[n] != target:
            raise ReadError(f"{d.path / header_name}:{line}: Transition_{n} is declared twice")
        targets[n] = target
    if sorted(targets) != list(range(len(targets))):
        raise ReadError(f"{d.path / header_name}: transitions {sorted(targets)} are not numbered 0, 1, 2...")
    out = []
    for n in range(len(targets)):
        out.append(ClfsmTransition(n, targets[n], d.source(f"State_{state}_Transition_{n}.expr")))
    return out


def _index(mm: str | None, rx: re.Pattern[str], count: int, where: Path) -> int | None:
    if mm is None:
        return None
    m = rx.search(mm)
    if m is None:
        return None
    index = int(m[1])
    if index >= count:
        line = mm.count("\n", 0, m.start()) + 1
        raise ReadError(f"{where}:{line}: names state {index}; there are {count}")
    return index


def _layout(d: _Dir, notes: list[str]) -> dict[str, tuple[float, float]]:
    """Each state's position from Layout.plist (its box's x and y); an unreadable plist loses
    the positions only."""
    try:
        raw = d.read_bytes("Layout.plist", MAX_PLIST_BYTES)
        if raw is None:
            return {}
        plist = plistlib.loads(raw)
    except (ReadError, plistlib.InvalidFileException, ValueError, OverflowError) as e:
        notes.append(f"Layout.plist not read ({str(e).splitlines()[0] if str(e) else type(e).__name__}): no positions")
        return {}
    except Exception as e:  # expat's errors and the like: a broken plist costs the layout only
        notes.append(f"Layout.plist not read ({type(e).__name__}): no positions")
        return {}
    states = plist.get("States") if isinstance(plist, dict) else None
    out: dict[str, tuple[float, float]] = {}
    if isinstance(states, dict):
        for name, box in states.items():
            if isinstance(name, str) and isinstance(box, dict):
                x, y = box.get("x"), box.get("y")
                if isinstance(x, int | float) and isinstance(y, int | float) and not isinstance(x, bool):
                    out[name] = (float(x), float(y))
    return out


def read_clfsm(path: Path) -> ClfsmMachine:
    """The clfsm machine at `path`, or a ReadError naming what stops it being imported."""
    why = refused_link(path)
    if why is not None:
        raise ReadError(f"{path}: {why}")
    if path.is_symlink():
        raise ReadError(f"{path}: a symlink; llfsm import follows none")
    d = _Dir(path)
    name = machine_name_of(path)
    names = _state_names(d)
    mm_name = f"{name}.mm"
    mm = d.read(mm_name)
    notes: list[str] = []
    initial = _index(mm, _INITIAL, len(names), path / mm_name)
    if initial is None:
        initial = names.index("InitialPseudoState") if "InitialPseudoState" in names else 0
        notes.append(f"{mm_name} sets no initial state: {names[initial]} is initial")
    suspended = _index(mm, _SUSPEND, len(names), path / mm_name)
    states = []
    for s in names:
        state = ClfsmState(s, _transitions(d, s, len(names)))
        for section in SECTIONS:
            src = d.source(f"State_{s}_{section}.mm")
            if src is not None:
                state.sections[section] = src
        state.variables = d.source(f"State_{s}_Variables.h")
        state.includes = d.source(f"State_{s}_Includes.h")
        state.methods = d.source(f"State_{s}_Methods.h")
        states.append(state)
    m = ClfsmMachine(path, name, states, initial, suspended, notes=notes)
    m.includes = d.source(f"{name}_Includes.h")
    m.variables = d.source(f"{name}_Variables.h")
    m.methods = d.source(f"{name}_Methods.h")
    m.layout = _layout(d, notes)
    used = _used_files(name, states)
    orphans = sorted(
        e for e in d.entries if e not in used and not e.startswith("._") and not _IGNORED.match(e) and e != "States"
    )
    if orphans:
        shown = orphans[:8]
        more = len(orphans) - len(shown)
        notes.append("ignored: " + ", ".join(shown) + (f" and {more} more" if more > 0 else ""))
    return m


def _used_files(name: str, states: list[ClfsmState]) -> set[str]:
    used = {f"{name}.mm", f"{name}.h", "Layout.plist", f"{name}_Includes.h", f"{name}_Variables.h", f"{name}_Methods.h"}
    for s in states:
        used.update((f"State_{s.name}.h", f"State_{s.name}.mm"))  # clfsm's glue, read for the targets only
        used.update(src.name for src in s.sections.values())
        used.update(t.guard.name for t in s.transitions if t.guard is not None)
        used.update(f"State_{s.name}_{k}" for k in ("Variables.h", "Includes.h", "Methods.h"))
    return used
