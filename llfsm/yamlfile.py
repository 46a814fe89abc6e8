"""YAML from files anyone may have written, read in bounded time and memory, with what is wrong
at its line: machine.yaml and layout.yaml (llfsm.lang.reader), launch files (llfsm.launch),
verification files (llfsm.props.file) and ROS 2 params files (llfsm.ros.parameter_files).

Every one of them refuses the same things here, the same way:

- a file larger than its reader's bound, or not a regular file (`machinedir.read_regular`: a
  FIFO would block the reader), or not UTF-8 (at the line of the first bad byte);
- anchors and aliases: a few lines of aliases compose into millions of nodes (an alias bomb);
- nesting deeper than the reader's bound: composing recurses, and a 5,000-deep document would
  exhaust the stack.  Both are found on the event stream, before any tree is built;
- text that is not YAML, at the line the library names.

The words are each reader's (a launch file says "not YAML", machine.yaml "invalid YAML" under
its rule code): `Refused` carries what was refused and where, and `Refused.say` puts it in the
words of a reader's table (`WORDS` holds the defaults).

A utility of the lowest layer, so that every reader can import it: PyYAML and the standard
library only (and llfsm.machinedir).
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import yaml

from .machinedir import FileTooLarge, NotRegularFile, read_regular

#: libyaml's C parser when PyYAML has it (about ten times faster), else the pure-Python one.
LOADER: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

#: What each kind of refusal says unless a reader words it otherwise.  Fields: `where` (the file
#: as the reader shows it), `line`, `column`, `detail` (the library's or the system's words),
#: `limit` (the bound passed: bytes or levels), `mib` (a size bound in MiB), `what` (the kind
#: of file: "a launch file").
WORDS: Mapping[str, str] = {
    "folder": "{where}: is a folder, not {what}",
    "not_file": "{where}: not a regular file",
    "unreadable": "{where}: cannot be read: {detail}",
    "large": "{where}: larger than {mib} MiB",
    "encoding": "{where}:{line}: not UTF-8 text",
    "alias": "{where}:{line}: anchors and aliases are not allowed in {what}",
    "depth": "{where}:{line}: nested deeper than {limit} levels",
    "syntax": "{where}:{line}: not YAML: {detail}",
}


class Refused(ValueError):
    """Why a YAML file or text was not read: `kind` is a key of WORDS; `line` and `column` count
    from 1 (1, 1 where there is no better place); `detail` is the library's or the system's words."""

    def __init__(self, kind: str, line: int = 1, column: int = 1, detail: str = "", limit: int = 0) -> None:
        super().__init__(f"{line}:{column}: {kind}{': ' + detail if detail else ''}")
        self.kind, self.line, self.column, self.detail, self.limit = kind, line, column, detail, limit

    def say(self, where: str, what: str = "this file", words: Mapping[str, str] = WORDS) -> str:
        """The one line a user sees, in `words` (a reader's own table; WORDS for what it leaves out)."""
        template = words.get(self.kind) or WORDS[self.kind]
        return template.format(
            where=where, what=what, line=self.line, column=self.column, detail=self.detail, limit=self.limit,
            mib=self.limit >> 20,
        )  # fmt: skip


def read_text(path: str | os.PathLike[str], max_bytes: int) -> str:
    """The text of the file at `path` (symlinks followed: a user names these files): Refused
    (`folder`, `not_file`, `unreadable`, `large`, `encoding`) for what cannot be read."""
    try:
        data = read_regular(path, max_bytes, follow=True)
    except NotRegularFile as e:
        raise Refused("folder" if e.folder else "not_file") from None
    except FileTooLarge:
        raise Refused("large", limit=max_bytes) from None
    except OSError as e:
        raise Refused("unreadable", detail=str(e.strerror or e)) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise Refused("encoding", data[: e.start].count(b"\n") + 1, 1, f"byte {e.start}") from None


def compose(text: str, max_depth: int, loader: type | None = None) -> yaml.Node | None:
    """The YAML tree of `text` (None for an empty document), or Refused: `alias`, `depth`
    (beyond `max_depth` collections inside each other), `syntax`.  `loader`: LOADER unless a
    reader has its own (the tests try both of PyYAML's)."""
    loader = loader or LOADER
    try:
        found = scan(text, max_depth, loader)
        if found is None:
            return yaml.compose(text, Loader=loader)
    except yaml.MarkedYAMLError as e:
        found = _library_limit(text, max_depth, loader, e)
        if found is None:
            m = e.problem_mark or e.context_mark
            line, column = (m.line + 1, m.column + 1) if m else (1, 1)
            found = Refused("syntax", line, column, str(e.problem or e.context))
    except (yaml.YAMLError, RecursionError) as e:
        found = Refused("syntax", detail=type(e).__name__)
    raise found


def scan(text: str, max_depth: int, loader: type | None = None) -> Refused | None:
    """Anchors, aliases or nesting beyond `max_depth`, found on the event stream before any tree
    is built (None: none); yaml.YAMLError where the text stops being YAML."""
    depth = 0
    for ev in yaml.parse(text, Loader=loader or LOADER):
        if isinstance(ev, yaml.AliasEvent) or getattr(ev, "anchor", None):
            return Refused("alias", ev.start_mark.line + 1, ev.start_mark.column + 1)
        if isinstance(ev, yaml.CollectionStartEvent):
            depth += 1
            if depth > max_depth:
                return Refused("depth", ev.start_mark.line + 1, ev.start_mark.column + 1, limit=max_depth)
        elif isinstance(ev, yaml.CollectionEndEvent):
            depth -= 1
    return None


def _library_limit(text: str, max_depth: int, loader: type, error: yaml.MarkedYAMLError) -> Refused | None:
    """Our own refusal when the YAML library refused the text first for one of its own limits;
    None when the text is simply not YAML.

    libyaml 0.2.6 (in PyYAML 6.0.4) caps nesting at 1,000 levels in its scanner, whose look-ahead
    reads up to 1,024 characters ahead of our event count: `[[[[...` is refused there, with the
    library's wording, before our count reaches the bound.  The pure-Python scanner has no such
    cap, so it decides (only on this error path, and it stops at our bound); a library whose own
    scanner also names a nesting or depth limit is taken at its word.
    """
    if loader is not yaml.SafeLoader:
        try:
            found = scan(text, max_depth, yaml.SafeLoader)
        except (yaml.YAMLError, RecursionError):
            found = None
        if found is not None:
            return found
    problem = f"{error.problem or ''} {error.context or ''}".lower()
    if "nesting" in problem or "depth" in problem:
        m = error.problem_mark or error.context_mark
        line, column = (m.line + 1, m.column + 1) if m else (1, 1)
        return Refused("depth", line, column, limit=max_depth)
    return None


def load(path: str | os.PathLike[str], max_bytes: int, max_depth: int) -> yaml.Node | None:
    """`read_text` then `compose`: a YAML file's tree, or Refused."""
    return compose(read_text(path, max_bytes), max_depth)
