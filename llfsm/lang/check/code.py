"""Rules on the code of sections, guards and variable initialisers: nesting and compile limits
(LF030), `global`/`return` and the like (LF034, LF036), reserved names and the machine's `self`
(LF013), bindings that cannot become attributes (LF038), names nothing defines (LF040, LF105,
with the likeliest cause: a C++ spelling, an rclpy name, a local of another section), `;` at
line ends (LF108), and rclpy habits (LF041, llfsm.lang.check.ros_habits).

Each file is scanned once (llfsm.lang.check.scan); the scoped walks (llfsm.lang.bindings,
llfsm.lang.scopes) run only for the rare file whose scan says they could find something.
"""

from __future__ import annotations

import ast
import builtins
import os
from collections.abc import Mapping

from ...interface_path import folders_around
from ...runtime.machine import MACROS
from ..bindings import BadBinding, find, name_map, state_map
from ..cpp import C_FUNCTIONS, CPP_NAMES
from ..model import Code, Machine, State
from ..positions import char_col, node_col
from ..reader import MAX_CODE_DEPTH
from ..scopes import Unresolved, section_bindings, unresolved
from .arrangement import references
from .checking import SUGGEST_AMONG, Checking
from .definitions import interface_imports
from .fields import message_fields
from .imports import imports
from .includes import imported_names
from .ros_habits import ROS_NAMES, ROS_QOS_NAMES, ros_habits
from .scan import compile_error, scan_code, single_expression, trailing_semicolons

#: Builtins, and the globals every module has (the compiled machine is a module).
BUILTINS = frozenset(dir(builtins)) | {"__file__", "__builtins__", "__cached__", "__loader__", "__spec__"}


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


def initialisers(c: Checking, m: Machine) -> None:
    """The code of Variables.py and of each state's variables file: it runs as the machine loads."""
    for state, code in [(None, m.variables_file)] + [(s, s.variables_file) for s in m.states]:
        if code is not None and code.file in c.read.trees:
            tree = c.read.trees[code.file]
            scan = scan_code(tree, {})
            if scan.too_deep is not None:
                too_deep(c, code, scan.too_deep)
                continue
            for node, _kind in scan.escapes:
                escape(c, code.file, code.text, node)
            declared = {id(st.target) for st in tree.body if isinstance(st, ast.AnnAssign)}
            for n in scan.reserved:
                if id(n) not in declared:  # a declared name is judged by variables.reserved
                    reserved_use(c, code, n)
            if scan.may_bind_variable:  # `self` somewhere: a lambda's own, or the machine's
                at = {(st.target.lineno, st.target.col_offset) for st in tree.body if isinstance(st, ast.AnnAssign)}
                for b in find(tree, {})[1]:
                    if b.how == "self" and (b.line, b.col) not in at:
                        machine_self(c, code, b)
            if not scan.escapes:
                compiles(c, code, tree)
                initialiser_names(c, m, state, code, tree)


def _base(c: Checking, m: Machine) -> Mapping[str, str]:
    """The machine-level name map (inputs are read by their bare names as variables are), and
    what Includes.py imports: once per machine, since per state it would cost states x variables."""
    if c.base is None:
        c.base = name_map([v.name for v in m.variables] + [i.name for i in m.inputs], None, [], MACROS)
        c.imported = imported_names(c)
    return c.base


def initialiser_names(c: Checking, m: Machine, s: State | None, code: Code, tree: ast.Module) -> None:
    """LF040 for a name an initialiser's value reads that nothing provides (`msg: Twist =
    Twist()` without the import): the machine would not load.  Annotations are left alone: the
    generated module never evaluates them."""
    values = [st.value for st in tree.body if isinstance(st, ast.AnnAssign) and st.value is not None]
    if not values:
        return
    base = _base(c, m)
    mapping = state_map(base, s.name, [v.name for v in s.variables]) if s is not None else base
    imported = c.imported
    names = {n.id for v in values for n in ast.walk(v) if isinstance(n, ast.Name)}
    if all(n in mapping or n in BUILTINS or (imported is not None and n in imported) for n in names):
        return
    for u in unresolved(ast.Module(body=[ast.Expr(v) for v in values], type_ignores=[]), _Known(mapping, imported)):
        undefined(c, m, s, code, u, star=imported is None)


