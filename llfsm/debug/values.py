"""How the history takes a machine's values (docs/debug.md, "History"): numbers, flags and
handles as they are, messages as their generated copies, anything else as bounded plain data
(llfsm.runtime.readout: a long string or a large list is cut, and says so); and how a taken
value is shown."""

from __future__ import annotations

import sys
from operator import attrgetter
from typing import Any

from ..msgs._message import is_message_class
from ..runtime.generated import variables_of
from ..runtime.machine import Machine
from ..runtime.readout import plain
from .recording import COPIED, DIRECT, MESSAGE

#: Annotations (and input types) whose values are taken as they are: immutable scalars.
_SCALARS = frozenset({"bool", "int", "float"})
#: ...and other annotations of values that cannot change in place.
_IMMUTABLE_TEXT = frozenset({"str", "bytes"})


def _named(annotation: str, namespace: dict[str, Any]) -> Any:
    """The class a dotted annotation names in the machine module's globals, if any."""
    first, *rest = annotation.split(".")
    if not first.isidentifier() or not all(p.isidentifier() for p in rest):
        return None  # list[int], X | None ...
    obj = namespace.get(first)
    for part in rest:
        obj = getattr(obj, part, None)
    return obj if isinstance(obj, type) else None


def shown(value: Any) -> Any:
    """A taken value as a person reads it (plain data)."""
    return plain(value)


class Values:
    """How one machine's variables and inputs are taken (see the module's docstring)."""

    __slots__ = ("fast", "kinds", "messages", "names", "replaced_only", "single", "slow")

    def __init__(self, cls: type[Machine]) -> None:
        variables = list(variables_of(cls))
        declared = {n for n, _ in variables}
        variables += [(e[0], e[1]) for e in cls.INPUTS if e[0] not in declared]
        namespace = vars(sys.modules[cls.__module__]) if cls.__module__ in sys.modules else {}
        fast, messages, slow = [], [], []
        for name, annotation in variables:
            named = None if annotation.strip() in _SCALARS else _named(annotation.strip(), namespace)
            if named is not None and is_message_class(named):
                messages.append((name, named))  # a copy (generated), compared field by field
            elif annotation.strip() in _SCALARS or (named is not None and named.__module__ != "builtins"):
                fast.append(name)  # a scalar, or a handle (a node, a publisher) shown as <Type>
            else:
                slow.append(name)
        self.messages = tuple(messages)
        self.slow = tuple(slow)
        self.names = tuple(fast) + tuple(n for n, _ in messages) + self.slow
        #: one C call for the scalars (attrgetter of one name gives the value, not a tuple)
        self.fast: Any = attrgetter(*fast) if fast else None
        self.single = len(fast) == 1
        #: how each value is taken, for a ringlet that records it (recording.py)
        self.kinds = (DIRECT,) * len(fast) + (MESSAGE,) * len(messages) + (COPIED,) * len(slow)
        #: values whose shown value changes only when the variable is assigned: immutable ones,
        #: and handles (shown by their type)
        self.replaced_only = frozenset(fast) | {n for n, a in variables if a.strip() in _IMMUTABLE_TEXT}

    def take(self, m: Machine) -> tuple[Any, ...]:
        """The machine's values now, in `names` order."""
        fast = self.fast
        out: tuple[Any, ...] = (fast(m),) if self.single else fast(m) if fast is not None else ()
        if self.messages:
            out += tuple(taken_copy(getattr(m, n, None), c) for n, c in self.messages)
        if self.slow:
            out += tuple(plain(getattr(m, n, None)) for n in self.slow)
        return out


def taken_copy(value: Any, cls: type[Any]) -> Any:
    """A message as it was (its generated copy, compared field by field); else plain data."""
    return value._copy() if type(value) is cls else plain(value)
