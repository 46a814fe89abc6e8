"""`llfsm check`: validate machine directories from their text alone.

This runs in CI on untrusted pull requests, so it never imports, executes or evaluates user
code: it reads bytes, YAML nodes and `ast` trees (see reader.py) and applies the rules of the
catalogue in diagnostics.py.
"""

from __future__ import annotations

import ast
import builtins
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from .compiler.rewrite import BadBinding, attribute_of, find, name_map
from .diagnostics import Diagnostic, Severity, diag
from .discover import MACHINE_SUFFIX, find_machines, machine_name_of
from .model import Code, Machine, State, is_valid_name
from .reader import ReadResult, node_col, read_machine
from .runtime.machine import MACROS, RESERVED

BUILTINS = frozenset(dir(builtins))
GENERATED_PREFIXES = ("ringlet_", "on_entry_", "internal_", "on_exit_", "on_suspend_", "on_resume_")


@dataclass
class MachineCheck:
    """The outcome of checking one machine directory."""

    path: Path
    read: ReadResult
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def machine(self) -> Machine | None:
        return self.read.machine

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.severity is Severity.ERROR]

    @property
    def ok(self) -> bool:
        return self.machine is not None and not self.errors


def check_machine(path: str | Path) -> MachineCheck:
    path = Path(path)
    read = read_machine(path)
    result = MachineCheck(path, read, list(read.diagnostics))
    _Checker(result).run()
    result.diagnostics = sorted(set(result.diagnostics), key=Diagnostic.sort_key)
    return result


def check_paths(paths: Iterable[Path]) -> list[MachineCheck]:
    out = []
    for p in paths:
        out.extend(check_machine(m) for m in find_machines(p))
    return out


