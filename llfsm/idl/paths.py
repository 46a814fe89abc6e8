"""Folders to search for users' interface packages, named before llfsm.msgs is imported.

`llfsm run` adds the folders around its machines to the message search path before it loads
them, but a run whose machines use no messages must not import llfsm.msgs (nor the re and
typing modules that come with it): its start-up would pay for them.  So the folders wait here
until llfsm.msgs._finder is imported, which takes them; once it has been, they go straight to it.
"""

from __future__ import annotations

import os
import sys

#: Folders named before llfsm.msgs._finder was imported, in order.
pending: list[str] = []


def add_search_path(path: str | os.PathLike[str]) -> None:
    """llfsm.msgs.add_search_path, without importing llfsm.msgs."""
    finder = sys.modules.get("llfsm.msgs._finder")
    if finder is not None:
        finder.add_search_path(path)
    else:
        pending.append(os.fspath(path))
