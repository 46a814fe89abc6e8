"""The names of the files in a machine directory, and the comment that ties a guard file to its
transition (SPEC 1 and 13, docs/machine-format.md).

One module says what a file of a machine is called, so that the reader, `check`, the compiler's
pointers and the editing library (llfsm.edit) can never disagree on a name.

A guard file written by llfsm's tools starts with a comment naming the transition's target,
`# -> TARGET`.  Python ignores it; `check` compares it with the target machine.yaml names at the
file's position (LF071), which is how a reorder of `transitions:` done by hand, which moves every
guard to another target without a word, is caught.
"""

from __future__ import annotations

import re

from .model import SECTIONS, is_valid_name

#: A state's code files: State_S_OnEntry.py ... State_S_Variables.py.
SECTION_RE = re.compile(r"State_(?P<state>.+)_(?P<kind>" + "|".join(SECTIONS) + r"|Variables)\.py\Z")
#: A guard file: State_S_Transition_N.expr.
GUARD_RE = re.compile(r"State_(?P<state>.+)_Transition_(?P<n>[0-9]+)\.expr\Z")
#: The files of a machine directory that are not a state's.
MACHINE_FILES = ("machine.yaml", "layout.yaml", "Includes.py", "Variables.py")
#: The guard comment: `# -> TARGET` on the first line (spaces around the arrow are free).
HEADER_RE = re.compile(r"#[ \t]*->[ \t]*(?P<target>[^\s#]+)[ \t]*\Z")
#: Longest state name llfsm's tools write: `State_<S>_OnSuspend.py` and build's temporary
#: names must stay within the file system's 255 bytes (names are ASCII).
MAX_STATE_NAME = 200


def guard_file(state: str, index: int) -> str:
    return f"State_{state}_Transition_{index}.expr"


def section_file(state: str, kind: str) -> str:
    """`kind`: one of SECTIONS, or "Variables"."""
    return f"State_{state}_{kind}.py"


def state_files(state: str) -> tuple[str, ...]:
    """The code files a state may have besides its guards."""
    return tuple(section_file(state, k) for k in (*SECTIONS, "Variables"))


def header(target: str) -> str:
    """The first line of a guard file llfsm writes, line end included."""
    return f"# -> {target}\n"


def header_target(text: str) -> str | None:
    """The target a guard file's first line names (`# -> TARGET`), or None when it has none."""
    first = text.split("\n", 1)[0].rstrip("\r")
    m = HEADER_RE.match(first.strip())
    return m["target"] if m else None


def with_header(text: str, target: str) -> str:
    """A guard file's text starting with `# -> target`: an existing guard comment is replaced
    (the file now belongs to a transition to `target`), otherwise the line is put first."""
    if header_target(text) is not None:
        rest = text.split("\n", 1)
        return header(target) + (rest[1] if len(rest) > 1 else "")
    return header(target) + text


def expression(text: str) -> str:
    """A guard as the arrows show it: its text without the guard comment, stripped."""
    if header_target(text) is not None:
        text = text.split("\n", 1)[1] if "\n" in text else ""
    return text.strip()


def is_machine_file(name: str) -> bool:
    """Whether `name` is a file a machine directory may hold (what llfsm.edit will write)."""
    if name in MACHINE_FILES:
        return True
    m = SECTION_RE.match(name) or GUARD_RE.match(name)
    if m is None or not is_valid_name(m["state"]) or len(m["state"]) > MAX_STATE_NAME:
        return False
    n = m.groupdict().get("n")
    return n is None or n == "0" or not n.startswith("0")
