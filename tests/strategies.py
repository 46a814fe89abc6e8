"""Hypothesis strategies: valid machine directories, and hostile mutations of them.

A `MachineSpec` is plain data, so hypothesis can shrink a failing machine to a small one, and
`write_spec` turns it into files.  The valid machines are built to pass `llfsm check` with no
error: names follow the rules, every guard file exists, the code only reads names it may.
Their code is safe to run in-process: arithmetic on the machine's own variables, bounded `for`
and `while` loops, the clfsm macros on the machine's own name; no I/O, nothing unbounded.
Every stored value is reduced modulo a prime, so a thousand rounds never build huge numbers.
A division may still fail (a divisor can be 0): that is a user error the run must report.

The mutations turn a valid directory into everything an untrusted pull request may hold:
missing files, unknown targets, random bytes, non-UTF-8, odd names, deep or aliased YAML,
oversized files, NUL bytes, symlinks out of the directory and loops, FIFOs, directories where
files belong, statements in guard files.
"""

from __future__ import annotations

import builtins
import keyword
import os
import shutil
import stat
from dataclasses import dataclass, field, replace
from pathlib import Path

import yaml
from hypothesis import strategies as st

from llfsm.lang.reader import MAX_FILE_BYTES, MAX_YAML_DEPTH
from llfsm.runtime.machine import MACROS, RESERVED

SECTION_KINDS = ("OnEntry", "OnExit", "Internal", "OnSuspend", "OnResume")
#: Modules `Includes.py` may import: standard library, no side effects on import.
SAFE_INCLUDES = (
    "import math",
    "from math import floor",
    "import operator as op",
    "import itertools",
    "import functools",
    "import string",
)
MOD = 9973  # every stored value is reduced modulo this prime


# -- the data ------------------------------------------------------------------------------------


@dataclass
class VarSpec:
    name: str
    annotation: str
    init: str | None  # None: declared without a value (starts as None)


@dataclass
class StateSpec:
    name: str
    transitions: list[tuple[str, str]] = field(default_factory=list)  # (target, guard source)
    sections: dict[str, str] = field(default_factory=dict)  # OnEntry... -> source
    variables: list[VarSpec] = field(default_factory=list)


@dataclass
class MachineSpec:
    name: str
    states: list[StateSpec]
    variables: list[VarSpec] = field(default_factory=list)
    includes: list[str] = field(default_factory=list)
    description: str | None = None
    initial: str | None = None
    suspended: str | None = None
    newline: str = "\n"  # "\r\n" for files saved on Windows
    bom: bool = False
    block_lists: bool = False  # `transitions:` as a block list rather than `[A, B]`
    #: OnEntry/OnResume of the implicit suspend state SUSPENDED (only when no state is the suspend state)
    implicit_suspend: dict[str, str] = field(default_factory=dict)

    @property
    def include_modules(self) -> set[str]:
        """Top-level modules that Includes.py imports (what the generated module may import)."""
        out = set()
        for line in self.includes:
            words = line.split()
            out.add(words[1].split(".")[0])
        return out


@dataclass(frozen=True)
class Scope:
    """What code at some point of a section may read and assign."""

    machine: str
    states: tuple[str, ...]
    variables: tuple[str, ...]  # machine variables and this state's own variables
    includes: tuple[str, ...]
    readable: tuple[str, ...] = ()  # locals and loop variables assigned before this point
    #: code of a variable initialiser: it runs while the machine is being loaded, when the
    #: status macros do not know it yet (see test_fuzz.py, the xfail on is_running)
    loading: bool = False
    others: tuple[str, ...] = ()  # the other machines loaded beside this one

    def with_readable(self, *names: str) -> Scope:
        return replace(self, readable=self.readable + names)


# -- names ---------------------------------------------------------------------------------------

_TAKEN = frozenset(MACROS | RESERVED | set(dir(builtins)) | {"math", "floor", "op", "itertools", "functools", "string"})


def _usable(name: str) -> bool:
    return name.isidentifier() and not keyword.iskeyword(name) and name not in _TAKEN and not name.startswith("__")


#: Words that YAML 1.1 would read as booleans or null: state names must still be read as written.
YAML_WORDS = ("ON", "Off", "yes", "No", "null", "Null", "y", "n", "true_", "NULL")

