"""What the rules of one machine share: the reader's result, the diagnostics so far, and what
is worked out once per machine rather than once per state or file.

Each rule module (structure, variables, includes, code, ros_habits, packages) is a set of
functions over one `Checking`; the driver (llfsm.lang.check) makes it and calls them in order.
docs/rules.md lists the rules.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...suggest import close_names
from ..diagnostics import Diagnostic, diag
from ..model import Loc
from ..reader import ReadResult

#: "Did you mean" is for hand-written machines: difflib compares a name with every candidate,
#: so a machine.yaml with 100,000 misspelt targets among 100,000 states would take hours.
#: Beyond these bounds, no suggestion (the diagnostic itself stays).
SUGGEST_AMONG = 1000
SUGGEST_AT_MOST = 100


class Suggester:
    """Close names for "did you mean", within a budget of `SUGGEST_AT_MOST` per machine."""

    def __init__(self) -> None:
        self.left = SUGGEST_AT_MOST

    def close(self, name: str, names: Iterable[str]) -> list[str]:
        names = names if isinstance(names, list | set | frozenset | dict) else list(names)
        if self.left <= 0 or len(names) > SUGGEST_AMONG or len(name) > 200:
            return []
        self.left -= 1
        return difflib.get_close_matches(name, [n for n in names if len(n) <= 200], n=1, cutoff=0.6)

    def did_you_mean(self, name: str, names: Iterable[str]) -> str:
        """` (did you mean 'END'?)` when a known name is close to `name`, else nothing."""
        close = self.close(name, names)
        if not close:
            return ""
        return f" (did you mean {' or '.join(repr(c) for c in close)}?)"

    def alike(self, name: str, names: Iterable[str]) -> str:
        """As `did_you_mean`, through llfsm.suggest, which ignores case (`X` for the field `x`,
        `WallBot` for the machine `wall_bot`): for names a user spells from memory."""
        names = names if isinstance(names, list | set | frozenset | dict) else list(names)
        if self.left <= 0 or len(names) > SUGGEST_AMONG or len(name) > 200:
            return ""
        self.left -= 1
        close = close_names(name, [n for n in names if len(n) <= 200])
        return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


@dataclass
class Checking:
    """One machine directory under check: where diagnostics go, and what the rules compute
    once for the whole machine (a machine.yaml with 100,000 transitions is checked in linear
    time only if nothing is recomputed per state or per guard)."""

    path: Path
    read: ReadResult
    diagnostics: list[Diagnostic]
    suggest: Suggester = field(default_factory=Suggester)
    #: files the reader could not use (already reported): one set, not a scan per guard
    unreadable: set[str] = field(default_factory=set)
    #: states whose LF104 warnings are already given (the first true guard silences the rest)
    always_true: set[str] = field(default_factory=set)
    #: the machine-level name map (bare name -> attribute), made by the first state's code
    base: Mapping[str, str] | None = None
    #: names Includes.py binds; None when it star-imports (any name may exist then)
    imported: set[str] | None = field(default_factory=set)
    #: name -> a section file binding it at its own level, made on the first undefined name
    section_locals: dict[str, str] | None = None
    #: file -> ids of the names its calls call, made on the file's first undefined name
    called: dict[str, set[int]] = field(default_factory=dict)
    #: the folders around the machine where `llfsm run` looks for interface packages (first import)
    interface_roots: list[str] | None = None
    #: what Includes.py imports (name -> dotted path), and the machine variables of a message
    #: type (name -> `pkg/msg/Name`): made by the first section that LF051 looks at
    message_paths: dict[str, str] | None = None
    message_variables: dict[str, str] | None = None
    #: the definitions LF051 has looked up (`pkg/msg/Name` -> its spec, or None), once each
    message_specs: dict[str, Any] = field(default_factory=dict)
    #: (file, line, column, machine) of each `suspend("M")` and family: LF050 across machines
    references: list[tuple[str, int, int, str]] = field(default_factory=list)

    @classmethod
    def of(cls, path: Path, read: ReadResult) -> Checking:
        return cls(
            path,
            read,
            list(read.diagnostics),
            unreadable={os.path.basename(d.file) for d in read.diagnostics},
        )

    def add(self, code: str, file: str, line: int, col: int, msg: str) -> None:
        inline = self.read.inline.get(file)
        if inline is not None:  # an inline guard: the rules name it by its file's name; it is in machine.yaml
            loc = inline.place(line, col)
            file, line, col = loc.file, loc.line, loc.column
        self.diagnostics.append(diag(code, self.path / file, line, col, msg))

    def at(self, code: str, loc: Loc, msg: str) -> None:
        self.add(code, loc.file, loc.line, loc.column, msg)
