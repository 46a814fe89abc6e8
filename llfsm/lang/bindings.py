"""Which bare names of machine code are the machine's, following Python's scopes.

Machine code names machine variables, state variables and the macros by their bare names
(`count += 1`, `after_ms(500)`); in the compiled module they are attributes of the machine
(`self.count`).  This module answers, from `ast` alone, where a piece of code uses such a name
and where it binds one in a way that cannot become an attribute (`:=`, import, def...): the
checker reports the second (LF038, LF013), the compiler (llfsm.compiler.rewrite) applies the
first to the text.  docs/machine-format.md describes the rules.

With scoping: a lambda parameter or a comprehension variable called `count` is not the machine
variable.  Machine variables keep their meaning inside nested functions and lambdas (as members
do in a C++ lambda capturing `this`): `def on_pose(msg): x = msg.x` sets the machine variable x.
The compiled section runs in a function whose parameter `self` is the machine, so a name becomes
`self.x` wherever that `self` is visible.  Where the user's code binds `self` itself (the first
parameter of a method of a class it defines, a lambda's parameter, a local), that `self` is
theirs, and the machine is reached through `MACHINE_ALIAS`, an alias the generated module binds
to the machine just before such a block: no parameter name a user may choose can hide the
machine.
"""

from __future__ import annotations

import ast
from collections import ChainMap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from .positions import Located, line_index
from .scopes import child_nodes

#: What the generated code calls the machine where the user's own `self` hides the parameter of
#: the generated function (names starting with `_llfsm` are refused in machine code, LF013).
MACHINE_ALIAS = "_llfsm_machine"


@dataclass(frozen=True)
class Edit:
    line: int  # 1-based
    start: int  # UTF-8 byte offsets on that line
    end: int
    text: str


@dataclass(frozen=True)
class BadBinding:
    """A machine variable bound in a way that cannot become `self.name` (`:=`, import, def...)."""

    name: str
    how: str
    line: int
    col: int  # byte offset


def _params(args: ast.arguments) -> set[str]:
    names = {a.arg for a in args.posonlyargs + args.args + args.kwonlyargs}
    if args.vararg:
        names.add(args.vararg.arg)
    if args.kwarg:
        names.add(args.kwarg.arg)
    return names


def _targets(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


class _Scope:
    """What one scope of user code hides of the machine's names.

    `here`: the names that code directly in this scope does not resolve to the machine (its
    parameters, comprehension variables, class attributes, and those of the scopes around).
    `inner`: what scopes nested in it inherit.  They differ for a class body only: as in
    Python, a name bound in a class body is visible in that body and nowhere else, not in its
    methods, lambdas or comprehensions (beyond the first iterable, evaluated in the class).
    `self_here` / `self_inner`: the same question for the name `self` itself, which user code
    may bind in any scope but the section's own: where it is the user's, the machine is
    reached through `MACHINE_ALIAS`, and where it is not, a use of `self` would be the machine."""

    __slots__ = ("function", "here", "inner", "self_here", "self_inner")

    def __init__(
        self,
        here: frozenset[str],
        inner: frozenset[str],
        function: bool,
        self_here: bool = False,
        self_inner: bool = False,
    ) -> None:
        self.here = here
        self.inner = inner
        self.function = function  # a def or lambda, or the section itself: where := binds
        self.self_here = self_here  # `self` in this scope is a name the user's code binds
        self.self_inner = self_inner  # ... and in the scopes nested in it


def _binds_self(nodes: Sequence[ast.stmt | ast.expr]) -> bool:
    """Whether code running in one function scope (a def's body, a lambda's expression) binds
    the name `self` in that scope: as a local (`self = ...`, `for self in`, import, def, class,
    except-as, a match pattern) or by `:=` inside a comprehension (PEP 572 binds it in the
    enclosing function).  Nested defs, lambdas and classes have scopes of their own."""
    code = ast.Module(body=nodes, type_ignores=[])  # type: ignore[arg-type]  # or a lambda's expression: only walked
    if "self" in own_locals(code):
        return True
    stack: list[ast.AST] = list(nodes)
    while stack:
        node = stack.pop()
        for child in child_nodes(node):
            if isinstance(child, ast.NamedExpr) and child.target.id == "self":
                return True
            if not isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda | ast.ClassDef):
                stack.append(child)
    return False