def state_code(c: Checking, m: Machine, s: State) -> None:
    """Every section and guard of state `s`."""
    mapping = state_map(_base(c, m), s.name, [v.name for v in s.variables])
    imported = c.imported
    files = list(s.sections.values()) + [t.guard for t in s.transitions if t.guard is not None]
    for code in files:
        tree = c.read.trees.get(code.file)
        if tree is None:
            continue
        is_guard = code.file.endswith(".expr")
        scan = scan_code(tree, mapping)
        if scan.too_deep is not None:
            too_deep(c, code, scan.too_deep)
            continue
        for node, _kind in scan.escapes:
            escape(c, code.file, code.text, node)
        if scan.may_bind_variable:  # rare: only then pay for the scoped walk
            _edits, bad = find(tree, mapping)
            for b in bad:
                if b.how == "self":
                    machine_self(c, code, b)
                else:
                    bad_binding(c, code, b)
        for n in scan.reserved:
            reserved_use(c, code, n)
        ros_habits(c, code, scan)
        message_fields(c, m, s, code, tree)
        references(c, code, tree)
        if scan.imports:
            imports(c, code, scan.imports)
        if not is_guard and ";" in code.text:
            for line, col in trailing_semicolons(code.text):
                c.add("LF108", code.file, line, col, "Python needs no `;` at the end of a statement; drop it")
        if (
            not scan.escapes
            and (not scan.plain or "__debug__" in code.text)  # `__debug__` cannot be assigned
            and (not is_guard or single_expression(tree))
        ):
            compiles(c, code, tree)
        # only a name that nothing outside the file provides needs the scoped walk (where,
        # and in which scope, the file binds it decides)
        if (not is_guard or single_expression(tree)) and any(
            not (name in mapping or name in BUILTINS or (imported is not None and name in imported))
            for name in scan.loads
        ):
            known = _Known(mapping, imported)
            for u in unresolved(tree, known):
                undefined(c, m, s, code, u, star=imported is None)


def undefined(c: Checking, m: Machine, s: State | None, code: Code, u: Unresolved, star: bool) -> None:
    """LF040 for a name nothing provides (LF105, a warning, when Includes.py star-imports,
    since the star may provide it), with the likeliest cause and its fix."""
    name, n = u.name, u.node
    state_vars = s.variables if s is not None else []
    called = id(n) in _called(c, code.file)
    if called:  # a function: a variable to declare would be the wrong advice
        declare = "import it in Includes.py (from a library, or a helper module beside the machine folder)"
    else:
        declare = (
            f"declare it in Variables.py (`{name}: int = 0`) to keep a value between sections and read it in guards"
        )
    other = locals_elsewhere(c, m).get(name)
    if u.assigned_at is not None:
        msg = f"name {name!r} is read before it is assigned (line {u.assigned_at}); assign it first, or {declare}"
    elif name in CPP_NAMES:
        msg = f"name {name!r} is not defined: Python spells it `{CPP_NAMES[name]}`"
    elif called and name in C_FUNCTIONS:
        msg = f"name {name!r} is not defined: it is C/C++; Python has {C_FUNCTIONS[name]}"
    elif name in ROS_NAMES:
        msg = f"name {name!r} is not defined: llfsm spells it {ROS_NAMES[name]}"
    elif name in ROS_QOS_NAMES:
        msg = f"name {name!r} is not defined: llfsm spells it `ros.{name}` (after `from llfsm import ros`)"
    elif name[:1].isupper() and (lines := interface_imports(name, _roots(c))):
        msg = f"name {name!r} is not defined: it is an interface type; import it in Includes.py: " + " or ".join(
            f"`{line}`" for line in lines
        )
    elif other is not None and other != code.file:
        msg = f"name {name!r} is a local of {other}: a section's locals last one section, as in clfsm; {declare}"
    elif c.suggest.left <= 0 or len(m.variables) + len(state_vars) > SUGGEST_AMONG:
        msg = f"name {name!r} is not defined: not a variable, an import, a builtin or a macro; {declare}"
    else:
        candidates = [k for k in c.base or {} if k not in MACROS] + [v.name for v in state_vars]
        candidates += sorted(c.imported or ()) + sorted(MACROS)
        close = c.suggest.close(name, candidates)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        msg = f"name {name!r} is not defined{hint}: not a variable, an import, a builtin or a macro; {declare}"
    if star:
        msg = f"{msg} (unless the star import of Includes.py provides it)"
    c.add("LF105" if star else "LF040", code.file, n.lineno, node_col(code.text, n), msg)


def _roots(c: Checking) -> list[str]:
    """The folders around the machine where `llfsm run` finds a user's interface packages."""
    if c.interface_roots is None:
        c.interface_roots = folders_around(os.fspath(c.path))
    return c.interface_roots


