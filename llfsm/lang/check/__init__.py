"""`llfsm check`: validate machine directories from their text alone.

This runs in CI on untrusted pull requests, so it never imports, executes or evaluates user
code: it reads bytes, YAML nodes and `ast` trees (llfsm.lang.reader) and applies the rules of
the catalogue (llfsm.lang.diagnostics, docs/rules.md).  The rules live in modules grouped by
what they look at, each a function over one `Checking` (llfsm.lang.check.checking):

- structure:  the directory's name, states, transitions, guards' shape, reachability, suspend state
- variables:  the variables declared (reserved names, duplicates, shadowing)
- inputs:     the inputs declared (names, values, bindings) and code that assigns one
- includes:   Includes.py
- imports:    what imports name: message types (LF042), packages (LF109), helpers (LF043)
- code:       sections, guards and initialisers (compile limits, bindings, undefined names)
- ros_habits: rclpy spellings (LF041)
- parameters: machine.yaml's `parameters:` (LF060-LF062)
- packages:   message packages package.xml does not declare (LF106)
- fields:     fields a message type does not have (LF051), read from definitions (definitions)
- arrangement: machines named by suspend("M") and family that none checked together is (LF050)
- untranslated: clfsm code `llfsm import` left for a person (LF080)

This module runs them in order for one machine (`check_machine`), and for many, over worker
processes when there are many (`diagnose`).

A new rule: its code, severity and summary in `RULES` (llfsm.lang.diagnostics; docs/rules.md
is generated from it, and a test keeps the two in step), a function in the module of what it
looks at that calls `Checking.add` or `Checking.at`, and a call in `run_rules` (or in the
function of that module that already walks what the rule needs: `code.state_code` for each
section and guard).
"""

from __future__ import annotations

import gc
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from ...workers import die_with_parent, usable_cores
from ..diagnostics import Diagnostic, Severity
from ..discover import find_machines
from ..model import Machine
from ..reader import ReadResult, read_machine
from . import code, includes, inputs, parameters, structure, untranslated, variables
from .arrangement import unknown_machines
from .checking import Checking
from .packages import undeclared_dependencies


@dataclass
class MachineCheck:
    """The outcome of checking one machine directory."""

    path: Path
    read: ReadResult
    diagnostics: list[Diagnostic] = field(default_factory=list)
    #: (file, line, column, machine) of each machine its code names by a literal (LF050)
    references: list[tuple[str, int, int, str]] = field(default_factory=list)

    @property
    def machine(self) -> Machine | None:
        return self.read.machine

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.severity is Severity.ERROR]

    @property
    def ok(self) -> bool:
        return self.machine is not None and not self.errors


def check_machine(path: str | Path, within: Path | None = None) -> MachineCheck:
    """Check one machine directory.  A machine directory that is a symlink leading out of the
    folder holding it is refused, not read, however it was named (machinedir.refused_link):
    an untrusted pull request must not get `llfsm check` to read files from elsewhere.
    `within` (the folder searched) is accepted for callers that pass it; the rule needs none."""
    path = Path(path)
    read = read_machine(path)  # refuses a linked directory by machinedir.refused_link, as everything does
    c = Checking.of(path, read)
    run_rules(c)
    diagnostics = sorted(set(_without_cascade(c.diagnostics)), key=Diagnostic.sort_key)
    return MachineCheck(path, read, diagnostics, c.references)


def run_rules(c: Checking) -> None:
    """Every rule, in the catalogue's order of concerns.  (The order matters only for "did you
    mean": its budget per machine goes to the first names that need it.)"""
    structure.machine_name(c)
    m = c.read.machine
    if m is None:
        return
    structure.states(c, m)
    includes.includes(c, m)
    variables.declarations(c, m)
    inputs.declarations(c, m)
    parameters.parameters(c, m)
    code.initialisers(c, m)
    for s in m.states:
        code.state_code(c, m, s)
    inputs.assignments(c, m)
    untranslated.untranslated(c, m)
    structure.orphans(c)
    structure.layout(c, m)
    structure.reachability(c, m)
    structure.suspend_state(c, m)
    c.diagnostics.extend(undeclared_dependencies(c.path, c.read.trees))