class _Checker:
    def __init__(self, result: MachineCheck) -> None:
        self.r = result
        self.path = result.path

    def add(self, code: str, file: str, line: int, col: int, msg: str) -> None:
        self.r.diagnostics.append(diag(code, self.path / file, line, col, msg))

    def at(self, code: str, loc: object, msg: str) -> None:
        self.add(code, loc.file, loc.line, loc.column, msg)  # type: ignore[attr-defined]

    # ------------------------------------------------------------------------------------
    def run(self) -> None:
        name = machine_name_of(self.path)
        if not self.path.name.endswith(MACHINE_SUFFIX):
            self.add(
                "LF010",
                "machine.yaml",
                1,
                1,
                f"the directory {self.path.name!r} must be named NAME.machine (NAME is the machine's name)",
            )
        elif not is_valid_name(name):
            self.add(
                "LF010", "machine.yaml", 1, 1, f"machine name {name!r} must be a Python identifier and not a keyword"
            )
        m = self.r.machine
        if m is None:
            return
        self.states(m)
        self.includes(m)
        self.variables(m)
        for s in m.states:
            self.code_of(m, s)
        for orphan in self.r.read.orphans:
            self.add(
                "LF101", orphan, 1, 1, f"{orphan} belongs to no state or transition of machine.yaml; it is ignored"
            )
        self.reachability(m)
        self.suspend_state(m)

    def suspend_state(self, m: Machine) -> None:
        """A suspended machine gets no ringlets and leaves by OnResume: some of its code never runs."""
        s = next((s for s in m.states if s.name == m.suspended), None)
        if s is None:
            return
        for t in s.transitions:
            self.at(
                "LF107",
                t.loc,
                f"transition {t.index} of the suspend state {s.name} never fires: a "
                "suspended machine gets no ringlets; resume() or restart() moves it on",
            )
        for sec in ("Internal", "OnExit", "OnSuspend"):
            if sec in s.sections and not s.sections[sec].is_empty:
                self.add(
                    "LF107",
                    s.sections[sec].file,
                    1,
                    1,
                    f"{sec} of the suspend state {s.name} never runs "
                    "(a suspended machine gets no ringlets and leaves it through OnResume)",
                )

    def states(self, m: Machine) -> None:
        seen: dict[str, State] = {}
        names = {s.name for s in m.states}
        for s in m.states:
            if s.implicit:
                continue
            if not is_valid_name(s.name):
                self.at("LF011", s.loc, f"state name {s.name!r} must be a Python identifier and not a keyword")
            if s.name in seen:
                self.at("LF012", s.loc, f"state {s.name} is declared twice (first at line {seen[s.name].loc.line})")
            else:
                seen[s.name] = s
            for t in s.transitions:
                if t.target not in names:
                    self.at("LF020", t.loc, f"transition {t.index} of {s.name} goes to unknown state {t.target!r}")
                self.guard(s, t.index, t.guard)
        if m.initial not in names:
            self.at("LF021", m.initial_loc, f"initial state {m.initial!r} is not a state of this machine")
        if m.suspended not in names:
            self.at("LF022", m.suspended_loc, f"suspend state {m.suspended!r} is not a state of this machine")

    def guard(self, s: State, index: int, code: Code | None) -> None:
        fname = f"State_{s.name}_Transition_{index}.expr"
        if code is None:
            if fname not in self.r.read.trees and not any(d.file.endswith(fname) for d in self.r.diagnostics):
                self.add(
                    "LF023",
                    "machine.yaml",
                    s.transitions[index].loc.line,
                    s.transitions[index].loc.column,
                    f"transition {index} of {s.name} has no guard file {fname}",
                )
            return
        tree = self.r.read.trees.get(fname)
        if tree is None:
            return  # a syntax error, already reported
        if len(tree.body) != 1 or not isinstance(tree.body[0], ast.Expr):
            where = tree.body[1] if len(tree.body) > 1 else (tree.body[0] if tree.body else None)
            line, col = (where.lineno, node_col(code.text, where)) if where is not None else (1, 1)
            what = "is empty" if not tree.body else "must be exactly one Python expression"
            self.add("LF024", fname, line, col, f"guard {fname} {what}, such as `after_ms(500)`")
            return
        expr = tree.body[0].value
        if isinstance(expr, ast.Constant):
            if not expr.value:
                self.add("LF103", fname, 1, 1, f"guard {fname} is always false: transition {index} never fires")
            else:
                for later in s.transitions[index + 1 :]:
                    self.add(
                        "LF104",
                        "machine.yaml",
                        later.loc.line,
                        later.loc.column,
                        f"transition {later.index} of {s.name} is never evaluated: "
                        f"transition {index} before it is always true",
                    )

    # -- python code ------------------------------------------------------------------------
    def includes(self, m: Machine) -> None:
        tree = self.r.read.trees.get("Includes.py")
        if tree is None or m.includes is None:
            return
        for stmt in tree.body:
            col = node_col(m.includes.text, stmt)
            if not isinstance(stmt, ast.Import | ast.ImportFrom):
                self.add(
                    "LF031",
                    "Includes.py",
                    stmt.lineno,
                    col,
                    f"Includes.py may hold only imports, not a `{type(stmt).__name__.lower()}` statement",
                )
            elif isinstance(stmt, ast.ImportFrom) and stmt.module == "__future__":
                self.add(
                    "LF031", "Includes.py", stmt.lineno, col, "`from __future__` imports are added by llfsm itself"
                )
            elif isinstance(stmt, ast.ImportFrom) and stmt.level:
                self.add(
                    "LF031",
                    "Includes.py",
                    stmt.lineno,
                    col,
                    "relative imports cannot work in a compiled machine; import by absolute name",
                )

    def imported_names(self) -> set[str] | None:
        """Names Includes.py binds; None if it star-imports (then any name may exist)."""
        tree = self.r.read.trees.get("Includes.py")
        if tree is None:
            return set()
        out = set()
        for stmt in tree.body:
            if isinstance(stmt, ast.Import | ast.ImportFrom):
                for a in stmt.names:
                    if a.name == "*":
                        return None
                    out.add((a.asname or a.name).split(".")[0])
        return out

    def variables(self, m: Machine) -> None:
        generated = {f"{p}{s.name}" for s in m.states for p in GENERATED_PREFIXES}
        state_attrs = {attribute_of(s.name, v.name): s.name for s in m.states for v in s.variables}
        machine_vars: dict[str, object] = {}
        for v in m.variables:
            self.reserved(v.name, v.loc, generated)
            if v.name in machine_vars:
                self.at("LF035", v.loc, f"machine variable {v.name} is declared twice")
            machine_vars[v.name] = v
            if v.name in state_attrs:
                self.at(
                    "LF013",
                    v.loc,
                    f"machine variable {v.name} collides with variable "
                    f"{v.name.split('__', 1)[1]} of state {state_attrs[v.name]}; rename one",
                )
        for s in m.states:
            seen: set[str] = set()
            for v in s.variables:
                self.reserved(v.name, v.loc, generated)
                if v.name in seen:
                    self.at("LF035", v.loc, f"variable {v.name} of state {s.name} is declared twice")
                seen.add(v.name)
                if v.name in machine_vars:
                    self.at(
                        "LF033", v.loc, f"state variable {v.name} of {s.name} shadows the machine variable {v.name}"
                    )
        # initialisers are code too
        for code in [m.variables_file] + [s.variables_file for s in m.states]:
            if code is not None and code.file in self.r.read.trees:
                self.no_escape(code.file, code.text, self.r.read.trees[code.file])

    def reserved(self, name: str, loc: object, generated: set[str]) -> None:
        if (
            name in RESERVED
            or name in MACROS
            or name.startswith("_llfsm")
            or name in generated
            or (name.startswith("__") and name.endswith("__"))
        ):
            what = "an llfsm macro" if name in MACROS else "reserved by llfsm"
            self.at("LF013", loc, f"variable name {name!r} is {what}; choose another name")

    def code_of(self, m: Machine, s: State) -> None:
        mvars = [v.name for v in m.variables]
        svars = [v.name for v in s.variables]
        mapping = name_map(mvars, s.name, svars, MACROS)
        imported = self.imported_names()
        files = list(s.sections.values()) + [t.guard for t in s.transitions if t.guard is not None]
        for code in files:
            tree = self.r.read.trees.get(code.file)
            if tree is None:
                continue
            is_guard = code.file.endswith(".expr")
            scan = _scan(tree, mapping)
            for node, _kind in scan.escapes:
                self.escape(code.file, code.text, node)
            if scan.may_bind_variable:  # rare: only then pay for the scoped walk
                _edits, bad = find(tree, mapping)
                for b in bad:
                    self.bad_binding(code, b)
            for n in scan.reserved:
                what = "is an llfsm macro and cannot be assigned" if n.id in MACROS else "is reserved by llfsm"
                self.add("LF013", code.file, n.lineno, node_col(code.text, n), f"`{n.id}` {what} in machine code")
            if imported is not None and (not is_guard or _single_expression(tree)):
                known = set(mapping) | imported | scan.bound | BUILTINS
                for name, n in scan.loads.items():
                    if name not in known:
                        self.add(
                            "LF105",
                            code.file,
                            n.lineno,
                            node_col(code.text, n),
                            f"name {name!r} is not a variable of this machine or state, an import, a builtin "
                            "or a macro, and is not assigned in this file",
                        )

    def bad_binding(self, code: Code, b: BadBinding) -> None:
        kind = "macro" if b.name in MACROS else "variable"
        self.add(
            "LF038",
            code.file,
            b.line,
            _col(code.text, b.line, b.col),
            f"{b.how} cannot bind the machine {kind} {b.name}; use a plain assignment or another name",
        )

    def escape(self, fname: str, text: str, node: ast.AST) -> None:
        col = node_col(text, node) if text else node.col_offset + 1  # type: ignore[attr-defined]
        if isinstance(node, ast.Global | ast.Nonlocal):
            kw = "global" if isinstance(node, ast.Global) else "nonlocal"
            self.add(
                "LF034",
                fname,
                node.lineno,
                col,
                f"`{kw}` is not allowed in machine code: machine variables are used by their bare names",
            )
        else:
            kw = {ast.Return: "return", ast.Yield: "yield", ast.YieldFrom: "yield", ast.Await: "await"}[type(node)]
            self.add(
                "LF036",
                fname,
                node.lineno,
                col,  # type: ignore[attr-defined]
                f"`{kw}` is not allowed at the top level of {fname}: a section runs inside the state's ringlet",
            )

    def no_escape(self, fname: str, text: str, tree: ast.AST) -> None:
        for node, _kind in _scan(tree, {}).escapes:
            self.escape(fname, text, node)

    # -- graph ---------------------------------------------------------------------------------
    def reachability(self, m: Machine) -> None:
        names = {s.name: s for s in m.states}
        if m.initial not in names:
            return
        seen = {m.initial}
        todo = [m.initial]
        while todo:
            for t in names[todo.pop()].transitions:
                if t.target in names and t.target not in seen:
                    seen.add(t.target)
                    todo.append(t.target)
        for s in m.states:
            if s.name not in seen and s.name != m.suspended and not s.implicit:
                self.at("LF102", s.loc, f"state {s.name} cannot be reached from the initial state {m.initial}")


