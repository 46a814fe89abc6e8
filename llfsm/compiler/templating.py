"""The one Jinja environment setup shared by everything llfsm generates (machine modules,
message modules, package and machine skeletons): strict about undefined names, so that a
template mistake fails loudly instead of writing a half-empty file."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import jinja2

TEMPLATES = Path(__file__).resolve().parent.parent / "templates"


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
    env.filters.update(filters)
    return env