state_names = st.one_of(
    st.sampled_from(("INITIAL", "END", "SUSPENDED", "PING", "Wait_And_Count", "A1", *YAML_WORDS)),
    st.from_regex(r"[A-Z][A-Za-z0-9_]{0,11}", fullmatch=True),
).filter(lambda n: _usable(n) and "__" not in n)
machine_names = st.one_of(
    st.sampled_from(("m", "counter", "ros2_ping_pong", "yes", "null", "Machine", "_m")),
    st.from_regex(r"[a-z][a-z0-9_]{0,14}", fullmatch=True),
).filter(_usable)
machine_var_names = st.from_regex(r"v[a-z0-9_]{0,7}", fullmatch=True).filter(_usable)
state_var_names = st.from_regex(r"w[a-z0-9_]{0,7}", fullmatch=True).filter(_usable)
annotations = st.sampled_from(("int", "float", "object", "int | None", "'int'", "list[int]", "typing.Any"))


# -- expressions ---------------------------------------------------------------------------------


@st.composite
def int_exprs(draw: st.DrawFn, scope: Scope, depth: int = 2) -> str:
    """An expression of number type (a float at worst) built from what `scope` may read."""
    m = repr(draw(st.sampled_from((scope.machine, *scope.others))))
    macros = ["machine_id()", "len(state_name())", "len(machine_name())"]
    if not scope.loading:
        macros += [f"int(is_running({m}))", f"int(is_suspended({m}))", f"len(state_name_of({m}))"]
    leaves: list[st.SearchStrategy[str]] = [
        st.integers(-3, 20).map(str),
        st.sampled_from(macros),
        st.integers(0, 40).map(lambda n: f"int(after_ms({n}))"),
    ]
    if scope.variables:
        leaves.append(st.sampled_from(scope.variables))
    if scope.readable:
        leaves.append(st.sampled_from(scope.readable))
    if depth <= 0 or draw(st.integers(0, 3)) == 0:
        return draw(st.one_of(leaves))
    a = draw(int_exprs(scope, depth - 1))
    b = draw(int_exprs(scope, depth - 1))
    form = draw(st.integers(0, 11))
    if form <= 4:
        # an initialiser that divides by zero stops the whole arrangement from loading: rarer there
        op = draw(st.sampled_from(("+", "-", "*") if scope.loading else ("+", "-", "*", "//", "%")))
        return f"({a} {op} {b})"
    if form == 5:
        return f"abs({a})"
    if form == 6:
        return f"{draw(st.sampled_from(('min', 'max')))}({a}, {b})"
    if form == 7:
        return f"({a} if {draw(bool_exprs(scope, depth - 1))} else {b})"
    if form == 8:
        return f"sum(k * {a} for k in range(3))"
    if form == 9:
        return f"(lambda q: q + {a})({b})"
    if form == 10 and "import math" in scope.includes:
        return f"math.floor(math.sqrt(abs({a})))"
    if form == 10 and "from math import floor" in scope.includes:
        return f"floor({a} / 3)"
    return f"-({a})"


@st.composite
def bool_exprs(draw: st.DrawFn, scope: Scope, depth: int = 2) -> str:
    m = repr(draw(st.sampled_from((scope.machine, *scope.others))))
    form = draw(st.integers(0, 9 if depth > 0 else 5))
    if form == 0:
        return draw(st.sampled_from(("True", "False")))
    if form == 1:
        unit, hi = draw(st.sampled_from((("after_ms", 50), ("after_us", 50_000), ("after", 1))))
        value = draw(st.integers(0, hi)) if unit != "after" else draw(st.sampled_from(("0", "0.01", "0.005")))
        return f"{unit}({value})"
    if form == 2 and not scope.loading:
        return draw(st.sampled_from((f"is_running({m})", f"is_suspended({m})", f"not is_suspended({m})")))
    if form == 4 and not scope.loading:
        return f"state_name_of({m}) != {draw(st.sampled_from(scope.states))!r}"
    if form in (2, 3, 4):
        return f"state_name() == {draw(st.sampled_from(scope.states))!r}"
    if form == 5:
        cmp = draw(st.sampled_from(("<", "<=", "==", "!=", ">", ">=")))
        return f"{draw(int_exprs(scope, 1))} {cmp} {draw(int_exprs(scope, 1))}"
    a = draw(bool_exprs(scope, depth - 1))
    if form == 6:
        return f"not ({a})"
    b = draw(bool_exprs(scope, depth - 1))
    return f"({a} {draw(st.sampled_from(('and', 'or')))} {b})"


