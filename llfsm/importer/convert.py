"""One clfsm machine (llfsm.importer.clfsm) to the files of an llfsm machine directory.

The structure is carried over exactly: the states in their order (the trace's `s` numbers
stay clfsm's), each state's transitions in priority order with their targets, the initial
and suspend states; `InitialPseudoState` stays the initial state it is in clfsm (its guard
`true` moves on at once, and a restart passes through it again, as in clfsm).  The code is
translated where it is clear (llfsm.importer.statements) and kept as marked lines elsewhere.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from .clfsm import ClfsmMachine, ClfsmState, Source
from .headers import translate_includes, translate_methods, translate_variables
from .kinds import Imports, annotation
from .report import Left, MachineReport
from .statements import MARKER, Translation, marked, translate_guard, translate_section
from .terms import Scope

#: Modules the translation may import: a variable never takes one of these names.
MODULES = frozenset({"ros", "math", "sys", "os", "time", "copy", "contextlib"})


@dataclass
class Imported:
    """The llfsm machine made from a clfsm one: relative path -> text, and its report."""

    name: str
    files: dict[str, str]
    report: MachineReport


@dataclass
class _File:
    """An output file being composed, and the lines left in it."""

    name: str
    lines: list[str] = field(default_factory=list)

    def place(self, t: Translation, source: Source, report: MachineReport) -> None:
        """Append `t`'s lines; each statement left is recorded at its line here and there."""
        reasons = iter([(line, why) for line, why in t.left if why])
        for text in t.lines:
            self.lines.append(text)
            if text.lstrip().startswith(MARKER + " ("):
                src_line, why = next(reasons, (0, ""))
                report.left.append(Left(self.name, len(self.lines), source.name, src_line, why))
        report.code += t.code
        report.left_lines += t.left_lines

    def text(self) -> str:
        return "\n".join(self.lines).rstrip("\n") + "\n" if any(ln.strip() for ln in self.lines) else ""


def convert(m: ClfsmMachine, name: str, machines: Mapping[str, str], states: Mapping[str, str]) -> Imported:
    """The llfsm machine `name` made from `m`; `machines` maps the names of the machines imported
    together to their llfsm names (the `suspend("...")` family follows them), `states` this
    machine's state names to llfsm's."""
    report = MachineReport(source=m.path, name=name, original=m.name, notes=list(m.notes))
    imports = Imports()
    files: dict[str, str] = {}
    machine_scope = Scope(imports, {}, machines, states, taken=set(MODULES))
    variables = _File("Variables.py")
    headers = [src for src in [m.includes, *(s.includes for s in m.states)] if src is not None]
    included = [(translate_includes(src.text, src.name, machine_scope), src) for src in headers]
    machine_vars: dict[str, tuple[str, str | None]] = {}
    for inc, _src in included:
        for d in inc.defines:  # constants first: the variables' initialisers may use them
            variables.lines.append(f"{d.python}: {annotation(d.kind)} = {d.value}  # #define in {d.source}")
            machine_vars[d.name] = (d.python, d.kind)
    machine_scope.variables = dict(machine_vars)
    if m.variables is not None:
        declared = translate_variables(m.variables.text, machine_scope)
        variables.place(declared.translation, m.variables, report)
        machine_vars.update(declared.names)
    methods = [src for src in [m.methods, *(s.methods for s in m.states)] if src is not None]
    for s in m.states:
        _state(m, s, machine_vars, machine_scope, report, files)
    includes_file = _includes([(inc.translation, src) for inc, src in included], methods, imports, report)
    files["machine.yaml"] = _machine_yaml(m, name, states)
    for f in (variables, includes_file):
        if f.text():
            files[f.name] = f.text()
    if m.layout:
        files["layout.yaml"] = _layout_yaml(m, states)
    report.files = len(files)
    return Imported(name, dict(sorted(files.items())), report)


def _state(
    m: ClfsmMachine,
    s: ClfsmState,
    machine_vars: dict[str, tuple[str, str | None]],
    machine_scope: Scope,
    report: MachineReport,
    files: dict[str, str],
) -> None:
    """The files of one state: its variables (with the statics of its sections), sections and guards."""
    new = machine_scope.states[s.name]
    scope = Scope(machine_scope.imports, dict(machine_vars), machine_scope.machines, machine_scope.states,
                  taken=set(machine_scope.taken))  # fmt: skip
    variables = _File(f"State_{new}_Variables.py")
    if s.variables is not None:
        declared = translate_variables(s.variables.text, scope)
        variables.place(declared.translation, s.variables, report)
        scope.variables = {**machine_vars, **declared.names}
    for section, src in s.sections.items():
        t = translate_section(src.text, scope)
        out = _File(f"State_{new}_{section}.py")
        out.place(t, src, report)
        for st in t.statics:
            variables.lines.append(
                f"{st.name}: {st.annotation}"
                + (f" = {st.initial}" if st.initial is not None else "")
                + f"  # static in {src.name}:{st.line}"
            )
            scope.taken.add(st.name)
        if out.text():
            files[out.name] = out.text()
    for tr in s.transitions:
        target = machine_scope.states[m.states[tr.target].name]
        out = _File(f"State_{new}_Transition_{tr.index}.expr", [f"# -> {target}"])
        if tr.guard is None:
            why = f"State_{s.name}_Transition_{tr.index}.expr is missing in the clfsm machine"
            t = Translation([*marked("", why, ""), "False"], 1, [(1, why)])
            out.place(t, Source(f"State_{s.name}_Transition_{tr.index}.expr", ""), report)
        else:
            out.place(translate_guard(tr.guard.text, scope), tr.guard, report)
        files[out.name] = out.text()
    if variables.text():
        files[variables.name] = variables.text()


def _includes(
    included: list[tuple[Translation, Source]], methods: list[Source], imports: Imports, report: MachineReport
) -> _File:
    """Includes.py: the imports the code needs, then what the headers held that has no Python."""
    out = _File("Includes.py")
    pending = included + [(translate_methods(src.text), src) for src in methods]
    out.lines.extend(imports.lines())
    for t, src in pending:
        if t.lines:
            out.lines.append(f"# from {src.name}")
        out.place(t, src, report)
    return out


def _machine_yaml(m: ClfsmMachine, name: str, states: Mapping[str, str]) -> str:
    lines = [f"description: Imported by llfsm import from the clfsm machine {m.name}.machine."]
    if m.initial != 0:
        lines.append(f"initial: {states[m.states[m.initial].name]}")
    if m.suspended is not None:
        lines.append(f"suspended: {states[m.states[m.suspended].name]}")
    lines.append("states:")
    for s in m.states:
        lines.append(f"  - name: {states[s.name]}")
        if s.transitions:
            targets = ", ".join(states[m.states[t.target].name] for t in s.transitions)
            lines.append(f"    transitions: [{targets}]")
    return "\n".join(lines) + "\n"


def _layout_yaml(m: ClfsmMachine, states: Mapping[str, str]) -> str:
    lines = ["# Where MiEditLLFSM drew each state (from Layout.plist): llfsm edit reads it, build ignores it.",
             "states:"]  # fmt: skip
    for s in m.states:
        if s.name in m.layout:
            x, y = m.layout[s.name]
            lines.append(f"  {states[s.name]}: {{x: {x:g}, y: {y:g}}}")
    return "\n".join(lines) + "\n"
