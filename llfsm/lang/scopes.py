"""Which names a piece of machine code reads that nothing defines: Python's scopes, from `ast`.

`check` used to call a name undefined only when no binding of it appeared anywhere in the file,
so `print(total)` followed by `total = 0` passed and failed at run time, while the commonest
beginner mistake (a value assigned in OnEntry and read in a guard) was only a warning.  This
module resolves every read the way CPython's symbol table does:

- a function or lambda sees its own bindings, then those of the functions around it, then the
  section's; it runs later (when called), so any binding in those scopes counts;
- a class body sees its own names, but nothing nested in it does;
- a comprehension has a scope of its own for its targets; `:=` inside binds in the enclosing
  function (PEP 572); it runs at once, like the section's own code;
- at the section's own level (and in comprehensions and class bodies that run there), a read
  needs a binding before it in the text, or one in a loop around it (`while`: the next round
  may read what this one wrote).

Nothing here imports or runs user code; each file costs one walk per pass.
"""

from __future__ import annotations

import ast
from collections.abc import Container
from dataclasses import dataclass, field

from .positions import Located

_FUNCS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
_COMPS = (ast.ListComp, ast.SetComp, ast.GeneratorExp, ast.DictComp)
_LOOPS = (ast.For, ast.AsyncFor, ast.While)


Pos = tuple[int, int]


@dataclass
class Unresolved:
    name: str
    node: ast.Name  # where it is read first
    assigned_at: int | None = None  # the line of a later binding at the section level, if any


#: The nodes that open a scope: the section's module, a function or lambda, a class, a comprehension.
_ScopeNode = (
    ast.Module
    | ast.FunctionDef
    | ast.AsyncFunctionDef
    | ast.Lambda
    | ast.ClassDef
    | ast.ListComp
    | ast.SetComp
    | ast.GeneratorExp
    | ast.DictComp
)


@dataclass
class _Scope:
    node: _ScopeNode
    kind: str  # section | function | class | comp
    bound: set[str] = field(default_factory=set)
    parent: _Scope | None = None


def child_nodes(node: ast.AST, _ast: type[ast.AST] = ast.AST) -> list[ast.AST]:
    """`ast.iter_child_nodes` as a list, in the same order, without its two generators."""
    out: list[ast.AST] = []
    for name in node._fields:
        v = getattr(node, name, None)
        if isinstance(v, _ast):
            out.append(v)
        elif type(v) is list:
            for item in v:
                if isinstance(item, _ast):
                    out.append(item)
    return out


def _params(args: ast.arguments) -> set[str]:
    names = {a.arg for a in args.posonlyargs + args.args + args.kwonlyargs}
    for a in (args.vararg, args.kwarg):
        if a is not None:
            names.add(a.arg)
    return names


def _body_ids(node: ast.Module | ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda | ast.ClassDef) -> set[int]:
    """ids of the statements (or the expression of a lambda) that run in `node`'s own scope;
    a set, since `stmt in body` compares one by one: quadratic for a long function."""
    body = node.body
    return {id(b) for b in body} if isinstance(body, list) else {id(body)}


def _end(node: Located) -> Pos:
    return (node.end_lineno or node.lineno, node.end_col_offset or 0)


def _start(node: Located) -> Pos:
    return (node.lineno, node.col_offset)


