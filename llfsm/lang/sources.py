"""The files of a machine directory, read with care, and their Python parsed: the part of the
reader (reader.py) that looks at bytes, tokens and `ast` trees.

A file is read only if it is a regular file inside the directory (a symlink out of it, a device,
a FIFO are refused), at most MAX_FILE_BYTES, UTF-8 without NUL bytes; its Python is parsed with
`ast` only, never imported or run, and what would make the parser or the compiler's tree walks
take too long or too much stack (a form feed in the indentation, a huge f-string) is refused
before `ast.parse` sees it.  Each refusal is a diagnostic; nothing here raises.
"""

from __future__ import annotations

import ast
import io
import os
import re
import tokenize
from pathlib import Path

from ..machinedir import NOFOLLOW, FileTooLarge, NotRegularFile, read_regular
from .cpp import syntax_hint
from .diagnostics import Diagnostic, diag
from .model import Code, Loc, Variable
from .positions import line_index, node_col, source_segment

MAX_FILE_BYTES = 1 << 20  # 1 MiB: no hand-written state section comes near this
#: Deepest `ast` nesting accepted in a code file.  Hand-written code stays far below; the
#: compiler's tree walks recurse, and a deeper tree would exhaust Python's stack in them.
MAX_CODE_DEPTH = 200
#: Most replacement fields in one f-string.  CPython 3.11 parses an f-string in time quadratic
#: in its fields (80,000 take seconds, a 1 MiB one minutes), so a bigger one is refused (LF039)
#: before `ast.parse` sees it; hand-written code has a handful.
MAX_FSTRING_FIELDS = 1000
#: A form feed in the indentation resets CPython's column count: re-indented into a method,
#: such a line would land at another nesting level than the one it was checked at.  (A form
#: feed alone on its line, or before a comment, is harmless: such lines have no indentation.)
_FORM_FEED_INDENT = re.compile(r"^[ \t]*\f[ \t\f]*[^\s#]", re.MULTILINE)


