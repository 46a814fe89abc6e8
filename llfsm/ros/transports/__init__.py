"""What moves the bus's messages: in process only (`inproc`, the default) or over DDS (`dds`).

Nodes and machines use `llfsm.ros`; a transport is chosen per run (`llfsm run --transport`,
or `LLFSM_TRANSPORT`) and never seen by machine code.  See `base.Transport` for the interface
and docs/transports.md for how it is built.
"""

from __future__ import annotations

from .base import Transport
from .inproc import InProcess


def make(name: str) -> Transport:
    """The transport called `name` (inproc or dds); ValueError for another name, ImportError
    (with what to install) when dds lacks the cyclonedds package."""
    if name == "inproc":
        return InProcess()
    if name == "dds":
        # deferred: optional dependency and start-up (cyclonedds is heavy; a run on the
        # in-process bus must never load it)
        try:
            import cyclonedds  # noqa: F401
        except ImportError:
            raise ImportError("--transport dds needs the cyclonedds package (pip install cyclonedds)") from None
        from .dds import DdsTransport  # deferred: start-up (it imports cyclonedds)

        return DdsTransport()
    raise ValueError(f"unknown transport {name!r} (choose inproc or dds)")
