"""`llfsm check`: validate machine directories from their text alone.

This runs in CI on untrusted pull requests, so it never imports, executes or evaluates user
code: it reads bytes, YAML nodes and `ast` trees (see reader.py) and applies the rules of the
catalogue in diagnostics.py.
"""

from __future__ import annotations

import ast
import builtins
import difflib
import io
import itertools
import os
import re
import tokenize
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ...compiler.rewrite import BadBinding, attribute_of, find, line_index, name_map, state_map
from ...runtime.machine import MACROS, RESERVED
from ...workers import die_with_parent, usable_cores
from ..diagnostics import Diagnostic, Severity, diag
from ..discover import MACHINE_SUFFIX, find_machines, machine_name_of
from ..model import MAX_MACHINE_NAME, Code, Machine, State, is_valid_name
from ..reader import MAX_CODE_DEPTH, ReadResult, node_col, read_machine
from ..scopes import Unresolved, child_nodes, section_bindings, unresolved
from .packages import undeclared_dependencies

#: Builtins, and the globals every module has (the compiled machine is a module).
BUILTINS = frozenset(dir(builtins)) | {"__file__", "__builtins__", "__cached__", "__loader__", "__spec__"}
GENERATED_PREFIXES = ("ringlet_", "on_entry_", "internal_", "on_exit_", "on_suspend_", "on_resume_")
#: Module-level names the compiled module itself uses (templates/machine.py.j2): an import in
#: Includes.py that rebinds one would break the class the module defines.
MODULE_NAMES = frozenset({"Machine", "super", "frozenset"})


#: Names from C, C++ and clfsm habits, and their Python spelling.
CPP_NAMES = {
    "true": "True",
    "false": "False",
    "TRUE": "True",
    "FALSE": "False",
    "null": "None",
    "NULL": "None",
    "nullptr": "None",
    "this": "a machine variable's bare name (no `this->`)",
}


#: Names rclpy code uses that llfsm spells otherwise (read without an import: LF040's hint).
ROS_NAMES = {
    "rclpy": "`from llfsm import ros` in Includes.py, then ros.Node(...), ros.ok()",
    "QoSPresetProfiles": "a preset such as `ros.qos_profile_sensor_data`, or `ros.QoSProfile(depth=10)`",
}
#: rclpy.qos names that `llfsm.ros` has under the same name (tests/test_qos.py keeps this in
#: step with ros.__all__; a list, so `check` never imports the bus).
ROS_QOS_NAMES = frozenset(
    {
        "QoSProfile",
        "ReliabilityPolicy",
        "HistoryPolicy",
        "DurabilityPolicy",
        "QoSReliabilityPolicy",
        "QoSHistoryPolicy",
        "QoSDurabilityPolicy",
        "qos_profile_sensor_data",
        "qos_profile_system_default",
        "qos_profile_services_default",
        "qos_profile_parameters",
        "qos_profile_parameter_events",
    }
)
_ROS_MESSAGE_MODULE = re.compile(r"(?P<pkg>[a-z][a-z0-9_]*)\.(?P<kind>msg|srv|action)(?:\.(?P<rest>.*))?\Z")


def ros_import_hint(module: str, stmt: ast.Import | ast.ImportFrom) -> str | None:
    """The llfsm spelling of an rclpy-style import, or None if the import is not one."""
    top = module.split(".")[0]
    if top == "rclpy":
        names = [a.name for a in stmt.names] if isinstance(stmt, ast.ImportFrom) else []
        same = [n for n in names if n in ROS_QOS_NAMES]
        if same:
            name = same[0]
            return f"`{name}` comes from rclpy, which llfsm machines do not use: `from llfsm import ros`, then `ros.{name}`"  # noqa: E501
        qos = [n for n in names if n in ROS_NAMES and n != "rclpy"]
        if qos:
            return f"`{qos[0]}` comes from rclpy, which llfsm machines do not use: pass {ROS_NAMES[qos[0]]}"
        return f"`{module}` is rclpy; llfsm machines use `from llfsm import ros` (ros.Node, ros.ok(), ...)"
    m = _ROS_MESSAGE_MODULE.match(module)
    if m is None:
        return None
    if isinstance(stmt, ast.ImportFrom):
        names = ", ".join(a.name for a in stmt.names)
        spelled = f"from llfsm.msgs.{module} import {names}"
    else:
        spelled = f"import llfsm.msgs.{module}"
    return f"ROS messages of {m['pkg']} come from llfsm.msgs: `{spelled}`"