class _Finder(ast.NodeVisitor):
    def __init__(self, mapping: Mapping[str, str], text: str | None = None) -> None:
        self.mapping = mapping
        self.text = text
        self.scopes: list[_Scope] = [_Scope(frozenset(), frozenset(), True)]
        self.edits: list[Edit] = []
        self.bad: list[BadBinding] = []
        # without the word `self` in the text no scope can bind it: skip `_binds_self`'s walks
        self.maybe_self = text is None or "self" in text

    def _hidden(self, name: str) -> bool:
        return name in self.scopes[-1].here

    def _push(self, names: set[str] | frozenset[str], function: bool = True, binds_self: bool = False) -> None:
        """A function-like scope (def, lambda, comprehension) nested in the current one;
        `binds_self`: its code binds `self` otherwise than as one of `names`."""
        outer = self.scopes[-1]
        inherited = outer.inner
        seen = inherited | names if names else inherited
        own_self = outer.self_inner or binds_self or "self" in names
        self.scopes.append(_Scope(seen, seen, function, own_self, own_self))

    def _machine_self(self, name: str, node: Located, scope: _Scope | None = None) -> None:
        """`self` used or bound where it is the machine's (the section's own level, or a scope
        that does not bind it): it would read or replace the compiled code's machine."""
        if name == "self" and not (scope or self.scopes[-1]).self_here:
            self.bad.append(BadBinding("self", "self", node.lineno, node.col_offset))

    def visit_Name(self, node: ast.Name) -> None:
        if node.id == "self":
            self._machine_self("self", node)
            return
        attr = self.mapping.get(node.id)
        if attr is not None and not self._hidden(node.id):
            if self.scopes[-1].self_here and attr.startswith("self."):
                # `def get(self): return count`: that `self` is the user's instance, so the
                # machine is reached through the alias the module binds before this block
                attr = f"{MACHINE_ALIAS}.{attr[5:]}"
            self.edits.append(Edit(node.lineno, node.col_offset, node.end_col_offset or node.col_offset, attr))

    def _bind(self, name: str | None, how: str, node: Located, hidden: bool | None = None) -> None:
        if name == "self":
            self._machine_self(name, node)
        elif name and name in self.mapping and not (self._hidden(name) if hidden is None else hidden):
            self.bad.append(BadBinding(name, how, node.lineno, node.col_offset))

    def _function(self, node: ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) -> None:
        # decorators, defaults and annotations are evaluated where the def stands
        for d in getattr(node, "decorator_list", []):
            self.visit(d)
        for d in node.args.defaults + [d for d in node.args.kw_defaults if d is not None]:
            self.visit(d)
        if not isinstance(node, ast.Lambda):
            self._bind(node.name, "def", node)
            a_ = node.args
            for a in [*a_.posonlyargs, *a_.args, *a_.kwonlyargs, a_.vararg, a_.kwarg]:
                if a is not None and a.annotation:
                    self.visit(a.annotation)
            if node.returns:
                self.visit(node.returns)
        body = node.body if isinstance(node.body, list) else [node.body]
        self._push(_params(node.args), binds_self=self.maybe_self and _binds_self(body))
        for stmt in body:
            self.visit(stmt)
        self.scopes.pop()

    visit_FunctionDef = visit_AsyncFunctionDef = visit_Lambda = _function

    def _comprehension(self, node: ast.ListComp | ast.SetComp | ast.GeneratorExp | ast.DictComp) -> None:
        gens = node.generators
        self.visit(gens[0].iter)  # evaluated in the enclosing scope (a class body's included)
        bound: set[str] = set()
        for g in gens:
            bound |= _targets(g.target)
        # the comprehension's own scope: all its targets, wherever they stand (Python's symbol
        # table binds them for the whole comprehension); a class body's names are not seen
        self._push(bound, function=False)
        for i, g in enumerate(gens):
            if i:
                self.visit(g.iter)
            for cond in g.ifs:
                self.visit(cond)
        if isinstance(node, ast.DictComp):
            self.visit(node.key)
            self.visit(node.value)
        else:
            self.visit(node.elt)
        self.scopes.pop()

    visit_ListComp = visit_SetComp = visit_GeneratorExp = visit_DictComp = _comprehension

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        self._bind(node.name, "class", node)
        for d in node.decorator_list + node.bases + [k.value for k in node.keywords]:
            self.visit(d)
        outer = self.scopes[-1]  # a class in a class body does not see that body's names either
        own = own_locals(ast.Module(body=node.body, type_ignores=[]))
        # the body sees its own names; what is nested in it sees only what the class's
        # surroundings see
        self.scopes.append(
            _Scope(outer.inner | own, outer.inner, False, outer.self_inner or "self" in own, outer.self_inner)
        )
        for stmt in node.body:
            self.visit(stmt)
        self.scopes.pop()

    def visit_NamedExpr(self, node: ast.NamedExpr) -> None:
        # `:=` in a comprehension binds in the enclosing function (PEP 572), so whether its
        # target is the machine's is decided there, not by the comprehension's variables
        function = next(s for s in reversed(self.scopes) if s.function)
        if node.target.id == "self":
            self._machine_self("self", node.target, function)
        else:
            self._bind(node.target.id, ":=", node.target, hidden=node.target.id in function.here)
        self.visit(node.value)

    def visit_JoinedStr(self, node: ast.JoinedStr) -> None:
        for value in node.values:
            if not isinstance(value, ast.FormattedValue):
                continue
            before = len(self.edits)
            self.visit(value.value)
            if len(self.edits) > before and self.text is not None:
                self.edits.extend(_self_documenting(self.text, value))
            if value.format_spec is not None:
                self.visit(value.format_spec)

    def visit_ExceptHandler(self, node: ast.ExceptHandler) -> None:
        self._bind(node.name, "except ... as", node)
        self.generic_visit(node)

    def visit_Import(self, node: ast.Import | ast.ImportFrom) -> None:
        for a in node.names:
            self._bind((a.asname or a.name).split(".")[0], "import", node)

    visit_ImportFrom = visit_Import

    def visit_MatchAs(self, node: ast.MatchAs) -> None:
        self._bind(node.name, "a match pattern", node)
        self.generic_visit(node)

    def visit_MatchStar(self, node: ast.MatchStar) -> None:
        self._bind(node.name, "a match pattern", node)

    def visit_MatchMapping(self, node: ast.MatchMapping) -> None:
        self._bind(node.rest, "a match pattern", node)
        self.generic_visit(node)


