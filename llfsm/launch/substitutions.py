"""Substitutions of ROS 2's launch front ends: `$(var N)`, `$(env N [DEFAULT])`,
`$(find-pkg-share PKG)`, `$(dirname)` and `$(eval EXPR)`.

The syntax is launch's own grammar (launch/share/launch/frontend/grammar.lark), read by hand
here: text with `$(NAME ARG ...)` in it, arguments separated by spaces, an argument either a
run of characters and nested substitutions or a quoted template ('...' or "...", which may hold
spaces, parentheses and nested substitutions), and a backslash escaping the next character
everywhere.  Two liberties: several spaces between arguments are one separator, and balanced
parentheses may appear in an unquoted argument (`$(eval 2*(3+4))`, which launch refuses).

A text is parsed once, when the file is read (so a bad substitution is refused with its file and
line before anything starts), and performed when the launch is planned, in order, against the
launch configurations and environment of that moment, as launch performs it when the action runs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TypeAlias

from .evaluate import ExpressionError, evaluate

#: The substitutions llfsm performs, and how many arguments each takes (min, max).
ARITY: dict[str, tuple[int, int]] = {
    "var": (1, 2),
    "env": (1, 2),
    "find-pkg-share": (1, 1),
    "dirname": (0, 0),
    "eval": (1, 1),
}
#: Nested substitutions deeper than this are refused (the parser recurses once per level).
MAX_DEPTH = 32
#: A performed value longer than this is refused: `let` can double a value at each line.
MAX_VALUE = 64 * 1024


@dataclass(frozen=True)
class Sub:
    """`$(name arg ...)`: each argument is itself a text."""

    name: str
    args: tuple[Text, ...]

    def __str__(self) -> str:
        return "$(" + " ".join([self.name, *(show(a) for a in self.args)]) + ")"


#: A parsed text: literal pieces and substitutions, in order.
Text: TypeAlias = tuple["str | Sub", ...]


class SubstitutionError(ValueError):
    """A text that is not a valid substitution, or one that cannot be performed: the message
    (its caller adds the file and line)."""


def show(text: Text) -> str:
    """The text as it could be written (for messages)."""
    return "".join(p if isinstance(p, str) else str(p) for p in text)


def literal(text: Text) -> str | None:
    """The text's value when it holds no substitution, else None."""
    if all(isinstance(p, str) for p in text):
        return "".join(p for p in text if isinstance(p, str))
    return None


def parse(source: str) -> Text:
    """The text `source` as launch reads an attribute value; SubstitutionError when a `$(` is
    not closed, names a substitution llfsm does not perform, or has the wrong arguments."""
    return tuple(_Parser(source).fragments(None))


class _Parser:
    def __init__(self, source: str) -> None:
        self.s = source
        self.i = 0
        self.depth = 0

    def fail(self, message: str) -> SubstitutionError:
        return SubstitutionError(f"bad substitution in {self.s!r}: {message}")

    def fragments(self, quote: str | None) -> list[str | Sub]:
        """Text and substitutions up to the closing `quote` (read past), or to the end."""
        out: list[str | Sub] = []
        buf: list[str] = []
        s, n = self.s, len(self.s)
        opened = self.i - 1
        while self.i < n:
            c = s[self.i]
            if c == quote:
                self.i += 1
                _flush(buf, out)
                return out or [""]
            if c == "$" and s.startswith("$(", self.i):
                _flush(buf, out)
                out.append(self.substitution())
            elif c == "\\" and self.i + 1 < n:
                buf.append(s[self.i + 1])
                self.i += 2
            else:
                buf.append(c)
                self.i += 1
        if quote is not None:
            raise self.fail(f"the quote {quote} at character {opened + 1} is never closed")
        _flush(buf, out)
        return out

    def substitution(self) -> Sub:
        start = self.i
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.fail(f"substitutions nested deeper than {MAX_DEPTH}")
        self.i += 2
        s, n = self.s, len(self.s)
        j = self.i
        if j < n and s[j].isascii() and s[j].isalpha():
            j += 1
            while j < n and s[j].isascii() and (s[j].isalnum() or s[j] in "_-"):
                j += 1
        name = s[self.i : j]
        if not name:
            raise self.fail(f"`$(` at character {start + 1} is not followed by a substitution's name")
        self.i = j
        args: list[Text] = []
        while True:
            if self.i >= n:
                raise self.fail(f"`$({name}` is never closed with `)`")
            c = s[self.i]
            if c == ")":
                self.i += 1
                break
            if c != " ":
                raise self.fail(f"unexpected {c!r} after `$({name}`")
            while self.i < n and s[self.i] == " ":
                self.i += 1
            if self.i < n and s[self.i] != ")":
                args.append(tuple(self.argument()))
        self.depth -= 1
        sub = Sub(name, tuple(args))
        problem = _arity_problem(sub)
        if problem is not None:
            raise self.fail(problem)
        return sub

    def argument(self) -> list[str | Sub]:
        s, n = self.s, len(self.s)
        if s[self.i] in "'\"":
            self.i += 1
            return self.fragments(s[self.i - 1])
        out: list[str | Sub] = []
        buf: list[str] = []
        parens = 0
        while self.i < n:
            c = s[self.i]
            if c == "$" and s.startswith("$(", self.i):
                _flush(buf, out)
                out.append(self.substitution())
                continue
            if c == "\\" and self.i + 1 < n:
                buf.append(s[self.i + 1])
                self.i += 2
                continue
            if c in "'\"":
                raise self.fail(
                    f"a quote inside an argument: quote the whole argument ({show(tuple(out))}{''.join(buf)}...)"
                )
            if c == " " and parens == 0:
                break
            if c == ")":
                if parens == 0:
                    break
                parens -= 1
            elif c == "(":
                parens += 1
            buf.append(c)
            self.i += 1
        _flush(buf, out)
        return out


