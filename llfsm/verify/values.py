"""Variable values compared by value (docs/verify.md, "What is explored").

A configuration holds each machine's variables as values that compare and hash as the values
they stand for: numbers, strings, bytes, None and tuples of those as they are (Python compares
`1 == 1.0 == True`, and so does verify); a list, dict, set or message as a `Frozen` tuple of its
kind and its frozen parts (messages by their fields); a handle to a bus entity (a node, a
publisher, a client) as the first such handle made of its kind and name (later ones behave
alike: publishing on the same topic), itself: one object per kind and name, so it compares and
hashes by identity, as cheaply as a small integer, and a step puts it back as it is (a
subscription's reader is frozen with what it holds, its newest message).

`thaw` gives the ringlet a value it may change in place: a new list, a new message.  Anything
else (an object of a class of the user's, a function, a file) cannot be compared by value:
`freeze` raises `Unfreezable` naming its type, and verify reports the variable.
"""

from __future__ import annotations

from enum import Enum
from typing import Any

#: The types a configuration holds as they are.
SCALARS: frozenset[type] = frozenset({int, float, str, bool, type(None), bytes})


class Frozen(tuple[Any, ...]):
    """A frozen value that is not a scalar: (kind, parts...).  Compared and hashed as a tuple."""

    __slots__ = ()


class Unfreezable(TypeError):
    """A value verify cannot compare by value (the message names its type)."""


class Handles:
    """The bus entities the machines made: the first of each kind and name stands for them all
    in a configuration (its canonical handle)."""

    def __init__(self) -> None:
        self.canonical: dict[tuple[str, ...], Any] = {}
        #: each handle's canonical one by its id, with the handle (kept alive, so the id is its
        #: own): what a handle is never changes, and a configuration is frozen at every step
        self.known: dict[int, tuple[Any, Any]] = {}
        #: the canonical handle of each handle frozen as that alone (all but readers), by id:
        #: what a machine's snapshot looks up first (llfsm.verify.snapshot), one dict look-up
        #: per handle; `known` keeps each object alive, so no other object can have its id
        self.plain: dict[int, Any] = {}

    def of(self, obj: Any) -> Any:
        """The canonical handle standing for `obj`, or None when `obj` is no handle."""
        hit = self.known.get(id(obj))
        if hit is not None and hit[0] is obj:
            return hit[1]
        key = _handle_key(obj)
        if key is None:
            return None
        first = self.canonical.setdefault(key, obj)
        self.known[id(obj)] = (obj, first)
        if key[0] != "subscription":
            self.plain[id(obj)] = first
        return first


def _handle_key(obj: Any) -> tuple[str, ...] | None:
    """What a handle is, for `Handles.of`: (kind, name...), or None for no handle."""
    # deferred: start-up of `llfsm verify` without the bus (a machine that never uses it)
    from ..ros.client import Client
    from ..ros.node import Node
    from ..ros.publisher import Publisher
    from ..ros.subscription import Subscription

    if isinstance(obj, Node):
        return ("node", obj.get_fully_qualified_name())
    if isinstance(obj, Publisher):
        return ("publisher", obj.topic_name, obj.msg_type._TYPE, "latched" if obj.transient_local else "")
    if isinstance(obj, Client):
        return ("client", obj.srv_name, obj.srv_type._TYPE)
    if isinstance(obj, Subscription):
        return ("subscription", obj.topic_name, obj.msg_type._TYPE, "push" if obj.callback is not None else "pull")
    return None


