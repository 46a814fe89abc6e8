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
