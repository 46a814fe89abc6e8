"""Skeletons: `llfsm new machine` (and, later, `llfsm new package`), rendered from templates/."""

from __future__ import annotations

from pathlib import Path

import jinja2

from .compiler.build import write_atomic
from .model import is_valid_name

TEMPLATES = Path(__file__).resolve().parent / "templates"


class ScaffoldError(Exception):
    pass


def _env(folder: str) -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES / folder)),
        keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined,
        autoescape=False,
    )


def _yaml_text(text: str) -> str:
    """A one-line YAML scalar that reads back as `text` whatever it holds."""
    import json

    return json.dumps(" ".join(text.split()))  # JSON strings are YAML strings


def create_machine(directory: Path, name: str, description: str | None = None) -> Path:
    """Write NAME.machine with a valid INITIAL -> END skeleton; never overwrites anything."""
    if not is_valid_name(name):
        raise ScaffoldError(
            f"{name!r} is not a valid machine name: use letters, digits and _, not starting "
            "with a digit, and not a Python keyword"
        )
    target = directory / f"{name}.machine"
    if target.exists():
        raise ScaffoldError(f"{target} already exists; nothing was written")
    env = _env("skeleton")
    files = {}
    for tpl in env.list_templates():
        files[tpl.removesuffix(".j2")] = env.get_template(tpl).render(
            name=name, description=_yaml_text(description or f"The machine {name}.")
        )
    target.mkdir(parents=True)
    for fname, text in files.items():
        write_atomic(target / fname, text)
    return target
