"""Code generation: a checked machine becomes the source of one readable Python module.

The template is templates/machine.py.j2; this module prepares what it renders (user code with
bare names rewritten, guards, pointers back to the user's files: llfsm.compiler.views), in
steps that `compile_machine` names, and verifies the result compiles, so that a mistake
surfaces at build time rather than at run time.  What the module must hold for the rest of
llfsm to read it (its header, pointers, source map, ringlet names) is llfsm.runtime.generated.
"""

from __future__ import annotations

import ast
import io
import re
import textwrap
import tokenize
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

import jinja2

from .. import __version__
from ..lang.bindings import MACHINE_ALIAS, Edit, attribute_of, find, name_map, own_locals, state_map, used_names
from ..lang.check import MachineCheck
from ..lang.diagnostics import Diagnostic, diag
from ..lang.files import expression
from ..lang.model import INPUT_TYPES, Code, Machine, State
from ..lang.parameter_types import parameter_type
from ..lang.scopes import child_nodes
from ..runtime.generated import (
    GENERATED_MARK,
    POINTER_END,
    SOURCE_LINE,
    SOURCE_MAP,
    enter_ringlet,
    hook_function,
    map_line,
    pointed,
    source_map_in,
    source_map_text,
    steady_ringlet,
)
from ..runtime.machine import MACROS
from ..templating import environment
from .literals import WIDTH, doc_lines, names_block, py, py_block
from .rewrite import apply
from .views import Block, GuardView, StateView, indent_code, lead

#: How a rewritten name that reaches the machine through its alias starts.
_ALIASED = MACHINE_ALIAS + "."

# -- text helpers ------------------------------------------------------------------------------


@cache
def _env() -> jinja2.Environment:
    env = environment(
        py=py,
        pyblock=py_block,
        names=names_block,
        code=indent_code,
        lead=lead,
        steady=steady_ringlet,
        hook=hook_function,
    )
    # what the rest of llfsm reads back out of the module (llfsm.runtime.generated)
    env.globals.update(generated_mark=GENERATED_MARK, source_line=SOURCE_LINE, source_map=SOURCE_MAP)
    return env


def _def_line(name: str, cls: str) -> str:
    """The `def` line of a ringlet, spread over three when a long name needs it."""
    one = f'def {name}(self: "{cls}") -> "int | None":'
    return one if len(one) <= WIDTH else f'def {name}(\n    self: "{cls}",\n) -> "int | None":'


def _wrap_doc(text: str, indent: int) -> str:
    """A one-line docstring of llfsm's own words (and names: no quotes, no escapes), at `indent`,
    over more lines if need be."""
    one = f'"""{text}"""'
    if indent + len(one) <= WIDTH:
        return one  # the usual case, without textwrap's cost (two per state of every machine)
    pad = " " * indent
    return textwrap.fill(
        f'"""{text}"""', WIDTH, initial_indent=pad, subsequent_indent=pad, break_long_words=False
    ).removeprefix(pad)


def class_name(machine: str) -> str:
    camel = "".join(p[:1].upper() + p[1:] for p in machine.split("_") if p)
    return (camel or "M") + "Machine"


AFTER = frozenset({"after", "after_ms", "after_us"})


def _after_use(tree: ast.AST) -> tuple[bool, bool]:
    """(uses an after* macro, uses one where it may run in another state): a use that is not a
    direct call (`f = after_ms`), or one inside a function or lambda (a callback may run later,
    in any state).  Only states that use after* need their entry time recorded."""
    used = escaped = False
    calls = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            calls.add(id(node.func))
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) and any(
            isinstance(n, ast.Name) and n.id in AFTER for n in ast.walk(node)
        ):
            escaped = True
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id in AFTER:
            used = True
            if id(node) not in calls:
                escaped = True
    return used, escaped


#: Nodes that give names a scope or bind them otherwise than as a plain `Name` (or, for an
#: f-string, need the text to rewrite): a tree without them is rewritten from its names alone.
#: (Comprehensions are walked: their scope only hides their own targets, see `_Flat`.)
_SCOPED: frozenset[type[ast.AST]] = frozenset(
    {
        ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef, ast.NamedExpr, ast.JoinedStr,
        ast.ExceptHandler, ast.Import, ast.ImportFrom, ast.alias, ast.Match, ast.MatchAs, ast.MatchStar,
        ast.MatchMapping, ast.Global, ast.Nonlocal,
    }
)  # fmt: skip
_COMPREHENSIONS: frozenset[type[ast.AST]] = frozenset({ast.ListComp, ast.SetComp, ast.GeneratorExp, ast.DictComp})