def freeze(value: Any, handles: Handles) -> Any:
    """`value` as a configuration holds it (see the module's docstring)."""
    t = type(value)
    if t in SCALARS:
        return value
    if t is tuple:
        if all(type(v) in SCALARS for v in value):
            return value  # the common case (names, coordinates) without a call per item
        parts = tuple(freeze(v, handles) for v in value)
        return parts if all(type(p) in SCALARS or type(p) is tuple for p in parts) else Frozen(("tuple", *parts))
    if t is list:
        return Frozen(("list", *(freeze(v, handles) for v in value)))
    if t is dict:
        return Frozen(("dict", *(p for k, v in value.items() for p in (freeze(k, handles), freeze(v, handles)))))
    if t is set or t is frozenset:
        return Frozen(("set" if t is set else "frozenset", frozenset(freeze(v, handles) for v in value)))
    fields = getattr(t, "_FIELDS", None)
    if fields is not None and hasattr(value, "_copy"):  # a message: by its fields
        return Frozen(("message", t, *(freeze(getattr(value, f), handles) for f, _ in fields)))
    if isinstance(value, Enum):  # immutable, compared by identity: FutureReturnCode.SUCCESS
        return value
    if hasattr(value, "_service") and hasattr(value, "_callbacks") and _is_future(value):  # by what it came to
        if value._exception is not None or value._callbacks or value._remote is not None:
            raise Unfreezable("a future with callbacks, an exception or a remote server")
        return Frozen(("future", value._service, value._done, freeze(value._result, handles)))
    first = handles.of(value)
    if first is not None:
        if id(value) in handles.plain:
            return first
        return Frozen(("reader", first, freeze(value.latest, handles), value._fresh))  # what it holds counts too
    raise Unfreezable(f"a {t.__module__}.{t.__qualname__}")


def _is_future(value: Any) -> bool:
    """A service call's future (the environment's own, llfsm.verify.environment.EnvFuture, too)."""
    from ..ros.task import Future  # deferred: start-up (only a machine that calls a service)

    return isinstance(value, Future)


def thaw(value: Any, handles: Handles) -> Any:
    """A fresh object for a frozen value (a scalar or a tuple of scalars is its own)."""
    if type(value) is not Frozen:
        return value
    kind = value[0]
    if kind == "list":
        return [thaw(v, handles) for v in value[1:]]
    if kind == "tuple":
        return tuple(thaw(v, handles) for v in value[1:])
    if kind == "dict":
        items = value[1:]
        return {thaw(items[i], handles): thaw(items[i + 1], handles) for i in range(0, len(items), 2)}
    if kind == "set":
        return {thaw(v, handles) for v in value[1]}
    if kind == "frozenset":
        return frozenset(thaw(v, handles) for v in value[1])
    if kind == "message":
        cls = value[1]
        msg = cls()
        for (name, _), v in zip(cls._FIELDS, value[2:], strict=True):
            setattr(msg, name, thaw(v, handles))
        return msg
    if kind == "future":
        from ..ros.task import Future  # deferred: start-up (only a machine that calls a service)

        future = Future(value[1])
        if value[2]:
            future.set_result(thaw(value[3], handles))
        return future
    if kind == "reader":
        sub = value[1]
        sub.latest = thaw(value[2], handles)
        sub._fresh = value[3]
        return sub
    raise AssertionError(kind)  # pragma: no cover


def shown(value: Any) -> str:
    """A frozen value as a person reads it in a counterexample: `[1, 2]`, `Twist(linear=...)`."""
    if isinstance(value, Enum):
        return f"{type(value).__name__}.{value.name}"
    if type(value) is not Frozen:
        key = None if type(value) in SCALARS or type(value) is tuple else _handle_key(value)
        return f"<{key[0]} {key[1]}>" if key is not None else repr(value)
    kind = value[0]
    if kind == "list":
        return "[" + ", ".join(shown(v) for v in value[1:]) + "]"
    if kind == "tuple":
        inner = ", ".join(shown(v) for v in value[1:])
        return f"({inner},)" if len(value) == 2 else f"({inner})"
    if kind == "dict":
        items = value[1:]
        return "{" + ", ".join(f"{shown(items[i])}: {shown(items[i + 1])}" for i in range(0, len(items), 2)) + "}"
    if kind in ("set", "frozenset"):
        if not value[1]:
            return f"{kind}()"  # as Python prints an empty one: `{}` is an empty dict
        inner = ", ".join(sorted(shown(v) for v in value[1]))
        return f"{{{inner}}}" if kind == "set" else f"frozenset({{{inner}}})"
    if kind == "message":
        cls = value[1]
        fields = ", ".join(f"{name}={shown(v)}" for (name, _), v in zip(cls._FIELDS, value[2:], strict=True))
        return f"{cls.__name__}({fields})"
    if kind == "future":
        return f"<future {'done: ' + shown(value[3]) if value[2] else 'pending'}>"
    if kind == "reader":
        return f"<subscription {value[1].topic_name}, latest {shown(value[2])}>"
    return repr(value)  # pragma: no cover
