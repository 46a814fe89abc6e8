"""What `llfsm import` says about each machine: files written, code lines translated, and
each statement left for a person at its line in the new machine and in the clfsm one."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from ..lang.diagnostics import shown


@dataclass(frozen=True)
class Left:
    """A statement left untranslated: where its marked lines start in the llfsm machine, and
    where it was in the clfsm one."""

    file: str
    line: int
    source: str
    source_line: int
    reason: str


@dataclass
class MachineReport:
    source: Path
    name: str  # the llfsm machine's name
    original: str  # the clfsm machine's name
    output: Path | None = None
    files: int = 0
    code: int = 0  # lines of code in the clfsm machine's files
    left_lines: int = 0  # of which left untranslated
    left: list[Left] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    error: str | None = None  # why the machine could not be imported (nothing written)

    @property
    def translated(self) -> int:
        return self.code - self.left_lines

    def as_dict(self) -> dict[str, object]:
        return {
            "source": str(self.source),
            "machine": self.name,
            "clfsm_name": self.original,
            "output": None if self.output is None else str(self.output),
            "error": self.error,
            "files": self.files,
            "lines": {"code": self.code, "translated": self.translated, "left": self.left_lines},
            "left": [
                {"file": x.file, "line": x.line, "source": x.source, "source_line": x.source_line, "reason": x.reason}
                for x in self.left
            ],
            "notes": self.notes,
        }


def share(translated: int, code: int) -> str:
    return "100%" if code == 0 else f"{100 * translated / code:.0f}%"


def format_text(reports: list[MachineReport]) -> str:
    out = []
    for r in reports:
        if r.error is not None:
            out.append(f"not imported: {shown(r.error)}\n")  # the error names the file
            continue
        head = f"{shown(str(r.source))} -> {shown(str(r.output))}: {r.files} files, "
        head += f"{r.translated} of {r.code} code lines translated ({share(r.translated, r.code)})"
        out.append(head + (f", {r.left_lines} left:\n" if r.left else "\n"))
        for x in r.left:
            out.append(f"  {x.file}:{x.line}: {shown(x.reason)} (clfsm {x.source}:{x.source_line})\n")
        for note in r.notes:
            out.append(f"  note: {shown(note)}\n")
    done = [r for r in reports if r.error is None]
    code = sum(r.code for r in done)
    translated = sum(r.translated for r in done)
    tail = f": {translated} of {code} code lines translated ({share(translated, code)})" if done else ""
    left = "; `llfsm check` lists what is left" if translated < code else ""
    out.append(f"imported {len(done)} of {len(reports)} machine(s){tail}{left}\n")
    return "".join(out)


def format_json(reports: list[MachineReport]) -> str:
    return json.dumps([r.as_dict() for r in reports], indent=2) + "\n"