# -- statements ----------------------------------------------------------------------------------

Line = tuple[int, str]  # (indent level, text)


@st.composite
def blocks(draw: st.DrawFn, scope: Scope, depth: int = 2, nested: bool = False) -> list[Line]:
    """A list of statements; each may be compound (if, for, while, try, match, def).  A nested
    block ends with `pass`, so that it is never only blank lines and comments."""
    out: list[Line] = [(0, "pass")] if nested else []
    n = draw(st.integers(1, 4))
    counter = len(scope.readable)
    for _ in range(n):
        lines, new = draw(statements(scope, depth, counter))
        counter += 1
        out.extend(lines)
        if new:
            scope = scope.with_readable(new)
    return out


@st.composite
def statements(draw: st.DrawFn, scope: Scope, depth: int, counter: int) -> tuple[list[Line], str | None]:
    """(lines, the local it assigns if later statements may read it)."""
    local = f"t{counter}"
    var = draw(st.sampled_from(scope.variables)) if scope.variables else None
    compound = depth > 0
    form = draw(st.integers(0, 19 if compound else 10))
    if form <= 2 and var:
        return [(0, f"{var} = ({draw(int_exprs(scope))}) % {MOD}")], None
    if form == 3 and var:
        op = draw(st.sampled_from(("+=", "-=")))
        return [(0, f"{var} {op} ({draw(int_exprs(scope))}) % 100")], None
    if form in (4, 5):
        return [(0, f"{local} = {draw(int_exprs(scope))}")], local
    if form == 6:
        return [(0, draw(st.sampled_from(("pass", "# just a comment", ""))))], None
    if form == 7:
        text = draw(st.sampled_from(('"""two\n  lines"""', "'''x'''", '"quote \\" inside"', "'tab\\there'")))
        return [(0, f"{local} = {text}")], local
    if form == 8:
        return [(0, f'{local} = f"{{{draw(int_exprs(scope, 1))}}} in {{state_name()}}"')], local
    if form == 9:
        return [(0, f"{local} = [k * 2 for k in range({draw(st.integers(0, 3))})]")], local
    if form == 10:
        m = repr(draw(st.sampled_from((scope.machine, *scope.others))))
        call = draw(st.sampled_from(("suspend_self()", f"suspend({m})", f"resume({m})", f"restart({m})")))
        return [(0, call)], None
    if form == 11:
        body = draw(blocks(scope, depth - 1, nested=True))
        lines = [(0, f"if {draw(bool_exprs(scope))}:"), *[(i + 1, t) for i, t in body]]
        if draw(st.booleans()):
            lines += [(0, "else:"), *[(i + 1, t) for i, t in draw(blocks(scope, depth - 1, nested=True))]]
        return lines, None
    if form == 12:
        k = f"k{counter}"
        body = draw(blocks(scope.with_readable(k), depth - 1, nested=True))
        return [(0, f"for {k} in range({draw(st.integers(0, 3))}):"), *[(i + 1, t) for i, t in body]], None
    if form == 13 and var:
        # bounded: an int above 100 halves until it is not; None or a float just ends the loop
        return [(0, f"while isinstance({var}, int) and {var} > 100:"), (1, f"{var} = {var} // 2")], None
    if form == 14 and var:
        a, b = draw(int_exprs(scope, 1)), draw(int_exprs(scope, 1))
        return [
            (0, "try:"),
            (1, f"{var} = ({a}) // ({b})"),
            (0, "except ZeroDivisionError:"),
            (1, f"{var} = 0"),
        ], None
    if form == 15 and var:
        return [
            (0, f"match {var}:"),
            (1, "case 0 | 1:"),
            *[(i + 2, t) for i, t in draw(blocks(scope, depth - 1, nested=True))],
            (1, "case _:"),
            (2, "pass"),
        ], None
    if form == 16 and var:
        fn = f"f{counter}"
        return [
            (0, f"def {fn}(q):"),
            (1, f"{var} = (q + {draw(int_exprs(scope, 1))}) % {MOD}"),
            (0, ""),
            (0, f"{fn}({draw(int_exprs(scope, 1))})"),
        ], None
    if form == 17 and var:
        return [(0, f"{var} = sum([{var} for {var} in range(3)]) % {MOD}  # the loop's own {var}")], None
    if form == 18:
        return [(0, f"{local} = lambda: {draw(int_exprs(scope, 1))}"), (0, f"{local}()")], local
    return [(0, f"{local} = {draw(bool_exprs(scope))}")], local