def _called(c: Checking, file: str) -> set[int]:
    """The ids of the names a call calls (`printf(...)`) in `file`: worked out when the file's
    first undefined name is found, once per file, so a clean file costs nothing and a file
    with thousands of undefined names one walk."""
    if file not in c.called:
        tree = c.read.trees.get(file)
        walk = ast.walk(tree) if tree is not None else ()
        c.called[file] = {id(x.func) for x in walk if isinstance(x, ast.Call) and isinstance(x.func, ast.Name)}
    return c.called[file]


def locals_elsewhere(c: Checking, m: Machine) -> dict[str, str]:
    """name -> the first code file of the machine that binds it at its own level."""
    if c.section_locals is None:
        c.section_locals = {}
        for st in m.states:
            for code in st.sections.values():
                tree = c.read.trees.get(code.file)
                if tree is not None:
                    for name in section_bindings(tree):
                        c.section_locals.setdefault(name, code.file)
    return c.section_locals


def bad_binding(c: Checking, code: Code, b: BadBinding) -> None:
    """LF038: a machine name bound in a way that cannot become an attribute (`:=`, import...)."""
    kind = "macro" if b.name in MACROS else "variable"
    c.add(
        "LF038",
        code.file,
        b.line,
        char_col(code.text, b.line, b.col),
        f"{b.how} cannot bind the machine {kind} {b.name}; use a plain assignment or another name",
    )


def machine_self(c: Checking, code: Code, b: BadBinding) -> None:
    """LF013 for `self` where it is the machine: the compiled code runs each section in a
    function whose `self` is the machine, so reading it would reach llfsm's internals and
    binding it would break the ringlet.  A `self` the user's code binds (a method's first
    parameter, a lambda's, a local of a function, a comprehension variable) is theirs."""
    c.add(
        "LF013",
        code.file,
        b.line,
        char_col(code.text, b.line, b.col),
        "`self` here would be the machine itself (a section runs in a function whose `self` is the "
        "machine), which llfsm reserves; use the machine's variables by their bare names (`self` is "
        "fine where a function, method, lambda or comprehension of yours binds it)",
    )


def reserved_use(c: Checking, code: Code, n: ast.Name) -> None:
    """LF013: code names `_llfsm*`, or assigns a macro."""
    what = "is an llfsm macro and cannot be assigned" if n.id in MACROS else "is reserved by llfsm"
    c.add("LF013", code.file, n.lineno, node_col(code.text, n), f"`{n.id}` {what} in machine code")


def escape(c: Checking, fname: str, text: str, node: ast.stmt | ast.expr) -> None:
    """LF034 for `global`/`nonlocal`; LF036 for `return`, `yield`, `await` at a section's level."""
    col = node_col(text, node) if text else node.col_offset + 1
    if isinstance(node, ast.Global | ast.Nonlocal):
        kw = "global" if isinstance(node, ast.Global) else "nonlocal"
        c.add(
            "LF034",
            fname,
            node.lineno,
            col,
            f"`{kw}` is not allowed in machine code: machine variables are used by their bare names",
        )
    else:
        kw = {ast.Return: "return", ast.Yield: "yield", ast.YieldFrom: "yield", ast.Await: "await"}[type(node)]
        c.add(
            "LF036",
            fname,
            node.lineno,
            col,
            f"`{kw}` is not allowed at the top level of {fname}: a section runs inside the state's ringlet",
        )


def too_deep(c: Checking, code: Code, node: ast.AST) -> None:
    """LF030: nested deeper than the compiler's recursive walks can follow."""
    line = getattr(node, "lineno", 1)
    col = char_col(code.text, line, node.col_offset) if hasattr(node, "col_offset") else 1
    c.add("LF030", code.file, line, col, f"code nested more than {MAX_CODE_DEPTH} levels deep; split it up")


def compiles(c: Checking, code: Code, tree: ast.Module) -> None:
    """Compile (never run) the code where the build will put it, inside a method, so that
    what only the compiler refuses (`break` outside a loop, `import *` in a function, 20
    nested loops...) is an error of `check` rather than a surprise of `build`."""
    error = compile_error(tree, guard=code.file.endswith(".expr"))
    if error is not None:
        line = error.lineno or 1
        col = char_col(code.text, line, (error.offset or 1) - 1)
        c.add("LF030", code.file, line, col, f"cannot be compiled: {error.msg}")