class _Files:
    """A machine directory's files and their Python, with what could not be read as diagnostics
    (the reader, reader.py, is built on it)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        # os.path.realpath, not Path.resolve: it never raises on a symlink loop (Python 3.11)
        self.real = Path(os.path.realpath(path))
        self.diags: list[Diagnostic] = []
        self.trees: dict[str, ast.Module] = {}
        self.raw: dict[str, bytes] = {}
        self.links: set[str] | frozenset[str] | None = None  # names that are symlinks, once listed
        self.inline: dict[str, Code] = {}  # inline guards by the name their file would have
        self.yaml_lines: list[str] = []
        self.nofollow = bool(NOFOLLOW)  # without O_NOFOLLOW, every file the careful way

    # -- files ---------------------------------------------------------------------------
    def where(self, name: str) -> str:
        return str(self.path / name)

    def report(self, code: str, name: str, line: int, col: int, msg: str) -> None:
        inline = self.inline.get(name)
        if inline is not None:  # an inline guard's problem is at its place in machine.yaml
            loc = inline.place(line, col)
            name, line, col = loc.file, loc.line, loc.column
        self.diags.append(diag(code, self.where(name), line, col, msg))

    def read(self, name: str) -> str | None:
        """The text of a file of the machine directory, or None (with a diagnostic) if unusable."""
        p = os.path.join(self.path, name)  # plain strings: this runs for every file of every machine
        try:
            data = None
            if self._listed_plain(name):
                try:
                    data = read_regular(p, MAX_FILE_BYTES)  # O_NOFOLLOW: still no symlink
                except OSError:
                    pass  # a symlink by now, or unreadable: the careful way reports it as before
            if data is None:  # a symlink (or not known not to be one): where does it lead?
                if os.path.islink(p):
                    target = Path(os.path.realpath(p))
                    if not target.is_relative_to(self.real):
                        self.report(
                            "LF037", name, 1, 1, f"{name} is a symlink leading out of the machine directory; refused"
                        )
                        return None
                data = read_regular(p, MAX_FILE_BYTES, follow=True)
        except NotRegularFile:
            self.report("LF002", name, 1, 1, f"{name} is not a regular file")
            return None
        except FileTooLarge:
            self.report("LF002", name, 1, 1, f"{name} is larger than {MAX_FILE_BYTES // 1024} KiB; refused")
            return None
        except OSError as e:
            self.report("LF002", name, 1, 1, f"cannot read {name}: {e.strerror or e}")
            return None
        self.raw[name] = data
        if b"\0" in data:
            self.report("LF002", name, 1, 1, f"{name} is a binary file (it contains NUL bytes)")
            return None
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            line = data[: e.start].count(b"\n") + 1
            self.report("LF002", name, line, 1, f"{name} is not UTF-8 text (byte {e.start})")
            return None
        # one line ending: CPython counts \r and \r\n as line ends, and so must every later step
        return text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n")

    def _listed_plain(self, name: str) -> bool:
        """Whether the directory listed `name` as no symlink (so it may be opened O_NOFOLLOW,
        without a `lstat` first).  One listing (file types from the directory itself) saves a
        `lstat` per file of every machine."""
        if self.links is None:
            try:
                with os.scandir(self.path) as it:
                    self.links = {e.name for e in it if e.is_symlink()}
            except OSError:
                self.links = frozenset({name})  # unknown: the careful way for every file
                self.nofollow = False
        return self.nofollow and name not in self.links

    # -- python --------------------------------------------------------------------------
    def parse(self, name: str, text: str) -> ast.Module | None:
        ff = _FORM_FEED_INDENT.search(text)
        if ff is not None:
            line = text.count("\n", 0, ff.start()) + 1
            self.report("LF030", name, line, 1, "a form feed in the indentation; put it on a line of its own")
            return None
        big = _huge_fstring(text)
        if big is not None:
            self.report(
                "LF039",
                name,
                big[0],
                big[1] + 1,
                f"an f-string with more than {MAX_FSTRING_FIELDS} replacement fields; build the text in steps",
            )
            return None
        try:
            tree = ast.parse(text, filename=name)
        except SyntaxError as e:
            line = e.lineno or 1
            col = e.offset if e.offset else 1  # the parser counts characters, not bytes
            hint = syntax_hint(line_index(text).lines[line - 1] if 1 <= line <= text.count("\n") + 1 else "", name)
            self.report("LF030", name, line, col, f"syntax error: {e.msg}" + (f"; {hint}" if hint else ""))
            return None
        except (RecursionError, MemoryError, ValueError) as e:
            self.report("LF030", name, 1, 1, f"cannot parse {name}: {type(e).__name__}")
            return None
        self.trees[name] = tree  # too deep a tree is refused by the checker's scan (MAX_CODE_DEPTH)
        return tree

    def code(self, name: str, text: str) -> Code:
        return Code(file=name, text=text, loc=Loc(file=name))

    def code_file(self, name: str, entries: set[str]) -> Code | None:
        """A section, guard or includes file of the directory, parsed for the checker; None
        when it is absent or unreadable (the reason is already reported)."""
        if name not in entries:
            return None
        text = self.read(name)
        if text is None:
            return None
        code = self.code(name, text)
        self.parse(name, text)
        return code

    def variables(self, name: str) -> tuple[list[Variable], Code | None]:
        text = self.read(name)
        if text is None:
            return [], None
        tree = self.parse(name, text)
        if tree is None:
            return [], None
        out: list[Variable] = []
        for stmt in tree.body:
            if isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name) and stmt.simple:
                ann = source_segment(text, stmt.annotation) or ast.unparse(stmt.annotation)
                init = None
                if stmt.value is not None:
                    init = source_segment(text, stmt.value) or ast.unparse(stmt.value)
                out.append(
                    Variable(
                        name=stmt.target.id,
                        annotation=ann,
                        initial=init,
                        loc=Loc(file=name, line=stmt.lineno, column=node_col(text, stmt)),
                    )
                )
            else:
                what = _describe(stmt)
                self.report(
                    "LF032",
                    name,
                    stmt.lineno,
                    node_col(text, stmt),
                    f"{what} in {name}: only annotated assignments such as `count: int = 0` are allowed",
                )
        return out, self.code(name, text)


def _huge_fstring(text: str) -> tuple[int, int] | None:
    """(line, 0-based column) of an f-string with more than MAX_FSTRING_FIELDS fields, if any.
    Tokenized only when the file holds that many braces at all: the common case costs a count."""
    if text.count("{") <= MAX_FSTRING_FIELDS:
        return None
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.STRING and tok.string.count("{") > MAX_FSTRING_FIELDS:
                quote = min(i for i in (tok.string.find("'"), tok.string.find('"')) if i >= 0)
                if "f" in tok.string[:quote].lower():
                    return tok.start
    except (tokenize.TokenError, SyntaxError):
        return None  # the parser reports it, in linear time: a broken token ends the string early
    return None


def _describe(stmt: ast.stmt) -> str:
    if isinstance(stmt, ast.Assign):
        return "an assignment without a type (write `name: type = value`)"
    if isinstance(stmt, ast.AnnAssign):
        return "an annotated assignment to something other than a plain name"
    if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) and isinstance(stmt.value.value, str):
        return "a string"
    return f"a `{type(stmt).__name__.lower()}` statement"