def _ros_time_has(attr: str) -> bool:
    """Whether llfsm's run-clock time has `attr` (read from llfsm's own code, not the user's)."""
    from ...ros.clock import Time

    return hasattr(Time, attr)


class _Known:
    """What machine code may read without binding it: machine and state variables, macros,
    names imported by Includes.py, builtins.  A view, not a set: building a set per file
    would cost the machine's variables once per file."""

    __slots__ = ("imported", "mapping")

    def __init__(self, mapping: Mapping[str, str], imported: set[str] | None) -> None:
        self.mapping = mapping
        self.imported = imported or set()

    def __contains__(self, name: object) -> bool:
        return name in self.mapping or name in self.imported or name in BUILTINS


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


def check_machine(path: str | Path, within: Path | None = None) -> MachineCheck:
    """Check one machine directory.  A machine directory that is a symlink leading out of the
    folder holding it is refused, not read, however it was named (discover.refused_link):
    an untrusted pull request must not get `llfsm check` to read files from elsewhere.
    `within` (the folder searched) is accepted for callers that pass it; the rule needs none."""
    path = Path(path)
    _suggester.left = SUGGEST_AT_MOST  # a budget per machine
    read = read_machine(path)  # refuses a linked directory by discover.refused_link, as everything does
    result = MachineCheck(path, read, list(read.diagnostics))
    _Checker(result).run()
    result.diagnostics = sorted(set(_without_cascade(result.diagnostics)), key=Diagnostic.sort_key)
    return result


#: Diagnostics that follow from an earlier one rather than from a mistake of their own: one
#: typo in machine.yaml (`transition:` for `transitions:`, a misspelt target) must give one
#: diagnostic, not that one plus an orphan file for each guard and an unreachable state for
#: each target.  They come back, if still true, once the first is fixed.
#: (A misspelt target is followed to the state it was meant for by `reachability` instead.)
_CASCADES = {
    "LF004": frozenset({"LF020", "LF021", "LF022", "LF101", "LF102", "LF104"}),
}


#: "Did you mean" is for hand-written machines: difflib compares a name with every candidate,
#: so a machine.yaml with 100,000 misspelt targets among 100,000 states would take hours.
#: Beyond these bounds, no suggestion (the diagnostic itself stays).
SUGGEST_AMONG = 1000
SUGGEST_AT_MOST = 100


class _Suggester:
    def __init__(self) -> None:
        self.left = SUGGEST_AT_MOST

    def close(self, name: str, names: Iterable[str]) -> list[str]:
        names = names if isinstance(names, list | set | frozenset | dict) else list(names)
        if self.left <= 0 or len(names) > SUGGEST_AMONG or len(name) > 200:
            return []
        self.left -= 1
        return difflib.get_close_matches(name, [n for n in names if len(n) <= 200], n=1, cutoff=0.6)


_suggester = _Suggester()


def _close_names(name: str, names: Iterable[str]) -> list[str]:
    return _suggester.close(name, names)


def did_you_mean(name: str, names: Iterable[str]) -> str:
    """` (did you mean 'END'?)` when a known name is close to `name`, else nothing."""
    close = _close_names(name, names)
    if not close:
        return ""
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)"


def _without_cascade(diags: list[Diagnostic]) -> list[Diagnostic]:
    codes = {d.code for d in diags}
    drop = frozenset().union(*(_CASCADES[c] for c in codes if c in _CASCADES))
    return [d for d in diags if d.code not in drop] if drop else diags


def check_paths(paths: Iterable[Path]) -> list[MachineCheck]:
    out = []
    for p in paths:
        out.extend(check_machine(m, p) for m in find_machines(p))
    return out


#: From this many machines on, `diagnose` spreads the work over worker processes.
PARALLEL_FROM = 48


def _diagnostics_of(path: Path, within: Path | None = None) -> list[Diagnostic]:
    return check_machine(path, within).diagnostics