@dataclass
class _Flat:
    """The names of a tree with no `_SCOPED` node: all of them (what `used_names` gives), and
    those outside comprehensions (the section's own level, where `own_locals` looks).  With
    no other scope and no other binder, a name is the section's own unless a comprehension
    binds it as a target: the rewrite may then take every name it maps, provided no
    comprehension target is one of them (else the scoped walk decides)."""

    names: list[ast.Name]
    outer: list[ast.Name]
    targets: set[str]  # names comprehensions bind (only their targets can, without `:=`)


def _flat_names(tree: ast.AST) -> _Flat | None:
    """One walk of a tree for the rewrite, `used_names` and `own_locals`; None if it has a
    `_SCOPED` node (then the scoped walks answer)."""
    out = _Flat([], [], set())
    stack: list[tuple[ast.AST, bool]] = [(tree, False)]
    name, scoped, comps, load = ast.Name, _SCOPED, _COMPREHENSIONS, ast.Load
    while stack:
        node, in_comp = stack.pop()
        for child in child_nodes(node):
            t = type(child)
            if t is name:
                n: ast.Name = child  # type: ignore[assignment]  # its type is ast.Name, exactly
                out.names.append(n)
                if not in_comp:
                    out.outer.append(n)
                elif type(n.ctx) is not load:
                    out.targets.add(n.id)
            elif t in scoped:
                return None
            else:
                stack.append((child, in_comp or t in comps))
    return out


class _Trees:
    """What the generator asks of each code tree, walked once per tree."""

    def __init__(self) -> None:
        self._flat: dict[int, _Flat | None] = {}
        self._used: dict[int, set[str]] = {}

    def flat(self, tree: ast.AST) -> _Flat | None:
        key = id(tree)
        if key not in self._flat:
            self._flat[key] = _flat_names(tree)
        return self._flat[key]

    def edits(self, tree: ast.AST, mapping: Mapping[str, str], text: str) -> list[Edit]:
        flat = self.flat(tree)
        if flat is None or "self" in flat.targets or any(t in mapping for t in flat.targets):
            return find(tree, mapping, text)[0]
        out = []
        for n in flat.names:
            attr = mapping.get(n.id)
            if attr is not None:
                out.append(Edit(n.lineno, n.col_offset, n.end_col_offset or n.col_offset, attr))
        return out

    def used(self, tree: ast.AST) -> set[str]:
        key = id(tree)
        if key not in self._used:
            flat = self.flat(tree)
            self._used[key] = used_names(tree) if flat is None else {n.id for n in flat.names}
        return self._used[key]

    def own_locals(self, tree: ast.AST) -> set[str]:
        flat = self.flat(tree)
        return own_locals(tree) if flat is None else {n.id for n in flat.outer if type(n.ctx) is not ast.Load}


def _block(
    code: Code,
    tree: ast.Module,
    mapping: Mapping[str, str],
    extra: list[Edit] | None = None,
    walks: _Trees | None = None,
) -> Block | None:
    if not tree.body:
        return None  # empty, or only comments: costs nothing at run time
    edits = (walks or _Trees()).edits(tree, mapping, code.text)
    text = apply(code.text, edits + (extra or []))
    lines = text.split("\n")
    first = 0
    while first < len(lines) and not lines[first].strip():
        first += 1
    body = "\n".join(lines[first:]).rstrip()
    alias = any(e.text.startswith(_ALIASED) for e in edits)
    if code.origin is not None:  # an inline guard: its line of machine.yaml (a block's lines follow one for one)
        return Block(code.origin.file, code.origin.line + first, body, alias)
    return Block(code.file, first + 1, body, alias)


def _guard_view(
    code: Code,
    tree: ast.Module,
    mapping: Mapping[str, str],
    index: int,
    target: int,
    target_name: str,
    to_suspend: bool,
    walks: _Trees | None = None,
) -> GuardView:
    block = _block(code, tree, mapping, walks=walks)
    assert block is not None  # the checker guarantees one expression
    has_comment = "#" in block.text and any(
        t.type == tokenize.COMMENT for t in tokenize.generate_tokens(io.StringIO(block.text).readline)
    )
    multiline = "\n" in block.text or has_comment
    expr = tree.body[0]
    constant = bool(expr.value.value) if isinstance(expr, ast.Expr) and isinstance(expr.value, ast.Constant) else None
    return GuardView(
        index, target, target_name, block.file, block.line, block.text, multiline, to_suspend, block.alias, constant
    )


