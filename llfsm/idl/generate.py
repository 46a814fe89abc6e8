"""Both generators over one package: the files of llfsm.msgs.<pkg> (docs/bus.md, "Messages").

A package is `__init__.py`, then per kind it defines (msg, srv, action) the module of its classes
(llfsm.idl.pygen) and their DDS form `_dds.py` (llfsm.idl.ddsgen).  The shipped packages
(llfsm.idl.shipped) and a user's (llfsm.idl.package) are generated alike; only the header
and where the definitions of other packages come from differ.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from pathlib import Path

import jinja2

from ..templating import environment
from . import ddsgen, pygen
from .codeformat import literal
from .spec import MessageSpec, PackageSpec

TEMPLATES = Path(__file__).resolve().parent / "templates"


@cache
def _env() -> jinja2.Environment:
    return environment(TEMPLATES, py=literal)


def render_package(package: PackageSpec, header: list[str], lookup: Callable[[str], MessageSpec]) -> dict[str, str]:
    """Relative path -> source: the package's __init__.py, and msg/__init__.py, msg/_dds.py,
    srv/__init__.py, srv/_dds.py, action/__init__.py, action/_dds.py for the kinds it has.
    `lookup` finds the definition of a message of another package by type name (the CDR code
    inlines nested messages)."""
    see = ".msg, .srv and .action" if package.actions else ".msg and .srv"
    out = {"__init__.py": "\n".join([*header, f'"""ROS interfaces of {package.name}: see {see}."""', ""])}
    kinds = (("msg", package.messages), ("srv", package.services), ("action", package.actions))
    for kind, present in kinds:
        if present:
            out[f"{kind}/__init__.py"] = pygen.render_module(package, kind, header, _env())
            out[f"{kind}/_dds.py"] = ddsgen.render_dds_module(package, kind, lookup, header, _env())
    return out
