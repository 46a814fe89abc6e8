"""The history compiled into a machine's ringlets (docs/debug.md, "History", "What it costs").

A watcher called after every ringlet costs a run several times its plain speed (a Python call
alone is three times a toggle's ringlet).  So, as the debugger's marks on transitions are
(traps.py), the history is compiled in: each ringlet of the machine is compiled again from its
generated module with, before each `return`, one append to the history's list of items, one
item a boundary (its number is its place; its round and run time follow from the scheduler's
rounds and clock: history.py).  The item is the cheapest that tells the ringlet apart:

- a ringlet that changes nothing: its code, `_llfsm_h_append(_llfsm_h_c3)`, a constant tuple
  (state it ran in, state after, transition fired, values taken, flags) held as a global of the
  variant, known to the history by its identity, one object for equal codes of any machine;
- a ringlet that can change one number, flag or handle only (`count += 1`): that value as it
  was at the ringlet's start, alone, `_llfsm_h_append(_llfsm_h_o0)`, where the state after
  tells which ringlet it was (the first such return into each state claims it; `claim`);
- otherwise a tuple of the code and, of each value it can change, the old value (a number, a
  flag or a handle: read at the start, its new value is the next record's old one, or the
  value now) or the old and new copies (a message, a list, anything that can change in place,
  a variable that may change outside its ringlets, an input: compared with the copy the history
  took last, `_llfsm_h_cache`, which the record updates), then the state after and the
  transition where they are not constants there.

Which values a ringlet can change is the monitor's analysis (llfsm.runtime.reads: what it
assigns, mutates or hands on).  What changed, name by name, is worked out when the history is
read, backwards from now.  No item but a copy is a new object the garbage collector follows,
and the scheduler runs its plain loops meanwhile: nothing is called between ringlets.

The suspend state's ringlets are left as they are: they run inside a command (the gate's, or a
transition into the suspend state), never as a turn of their own.
"""

from __future__ import annotations

import ast
from collections.abc import Callable
from typing import Any

from ..runtime.reads import ClassReads, is_self_attr

#: Names in a recording variant's namespace (machine code cannot use `_llfsm_` names: LF013).
APPEND, CODE, CACHE, ENCODE, PLAIN = (f"_llfsm_h_{n}" for n in ("append", "c", "cache", "encode", "plain"))
_LOCAL = "_llfsm_h_"
#: Flags of a record's code: the state after, or the transition, is not a constant where the
#: ringlet returns, and ends the record instead.
AFTER_AT_END, FIRED_AT_END = 1, 2
#: How a value is taken: read at the start and at the end (an immutable value or a handle);
#: compared with the history's last take (`CACHE`) as it is, as a message's copy, as plain data.
DIRECT, CACHED, MESSAGE, COPIED = range(4)


#: Claims a value-only record: (machine's state after, (state it ran in, transition, value
#: index)) -> whether records of that meaning may be the value alone (History.claim).
Claim = Callable[[int, tuple[int, int | None, int]], bool]


def message_name(k: int) -> str:
    """The namespace name of the message class of value k."""
    return f"{_LOCAL}m{k}"


def taken_by(
    reads: ClassReads, names: tuple[str, ...], kinds: tuple[int, ...], inputs: set[str], replaced_only: frozenset[str]
) -> dict[str, tuple[tuple[int, int], ...]]:
    """For each ringlet (by function name): (index into `names`, how it is taken) of each value
    it may change.  `kinds`: each value's kind (DIRECT for an immutable one or a handle, MESSAGE,
    COPIED), as history.Values sorts them.  A value in `replaced_only` (a number, a string, a
    handle shown by its type) changes only where the ringlet assigns the variable, whatever else
    it does with it (`is_running(bot)` hands `bot` on, and cannot change it)."""
    always = {v for v in names if v in inputs or reads.is_escaped(v)}
    out: dict[str, tuple[tuple[int, int], ...]] = {}
    for fn, ringlet in reads.ringlets.items():
        groups = {reads.group.get(t, t) for t in ringlet.touches}
        assigned = _assigned(reads.trees[fn])
        mine = {v for v in names if (v in assigned if v in replaced_only else reads.group.get(v, v) in groups)} | always
        out[fn] = tuple(
            (k, CACHED if kinds[k] == DIRECT and v in always else kinds[k]) for k, v in enumerate(names) if v in mine
        )
    return out