def _variables_block(code: Code, tree: ast.Module, mapping: Mapping[str, str]) -> Block | None:
    """Variables.py as `self.name: type = value` lines, kept line for line; no value means None."""
    extra: list[Edit] = []
    for stmt in tree.body:
        if isinstance(stmt, ast.AnnAssign) and stmt.value is None:
            extra.append(
                Edit(stmt.end_lineno or stmt.lineno, stmt.end_col_offset or 0, stmt.end_col_offset or 0, " = None")
            )
    return _block(code, tree, mapping, extra)


def input_entries(m: Machine) -> tuple[tuple[object, ...], ...]:
    """The class's INPUTS: per input (name, type, default, domain, topic, msg, field), values of
    the input's type (a float input's `1` is 1.0), a missing default the type's zero, a bool's
    domain both values when none is given (llfsm.runtime.inputs names the positions)."""
    out = []
    for i in m.inputs:
        kind = INPUT_TYPES[i.type]
        default = kind() if i.default is None else kind(i.default)
        domain = tuple(kind(v) for v in i.values())
        out.append((i.name, i.type, default, domain, i.topic, i.msg, i.field))
    return tuple(out)


class CompileError(Exception):
    """The generated module does not compile: reported against the user's file."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = diagnostics


def compile_machine(checked: MachineCheck, fingerprint: str, source: str) -> str:
    """Source of the module for a machine that passed `check` (no errors).  `source`: the
    machine folder as the module names it, relative to the folder the module is written to
    (llfsm.machinedir.source_ref), so that the module holds no absolute path."""
    m = checked.machine
    assert m is not None and checked.ok, "compile only machines that check clean"
    states = _States(m, checked.read.trees)
    views = [states.view(s) for s in m.states]
    blocks = _machine_blocks(m, checked.read.trees, states.base)
    context = _template_context(m, states, views, blocks, fingerprint, source)
    text = _with_source_map(_env().get_template("machine.py.j2").render(context))
    if not _pieces_are_safe([blocks.includes, blocks.variables, *blocks.state_variables], views):
        _verify(text, m)
    return text


def _entry_times(m: Machine, trees: Mapping[str, ast.Module]) -> tuple[bool, set[str]]:
    """Which states record their entry time: (all of them, because an after* macro may run in
    any state; else those whose own code uses one)."""
    stamp_all = False
    after_states: set[str] = set()
    for s in m.states:
        codes = [*s.sections.values(), *(t.guard for t in s.transitions if t.guard is not None)]
        for code in codes:
            tree = trees.get(code.file)
            if tree is not None and "after" in code.text:  # the text first: most code never says it
                used, escaped = _after_use(tree)
                if used:
                    after_states.add(s.name)
                stamp_all = stamp_all or escaped
    for loaded in (m.includes, m.variables_file, *(s.variables_file for s in m.states)):
        tree = trees.get(loaded.file) if loaded is not None else None
        if tree is not None and loaded is not None and "after" in loaded.text and any(_after_use(tree)):
            stamp_all = True
    return stamp_all, after_states


class _States:
    """What every state's view needs to know of the machine, and the view of each state."""

    def __init__(self, m: Machine, trees: Mapping[str, ast.Module]) -> None:
        self.trees = trees
        self.names = [s.name for s in m.states]
        self.index = {n: i for i, n in enumerate(self.names)}
        self.suspended = self.index[m.suspended]
        mvars = [v.name for v in m.variables] + [i.name for i in m.inputs]  # inputs read as variables are
        self.base = name_map(mvars, None, [], MACROS)  # once: per state it would cost states x variables
        self.stamp_all, self.after_states = _entry_times(m, trees)
        self.walks = _Trees()  # each tree walked once for the rewrite, its names and its locals
        self.cls = class_name(m.name)

    def view(self, s: State) -> StateView:
        mapping = state_map(self.base, s.name, [v.name for v in s.variables])
        sv = StateView(
            name=s.name,
            accepting=s.accepting,
            is_suspend=self.index[s.name] == self.suspended,
            doc=None,
            entry=self._section(s, "OnEntry", mapping),
            internal=self._section(s, "Internal", mapping),
            exit=self._section(s, "OnExit", mapping),
            stamp=self.stamp_all or s.name in self.after_states,
        )
        sv.enter_def = _def_line(enter_ringlet(s.name), self.cls)
        sv.steady_def = _def_line(steady_ringlet(s.name), self.cls)
        if not sv.is_suspend:
            targets = ", ".join(t.target for t in s.transitions) or "none: accepting"
            sv.doc = _wrap_doc(f"Ringlet of {s.name} (transitions to {targets}).", 4)
            sv.enter_doc = _wrap_doc(f"{s.name} was just entered: OnEntry, then as {steady_ringlet(s.name)}.", 4)
            self._guards(sv, s, mapping)
        sv.guards_code = "".join(g.code() for g in sv.guards)
        if not sv.falls_through:
            sv.internal = None  # never runs: a guard before it always fires
        self._own_methods(sv, s, mapping)
        if sv.entry_method and sv.entry is not None:
            sv.hooks.append(("on_entry", sv.entry))
        if sv.internal_method and sv.internal is not None:
            sv.hooks.append(("internal", sv.internal))
        if sv.exit is not None:
            sv.hooks.append(("on_exit", sv.exit))
        for hook, secname in (("on_suspend", "OnSuspend"), ("on_resume", "OnResume")):
            b = self._section(s, secname, mapping)
            if b is not None:
                sv.command_hooks.append((hook, b))
        return sv

    def _section(self, s: State, name: str, mapping: Mapping[str, str]) -> Block | None:
        code = s.sections.get(name)
        return _block(code, self.trees[code.file], mapping, walks=self.walks) if code is not None else None

    def _guards(self, sv: StateView, s: State, mapping: Mapping[str, str]) -> None:
        """The state's guards in priority order, up to the first that is constant true."""
        for t in s.transitions:
            assert t.guard is not None
            target = self.index[t.target]
            to_suspend = target == self.suspended
            g = _guard_view(
                t.guard, self.trees[t.guard.file], mapping, t.index, target, t.target, to_suspend, self.walks
            )
            g.exits, g.state = sv.exit is not None, s.name
            sv.guards.append(g)
            if g.constant:
                break  # the transition always fires here: the rest is never evaluated

    def _own_methods(self, sv: StateView, s: State, mapping: Mapping[str, str]) -> None:
        """Whether OnEntry and Internal get methods of their own: when one binds a local that
        another part of the state also uses (see StateView.entry_method)."""
        if sv.is_suspend:
            return
        trees, walks = self.trees, self.walks
        parts = {sec: trees[c.file] for sec, c in s.sections.items() if sec in ("OnEntry", "Internal")}
        parts.update({f"guard{t.index}": trees[t.guard.file] for t in s.transitions if t.guard is not None})
        for part in ("OnEntry", "Internal"):
            if part in parts:
                mine = {n for n in walks.own_locals(parts[part]) if n not in mapping}
                if mine and mine & set().union(*(walks.used(tr) for k, tr in parts.items() if k != part)):
                    if part == "OnEntry":
                        sv.entry_method = sv.entry is not None
                    else:
                        sv.internal_method = sv.internal is not None


