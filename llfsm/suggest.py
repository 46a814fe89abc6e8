"""Close names that exist, for "not found" lines: after a verb has waited for `/turtle1/cmdvel`
in vain, the line that says so names `/turtle1/cmd_vel`, which the graph has; `bag play
--topics` names the bag's topics the same way.  Stdlib only (difflib), for every layer.

A name is close when it reads almost the same (difflib's ratio, ignoring case), or when it is
the same last part in another namespace (`cmd_vel` typed for `/turtle1/cmd_vel`).  Hidden
names (a part starting with `_`) are offered only for a hidden name.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: How alike two names must read (difflib's ratio) to be offered.
CLOSE = 0.75
#: At most this many names are offered.
AT_MOST = 3


def close_names(name: str, names: Iterable[str]) -> list[str]:
    """The existing names closest to `name`, best first (none equal to it)."""
    hidden = any(part.startswith("_") for part in name.split("/"))
    candidates = [n for n in names if n != name and (hidden or not any(p.startswith("_") for p in n.split("/")))]
    last = name.rstrip("/").rsplit("/", 1)[-1].lower()
    scored = []
    for n in candidates:
        ratio = difflib.SequenceMatcher(None, name.lower(), n.lower()).ratio()
        if ratio >= CLOSE or (last and n.rstrip("/").rsplit("/", 1)[-1].lower() == last):
            scored.append((-ratio, n))
    return [n for _, n in sorted(scored)[:AT_MOST]]


def did_you_mean(name: str, names: Iterable[str]) -> str:
    """`; did you mean '/turtle1/cmd_vel'?` when close names exist, else ''."""
    close = close_names(name, names)
    if not close:
        return ""
    return "; did you mean " + " or ".join(f"'{n}'" for n in close) + "?"