def render(lines: list[Line], indent: str, newline: str) -> str:
    return newline.join(f"{indent * level}{text}" if text else "" for level, text in lines) + newline


@st.composite
def code_files(draw: st.DrawFn, scope: Scope, newline: str) -> str:
    indent = draw(st.sampled_from(("    ", "  ", "\t")))
    lines = draw(blocks(scope))
    if draw(st.integers(0, 4)) == 0:
        lines = [(0, "# a comment first"), (0, ""), *lines]
    return render(lines, indent, newline)


@st.composite
def guards(draw: st.DrawFn, scope: Scope, newline: str) -> str:
    expr = draw(bool_exprs(scope))
    form = draw(st.integers(0, 5))
    if form == 0:
        return f"{expr}  # the reason{newline}"
    if form == 1:
        return f"# why this transition{newline}{expr}{newline}"
    if form == 2:
        return f"({expr}{newline} and {draw(bool_exprs(scope, 1))})  # two lines{newline}"
    if form == 3:
        return expr  # no newline at the end
    return expr + newline


@st.composite
def variable_lists(draw: st.DrawFn, names: st.SearchStrategy[str], scope: Scope, exclude: set[str]) -> list[VarSpec]:
    chosen = draw(st.lists(names.filter(lambda n: n not in exclude), max_size=4, unique=True))
    out: list[VarSpec] = []
    for name in chosen:
        init: str | None
        form = draw(st.integers(0, 9))
        if form == 0:
            init = None
        elif form <= 5 or not scope.variables:
            init = str(draw(st.integers(-5, 50)))
        else:
            init = f"({draw(int_exprs(scope, 1))}) % {MOD}"
        out.append(VarSpec(name, draw(annotations), init))
        if init is not None:  # later initialisers may use it (None + 1 would stop the loading)
            scope = replace(scope, variables=(*scope.variables, name))
    return out


# -- whole machines ------------------------------------------------------------------------------


@st.composite
def machine_specs(draw: st.DrawFn, name: str | None = None, others: tuple[str, ...] = ()) -> MachineSpec:
    """A machine that `llfsm check` accepts with no error; its code may name the machines
    `others` in macros (`is_running`, `suspend`...), which must then be loaded beside it."""
    name = name or draw(machine_names)
    names = draw(st.lists(state_names, min_size=1, max_size=6, unique=True))
    newline = draw(st.sampled_from(("\n", "\n", "\n", "\r\n")))
    includes = draw(st.lists(st.sampled_from(SAFE_INCLUDES), max_size=3, unique=True))
    base = Scope(name, tuple(names), (), tuple(includes), loading=True, others=others)
    mvars = draw(variable_lists(machine_var_names, base, set()))
    mscope = replace(base, variables=tuple(v.name for v in mvars), loading=False)
    suspended = draw(st.one_of(st.none(), st.sampled_from(names)))
    states = []
    for sname in names:
        loading = replace(mscope, loading=True, variables=tuple(v.name for v in mvars if v.init is not None))
        svars = draw(variable_lists(state_var_names, loading, {v.name for v in mvars}))
        scope = replace(mscope, variables=mscope.variables + tuple(v.name for v in svars))
        targets = draw(st.lists(st.sampled_from(names), max_size=3))
        kinds = draw(st.lists(st.sampled_from(SECTION_KINDS), max_size=5, unique=True))
        sections = {k: draw(code_files(scope, newline)) for k in kinds}
        states.append(
            StateSpec(
                sname,
                [(t, draw(guards(scope, newline))) for t in targets],
                sections,
                svars,
            )
        )
    implicit_suspend = {}
    if suspended is None and "SUSPENDED" not in names:
        kinds = draw(st.lists(st.sampled_from(("OnEntry", "OnResume")), max_size=2, unique=True))
        implicit_suspend = {k: draw(code_files(mscope, newline)) for k in kinds}
    return MachineSpec(
        name=name,
        states=states,
        implicit_suspend=implicit_suspend,
        variables=mvars,
        includes=includes,
        description=draw(st.one_of(st.none(), st.text(max_size=60))),
        initial=draw(st.one_of(st.none(), st.sampled_from(names))),
        suspended=suspended,
        newline=newline,
        bom=draw(st.integers(0, 9)) == 0,
        block_lists=draw(st.booleans()),
    )


