"""What templates/machine.py.j2 renders: user code ready to go into the module (`Block`), each
guard with the lines that take its transition (`GuardView`), and each state with its ringlets'
parts (`StateView`).  llfsm.compiler.generate makes them from a checked machine; the names,
pointers and ringlet numbers they write are the generated module's contract
(llfsm.runtime.generated).
"""

from __future__ import annotations

import io
import tokenize
from dataclasses import dataclass, field

from ..runtime.generated import POINTER_END, enter_ringlet, pointer
from .rewrite import ALIAS_LINE


def _string_continuation_lines(text: str) -> set[int]:
    """Lines (1-based) that start inside a multi-line string: indenting them would change it."""
    out: set[int] = set()
    if '"""' not in text and "'''" not in text and "\\\n" not in text and "\\\r" not in text:
        return out  # only a triple-quoted string or a backslash-continued one spans lines
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if (tok.type == tokenize.STRING and tok.end[0] > tok.start[0]) or (
                tok.type == getattr(tokenize, "FSTRING_MIDDLE", -1) and tok.end[0] > tok.start[0]
            ):
                out.update(range(tok.start[0] + 1, tok.end[0] + 1))
    except (tokenize.TokenError, SyntaxError):
        pass
    return out


def indent_code(text: str, width: int) -> str:
    prefix = " " * width
    keep = _string_continuation_lines(text)
    lines = text.split("\n")
    return "\n".join(line if (i + 1 in keep or not line.strip()) else prefix + line for i, line in enumerate(lines))


def marked_pointer(file: str, line: int) -> str:
    """A pointer comment as the template writes it: ended by the mark that tells the source map
    it is the compiler's (llfsm.compiler.generate takes the marks off)."""
    return pointer(file, line) + POINTER_END


@dataclass
class Block:
    """User code ready for the template: rewritten, trimmed, with the place of its first line."""

    file: str
    line: int
    text: str
    #: The code reaches the machine through `MACHINE_ALIAS` (a method or function of the user's
    #: binds `self`): the alias is bound on the line before the block's pointer.
    alias: bool = False


def lead(block: Block | GuardView, width: int) -> str:
    """The lines before a block of user code, at its indentation: its pointer, and first the
    alias of the machine when the block needs it.  The alias line comes before the pointer so
    that the code still follows its pointer line for line; it is written only for a block in
    which the user's own `self` hides the machine's, so other modules do not change at all."""
    pad = " " * width
    alias = f"{pad}{ALIAS_LINE}\n" if block.alias else ""
    return f"{alias}{pad}{marked_pointer(block.file, block.line)}"


@dataclass
class GuardView:
    index: int
    target: int
    target_name: str
    file: str
    line: int
    text: str
    multiline: bool
    to_suspend: bool
    alias: bool = False
    #: A guard that is a constant: True (truthy) fires at once, False never; None for the rest.
    #: A constant is written as what it does, not as a dead `if True:` or `if False:` block.
    constant: bool | None = None
    #: The state has an OnExit, which the transition runs first.
    exits: bool = False
    state: str = ""

    def code(self) -> str:
        """The guard's lines in a ringlet: its pointer, the test, and the lines that take the
        transition; a constant as what it does.  Made here, once for both ringlets, rather than
        by the template: a template macro per guard cost a tenth of a build's time."""
        if self.constant is None:
            test = (
                f"    if ({self.first_line}\n{self.other_lines}\n    ):\n"
                if self.multiline
                else f"    if {self.text}:\n"
            )
            return f"{lead(self, 4)}\n{test}{self.fire(8)}"
        if self.constant:
            return f"    # {self.where} is always true: the transition fires at once\n{self.fire(4)}"
        return f"    # {self.where} is always false: the transition never fires\n"

    @property
    def where(self) -> str:
        """The guard's file, or its line of machine.yaml when it is written inline there."""
        return f"{self.file}:{self.line}" if self.file == "machine.yaml" else self.file

    def fire(self, width: int) -> str:
        """The lines that take the transition, at `width`."""
        pad = " " * width
        lines = [f"self.on_exit_{self.state}()"] if self.exits else []
        if self.to_suspend:
            lines.append("self._enter_suspend_state()")
        else:
            lines.append(f"self._state = {self.target}  # {self.target_name}")
            lines.append(f"self._run = {enter_ringlet(self.target_name)}")
        lines.append(f"return {self.index}")
        return "".join(f"{pad}{line}\n" for line in lines)

    @property
    def first_line(self) -> str:
        return self.text.split("\n", 1)[0]

    @property
    def other_lines(self) -> str:
        """Lines after the first, indented under `if (`: kept line for line so run-time errors map
        to the right line, and indented knowing the whole guard, so a string that spans lines
        keeps its value."""
        return indent_code(self.text, 8).split("\n", 1)[1] if "\n" in self.text else ""


@dataclass
class StateView:
    name: str
    accepting: bool
    is_suspend: bool
    doc: str | None
    entry: Block | None
    internal: Block | None
    exit: Block | None
    #: The guards the steady ringlet tests, in order, up to a constant true one (what follows
    #: it never runs, and is not written).
    guards: list[GuardView] = field(default_factory=list)
    #: Their lines, as both ringlets write them (made once, here rather than by the template).
    guards_code: str = ""
    hooks: list[tuple[str, Block]] = field(default_factory=list)
    #: OnSuspend / OnResume: functions beside the ringlets, which the ON_SUSPEND / ON_RESUME
    #: tables name (a class body cannot name its own methods once mypyc compiles it).
    command_hooks: list[tuple[str, Block]] = field(default_factory=list)
    #: OnEntry / Internal are inlined into their ringlet unless one binds a local that another
    #: part of the state (the other section, a guard) also uses; then it gets a method of its
    #: own, so that the reader sees at once that its locals are its own, as the locals of a
    #: clfsm section are.
    entry_method: bool = False
    internal_method: bool = False
    #: The entry ringlet records the entry time: only states whose code uses after* need it.
    stamp: bool = False
    #: The `def` lines of the two ringlets (spread over lines when a long name needs it), and
    #: the entry ringlet's docstring.
    enter_def: str = ""
    steady_def: str = ""
    enter_doc: str = ""

    @property
    def falls_through(self) -> bool:
        """No guard is constant true: Internal (and an accepting state's finish) can run."""
        return not any(g.constant for g in self.guards)

    @property
    def has_on_suspend(self) -> bool:
        return any(h == "on_suspend" for h, _ in self.command_hooks)

    @property
    def has_on_resume(self) -> bool:
        return any(h == "on_resume" for h, _ in self.command_hooks)