_BINDERS = (
    ast.NamedExpr,
    ast.Import,
    ast.ImportFrom,
    ast.FunctionDef,
    ast.AsyncFunctionDef,
    ast.ClassDef,
    ast.ExceptHandler,
    ast.MatchAs,
    ast.MatchStar,
    ast.MatchMapping,
)
_NESTS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)
_ESCAPES = (ast.Return, ast.Yield, ast.YieldFrom, ast.Await)


@dataclass
class _Scanned:
    loads: dict[str, ast.Name] = field(default_factory=dict)  # first use of each name read
    bound: set[str] = field(default_factory=set)  # every name the code binds, in any scope
    reserved: list[ast.Name] = field(default_factory=list)  # `self`, `_llfsm*`, or a macro assigned
    escapes: list[tuple[ast.AST, str]] = field(default_factory=list)  # global/nonlocal; top-level return...
    may_bind_variable: bool = False  # a :=, import, def... binds a name of the mapping somewhere


def _scan(tree: ast.AST, mapping: dict[str, str]) -> _Scanned:
    """Everything the checker needs from a code file, in one traversal (checks run on every
    file of every machine in CI, so this is the checker's hot path)."""
    out = _Scanned()
    bound = out.bound
    stack: list[tuple[ast.AST, bool]] = [(tree, False)]
    while stack:
        node, nested = stack.pop()
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Name):
                if child.id == "self" or child.id.startswith("_llfsm"):
                    out.reserved.append(child)
                elif isinstance(child.ctx, ast.Load):
                    out.loads.setdefault(child.id, child)
                else:
                    bound.add(child.id)
                    if child.id in MACROS:
                        out.reserved.append(child)
                continue
            if isinstance(child, ast.arg):
                bound.add(child.arg)
            elif isinstance(child, ast.alias):
                bound.add((child.asname or child.name).split(".")[0])
            elif (
                isinstance(
                    child,
                    ast.FunctionDef
                    | ast.AsyncFunctionDef
                    | ast.ClassDef
                    | ast.ExceptHandler
                    | ast.MatchAs
                    | ast.MatchStar,
                )
                and child.name
            ):
                bound.add(child.name)
            elif isinstance(child, ast.MatchMapping) and child.rest:
                bound.add(child.rest)
            elif isinstance(child, ast.Global | ast.Nonlocal):
                bound.update(child.names)
            if isinstance(child, ast.Global | ast.Nonlocal):
                out.escapes.append((child, "global"))
            elif not nested and isinstance(child, _ESCAPES):
                out.escapes.append((child, "return"))
            if isinstance(child, _BINDERS):
                names = (
                    [a.asname or a.name.split(".")[0] for a in child.names]
                    if isinstance(child, ast.Import | ast.ImportFrom)
                    else [
                        getattr(child, "name", None)
                        or getattr(getattr(child, "target", None), "id", None)
                        or getattr(child, "rest", None)
                    ]
                )
                if any(n in mapping for n in names if n):
                    out.may_bind_variable = True
            stack.append((child, nested or isinstance(child, _NESTS)))
    return out


def _single_expression(tree: ast.Module) -> bool:
    return len(tree.body) == 1 and isinstance(tree.body[0], ast.Expr)


def _col(text: str, line: int, byte_col: int) -> int:
    lines = text.splitlines()
    if 1 <= line <= len(lines):
        return len(lines[line - 1].encode("utf-8")[:byte_col].decode("utf-8", "replace")) + 1
    return byte_col + 1