@st.composite
def arrangements(draw: st.DrawFn) -> list[MachineSpec]:
    """Two or three machines that name each other in their macros, loaded together."""
    names = draw(st.lists(machine_names, min_size=2, max_size=3, unique=True))
    return [draw(machine_specs(n, tuple(o for o in names if o != n))) for n in names]


def _yaml_string(text: str) -> str:
    """A double-quoted YAML scalar holding exactly `text`, whatever characters it has."""
    dumped = yaml.safe_dump(text, default_style='"', allow_unicode=False, width=1 << 30)
    return dumped.rstrip("\n").removesuffix("\n...")


def machine_yaml(spec: MachineSpec) -> str:
    lines = []
    if spec.description is not None:
        lines.append(f"description: {_yaml_string(spec.description)}")
    if spec.initial is not None:
        lines.append(f"initial: {spec.initial}")
    if spec.suspended is not None:
        lines.append(f"suspended: {spec.suspended}")
    lines.append("states:")
    for s in spec.states:
        lines.append(f"  - name: {s.name}")
        if s.transitions and spec.block_lists:
            lines.append("    transitions:")
            lines.extend(f"      - {t}" for t, _ in s.transitions)
        elif s.transitions:
            lines.append(f"    transitions: [{', '.join(t for t, _ in s.transitions)}]")
    return spec.newline.join(lines) + spec.newline


def _variables_file(variables: list[VarSpec], newline: str) -> str:
    out = []
    for i, v in enumerate(variables):
        line = f"{v.name}: {v.annotation}" + (f" = {v.init}" if v.init is not None else "")
        if i % 2:
            line += "  # a comment"
        out.append(line)
    return newline.join(out) + newline


def spec_files(spec: MachineSpec) -> dict[str, str]:
    """File name -> text of every file of the machine directory."""
    nl = spec.newline
    files = {"machine.yaml": machine_yaml(spec)}
    if spec.includes:
        files["Includes.py"] = nl.join(["# what every state may use", *spec.includes]) + nl
    if spec.variables:
        files["Variables.py"] = _variables_file(spec.variables, nl)
    for s in spec.states:
        for kind, text in s.sections.items():
            files[f"State_{s.name}_{kind}.py"] = text
        if s.variables:
            files[f"State_{s.name}_Variables.py"] = _variables_file(s.variables, nl)
        for i, (_target, guard) in enumerate(s.transitions):
            files[f"State_{s.name}_Transition_{i}.expr"] = guard
    for kind, text in spec.implicit_suspend.items():
        files[f"State_SUSPENDED_{kind}.py"] = text
    return files


def write_spec(spec: MachineSpec, root: Path, dirname: str | None = None) -> Path:
    d = root / (dirname or f"{spec.name}.machine")
    d.mkdir(parents=True)
    for fname, text in spec_files(spec).items():
        (d / fname).write_bytes(("\ufeff" if spec.bom else "").encode() + text.encode("utf-8"))
    return d


# -- mutations -----------------------------------------------------------------------------------

#: Names a state, a target or a machine may be given that break the naming rules one way or another.
ODD_NAMES = st.one_of(
    st.sampled_from(
        (
            "",
            "class",
            "None",
            "True",
            "2B",
            "with-dash",
            "dot.ted",
            "spa ce",
            "../up",
            "a/b",
            "émoji_😀",
            "ünïcödé",
            "x" * 300,
            "__init__",
            "self",
            "_llfsm_x",
            "ringlet_A",
            '"quoted"',
            "new\nline",
            "tab\tbed",
            "\x1b[31mred",
            "%s%n",
            "'; import os; os.system('x'); '",
        )
    ),
    st.text(max_size=20),
)

