"""A machine read out for people: its description, its variables and inputs as plain values, and
what changed since the last look.  The one place that reads a compiled machine for display:
the state topics and the page (`description`), `--trace`'s variable events (`Changes`), and the
debugger's variables, history and breakpoints (llfsm.debug) all come here.

Plain values are what JSON and YAML can carry: None, bool, int, float, str, lists and dicts of
them.  A message becomes a dict of its fields; a handle (a node, a publisher) its type's name in
angle brackets, never its `repr` (user code, and no value to anyone).  They are bounded
(SPEC 18): a string longer than TEXT characters, a sequence or mapping longer than ITEMS, and
anything nested deeper than DEPTH is cut, and the cut says so in the value itself, so memory
and a page's size stay bounded whatever a variable holds.

Light, as the rest of the runtime: only a run that traces variables, debugs or serves the page
calls into it.
"""

from __future__ import annotations

from .generated import inputs_of, variables_of

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any

    from .machine import Machine

#: Longest text kept whole, most items of a sequence or mapping, deepest nesting.
TEXT = 200
ITEMS = 32
DEPTH = 6
#: What a cut value says (the tests and the docs look for this word).
CUT = "truncated"


def variable_names(cls: type[Machine]) -> tuple[str, ...]:
    """The machine variables of `cls`, in the order Variables.py declares them."""
    return tuple(name for name, _annotation in variables_of(cls))


def plain(value: object, depth: int = 0) -> Any:
    """`value` as plain data, bounded (see the module's docstring)."""
    t = type(value)
    if value is None or t is bool or t is int:
        return value
    if t is float:
        return value if value == value and value not in (float("inf"), float("-inf")) else repr(value)
    if t is str:
        s: str = value  # type: ignore[assignment]
        if len(s) <= TEXT or _was_cut(s, TEXT, " characters"):
            return s  # whole, or cut already (plain data shown again says its own length)
        return f"{s[:TEXT]}… ({len(s):,} characters, {CUT})"
    if depth >= DEPTH:
        return f"… (nested deeper than {DEPTH}, {CUT})"
    if t is list or t is tuple or t is set or t is frozenset:
        items: list[Any] | tuple[Any, ...] = value if t is list or t is tuple else sorted(value, key=repr)  # type: ignore[assignment, call-overload]
        out = [plain(v, depth + 1) for v in items[:ITEMS]]
        if len(items) > ITEMS:
            last = items[-1]
            cut = (
                len(items) == ITEMS + 1
                and type(last) is str
                and last.startswith("… (")
                and last.endswith(f" items, {CUT})")
            )
            out.append(last if cut else f"… ({len(items):,} items, {CUT})")  # cut already: as it says
        return out
    if t is dict:
        d: dict[Any, Any] = value  # type: ignore[assignment]
        res = {str(k): plain(v, depth + 1) for k, v in list(d.items())[:ITEMS]}
        if len(d) > ITEMS:
            said = d.get("…")
            cut = len(d) == ITEMS + 1 and type(said) is str and said.endswith(f" items, {CUT}")
            res["…"] = said if cut else f"{len(d):,} items, {CUT}"  # cut already: as it says
        return res
    if t is bytes or t is bytearray:
        b: bytes = value  # type: ignore[assignment]
        return plain(list(b), depth)
    fields = getattr(t, "_FIELDS", None)
    if fields is not None and getattr(t, "_TYPE", None):  # a message: its fields
        return {f: plain(getattr(value, f), depth + 1) for f, _ in fields}
    for base in (bool, int, float, str):  # an IntEnum, a str subclass...
        if isinstance(value, base):
            return plain(base(value), depth)
    return f"<{t.__name__}>"


def _was_cut(s: str, keep: int, unit: str) -> bool:
    """Whether `s` is a text `plain` cut: `keep` characters, then what it says of the whole."""
    return s.endswith(f"{unit}, {CUT})") and s[keep : keep + 3] == "… (" and len(s) <= keep + 40


def values_of(m: Machine, names: tuple[str, ...]) -> dict[str, Any]:
    """The plain value of each of `names` on `m` (a name it does not hold yet is left out)."""
    out = {}
    for name in names:
        try:
            out[name] = plain(getattr(m, name))
        except AttributeError:
            continue
    return out


class Changes:
    """What changed in machines' variables and inputs since each one was last looked at: the
    plain values of the last look are kept, one dict per machine, and compared with the new
    ones.  A value changed in place (a list appended to) counts too, since plain values are
    copies."""

    __slots__ = ("last", "names")

    def __init__(self) -> None:
        self.last: dict[int, dict[str, Any]] = {}
        self.names: dict[int, tuple[str, ...]] = {}

    def first(self, m: Machine) -> dict[str, Any]:
        """Start following `m`: its values now."""
        cls = type(m)
        own = variable_names(cls)
        names = self.names[m._id] = own + tuple(n for n in inputs_of(cls) if n not in own)
        now = self.last[m._id] = values_of(m, names)
        return dict(now)

    def changed(self, m: Machine) -> dict[str, list[Any]]:
        """{name: [old, new]} for each value of `m` that changed since the last look."""
        old = self.last.get(m._id)
        if old is None:
            self.first(m)
            return {}
        new = values_of(m, self.names[m._id])
        if new == old:
            return {}
        self.last[m._id] = new
        return {k: [old.get(k), v] for k, v in new.items() if k not in old or old[k] != v}


def description(cls: type[Machine]) -> dict[str, Any]:
    """The structure /llfsm/M/description carries and `--trace` records, from the compiled class
    alone (its guard text is embedded by the compiler; a module built before that has none, and
    says so with empty transition lists)."""
    states = cls.STATES
    trans = cls.TRANSITIONS or ((),) * len(states)
    return {
        "name": cls.NAME,
        "description": cls.DESCRIPTION,
        "states": [
            {
                "name": name,
                "transitions": [
                    {"index": i, "target": states[target], "guard": guard} for i, (target, guard) in enumerate(ts)
                ],
                "accepting": i in cls.ACCEPTING,
            }
            for i, (name, ts) in enumerate(zip(states, trans, strict=True))
        ],
        "initial": states[cls.INITIAL],
        "suspend": states[cls.SUSPENDED],
        # SPEC 11: what the machine reads from outside (llfsm.runtime.inputs gives the positions)
        "inputs": [
            {
                "name": name,
                "type": kind,
                "default": default,
                "domain": list(domain),
                "topic": topic,
                "msg": msg,
                "field": field,
            }
            for name, kind, default, domain, topic, msg, field in cls.INPUTS
        ],
    }
