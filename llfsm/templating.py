"""The one Jinja environment setup shared by everything llfsm generates (machine modules,
message modules, package and machine skeletons): strict about undefined names, so that a
template mistake fails loudly instead of writing a half-empty file."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import jinja2

TEMPLATES = Path(__file__).resolve().parent / "templates"

#: Line 2 of every generated Python file.  PEP 263 reads an encoding declaration from line 1
#: or 2 only, and the first that matches wins: lines 1 and 2 are fixed text, this one declares
#: UTF-8 itself, and whatever a header carries from a user's path or name starts on line 3.
CODING_LINE = "# -*- coding: utf-8 -*-"


def comment_text(value: object) -> str:
    """`value` as the rest of one `#` comment line: JSON string escapes, ASCII only.

    Paths and names come from users (and from pull requests): a newline in a folder name
    would end the comment and start code, a `coding=utf_7` would be an encoding declaration on
    line 1 or 2, a non-UTF-8 name (a surrogate-escaped byte) could not even be written.  JSON
    escapes turn every line end, control character, quote, backslash, non-ASCII character and
    lone surrogate into ASCII text, and `json.loads('"' + text + '"')` gives the value back
    (the run-time reads the `# Source:` line that way)."""
    return json.dumps(str(value), ensure_ascii=True)[1:-1]


def header_lines(title: str, **fields: object) -> list[str]:
    """The comment lines that open a generated Python file: `title` (llfsm's own text, never
    a user's), the coding line, then one `# Key: value` line per field, each value escaped."""
    if "\n" in title or "\r" in title or not title.isascii():
        raise ValueError("a header title is llfsm's own one-line ASCII text")
    return [f"# {title}", CODING_LINE, *(f"# {key}: {comment_text(value)}" for key, value in fields.items())]


def environment(
    folder: Path = TEMPLATES, *, trim: bool = True, autoescape: Any = False, **filters: Callable[..., Any]
) -> jinja2.Environment:
    """`trim`: block tags leave no stray whitespace (trim/lstrip), as generated Python needs."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(folder)),
        trim_blocks=trim,
        lstrip_blocks=trim,
        keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined,
        autoescape=autoescape,
    )
    env.filters["comment"] = comment_text
    env.filters.update(filters)
    return env