def _self_documenting(text: str, field: ast.FormattedValue) -> list[Edit]:
    """Edits that keep `f"{x=}"` printing `x=` once `x` becomes `self.x`.

    Python prints the text of the field as written, so `{x=}` rewritten to `{self.x=}` would
    print `self.x=`.  The field becomes the same text as a literal followed by a plain field:
    `x={self.x!r}` (repr, as `=` implies without a conversion or format spec).  No edit when
    the field is not self-documenting, or when its text cannot be found on one line."""
    expr = field.value
    lines = line_index(text).lines
    if expr.lineno != expr.end_lineno or not 1 <= expr.lineno <= len(lines):
        return []
    raw = lines[expr.lineno - 1].encode("utf-8")
    brace = expr.col_offset - 1
    while brace >= 0 and raw[brace : brace + 1] in (b" ", b"\t", b"("):
        brace -= 1
    if brace < 0 or raw[brace : brace + 1] != b"{":
        return []
    eq = expr.end_col_offset or 0
    while eq < len(raw) and raw[eq : eq + 1] in (b" ", b"\t", b")"):
        eq += 1
    if raw[eq : eq + 1] != b"=" or raw[eq + 1 : eq + 2] == b"=":
        return []
    after = eq + 1
    while after < len(raw) and raw[after : after + 1] in (b" ", b"\t"):
        after += 1
    nxt = raw[after : after + 1]
    if nxt not in (b"}", b"!", b":"):
        return []
    literal = raw[brace + 1 : after].decode("utf-8").replace("{", "{{").replace("}", "}}")
    return [
        Edit(expr.lineno, brace, brace, literal),
        Edit(expr.lineno, eq, after, "!r" if nxt == b"}" else ""),
    ]