@dataclass
class _MachineBlocks:
    """The machine's own user code: Includes.py, Variables.py and the states' Variables.py."""

    includes: Block | None
    variables: Block | None
    state_variables: list[Block]


def _machine_blocks(m: Machine, trees: Mapping[str, ast.Module], base: Mapping[str, str]) -> _MachineBlocks:
    includes = None
    if m.includes is not None and trees.get("Includes.py") is not None:
        includes = _block(m.includes, trees["Includes.py"], {})
    variables = None
    if m.variables_file is not None and "Variables.py" in trees:
        variables = _variables_block(m.variables_file, trees["Variables.py"], base)
    state_variables = []
    for s in m.states:
        declared = s.variables_file
        if declared is not None and declared.file in trees:
            svars = [v.name for v in s.variables]
            b = _variables_block(declared, trees[declared.file], state_map(base, s.name, svars))
            if b is not None:
                state_variables.append(b)
    return _MachineBlocks(includes, variables, state_variables)


def _template_context(
    m: Machine, states: _States, views: list[StateView], blocks: _MachineBlocks, fingerprint: str, source: str
) -> dict[str, object]:
    """What templates/machine.py.j2 is rendered with."""
    names, index, susp = states.names, states.index, states.suspended
    accepting = tuple(i for i, s in enumerate(m.states) if s.accepting and i != susp)
    return {
        "version": __version__,
        "fingerprint": fingerprint,
        "m": {
            "name": m.name,
            "class_name": states.cls,
            "docstring": doc_lines(f"{m.name}: {m.description}" if m.description else f"The machine {m.name}.", 0),
            "class_doc": doc_lines(m.description or f"The machine {m.name}.", 4),
            "state_names": tuple(names),
            "initial": index[m.initial],
            "suspended": susp,
            "accepting": accepting,
            "accepting_names": ", ".join(names[i] for i in accepting),
            "source_dir": source,
            "description": m.description or "",
            # per state, (target index, guard as written) in priority order: for the description
            # a run publishes on /llfsm/NAME/description and the web view draws
            "transitions": tuple(
                tuple((index[t.target], expression(t.guard.text) if t.guard is not None else "") for t in s.transitions)
                for s in m.states
            ),
            # machine.yaml's `parameters:`: (variable, rclpy type name) for llfsm.ros.control
            "parameters": _parameters(m),
            "variable_types": tuple((v.name, " ".join(v.annotation.split())) for v in m.variables),
            "enter": [enter_ringlet(v.name) for v in views],
            "steady": [steady_ringlet(v.name) for v in views],
            "includes": blocks.includes,
            "variables": blocks.variables,
            "state_variables": blocks.state_variables,
            "states": views,
            "slots": tuple(
                [v.name for v in m.variables]
                + [attribute_of(s.name, v.name) for s in m.states for v in s.variables]
                + [i.name for i in m.inputs]
            ),
            "inputs": input_entries(m),
            # declared for type checkers and mypyc (--native), which otherwise know no such attribute
            "input_annotations": tuple((i.name, i.type) for i in m.inputs),
            "on_suspend": [hook_function("on_suspend", v.name) if v.has_on_suspend else "None" for v in views],
            "on_resume": [hook_function("on_resume", v.name) if v.has_on_resume else "None" for v in views],
        },
    }


