"""Breakpoints: `--break EXPR`, `b EXPR` at the prompt, a click on the page's diagram
(docs/debug.md, "Breakpoints").

EXPR is an atom of the property language (llfsm.props.atoms: `state(m) == "S"`, `m.count > 3`,
`published("/topic")`, `suspended(m)` ...), plus the debugger's `fired(m, "S", N)`: transition N
of m's state S fired in the last ringlet.  A breakpoint is edge-triggered: the run pauses at the
first ringlet boundary where EXPR becomes true (false at the boundary before), so a continue
does not stop again at once.  An expression of events (published, fired) is true only at the
boundary right after its event, so each event pauses.

An expression is judged after the ringlets of the machines it reads (another machine's ringlet
cannot change what it reads), and after every ringlet when it reads events.  One that cannot be
evaluated (a division by zero at run time) counts as false and is said once.  A text that does
not parse, or names a machine, state or variable that does not exist, is refused before the run
starts (`BreakError`, one line: the text and what is wrong in it, with a caret for a syntax
error).
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Sequence
from typing import Any

from ..props.atoms import Atom, MachineInfo, PropertyError, compile_atom, infos_of


class BreakError(ValueError):
    """A break expression that is refused: one line (a usage error before the run, status 2)."""


class Breakpoint:
    """One expression and what it last evaluated to."""

    __slots__ = ("atom", "number", "said", "value")

    def __init__(self, number: int, atom: Atom, value: bool) -> None:
        self.number = number
        self.atom = atom
        self.value = value
        self.said = False

    @property
    def text(self) -> str:
        return self.atom.text

    def __repr__(self) -> str:
        return f"{self.number}: {self.text}"


def compile_break(text: str, infos: dict[str, MachineInfo], where: str = "--break") -> Atom:
    """The atom of a break expression, or BreakError saying what is wrong and where."""
    src = text.strip()
    try:
        ast.parse(src, mode="eval")
    except SyntaxError as e:
        col = (e.offset or 1) - 1 if (e.lineno or 1) == 1 else 0
        raise BreakError(f"{where} {src!r}: not an expression ({e.msg}), here: {src[:col]}^{src[col:]}") from None
    except (RecursionError, MemoryError, ValueError):
        raise BreakError(f"{where} {src[:60]!r}: too deeply nested") from None
    try:
        return compile_atom(src, infos, where, fired=True)
    except PropertyError as e:
        raise BreakError(str(e)) from None


class Breakpoints:
    """The run's breakpoints, numbered from 1 in the order they were made (as pdb numbers them)."""

    def __init__(self, classes: Sequence[type[Any]], say: Callable[[str], None]) -> None:
        self.infos = infos_of(classes)
        self.say = say
        self.items: list[Breakpoint] = []
        self._next = 1
        #: machine index -> the breakpoints judged after its ringlets; those judged after every one
        self._by_machine: dict[int, list[Breakpoint]] = {}
        self._every: list[Breakpoint] = []
        self.reads_published = False

    def add(self, text: str, machines: Sequence[Any], where: str = "break") -> Breakpoint:
        """A new breakpoint (BreakError if the text is refused), judged from now on."""
        atom = compile_break(text, self.infos, where)
        for b in self.items:
            if b.text == atom.text:
                return b  # the same text twice is one breakpoint
        bp = Breakpoint(self._next, atom, False)
        bp.value = False if atom.reads_published else self._eval(bp, machines, ())
        self._next += 1
        self.items.append(bp)
        self._index()
        return bp

    def remove(self, number: int | None = None, text: str | None = None) -> list[Breakpoint]:
        """Remove breakpoint `number`, or the one of `text`, or all (neither given): those removed."""
        if number is None and text is None:
            gone, self.items = self.items, []
        else:
            gone = [b for b in self.items if b.number == number or (text is not None and b.text == text.strip())]
            self.items = [b for b in self.items if b not in gone]
        self._index()
        return gone

    def _index(self) -> None:
        self._by_machine = {}
        self._every = []
        for b in self.items:
            if b.atom.reads_published:
                self._every.append(b)
            else:
                for i in b.atom.machines:
                    self._by_machine.setdefault(i, []).append(b)
        self.reads_published = any(b.atom.reads_published for b in self.items)

    def _eval(self, b: Breakpoint, machines: Sequence[Any], events: Any) -> bool:
        try:
            return bool(b.atom.fn(machines, events))
        except Exception as e:  # evaluated on a live run: anything may go wrong, and counts as false
            if not b.said:
                b.said = True
                self.say(f"llfsm: break {b.number}: `{b.text}` could not be evaluated: {type(e).__name__}: {e}")
            return False

    def refresh(self, machines: Sequence[Any]) -> None:
        """Judge every breakpoint again without pausing (values were set while paused)."""
        for b in self.items:
            if not b.atom.reads_published:
                b.value = self._eval(b, machines, ())

    def hit(self, index: int, machines: Sequence[Any], events: Any) -> Breakpoint | None:
        """After a ringlet of machine `index`: the first breakpoint that became true, if any
        (every one is judged, so each keeps its value for the next edge)."""
        first = None
        for group in (self._by_machine.get(index, ()), self._every):
            for b in group:
                now = self._eval(b, machines, events)
                if now and not b.value and first is None:
                    first = b
                b.value = now and not b.atom.reads_published
        return first