class RingletRecorder:
    """What compiles one machine's ringlets to record themselves (traps.Recorder's first half):
    `taken`, by ringlet name, the values each takes (`taken_by`); `names`, the machine's values'
    names; `trap`, the name of the breakpoints' trap call."""

    def __init__(
        self,
        suspended: int,
        taken: dict[str, tuple[tuple[int, int], ...]],
        names: tuple[str, ...],
        trap: str,
        namespace: dict[str, Any],
        register: Callable[[tuple[Any, ...]], tuple[Any, ...]],
        claim: Claim,
    ) -> None:
        #: the variant's namespace: each record's code goes in as a global, the object the
        #: history registered (`register`), by which it knows a code from a value
        self.namespace = namespace
        self.register = register
        self.claim = claim
        self.suspended = suspended
        self.by_ringlet = taken
        self.names = names
        self.trap = trap
        self.state = 0
        self.taken: tuple[tuple[int, int], ...] = ()

    def __call__(self, node: ast.FunctionDef, state: int) -> ast.FunctionDef:
        """The ringlet `node` (of `state`) with a record appended before each return (and before
        the breakpoints' trap calls just before it, so that a pause there shows this ringlet)."""
        self.state, self.taken = state, self.by_ringlet.get(node.name, ())
        starts = [
            _assign(_LOCAL + f"o{k}", _self(self.names[k])) for k, how in self.taken if how == DIRECT
        ]  # the old values of immutables: read before anything runs
        body = list(node.body)
        doc = body[:1] if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) else []
        new_body, known, ends = self.block(body[len(doc) :], state)
        if not ends:  # falls off its end: returns None there
            new_body = self.returning(new_body, ast.Return(value=None), known)
        node.body = [*doc, *starts, *new_body]
        return node

    def block(self, stmts: list[ast.stmt], known: int | None) -> tuple[list[ast.stmt], int | None, bool]:
        """The block with records before its returns; the state known after it (None: not
        known), and whether it ends in a return."""
        out: list[ast.stmt] = []
        for n, st in enumerate(stmts):
            if isinstance(st, ast.Return):
                return self.returning(out, st, known), known, True
            sets = _sets_state(st, self.suspended)
            if sets is not None:
                known = sets if sets >= 0 else None
            elif isinstance(st, ast.If):  # the state after it: the one its branches that go on leave
                st.body, k_body, ends_body = self.block(st.body, known)
                st.orelse, k_else, ends_else = self.block(st.orelse, known) if st.orelse else ([], known, False)
                going = {k for k, ends in ((k_body, ends_body), (k_else, ends_else)) if not ends}
                if len(going) > 1 or None in going:
                    known = None
                elif going:
                    known = going.pop()
                out.append(st)
                if ends_body and ends_else:
                    return [*out, *stmts[n + 1 :]], known, True  # what follows is never reached
                continue
            elif isinstance(st, ast.For | ast.AsyncFor | ast.While | ast.With | ast.AsyncWith | ast.Try):
                for attr in ("body", "orelse", "finalbody"):
                    inner = getattr(st, attr, None)
                    if inner:
                        setattr(st, attr, self.block(inner, known)[0])
                for h in getattr(st, "handlers", ()):
                    h.body = self.block(h.body, known)[0]
                if any(_sets_state(n, self.suspended) is not None for n in ast.walk(st) if isinstance(n, ast.stmt)):
                    known = None
            out.append(st)
        return out, known, False

    def returning(self, out: list[ast.stmt], ret: ast.Return, known: int | None) -> list[ast.stmt]:
        """`out` (what came before the return), the record, then the return."""
        traps: list[ast.stmt] = []
        while out and _is_trap(out[-1], self.trap):
            traps.insert(0, out.pop())
        flags = 0
        extra: list[ast.expr] = []
        stmts: list[ast.stmt] = []
        if known is None:
            flags |= AFTER_AT_END
            extra.append(_self("_state"))
        value = ret.value
        if value is None or isinstance(value, ast.Constant):
            fired = None if value is None else value.value
        else:  # not what the compiler writes; kept in a local, returned after the record
            flags |= FIRED_AT_END
            stmts.append(_assign(_LOCAL + "r", value))
            extra.append(_load(_LOCAL + "r"))
            ret = ast.Return(value=_load(_LOCAL + "r"))
            fired = None
        code = (self.state, known, fired, self.taken, flags)  # whose: its place tells
        name = f"{CODE}{len(self.namespace)}"
        self.namespace[name] = code = self.register(code)
        item: ast.expr = _load(name)
        after: list[ast.stmt] = []
        if (
            not flags
            and len(self.taken) == 1
            and self.taken[0][1] == DIRECT
            and self.claim(known, (self.state, fired, self.taken[0][0]))  # type: ignore[arg-type]  # flags: known
        ):
            item = _load(_LOCAL + f"o{self.taken[0][0]}")  # the old value alone: the state after tells the rest
        elif self.taken or extra:
            items: list[ast.expr] = [item]
            for k, how in self.taken:
                if how == DIRECT:
                    items.append(_load(_LOCAL + f"o{k}"))  # the new value is the next record's old, or now's
                    continue
                new = _LOCAL + f"n{k}"
                value_now: ast.expr = _self(self.names[k])
                if how == MESSAGE:
                    value_now = ast.Call(func=_load(ENCODE), args=[value_now, _load(message_name(k))], keywords=[])
                elif how == COPIED:
                    value_now = ast.Call(func=_load(PLAIN), args=[value_now], keywords=[])
                stmts.append(_assign(new, value_now))
                cached = ast.Subscript(value=_load(CACHE), slice=ast.Constant(k), ctx=ast.Load())
                items += [cached, _load(new)]
                after.append(
                    ast.Assign(
                        targets=[ast.Subscript(value=_load(CACHE), slice=ast.Constant(k), ctx=ast.Store())],
                        value=_load(new),
                    )
                )
            item = ast.Tuple(elts=[*items, *extra], ctx=ast.Load())
        call = ast.Call(func=_load(APPEND), args=[item], keywords=[])
        made = [*stmts, ast.Expr(value=call), *after, *traps, ret]
        for n in made:
            ast.copy_location(n, ret)
        return [*out, *made]