def _parameters(m: Machine) -> tuple[tuple[str, str], ...]:
    """The variables of `parameters:` with their parameter types (check has made sure each fits)."""
    annotations = {v.name: v.annotation for v in m.variables}
    out: list[tuple[str, str]] = []
    for p in m.parameters:
        kind = parameter_type(annotations.get(p.name, ""))
        if kind is not None and p.name not in dict(out):
            out.append((p.name, kind))
    return tuple(out)


#: Text in user code that the assembly of the module (indenting it, joining a guard's lines)
#: must take care over: tabs, form feeds, backslash continuations, strings that span lines.
_ASSEMBLY_RISKS = ("\t", "\f", "\\", '"""', "'''")


#: The start of an f-string (a prefix with f, then a quote, not inside a longer name); it may
#: also match inside a string or a comment, which only costs the compile.
_FSTRING = re.compile(r"(?<!\w)(?:[rR][fF]|[fF][rR]?)['\"]")


def _pieces_are_safe(blocks: list[Block | None], views: list[StateView]) -> bool:
    """Whether the module is known to compile without compiling it (about a quarter of the CPU a
    cold build spends per machine).

    `check` has proved every piece compiles where the module puts it (a method body, a guard
    as an `if` condition): a plain piece cannot fail (check._PLAIN), the rest check compiled.
    The rewrite to `self.name` cannot break one (check refuses the bindings that cannot take an
    attribute, LF038).  What is left is the assembly: indenting a piece into the template, and
    rewriting inside f-strings, whose positions CPython 3.11 reports loosely.  A piece with any
    of those risks, or a guard on several lines, has the whole module compiled as before."""
    texts = [b.text for b in blocks if b is not None]
    for v in views:
        for b in (v.entry, v.internal, v.exit, *(b for _, b in v.command_hooks)):
            if b is not None:
                texts.append(b.text)
        for g in v.guards:
            if g.multiline:
                return False
            texts.append(g.text)
    return not any(risk in t for t in texts for risk in _ASSEMBLY_RISKS) and not any(_FSTRING.search(t) for t in texts)


def _with_source_map(rendered: str) -> str:
    """Replace the pointer marks with the module's source map: only lines the template wrote
    count as pointers, never a user's comment that happens to look like one."""
    lines = rendered.split("\n")
    entries = []
    for i, line in enumerate(lines):
        if line.endswith(POINTER_END):
            lines[i] = line[: -len(POINTER_END)]
            entries.append((i + 1, *pointed(lines[i])))
    return "\n".join(lines).replace("__SOURCE_MAP__", source_map_text(tuple(entries)))


def _verify(source: str, m: Machine) -> None:
    """Compile (never run) the generated text, so a mistake surfaces at build time, not at run time."""
    try:
        compile(source, f"<{m.name}>", "exec", dont_inherit=True)
    except SyntaxError as e:
        mapped = map_line("", e.lineno or 1, source_map_in(source))
        file, line = mapped if mapped else ("machine.yaml", 1)
        raise CompileError([diag("LF030", m.path / file, line, 1, f"cannot be compiled: {e.msg}")]) from None