def attribute_of(state: str, variable: str) -> str:
    """The machine attribute holding variable `variable` of state `state`."""
    return f"{state}__{variable}"


def name_map(
    machine_vars: list[str], state: str | None, state_vars: list[str], macros: frozenset[str]
) -> dict[str, str]:
    """Bare name -> replacement in the code of `state` (None: machine-level code)."""
    m = {name: f"self.{name}" for name in macros}
    m.update({v: f"self.{v}" for v in machine_vars})
    if state is not None:
        m.update({v: f"self.{attribute_of(state, v)}" for v in state_vars})
    return m


def state_map(base: Mapping[str, str], state: str, state_vars: list[str]) -> Mapping[str, str]:
    """`name_map` for the code of `state`, given the machine-level map: a view over both, so
    that a machine with many states and many variables costs states + variables, not their
    product."""
    own = {v: f"self.{attribute_of(state, v)}" for v in state_vars}
    return _StateMap(own, base)  # type: ignore[arg-type]  # ChainMap's hint wants mutable maps; base is only read


class _StateMap(ChainMap[str, str]):
    """A ChainMap of a state's own map over the machine's, whose lookups ask the two maps
    directly: ChainMap's own `in` and `get` build a generator each, and every name of every
    code file is looked up (by check, then by the rewrite)."""

    def __contains__(self, key: object) -> bool:
        own, base = self.maps
        return key in own or key in base

    def get(self, key: str, default: str | None = None) -> str | None:  # type: ignore[override]  # str defaults only
        own, base = self.maps
        value = own.get(key)
        return value if value is not None else base.get(key, default)


def find(tree: ast.AST, mapping: Mapping[str, str], text: str | None = None) -> tuple[list[Edit], list[BadBinding]]:
    """Where `tree` uses a name of `mapping` (bare name -> replacement text).  With the source
    `text`, self-documenting f-string fields (`{x=}`) keep printing what the user wrote."""
    f = _Finder(mapping, text)
    f.visit(tree)
    return f.edits, f.bad


def own_locals(tree: ast.AST) -> set[str]:
    """Names a piece of code binds in its own scope: not inside nested functions, lambdas,
    classes or comprehensions (those have scopes of their own)."""
    out: set[str] = set()
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        for child in child_nodes(node):
            if isinstance(child, ast.Name) and not isinstance(child.ctx, ast.Load):
                out.add(child.id)
            elif isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                out.add(child.name)
                continue
            elif isinstance(child, ast.Lambda | ast.ListComp | ast.SetComp | ast.DictComp | ast.GeneratorExp):
                continue
            elif isinstance(child, ast.alias):
                out.add((child.asname or child.name).split(".")[0])
            elif (isinstance(child, ast.ExceptHandler) and child.name) or (
                isinstance(child, ast.MatchAs | ast.MatchStar) and child.name
            ):
                out.add(child.name)
            stack.append(child)
    return out


def used_names(tree: ast.AST) -> set[str]:
    """Every bare name a piece of code mentions, in any scope."""
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