def _assigned(tree: ast.FunctionDef) -> set[str]:
    """The names `self.NAME` is assigned, augmented or deleted as in a ringlet."""
    return {
        n.attr
        for n in ast.walk(tree)
        if isinstance(n, ast.Attribute)
        and isinstance(n.ctx, ast.Store | ast.Del)
        and isinstance(n.value, ast.Name)
        and n.value.id == "self"
    }


def _sets_state(node: ast.AST, suspended: int) -> int | None:
    """The state a statement makes current: `self._state = K` (K; -1 when K is not a constant),
    `self._enter_suspend_state()` (the suspend state); None for any other statement."""
    if isinstance(node, ast.Assign) and len(node.targets) == 1 and is_self_attr(node.targets[0], "_state"):
        v = node.value
        return v.value if isinstance(v, ast.Constant) and isinstance(v.value, int) else -1
    if (
        isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Call)
        and is_self_attr(node.value.func, "_enter_suspend_state")
    ):
        return suspended
    return None


def _is_trap(st: ast.stmt, trap: str) -> bool:
    return (
        isinstance(st, ast.Expr)
        and isinstance(st.value, ast.Call)
        and isinstance(st.value.func, ast.Name)
        and st.value.func.id == trap
    )


def _load(name: str) -> ast.Name:
    return ast.Name(id=name, ctx=ast.Load())


def _self(attr: str) -> ast.Attribute:
    return ast.Attribute(value=_load("self"), attr=attr, ctx=ast.Load())


def _assign(name: str, value: ast.expr) -> ast.Assign:
    return ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())], value=value)


def namespace_of(append: Any, cache: list[Any], encode: Any, plain: Any, messages: dict[int, type]) -> dict[str, Any]:
    """What a recording variant's ringlets find in their namespace (their codes join it as
    they are compiled)."""
    ns: dict[str, Any] = {APPEND: append, CACHE: cache, ENCODE: encode, PLAIN: plain}
    ns.update({message_name(k): cls for k, cls in messages.items()})
    return ns