HOSTILE_YAML = st.sampled_from(
    (
        "states: !!python/object/apply:os.system ['echo PWNED']\n",
        "description: !!python/object/apply:os.system ['echo PWNED']\nstates:\n  - name: A\n",
        "states:\n  - name: !!python/name:os.system A\n",
        "a: &a [x, x]\nb: &b [*a, *a]\nstates:\n  - name: A\n",
        "states:\n  - &s {name: A}\n  - *s\n",
        "states: " + "[" * (MAX_YAML_DEPTH + 2) + "]" * (MAX_YAML_DEPTH + 2) + "\n",
        "states: " + "[" * 5000 + "\n",
        "states:\n  - name: A\n    transitions: [" + ", ".join(["A"] * 2000) + "]\n",
        "states:\n  - {name: A, name: B}\n",
        "states:\n  - name: A\n    transitions: {B: C}\n",
        "? [complex, key]\n: 1\nstates:\n  - name: A\n",
        "%YAML 1.1\n---\nstates:\n  - name: A\n...\n---\nstates: []\n",
        "states:\n  - name: A\n\t- name: B\n",
        "states:\n  - name: 0x1F\n  - name: 1e3\n  - name: .inf\n",
        "initial: [A]\nsuspended: {B: 1}\ndescription: [x]\nstates:\n  - name: A\n",
        "states:\n  - name: A\n    transitions: [~, null, '', \"\"]\n",
        "",
        "\ufeff",
        "---\n",
        "- just\n- a\n- list\n",
    )
)

#: Things an untrusted pull request might put in a code file.
HOSTILE_CODE = st.sampled_from(
    (
        "x = 1\nbreak\n",
        "from math import *\n",
        "global g\n",
        "return 3\n",
        "yield\n",
        "await x\n",
        "def f(a, a):\n    pass\n",
        "class K:\n    return 1\n",
        "1 +" * 50 + "1\n",
        "(" * 300 + ")" * 300 + "\n",
        "-" * 5000 + "1\n",
        "1+" * 1200 + "1\n",
        "x = 1\n\x0cimport os\n",
        "x = 1\rimport os\r",
        "s = '\u2028'\nself = 3\n",
        "__import__('os').system('echo PWNED')\n",
        "if True:\n\tx = 1\n        y = 2\n",
        "x: int = (self := 1)\n",
        "import os as Machine\n",
        "from os import path as super\n",
        "a, b\n",
        "True;\n",
        "x = 1\n",
        "lambda: (yield)\n",
        '"""unterminated\n',
        "\\\n",
        "# only a comment\n",
        "\n\n\n",
    )
)

FILE_MUTATIONS = ("delete", "bytes", "text", "code", "latin1", "nul", "huge", "symlink_out", "symlink_loop")
FILE_MUTATIONS += ("symlink_abs", "symlink_dir", "fifo", "dir", "truncate", "bom_only")
YAML_MUTATIONS = ("rename_state", "target", "initial", "suspended", "hostile_yaml", "random_yaml")
DIR_MUTATIONS = ("rename_dir", "orphan", "guard_statement", "symlink_machine_dir")

Mutation = tuple[str, int, object]

mutations: st.SearchStrategy[Mutation] = st.one_of(
    st.tuples(
        st.sampled_from(FILE_MUTATIONS),
        st.integers(0, 1000),
        st.one_of(st.binary(max_size=64), st.text(max_size=64), HOSTILE_CODE),
    ),
    st.tuples(
        st.sampled_from(YAML_MUTATIONS),
        st.integers(0, 1000),
        st.one_of(ODD_NAMES, HOSTILE_YAML, st.recursive(st.none() | st.text(max_size=8), st.lists)),
    ),
    st.tuples(st.sampled_from(DIR_MUTATIONS), st.integers(0, 1000), st.one_of(ODD_NAMES, HOSTILE_CODE)),
)


def _as_text(value: object) -> str:
    if isinstance(value, bytes):
        return value.decode("latin-1")
    return value if isinstance(value, str) else repr(value)


