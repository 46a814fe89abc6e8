"""`llfsm import`: clfsm (MiEditLLFSM) machine directories to llfsm machine directories.

- `clfsm`: reading a clfsm directory (which file carries what), safely;
- `cxx` (tree-sitter), `statements`, `expressions`, `calls`, `headers`, `terms`, `kinds`,
  `literals`: translating its C++ where the meaning is clear, keeping the rest as lines
  `llfsm check` reports (LF080);
- `convert`: one clfsm machine to the files of an llfsm machine, which llfsm.edit writes (as it
  writes every machine directory: the whole directory or none of it, SPEC 13);
- `report`: what was written, translated and left.

Nothing of a clfsm machine is ever executed: its files are read as text and parsed.
"""

from __future__ import annotations

import keyword
import re
from dataclasses import dataclass
from pathlib import Path

from ..edit import EditError, MachineExists, apply, write_machine
from ..lang.discover import find_machines
from ..lang.model import MAX_MACHINE_NAME
from .clfsm import ClfsmMachine, ReadError, is_clfsm_machine, read_clfsm
from .convert import convert
from .cxx import ParserMissing
from .report import MachineReport

__all__ = ["ParserMissing", "import_machines", "llfsm_name"]


def llfsm_name(name: str, taken: set[str] | frozenset[str] = frozenset()) -> str:
    """`name` as an llfsm machine or state name (SPEC 1): what is not a letter, digit or `_`
    becomes `_`, a leading digit gets a `_` before it, a keyword or a name in `taken` a `_`
    after it."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)[: MAX_MACHINE_NAME - 4] or "_"
    if out[0].isdigit():
        out = "_" + out
    while keyword.iskeyword(out) or out in taken:
        out += "_"
    return out


@dataclass
class _Found:
    path: Path
    machine: ClfsmMachine | None
    report: MachineReport


def _sources(paths: list[Path]) -> list[_Found]:
    found: list[_Found] = []
    for p in paths:
        machines = [p] if p.name.endswith(".machine") else [m for m in find_machines(p) if is_clfsm_machine(m)]
        if not machines:
            r = MachineReport(
                source=p,
                name="",
                original="",
                error="no clfsm machine directory (NAME.machine with a States file) here",
            )
            found.append(_Found(p, None, r))
        for m in machines:
            r = MachineReport(source=m, name="", original=m.name.removesuffix(".machine"))
            try:
                if (m / "machine.yaml").exists():
                    raise ReadError(f"{m}: already an llfsm machine (it has a machine.yaml)")
                found.append(_Found(m, read_clfsm(m), r))
            except ReadError as e:
                r.error = str(e)
                found.append(_Found(m, None, r))
    return found


def import_machines(paths: list[Path], out: Path, force: bool = False) -> list[MachineReport]:
    """Import every clfsm machine found at `paths` into `out`; a report per machine (one that
    could not be read or written has `error` set, and nothing of it was written)."""
    found = _sources(paths)
    names: dict[str, str] = {}
    taken: set[str] = set()
    for f in found:
        if f.machine is None:
            continue
        new = llfsm_name(f.machine.name, taken)
        taken.add(new)
        f.report.name = new
        if f.machine.name in names:
            f.report.notes.append(
                f"another machine imported here is named {f.machine.name} too: this one is {new}, and "
                f'suspend("{f.machine.name}") calls mean the first'
            )
        else:
            names[f.machine.name] = new
            if new != f.machine.name:
                f.report.notes.append(f'renamed {f.machine.name} to {new} (an llfsm name); suspend("...") calls follow')
    for f in found:
        if f.machine is None:
            continue
        states: dict[str, str] = {}
        for s in f.machine.states:
            states[s.name] = llfsm_name(s.name, set(states.values()))
            if states[s.name] != s.name:
                f.report.notes.append(f"state {s.name} renamed {states[s.name]} (an llfsm name)")
        imported = convert(f.machine, f.report.name, names, states)
        imported.report.notes = f.report.notes + imported.report.notes
        try:
            apply(write_machine(out, imported.name, imported.files, replace=force))
            imported.report.output = out / f"{imported.name}.machine"
        except MachineExists as e:
            imported.report.error = f"{e} (--force replaces it)"
        except EditError as e:
            imported.report.error = str(e)
        f.report = imported.report
    return [f.report for f in found]
