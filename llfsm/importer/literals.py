"""C literals as Python writes them: numbers, characters, strings (their escapes decoded
and written again, so a Python literal never means something else than the C one)."""

from __future__ import annotations

import re

_INT = re.compile(r"(?P<body>0[xX][0-9a-fA-F']+|0[bB][01']+|0[0-7']*|[1-9][0-9']*)(?P<suffix>[uUlLzZ]*)\Z")
_FLOAT = re.compile(
    r"(?P<body>(?:[0-9']+\.[0-9']*|\.[0-9']+)(?:[eE][+-]?[0-9]+)?|[0-9']+[eE][+-]?[0-9]+)(?P<suffix>[fFlL]?)\Z"
)
_ESCAPES = {"n": "\n", "t": "\t", "r": "\r", "a": "\a", "b": "\b", "f": "\f", "v": "\v", "\\": "\\", "'": "'",
            '"': '"', "?": "?", "e": "\x1b"}  # fmt: skip


class LiteralError(ValueError):
    """A literal Python has no faithful spelling for (a raw or wide string, a hex float)."""


def number(text: str) -> tuple[str, str]:
    """(Python literal, kind) of a C number literal: `0644` is `0o644`, `1.0f` is `1.0`."""
    if text[:1] in "+-":  # tree-sitter reads `-2.0` as one literal
        body, kind = number(text[1:].lstrip())
        return text[0] + body, kind
    m = _INT.match(text)
    if m:
        body = m["body"].replace("'", "")
        if len(body) > 1 and body[0] == "0" and body[1] not in "xXbB":
            body = "0o" + body[1:]
        return body, "int"
    m = _FLOAT.match(text)
    if m:
        body = m["body"].replace("'", "")
        if body.startswith("."):
            body = "0" + body
        if body.endswith("."):
            body += "0"
        return body, "float"
    raise LiteralError(f"the number {text} has no Python spelling")


def decode(body: str) -> str:
    """The characters of the inside of a C string or character literal."""
    out: list[str] = []
    i = 0
    while i < len(body):
        ch = body[i]
        if ch != "\\":
            out.append(ch)
            i += 1
            continue
        nxt = body[i + 1 : i + 2]
        if nxt in _ESCAPES:
            out.append(_ESCAPES[nxt])
            i += 2
        elif nxt == "x":
            m = re.match(r"[0-9a-fA-F]+", body[i + 2 :])
            if not m:
                raise LiteralError("a \\x escape without digits")
            out.append(chr(int(m[0], 16) & 0xFF))
            i += 2 + len(m[0])
        elif nxt.isdigit():
            m = re.match(r"[0-7]{1,3}", body[i + 1 :])
            if not m:
                raise LiteralError(f"the escape \\{nxt}")
            out.append(chr(int(m[0], 8)))
            i += 1 + len(m[0])
        elif nxt in ("u", "U"):
            width = 4 if nxt == "u" else 8
            digits = body[i + 2 : i + 2 + width]
            if not re.fullmatch(r"[0-9a-fA-F]{%d}" % width, digits):  # noqa: UP031
                raise LiteralError("a bad \\u escape")
            out.append(chr(int(digits, 16)))
            i += 2 + width
        else:
            raise LiteralError(f"the escape \\{nxt}")
    return "".join(out)


def python_string(value: str, quote: str = '"', fstring: bool = False) -> str:
    """`value` as the inside of a Python string literal in `quote` (braces doubled in an
    f-string)."""
    out = []
    for ch in value:
        if ch == "\\":
            out.append("\\\\")
        elif ch == quote:
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ch == "\r":
            out.append("\\r")
        elif fstring and ch in "{}":
            out.append(ch * 2)
        elif not ch.isprintable():
            out.append(ch.encode("unicode_escape").decode("ascii"))
        else:
            out.append(ch)
    return "".join(out)


def string_value(node_text: str) -> str:
    """The value of one C string literal (`"a\\n"`); a prefixed or raw literal is refused."""
    if not (node_text.startswith('"') and node_text.endswith('"') and len(node_text) >= 2):
        raise LiteralError("a raw, wide or prefixed string literal")
    return decode(node_text[1:-1])
