"""The in-process transport (the default): everything a run sends stays in its process.

The bus's own delivery (publisher -> readers, client -> server, in the executor's fixed order)
is all there is, so a run under `--clock sim` is reproducible byte for byte.  This class adds
nothing to it; it exists so that a run always has a transport and the bus never asks which.
"""

from __future__ import annotations

from .base import Transport


class InProcess(Transport):
    name = "inproc"
    remote = False


def make(name: str) -> Transport:
    """The transport called `name` (inproc or dds); ValueError for another name, ImportError
    (with what to install) when dds lacks the cyclonedds package."""
    if name == "inproc":
        return InProcess()
    if name == "dds":
        try:
            import cyclonedds  # noqa: F401
        except ImportError:
            raise ImportError("--transport dds needs the cyclonedds package (pip install cyclonedds)") from None
        from .dds import DdsTransport

        return DdsTransport()
    raise ValueError(f"unknown transport {name!r} (choose inproc or dds)")