def _as_bytes(value: object) -> bytes:
    if isinstance(value, bytes):
        return value
    return _as_text(value).encode("utf-8", "surrogatepass")


def _files(d: Path) -> list[str]:
    try:
        return sorted(os.listdir(d))
    except OSError:
        return []


def _replace(p: Path) -> None:
    """Remove whatever is at p (file, link, FIFO or folder) so that something else can go there."""
    if p.is_symlink() or not p.is_dir():
        p.unlink(missing_ok=True)
    else:
        shutil.rmtree(p)


def _put(p: Path, data: bytes | str) -> None:
    """Write a fresh regular file at p, whatever was there (writing into a FIFO would block)."""
    _replace(p)
    p.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8", "surrogatepass"))


def _content(p: Path) -> bytes:
    """The bytes of a regular file that is not a symlink, else nothing."""
    return p.read_bytes() if p.is_file() and not p.is_symlink() else b""


def apply_mutation(case: Path, machine: Path, spec: MachineSpec, mutation: Mutation) -> Path:
    """Mutate the machine directory `machine` (inside the folder `case`); returns its path,
    which a renaming mutation changes.  Targets of symlinks are created inside `case` and
    linked relatively, so that a copy of `case` behaves the same."""
    kind, index, value = mutation
    files = _files(machine)
    target = machine / files[index % len(files)] if files else machine / "machine.yaml"
    outside = case / "outside.py"
    if not outside.exists():
        outside.write_text("secret = 'outside the machine directory'\n")
    if kind == "delete":
        _replace(target)
    elif kind == "bytes":
        data = _content(target)
        cut = index % (len(data) + 1)
        _put(target, data[:cut] + _as_bytes(value) + data[cut:])
    elif kind in ("text", "code"):
        _put(target, _as_text(value))
    elif kind == "latin1":
        _put(target, "x = 'café'\n".encode("latin-1"))
    elif kind == "nul":
        _put(target, b"x = 1\n\0\n")
    elif kind == "huge":
        _put(target, b"#" * MAX_FILE_BYTES + b"\n")  # one byte above the limit
    elif kind == "truncate":
        data = _content(target)
        _put(target, data[: index % (len(data) + 1)])
    elif kind == "bom_only":
        _put(target, b"\xef\xbb\xbf")
    elif kind == "symlink_out":
        _replace(target)
        target.symlink_to(os.path.relpath(outside, machine))
    elif kind == "symlink_abs":
        _replace(target)
        target.symlink_to("/etc/passwd")
    elif kind == "symlink_loop":
        _replace(target)
        target.symlink_to(target.name)
    elif kind == "symlink_dir":
        _replace(target)
        target.symlink_to("..")
    elif kind == "fifo":
        _replace(target)
        os.mkfifo(target)
    elif kind == "dir":
        _replace(target)
        target.mkdir()
        (target / "inner.py").write_text("x = 1\n")
    elif kind in YAML_MUTATIONS:
        _mutate_yaml(machine, spec, kind, index, value)
    elif kind == "rename_dir":
        name = f"{_as_text(value)}.machine" if index % 2 else _as_text(value) or "x"
        new = case / name
        try:
            if "/" in name or "\0" in name or name in (".", "..") or new.exists():
                new = case / "not a machine name.machine"
            machine.rename(new)
            machine = new
        except (OSError, ValueError):  # a name too long for the file system, say
            pass
    elif kind == "orphan":
        name = (
            f"State_{_as_text(value)}_OnEntry.py"
            if index % 2
            else f"State_{spec.states[0].name}_Transition_{index}.expr"
        )
        try:
            _put(machine / name, "x = 1\n")
        except (OSError, ValueError):
            pass
    elif kind == "guard_statement":
        guards = [f for f in files if f.endswith(".expr")]
        if guards:
            _put(machine / guards[index % len(guards)], _as_text(value))
    elif kind == "symlink_machine_dir":
        elsewhere = case / "elsewhere"
        if not elsewhere.exists() and machine.is_dir():
            copy_case(machine, elsewhere)
        link = case / "inside" / machine.name
        link.parent.mkdir(exist_ok=True)
        if not link.exists() and not link.is_symlink():
            link.symlink_to(os.path.relpath(elsewhere, link.parent))
        return link.parent  # a folder to search, holding a symlinked machine
    return machine