#: Diagnostics that follow from an earlier one rather than from a mistake of their own: one
#: typo in machine.yaml (`transition:` for `transitions:`, a misspelt target) must give one
#: diagnostic, not that one plus an orphan file for each guard and an unreachable state for
#: each target.  They come back, if still true, once the first is fixed.
#: (A misspelt target is followed to the state it was meant for by `reachability` instead.)
_CASCADES = {
    "LF004": frozenset({"LF020", "LF021", "LF022", "LF101", "LF102", "LF104"}),
}


def _without_cascade(diags: list[Diagnostic]) -> list[Diagnostic]:
    codes = {d.code for d in diags}
    drop = frozenset().union(*(_CASCADES[c] for c in codes if c in _CASCADES))
    return [d for d in diags if d.code not in drop] if drop else diags


def check_paths(paths: Iterable[Path]) -> list[MachineCheck]:
    out: list[MachineCheck] = []
    for p in paths:
        out.extend(check_machine(m, p) for m in find_machines(p))
    return out


#: From this many machines on, `diagnose` spreads the work over worker processes.
PARALLEL_FROM = 48


#: What one machine's check hands back to `diagnose`: its diagnostics and the machines it names.
_Outcome = tuple[list[Diagnostic], list[tuple[str, int, int, str]]]


def _outcome_of(path: Path, within: Path | None = None) -> _Outcome:
    checked = check_machine(path, within)
    return checked.diagnostics, checked.references


def diagnose(paths: Iterable[Path], jobs: int | None = None) -> tuple[int, list[Diagnostic]]:
    """(number of machines, their diagnostics in a stable order) for `llfsm check`.

    Large trees (a monorepo of machines in CI) are checked by worker processes, one per core;
    workers send back only diagnostics (and the machine names each machine's code gives, for
    LF050), so memory stays flat however many machines there are.  The order of the output
    never depends on the number of workers.
    """
    found = [(m, p) for p in paths for m in find_machines(p)]
    machines, roots = [m for m, _ in found], [p for _, p in found]
    return len(machines), _across(machines, _outcomes(machines, roots, jobs))


def _across(machines: list[Path], outcomes: Iterable[_Outcome]) -> list[Diagnostic]:
    """Each machine's diagnostics, with LF050 among them when several machines are checked."""
    names = _names_around(machines) if len(machines) > 1 else None
    out: list[Diagnostic] = []
    for diags, refs in outcomes:
        extra = unknown_machines(names, refs) if names is not None and refs else []
        out.extend(sorted(diags + extra, key=Diagnostic.sort_key) if extra else diags)
    return out


def _names_around(machines: list[Path]) -> set[str]:
    """The machines checked, and those beside them (pre-commit passes only the machines a
    commit changed, not the ones beside them that they suspend)."""
    names = {m.name.removesuffix(".machine") for m in machines}
    for folder in {m.parent for m in machines}:
        try:
            with os.scandir(folder) as entries:
                names.update(e.name.removesuffix(".machine") for e in entries if e.name.endswith(".machine"))
        except OSError:
            continue
    return names


def _outcomes(machines: list[Path], roots: list[Path], jobs: int | None) -> Iterable[_Outcome]:
    cores = usable_cores()
    if jobs is None:
        jobs = cores if len(machines) >= PARALLEL_FROM else 1
    # more workers than cores only add memory and switching: `-j 10000` must not fork 10,000
    jobs = min(jobs, cores, len(machines))
    if jobs <= 1 or len(machines) < 2:
        return [_outcome_of(m, p) for m, p in zip(machines, roots, strict=True)]
    # deferred: start-up (a check of a few machines never starts worker processes)
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    gc.freeze()  # the workers' collector leaves the inherited objects alone: fewer pages copied
    try:
        with ProcessPoolExecutor(
            max_workers=jobs, mp_context=ctx, initializer=die_with_parent, initargs=(os.getpid(),)
        ) as pool:
            return list(pool.map(_outcome_of, machines, roots, chunksize=max(1, len(machines) // (jobs * 8))))
    finally:
        gc.unfreeze()  # every worker is forked by now; a caller that goes on collects as before