class _Resolver:
    """Two walks: the first finds every scope's bindings (and, at the section level, where each
    takes effect and which loops hold it); the second resolves each read."""

    def __init__(self) -> None:
        self.scopes: dict[int, _Scope] = {}
        self.first_binding: dict[str, Pos] = {}  # section level: earliest effect of each name
        self.loop_bound: dict[int, set[str]] = {}  # id(section-level loop) -> names bound in it
        self.out: dict[str, Unresolved] = {}

    # -- pass 1 ----------------------------------------------------------------------------
    def collect(self, tree: ast.Module) -> None:
        root = _Scope(tree, "section")
        self.scopes[id(tree)] = root
        # explicit stack of (node to handle, its scope, section-level loops around it)
        stack: list[tuple[ast.AST, _Scope, tuple[ast.AST, ...]]] = [(c, root, ()) for c in tree.body]
        while stack:
            node, scope, loops = stack.pop()
            self._collect_one(node, scope, loops, stack)

    def _bind(self, scope: _Scope, name: str, at: Pos | None, loops: tuple[ast.AST, ...]) -> None:
        scope.bound.add(name)
        if scope.kind == "section":
            if at is not None and (name not in self.first_binding or at < self.first_binding[name]):
                self.first_binding[name] = at
            for loop in loops:
                self.loop_bound.setdefault(id(loop), set()).add(name)

    def _collect_one(
        self,
        child: ast.AST,
        scope: _Scope,
        loops: tuple[ast.AST, ...],
        stack: list[tuple[ast.AST, _Scope, tuple[ast.AST, ...]]],
    ) -> None:
        if isinstance(child, (*_FUNCS, ast.ClassDef)):
            if not isinstance(child, ast.Lambda):
                self._bind(scope, child.name, _end(child), loops)
            kind = "class" if isinstance(child, ast.ClassDef) else "function"
            inner = _Scope(child, kind, parent=scope)
            if not isinstance(child, ast.ClassDef):
                inner.bound |= _params(child.args)
            self.scopes[id(child)] = inner
            # decorators, defaults, bases: in the enclosing scope; the body: in the new one
            body_ids = _body_ids(child)
            for sub in child_nodes(child):
                if id(sub) in body_ids:
                    stack.append((sub, inner, ()))
                elif not isinstance(sub, ast.arguments):
                    stack.append((sub, scope, loops))
                else:
                    for d in sub.defaults + [d for d in sub.kw_defaults if d is not None]:
                        stack.append((d, scope, loops))
            return
        if isinstance(child, _COMPS):
            inner = _Scope(child, "comp", parent=scope)
            self.scopes[id(child)] = inner
            for g in child.generators:
                for n in ast.walk(g.target):
                    if isinstance(n, ast.Name):
                        inner.bound.add(n.id)
            stack.append((child.generators[0].iter, scope, loops))
            for sub in child_nodes(child):
                if sub is not child.generators[0]:
                    stack.append((sub, inner, loops))
            g0 = child.generators[0]
            stack.append((g0.target, inner, loops))
            for cond in g0.ifs:
                stack.append((cond, inner, loops))
            return
        if isinstance(child, ast.NamedExpr):
            target = scope
            while target.kind == "comp" and target.parent is not None:
                target = target.parent
            self._bind(target, child.target.id, _end(child), loops)
            stack.append((child.value, scope, loops))
            return
        if isinstance(child, ast.Name):
            if isinstance(child.ctx, ast.Store):
                self._bind(scope, child.id, self._effect.get(id(child), _end(child)), loops)
            return
        if isinstance(child, ast.alias):
            self._bind(scope, (child.asname or child.name).split(".")[0], self._effect.get(id(child)), loops)
            return
        if isinstance(child, ast.ExceptHandler) and child.name:
            self._bind(scope, child.name, _start(child), loops)
        elif isinstance(child, ast.MatchAs | ast.MatchStar) and child.name:
            self._bind(scope, child.name, _end(child), loops)
        elif isinstance(child, ast.MatchMapping) and child.rest:
            self._bind(scope, child.rest, _end(child), loops)
        self._note_effects(child)
        inner_loops = (*loops, child) if isinstance(child, _LOOPS) and scope.kind == "section" else loops
        for sub in child_nodes(child):
            stack.append((sub, scope, inner_loops))

    _effect: dict[int, Pos]

    def _note_effects(self, stmt: ast.AST) -> None:
        """Where the names a statement binds take effect: after the whole statement for an
        assignment or import (`x = x + 1` reads x first), after the iterable for a `for`."""
        at: Pos | None = None
        targets: list[ast.expr] = []
        if isinstance(stmt, ast.Assign):
            at, targets = _end(stmt), stmt.targets
        elif isinstance(stmt, ast.AugAssign):
            at, targets = _end(stmt), [stmt.target]
        elif isinstance(stmt, ast.AnnAssign):
            # `x: int` alone binds nothing: the name is local, but unset
            at, targets = (_end(stmt) if stmt.value is not None else (1 << 30, 0)), [stmt.target]
        elif isinstance(stmt, ast.For | ast.AsyncFor):
            at, targets = _end(stmt.iter), [stmt.target]
        elif isinstance(stmt, ast.Import | ast.ImportFrom):
            for a in stmt.names:
                self._effect[id(a)] = _end(stmt)
            return
        elif isinstance(stmt, ast.withitem) and stmt.optional_vars is not None:
            at, targets = _end(stmt.optional_vars), [stmt.optional_vars]
        if at is None:
            return
        for t in targets:
            for n in ast.walk(t):
                if isinstance(n, ast.Name):
                    self._effect[id(n)] = at

    # -- pass 2 ----------------------------------------------------------------------------
    def resolve(self, tree: ast.Module, known: Container[str]) -> None:
        root = self.scopes[id(tree)]
        stack: list[tuple[ast.AST, _Scope, tuple[ast.AST, ...]]] = [(c, root, ()) for c in tree.body]
        while stack:
            child, scope, loops = stack.pop()
            inner = self.scopes.get(id(child))
            if inner is not None and inner.node is child:
                opener = inner.node  # (child itself, as the scope types it)
                if isinstance(opener, _COMPS):
                    # the first iterable runs in the enclosing scope
                    stack.append((opener.generators[0].iter, scope, loops))
                    for sub in child_nodes(opener):
                        if sub is not opener.generators[0]:
                            stack.append((sub, inner, loops))
                    stack.append((opener.generators[0].target, inner, loops))
                    for cond in opener.generators[0].ifs:
                        stack.append((cond, inner, loops))
                else:
                    body_ids = _body_ids(opener)
                    for sub in child_nodes(child):
                        if id(sub) in body_ids:
                            stack.append((sub, inner, ()))
                        else:
                            stack.append((sub, scope, loops))
                continue
            if isinstance(child, ast.Name):
                if isinstance(child.ctx, ast.Load | ast.Del):
                    self.read(child, scope, loops, known)
                continue
            if isinstance(child, ast.AugAssign) and isinstance(child.target, ast.Name):
                self.read(child.target, scope, loops, known)  # `x += 1` reads x first
            inner_loops = (*loops, child) if isinstance(child, _LOOPS) and scope.kind == "section" else loops
            for sub in child_nodes(child):
                stack.append((sub, scope, inner_loops))

    def read(self, node: ast.Name, scope: _Scope, loops: tuple[ast.AST, ...], known: Container[str]) -> None:
        name = node.id
        if name in self.out and _start(self.out[name].node) <= _start(node):
            return
        s: _Scope | None = scope
        deferred = False  # inside a function: it runs when called, after the section's code
        first = True
        while s is not None:
            if s.kind == "class" and not first:
                s = s.parent  # a class body's names are not seen by what is nested in it
                continue
            if name in s.bound:
                if s.kind != "section" or deferred:
                    return
                at = self.first_binding.get(name)
                if at is not None and at <= _start(node):
                    return
                if any(name in self.loop_bound.get(id(loop), ()) for loop in loops):
                    return
                if name in known:
                    return  # a machine variable bound later in the file is still the machine's
                line = at[0] if at is not None and at[0] < (1 << 30) else None
                self.out[name] = Unresolved(name, node, line)
                return
            if s.kind == "function":
                deferred = True
            first = False
            s = s.parent
        if name in known:
            return
        self.out[name] = Unresolved(name, node)


def unresolved(tree: ast.Module, known: Container[str]) -> list[Unresolved]:
    """Names `tree` reads that neither its own bindings (where Python would see them) nor
    `known` (a container: machine variables, imports, builtins, macros) provide."""
    r = _Resolver()
    r._effect = {}  # filled as statements are met, before the names inside them
    r.collect(tree)
    r.resolve(tree, known)
    return sorted(r.out.values(), key=lambda u: _start(u.node))


def section_bindings(tree: ast.Module) -> set[str]:
    """Names a file binds at its own level (its locals): for the hint that a name read in one
    section is a local of another."""
    r = _Resolver()
    r._effect = {}
    r.collect(tree)
    return r.scopes[id(tree)].bound