def _mutate_yaml(machine: Path, spec: MachineSpec, kind: str, index: int, value: object) -> None:
    y = machine / "machine.yaml"
    data = _content(y)
    text = data.decode("utf-8", "surrogateescape") if data else machine_yaml(spec)
    names = [s.name for s in spec.states]
    odd = _as_text(value)
    if kind == "rename_state":
        old = names[index % len(names)]
        text = text.replace(f"name: {old}", f"name: {_yaml_string(odd)}", 1)
    elif kind == "target":
        text = text.replace("transitions: [", f"transitions: [{_yaml_string(odd)}, ", 1)
        text = text.replace("transitions:\n", f"transitions:\n      - {_yaml_string(odd)}\n", 1)
    elif kind == "initial":
        text = f"initial: {_yaml_string(odd)}\n" + text
    elif kind == "suspended":
        text = f"suspended: {_yaml_string(odd)}\n" + text
    elif kind == "hostile_yaml":
        text = odd
    elif kind == "random_yaml":
        try:
            text = yaml.safe_dump(value if index % 2 else {"states": value}) if not isinstance(value, str) else odd
        except yaml.YAMLError:
            text = odd
    _put(y, text.encode("utf-8", "surrogateescape"))


@st.composite
def mutated_machines(draw: st.DrawFn) -> tuple[MachineSpec, list[Mutation]]:
    return draw(machine_specs()), draw(st.lists(mutations, min_size=1, max_size=3))


# -- copying a case ------------------------------------------------------------------------------


def copy_case(src: Path, dst: Path) -> None:
    """Copy a folder exactly: symlinks as symlinks, FIFOs as FIFOs (shutil.copytree would
    block reading a FIFO), unreadable names as they are."""
    dst.mkdir()
    for entry in sorted(os.listdir(src)):
        s, d = src / entry, dst / entry
        mode = os.lstat(s).st_mode
        if stat.S_ISLNK(mode):
            d.symlink_to(os.readlink(s))
        elif stat.S_ISDIR(mode):
            copy_case(s, d)
        elif stat.S_ISFIFO(mode):
            os.mkfifo(d)
        else:
            shutil.copyfile(s, d)


# -- hostile paths -------------------------------------------------------------------------------

#: Pieces of folder names that try to change what generated code means or what an output format
#: says: line breaks (a header comment would end and code start), encoding declarations
#: (PEP 263 reads lines 1-2), quotes and backslashes (string literals), URI delimiters (SARIF),
#: terminal escapes, Unicode line separators, bytes that are not UTF-8.
HOSTILE_FRAGMENTS = (
    "\n",
    "\r",
    "\r\n",
    "coding=utf_7",
    "# -*- coding: latin-1 -*-",
    "vim: set fileencoding=utf_7 :",
    "+AGEAYQ-",
    "'",
    '"',
    '"""',
    "\\",
    "\\n",
    "#",
    "%",
    "%2F",
    "?",
    ":",
    " ",
    "\t",
    "\x1b[31m",
    "\u2028",
    "\x85",
    "\x0c",
    "é",
    "{",
    "}",
    "$(touch x)",
    "raise SystemExit(7)",
)


def _fs_text(data: bytes) -> str:
    """Bytes as a file-name component: no `/` and no NUL, decoded as the file system does."""
    return os.fsdecode(data.replace(b"/", b"_").replace(b"\0", b"_"))


@st.composite
def hostile_folder_names(draw: st.DrawFn) -> str:
    """A folder name (one path component) made of hostile pieces, at most 200 bytes."""
    piece = st.one_of(
        st.sampled_from(HOSTILE_FRAGMENTS),
        st.text(st.characters(blacklist_characters="/\0", blacklist_categories=("Cs",)), max_size=4),
        st.binary(min_size=1, max_size=3).map(_fs_text),
    )
    name = "".join(draw(st.lists(piece, min_size=1, max_size=6)))
    if name in ("", ".", ".."):
        name = f"x{name}"
    while len(os.fsencode(name)) > 200:
        name = name[:-1]
    return name or "x"