def _flush(buf: list[str], out: list[str | Sub]) -> None:
    if buf:
        out.append("".join(buf))
        buf.clear()


def _arity_problem(sub: Sub) -> str | None:
    """What is wrong with a substitution's name or number of arguments, if anything."""
    if sub.name not in ARITY:
        return f"llfsm launch does not perform $({sub.name}) (it performs {', '.join(ARITY)})"
    low, high = ARITY[sub.name]
    if sub.name == "eval" and len(sub.args) == 2:
        return "$(eval) takes one expression: a launch file cannot import modules"
    if sub.name == "eval" and len(sub.args) > 2:
        return "$(eval) takes one argument: quote the whole expression, as in $(eval \"'$(var a)' == 'x'\")"
    if not low <= len(sub.args) <= high:
        want = str(low) if low == high else f"{low} or {high}"
        return f"$({sub.name}) takes {want} argument{'' if high == 1 else 's'}, not {len(sub.args)}"
    return None


class Context:
    """What a substitution reads: the launch configurations and environment in scope, and the
    file whose text it is (for `$(dirname)`)."""

    def __init__(self, configurations: dict[str, str], environment: dict[str, str], file: str) -> None:
        self.configurations = configurations
        self.environment = environment
        self.file = file


def perform(text: Text, ctx: Context) -> str:
    """The text's value; SubstitutionError when a substitution cannot be performed (an unset
    launch configuration or environment variable with no default, a package not found, an
    expression refused)."""
    out = []
    size = 0
    for part in text:
        value = part if isinstance(part, str) else _perform_one(part, ctx)
        size += len(value)
        if size > MAX_VALUE:
            raise SubstitutionError(f"{show(text)[:60]}...: its value is longer than {MAX_VALUE // 1024} KiB")
        out.append(value)
    return "".join(out)


def _perform_one(sub: Sub, ctx: Context) -> str:
    args = [perform(a, ctx) for a in sub.args]
    if sub.name == "var":
        if args[0] in ctx.configurations:
            return ctx.configurations[args[0]]
        if len(args) == 2:
            return args[1]
        raise SubstitutionError(f"$(var {args[0]}): no launch argument or `let` named {args[0]!r} is set here")
    if sub.name == "env":
        value = ctx.environment.get(args[0], args[1] if len(args) == 2 else None)
        if value is None:
            raise SubstitutionError(f"$(env {args[0]}): the environment variable {args[0]} is not set (give a default)")
        return value
    if sub.name == "dirname":
        return os.path.dirname(os.path.abspath(ctx.file))
    if sub.name == "find-pkg-share":
        return find_package_share(args[0], ctx.environment)
    if sub.name == "eval":
        try:
            return evaluate(args[0])
        except ExpressionError as e:
            raise SubstitutionError(f"$(eval {args[0]!r}): {e}") from None
    raise AssertionError(sub.name)  # parse() refused every other name


def find_package_share(package: str, environment: dict[str, str]) -> str:
    """`<prefix>/share/<package>` of the first prefix of AMENT_PREFIX_PATH whose ament index
    lists the package, as ament_index_python's get_package_share_directory finds it."""
    prefixes = [p for p in environment.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    if not package or "/" in package or package in (".", ".."):
        raise SubstitutionError(f"$(find-pkg-share {package}): not a package name")
    for prefix in prefixes:
        marker = os.path.join(prefix, "share", "ament_index", "resource_index", "packages", package)
        if os.path.isfile(marker):
            return os.path.join(prefix, "share", package)
    where = (
        "AMENT_PREFIX_PATH is not set: did you `source install/setup.bash`?"
        if not prefixes
        else f"not in the ament index of {', '.join(prefixes)}"
    )
    raise SubstitutionError(f"$(find-pkg-share {package}): package {package!r} not found ({where})")