def diagnose(paths: Iterable[Path], jobs: int | None = None) -> tuple[int, list[Diagnostic]]:
    """(number of machines, their diagnostics in a stable order) for `llfsm check`.

    Large trees (a monorepo of machines in CI) are checked by worker processes, one per core;
    workers send back only diagnostics, so memory stays flat however many machines there are.
    The order of the output never depends on the number of workers.
    """
    found = [(m, p) for p in paths for m in find_machines(p)]
    machines, roots = [m for m, _ in found], [p for _, p in found]
    cores = usable_cores()
    if jobs is None:
        jobs = cores if len(machines) >= PARALLEL_FROM else 1
    # more workers than cores only add memory and switching: `-j 10000` must not fork 10,000
    jobs = min(jobs, cores, len(machines))
    if jobs <= 1 or len(machines) < 2:
        return len(machines), [d for m, p in found for d in check_machine(m, p).diagnostics]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    import gc

    gc.freeze()  # the workers' collector leaves the inherited objects alone: fewer pages copied
    try:
        with ProcessPoolExecutor(
            max_workers=jobs, mp_context=ctx, initializer=die_with_parent, initargs=(os.getpid(),)
        ) as pool:
            chunks = pool.map(_diagnostics_of, machines, roots, chunksize=max(1, len(machines) // (jobs * 8)))
            return len(machines), [d for chunk in chunks for d in chunk]
    finally:
        gc.unfreeze()  # every worker is forked by now; a caller that goes on collects as before


class _Checker:
    def __init__(self, result: MachineCheck) -> None:
        self.r = result
        self.path = result.path
        #: files the reader could not use (already reported): one set, not a scan per guard,
        #: so that a machine.yaml with 100 000 transitions is checked in linear time
        self.unreadable = {os.path.basename(d.file) for d in result.read.diagnostics}
        self.always_true: set[str] = set()  # states whose LF104 warnings are already given
        self._base: Mapping[str, str] | None = None  # the machine-level name map
        self._imported: set[str] | None = set()
        self._locals: dict[str, str] | None = None  # name -> a section file binding it

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
        elif len(name) > MAX_MACHINE_NAME:
            self.add(
                "LF014",
                "machine.yaml",
                1,
                1,
                f"machine name {name[:20]}... is {len(name)} characters long; at most {MAX_MACHINE_NAME} "
                "fit the file names a build writes",
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
        self.r.diagnostics.extend(undeclared_dependencies(self.path, self.r.read.trees))

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
        declared = [s.name for s in m.states if not s.implicit]  # what "did you mean" offers
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
                    self.at(
                        "LF020",
                        t.loc,
                        f"transition {t.index} of {s.name} goes to unknown state {t.target!r}"
                        + did_you_mean(t.target, declared),
                    )
                self.guard(s, t.index, t.guard)
        if m.initial not in names:
            self.at(
                "LF021",
                m.initial_loc,
                f"initial state {m.initial!r} is not a state of this machine" + did_you_mean(m.initial, declared),
            )
        if m.suspended not in names:
            self.at(
                "LF022",
                m.suspended_loc,
                f"suspend state {m.suspended!r} is not a state of this machine" + did_you_mean(m.suspended, declared),
            )

    def guard(self, s: State, index: int, code: Code | None) -> None:
        fname = f"State_{s.name}_Transition_{index}.expr"
        if code is None:
            if fname not in self.r.read.trees and fname not in self.unreadable:
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
        if isinstance(expr, ast.Tuple):
            # `a, b` is always true, and `if a, b:` is not even Python
            self.add(
                "LF024",
                fname,
                expr.lineno,
                node_col(code.text, expr),
                f"guard {fname} is a tuple, which is always true; join conditions with `and` or `or`",
            )
            return
        semicolon = _semicolon(code.text)
        if semicolon is not None:
            self.add("LF024", fname, *semicolon, f"guard {fname} must be one expression, without `;`")
            return
        if isinstance(expr, ast.Constant):
            if not expr.value:
                self.add("LF103", fname, 1, 1, f"guard {fname} is always false: transition {index} never fires")
            elif s.name not in self.always_true:  # the first true guard silences all later ones
                self.always_true.add(s.name)
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
        self.ros_habits(
            m.includes, _Scanned(imports=[s for s in tree.body if isinstance(s, ast.Import | ast.ImportFrom)])
        )
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
            else:
                for a in stmt.names:
                    bound = (a.asname or a.name).split(".")[0]
                    if bound in MODULE_NAMES or bound.startswith("_llfsm"):
                        self.add(
                            "LF013",
                            "Includes.py",
                            stmt.lineno,
                            col,
                            f"Includes.py binds `{bound}`, which the compiled module uses itself; "
                            "import it under another name (`import x as y`)",
                        )

    def ros_habits(self, code: Code, scan: _Scanned) -> None:
        """LF041: rclpy spellings that llfsm does not take, with the llfsm spelling."""
        for stmt in scan.imports:
            modules = [stmt.module or ""] if isinstance(stmt, ast.ImportFrom) else [a.name for a in stmt.names]
            if isinstance(stmt, ast.ImportFrom) and stmt.level:
                continue
            for mod in modules:
                if self.is_helper(mod):
                    continue
                hint = ros_import_hint(mod, stmt)
                if hint is not None:
                    self.add("LF041", code.file, stmt.lineno, node_col(code.text, stmt), hint)
                    break
        for attr in scan.to_msg:
            now = attr.value
            if (
                isinstance(now, ast.Call)
                and isinstance(now.func, ast.Attribute)
                and now.func.attr == "now"
                and not _ros_time_has("to_msg")
            ):
                self.add(
                    "LF041",
                    code.file,
                    attr.lineno,
                    node_col(code.text, attr),
                    "llfsm's clock time has no to_msg(): `s, ns = node.get_clock().now().seconds_nanoseconds()` "
                    "then `Time(sec=s, nanosec=ns)` (from llfsm.msgs.builtin_interfaces.msg import Time)",
                )

    def is_helper(self, module: str) -> bool:
        """Whether `module` names a helper module or package of the user's, beside the machine
        (where `llfsm run` lets machines import them): `my_msgs.msg` is then theirs, not ROS's."""
        top = module.split(".")[0]
        if not top.isidentifier():
            return False
        parent = self.path.parent
        return (parent / top).is_dir() or (parent / f"{top}.py").is_file()

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
        state_attrs: dict[str, tuple[str, str]] = {}  # attribute -> (state, variable) it stores
        machine_vars: dict[str, object] = {}
        for v in m.variables:
            self.reserved(v.name, v.loc, generated)
            if v.name in machine_vars:
                self.at("LF035", v.loc, f"machine variable {v.name} is declared twice")
            machine_vars[v.name] = v
        for s in m.states:
            seen: set[str] = set()
            for v in s.variables:
                self.reserved(v.name, v.loc, generated)
                if v.name in seen:
                    self.at("LF035", v.loc, f"variable {v.name} of state {s.name} is declared twice")
                    continue
                seen.add(v.name)
                if v.name in machine_vars:
                    self.at(
                        "LF033", v.loc, f"state variable {v.name} of {s.name} shadows the machine variable {v.name}"
                    )
                # state variables live in attributes STATE__name: names with `__` can meet
                attr = attribute_of(s.name, v.name)
                clash = (
                    f"the machine variable {attr}"
                    if attr in machine_vars
                    else f"variable {state_attrs[attr][1]} of state {state_attrs[attr][0]}"
                    if attr in state_attrs
                    else f"the method {attr} llfsm generates"
                    if attr in generated
                    else None
                )
                if clash is not None:
                    self.at("LF013", v.loc, f"variable {v.name} of state {s.name} is stored as {attr}, as is {clash}")
                elif attr.startswith("__"):
                    self.at(
                        "LF013",
                        v.loc,
                        f"variable {v.name} of state {s.name} is stored as {attr}, a name Python mangles; "
                        "rename the state",
                    )
                state_attrs.setdefault(attr, (s.name, v.name))
        # initialisers are code too
        for code in [m.variables_file] + [s.variables_file for s in m.states]:
            if code is not None and code.file in self.r.read.trees:
                tree = self.r.read.trees[code.file]
                scan = _scan(tree, {})
                if scan.too_deep is not None:
                    self.too_deep(code, scan.too_deep)
                    continue
                for node, _kind in scan.escapes:
                    self.escape(code.file, code.text, node)
                declared = {id(st.target) for st in tree.body if isinstance(st, ast.AnnAssign)}
                for n in scan.reserved:
                    if id(n) not in declared:  # a declared name is judged by `reserved` above
                        self.reserved_use(code, n)
                if scan.may_bind_variable:  # `self` somewhere: a lambda's own, or the machine's
                    at = {(st.target.lineno, st.target.col_offset) for st in tree.body if isinstance(st, ast.AnnAssign)}
                    for b in find(tree, {})[1]:
                        if b.how == "self" and (b.line, b.col) not in at:
                            self.machine_self(code, b)
                if not scan.escapes:
                    self.compiles(code, tree)

    def reserved(self, name: str, loc: object, generated: set[str]) -> None:
        if (
            name in RESERVED
            or name in MACROS
            or name.startswith("_llfsm")
            or name in generated
            or name.startswith("__")  # a dunder, or a private name that Python would mangle
        ):
            what = (
                "an llfsm macro"
                if name in MACROS
                else "a private name, which Python mangles inside the compiled class"
                if name.startswith("__") and not name.endswith("__")
                else "reserved by llfsm"
            )
            self.at("LF013", loc, f"variable name {name!r} is {what}; choose another name")

    def machine_self(self, code: Code, b: BadBinding) -> None:
        """LF013 for `self` where it is the machine: the compiled code runs each section in a
        function whose `self` is the machine, so reading it would reach llfsm's internals and
        binding it would break the ringlet.  A `self` the user's code binds (a method's first
        parameter, a lambda's, a local of a function, a comprehension variable) is theirs."""
        self.add(
            "LF013",
            code.file,
            b.line,
            _col(code.text, b.line, b.col),
            "`self` here would be the machine itself (a section runs in a function whose `self` is the "
            "machine), which llfsm reserves; use the machine's variables by their bare names (`self` is "
            "fine where a function, method, lambda or comprehension of yours binds it)",
        )

    def reserved_use(self, code: Code, n: ast.Name) -> None:
        what = "is an llfsm macro and cannot be assigned" if n.id in MACROS else "is reserved by llfsm"
        self.add("LF013", code.file, n.lineno, node_col(code.text, n), f"`{n.id}` {what} in machine code")

    def too_deep(self, code: Code, node: ast.AST) -> None:
        line = getattr(node, "lineno", 1)
        col = node_col(code.text, node) if hasattr(node, "col_offset") else 1
        self.add("LF030", code.file, line, col, f"code nested more than {MAX_CODE_DEPTH} levels deep; split it up")

    def compiles(self, code: Code, tree: ast.Module) -> None:
        """Compile (never run) the code where the build will put it, inside a method, so that
        what only the compiler refuses (`break` outside a loop, `import *` in a function, 20
        nested loops...) is an error of `check` rather than a surprise of `build`."""
        error = _compile_error(tree, guard=code.file.endswith(".expr"))
        if error is not None:
            line = error.lineno or 1
            col = _col(code.text, line, (error.offset or 1) - 1)
            self.add("LF030", code.file, line, col, f"cannot be compiled: {error.msg}")

    def code_of(self, m: Machine, s: State) -> None:
        if self._base is None:  # once per machine: per state it would cost states x variables
            self._base = name_map([v.name for v in m.variables], None, [], MACROS)
            self._imported = self.imported_names()
        mapping = state_map(self._base, s.name, [v.name for v in s.variables])
        imported = self._imported
        files = list(s.sections.values()) + [t.guard for t in s.transitions if t.guard is not None]
        for code in files:
            tree = self.r.read.trees.get(code.file)
            if tree is None:
                continue
            is_guard = code.file.endswith(".expr")
            scan = _scan(tree, mapping)
            if scan.too_deep is not None:
                self.too_deep(code, scan.too_deep)
                continue
            for node, _kind in scan.escapes:
                self.escape(code.file, code.text, node)
            if scan.may_bind_variable:  # rare: only then pay for the scoped walk
                _edits, bad = find(tree, mapping)
                for b in bad:
                    if b.how == "self":
                        self.machine_self(code, b)
                    else:
                        self.bad_binding(code, b)
            for n in scan.reserved:
                self.reserved_use(code, n)
            self.ros_habits(code, scan)
            if not is_guard and ";" in code.text:
                for line, col in _trailing_semicolons(code.text):
                    self.add("LF108", code.file, line, col, "Python needs no `;` at the end of a statement; drop it")
            if (
                not scan.escapes
                and (not scan.plain or "__debug__" in code.text)  # `__debug__` cannot be assigned
                and (not is_guard or _single_expression(tree))
            ):
                self.compiles(code, tree)
            # only a name that nothing outside the file provides needs the scoped walk (where,
            # and in which scope, the file binds it decides)
            if (not is_guard or _single_expression(tree)) and any(
                not (name in mapping or name in BUILTINS or (imported is not None and name in imported))
                for name in scan.loads
            ):
                known = _Known(mapping, imported)
                for u in unresolved(tree, known):
                    self.undefined(m, s, code, u, star=imported is None)

    def undefined(self, m: Machine, s: State, code: Code, u: Unresolved, star: bool) -> None:
        """LF040 for a name nothing provides (LF105, a warning, when Includes.py star-imports,
        since the star may provide it), with the likeliest cause and its fix."""
        name, n = u.name, u.node
        declare = (
            f"declare it in Variables.py (`{name}: int = 0`) to keep a value between sections and read it in guards"
        )
        other = self.locals_elsewhere(m).get(name)
        if u.assigned_at is not None:
            msg = f"name {name!r} is read before it is assigned (line {u.assigned_at}); assign it first, or {declare}"
        elif name in CPP_NAMES:
            msg = f"name {name!r} is not defined: Python spells it `{CPP_NAMES[name]}`"
        elif name in ROS_NAMES:
            msg = f"name {name!r} is not defined: llfsm spells it {ROS_NAMES[name]}"
        elif name in ROS_QOS_NAMES:
            msg = f"name {name!r} is not defined: llfsm spells it `ros.{name}` (after `from llfsm import ros`)"
        elif other is not None and other != code.file:
            msg = f"name {name!r} is a local of {other}: a section's locals last one section, as in clfsm; {declare}"
        elif _suggester.left <= 0 or len(m.variables) + len(s.variables) > SUGGEST_AMONG:
            msg = f"name {name!r} is not defined: not a variable, an import, a builtin or a macro; {declare}"
        else:
            candidates = [k for k in self._base or {} if k not in MACROS] + [v.name for v in s.variables]
            candidates += sorted(self._imported or ()) + sorted(MACROS)
            close = _close_names(name, candidates)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            msg = f"name {name!r} is not defined{hint}: not a variable, an import, a builtin or a macro; {declare}"
        if star:
            msg = f"{msg} (unless the star import of Includes.py provides it)"
        self.add("LF105" if star else "LF040", code.file, n.lineno, node_col(code.text, n), msg)

    def locals_elsewhere(self, m: Machine) -> dict[str, str]:
        """name -> the first code file of the machine that binds it at its own level."""
        if self._locals is None:
            self._locals = {}
            for st in m.states:
                for c in st.sections.values():
                    tree = self.r.read.trees.get(c.file)
                    if tree is not None:
                        for name in section_bindings(tree):
                            self._locals.setdefault(name, c.file)
        return self._locals

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

    # -- graph ---------------------------------------------------------------------------------
    def reachability(self, m: Machine) -> None:
        names = {s.name: s for s in m.states}
        if m.initial not in names:
            return
        seen = {m.initial}
        todo = [m.initial]
        meant: dict[str, str | None] = {}  # a misspelt target -> the state it was meant for
        while todo:
            for t in names[todo.pop()].transitions:
                target = t.target
                if target not in names:  # already LF020: follow it where it was meant to go
                    if target not in meant:
                        close = _close_names(target, names)
                        meant[target] = close[0] if close else None
                    target = meant[target]
                if target is not None and target not in seen:
                    seen.add(target)
                    todo.append(target)
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

#: Node types that no compiler check can refuse inside a method body, whatever surrounds them
#: (the parser has already accepted them).  A file made only of these, shallow enough that 20
#: nested blocks are impossible, skips the bytecode compile: the compile is a third of check's
#: time, and almost every section and guard is this simple.  The rest (break, starred targets,
#: lambdas, async comprehensions, import *, ...) is compiled as before.
_PLAIN: frozenset[type[ast.AST]] = frozenset(
    {
        ast.Expr, ast.Assign, ast.AugAssign, ast.AnnAssign, ast.If, ast.For, ast.While, ast.Pass,
        ast.Import, ast.ImportFrom, ast.alias, ast.Assert, ast.Raise, ast.Delete, ast.With, ast.withitem,
        ast.Try, ast.ExceptHandler, ast.BoolOp, ast.BinOp, ast.UnaryOp, ast.Compare, ast.Call,
        ast.keyword, ast.IfExp, ast.Attribute, ast.Subscript, ast.Slice, ast.Name, ast.Constant,
        ast.List, ast.Tuple, ast.Dict, ast.Set, ast.JoinedStr, ast.FormattedValue,
        ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp, ast.comprehension,
        ast.Load, ast.Store, ast.Del,
        ast.And, ast.Or, ast.Add, ast.Sub, ast.Mult, ast.MatMult, ast.Div, ast.Mod, ast.Pow, ast.LShift,
        ast.RShift, ast.BitOr, ast.BitXor, ast.BitAnd, ast.FloorDiv, ast.Invert, ast.Not, ast.UAdd,
        ast.USub, ast.Eq, ast.NotEq, ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Is, ast.IsNot, ast.In,
        ast.NotIn,
    }
)  # fmt: skip
_PLAIN_DEPTH = 20  # CPython refuses more than 20 statically nested blocks


_PLAIN_IF_CHECKED = (ast.ImportFrom, ast.Call, ast.Try, ast.comprehension)
_PLAIN_IF_CHECKED_T: frozenset[type[ast.AST]] = frozenset(_PLAIN_IF_CHECKED)
_NESTS_T: frozenset[type[ast.AST]] = frozenset(_NESTS)
#: The node types `_scan` notes something about (besides `Name`): every other node is only
#: walked through.  (`ast.parse` makes nodes of these exact classes, never of subclasses.)
_SPECIAL: frozenset[type[ast.AST]] = frozenset(
    {ast.Import, ast.ImportFrom, ast.Attribute, ast.arg, ast.alias, ast.Global, ast.Nonlocal}
    | {ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.ExceptHandler, ast.MatchAs, ast.MatchStar}
    | {ast.MatchMapping, *_BINDERS, *_ESCAPES}
)


def _plain_as_used(node: ast.AST) -> bool:
    """For a `_PLAIN_IF_CHECKED` node: whether none of its compile-time-only errors applies."""
    if isinstance(node, ast.ImportFrom):
        return node.module != "__future__" and all(a.name != "*" for a in node.names)
    if isinstance(node, ast.Call):
        given = [k.arg for k in node.keywords if k.arg is not None]
        return len(given) == len(set(given))  # `keyword argument repeated` is the compiler's
    if isinstance(node, ast.Try):
        return all(h.type is not None for h in node.handlers[:-1])
    return not node.is_async  # type: ignore[attr-defined]  # a comprehension


@dataclass
class _Scanned:
    loads: dict[str, ast.Name] = field(default_factory=dict)  # first use of each name read
    bound: set[str] = field(default_factory=set)  # every name the code binds, in any scope
    reserved: list[ast.Name] = field(default_factory=list)  # `_llfsm*`, or a macro assigned
    escapes: list[tuple[ast.AST, str]] = field(default_factory=list)  # global/nonlocal; top-level return...
    may_bind_variable: bool = False  # a :=, import, def... binds a name of the mapping, or `self` is used
    too_deep: ast.AST | None = None  # the first node nested deeper than MAX_CODE_DEPTH: stop there
    plain: bool = True  # only `_PLAIN` nodes, used as it allows: compiling to bytecode cannot fail
    imports: list[ast.Import | ast.ImportFrom] = field(default_factory=list)  # for LF041
    to_msg: list[ast.Attribute] = field(default_factory=list)  # `x.to_msg`, for LF041


def _scan(tree: ast.AST, mapping: dict[str, str]) -> _Scanned:
    """Everything the checker needs from a code file, in one traversal (checks run on every
    file of every machine in CI, so this is the checker's hot path)."""
    out = _Scanned()
    bound = out.bound
    stack: list[tuple[ast.AST, bool, int]] = [(tree, False, 0)]
    name_t, plain_t, checked_t, special_t, nests_t = ast.Name, _PLAIN, _PLAIN_IF_CHECKED_T, _SPECIAL, _NESTS_T
    while stack:
        node, nested, depth = stack.pop()
        if depth > MAX_CODE_DEPTH:
            # the compiler's walks recurse: a deeper tree would exhaust Python's stack in them
            out.too_deep = node
            return out
        for child in child_nodes(node):
            t = type(child)
            if out.plain and (
                t not in plain_t or depth >= _PLAIN_DEPTH or (t in checked_t and not _plain_as_used(child))
            ):
                out.plain = False
            if t is not name_t and t not in special_t:  # most nodes: nothing to note, only to walk
                stack.append((child, nested or t in nests_t, depth + 1))
                continue
            if t is name_t:
                if child.id == "self":
                    # the user's own in a method, lambda or comprehension that binds it, else
                    # the machine's: the scoped walk decides (LF013 there)
                    out.may_bind_variable = True
                elif child.id.startswith("_llfsm"):
                    out.reserved.append(child)
                elif isinstance(child.ctx, ast.Load | ast.Del):  # `del x` reads x as well
                    out.loads.setdefault(child.id, child)
                else:
                    bound.add(child.id)
                    if child.id in MACROS:
                        out.reserved.append(child)
                continue
            if isinstance(child, ast.Import | ast.ImportFrom):
                out.imports.append(child)
            elif isinstance(child, ast.Attribute) and child.attr == "to_msg":
                out.to_msg.append(child)
            if isinstance(child, ast.arg):
                bound.add(child.arg)
                if child.arg == "self":  # the scoped walk looks for machine names it would hide
                    out.may_bind_variable = True
                elif child.arg.startswith("_llfsm"):
                    out.reserved.append(
                        ast.Name(id=child.arg, ctx=ast.Store(), lineno=child.lineno, col_offset=child.col_offset)
                    )
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
            stack.append((child, nested or isinstance(child, _NESTS), depth + 1))
    return out


def _located(node: ast.AST) -> ast.AST:
    node.lineno = node.end_lineno = 1  # type: ignore[attr-defined]
    node.col_offset = node.end_col_offset = 0  # type: ignore[attr-defined]
    return node


def _compile_error(tree: ast.Module, guard: bool) -> SyntaxError | None:
    """The error `compile` gives for code placed in a method body as the generated module
    places it (a guard as the condition of an `if`); None if it compiles."""
    body: list[ast.stmt] = tree.body
    if guard:
        body = [_located(ast.If(test=tree.body[0].value, body=[_located(ast.Pass())], orelse=[]))]  # type: ignore[attr-defined]
    args = ast.arguments(
        posonlyargs=[], args=[_located(ast.arg(arg="self"))], kwonlyargs=[], kw_defaults=[], defaults=[]
    )
    method = ast.FunctionDef(name="_llfsm_check", args=args, body=body or [_located(ast.Pass())], decorator_list=[])
    try:
        with warnings.catch_warnings():  # `x is 1` and the like: not check's business, nor stderr's
            warnings.simplefilter("ignore")
            compile(ast.Module(body=[_located(method)], type_ignores=[]), "<check>", "exec", dont_inherit=True)
    except SyntaxError as e:
        return e
    except (RecursionError, MemoryError, ValueError, TypeError) as e:
        return SyntaxError(f"{type(e).__name__}")
    return None


def _semicolon(text: str) -> tuple[int, int] | None:
    """(line, column) of a `;` token in a guard, if any: `x;` parses as one statement, but the
    guard becomes the condition of an `if`, where a `;` is a syntax error."""
    if ";" not in text:
        return None
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.OP and tok.string == ";":
                return tok.start[0], tok.start[1] + 1
    except (tokenize.TokenError, SyntaxError):
        return None
    return None


def _trailing_semicolons(text: str) -> list[tuple[int, int]]:
    """(line, column) of each `;` that ends a line's code (C++'s habit); `a = 1; b = 2` is left
    alone.  At most a few: one per line is enough to make the point."""
    out: list[tuple[int, int]] = []
    try:
        toks = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError):
        return out
    for tok, nxt in itertools.pairwise(toks):
        if tok.type == tokenize.OP and tok.string == ";" and nxt.type in (tokenize.NEWLINE, tokenize.COMMENT):
            out.append((tok.start[0], tok.start[1] + 1))
            if len(out) >= 20:
                break
    return out


def _single_expression(tree: ast.Module) -> bool:
    return len(tree.body) == 1 and isinstance(tree.body[0], ast.Expr)


def _col(text: str, line: int, byte_col: int) -> int:
    return line_index(text).char_col(line, byte_col)
