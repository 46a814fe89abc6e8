"""What every planner shares: the machine directory as read at the start of a plan, its
machine.yaml as a round-trip document, the files written so far, and the rules on names.

A plan reads each file at most once (`read`) and remembers what it read, so the `Change` it
ends with knows every file's `before`; `write` stages new bytes; `change` drops the writes that
change nothing, so a Change touches only the files an edit really touches.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ruamel.yaml.comments import CommentedMap, CommentedSeq

from ..lang.files import MAX_STATE_NAME, guard_file, with_header
from ..lang.model import is_valid_name
from ..machinedir import LAYOUT_FILE, MACHINE_SUFFIX
from .change import Change, EditError, check_root, read_plain
from .yaml_doc import YamlDoc, flow_seq, is_flow, line_of, new_map

MACHINE_YAML = "machine.yaml"


def check_name(name: object, what: str) -> str:
    """`name` if it is a valid state or machine name (SPEC 1), else EditError; run before the
    name is part of any path."""
    if not isinstance(name, str):
        raise EditError(f"{what} must be a name, not {type(name).__name__}")
    shown = repr(name) if len(name) <= 40 else repr(name[:39] + "…")
    if len(name) > MAX_STATE_NAME:
        raise EditError(f"{what} {shown} is {len(name)} characters long; at most {MAX_STATE_NAME}")
    if not is_valid_name(name):
        raise EditError(
            f"{what} {shown} is not a valid name: letters, digits and _ (ASCII), not starting with a digit, "
            "not a Python keyword"
        )
    return name


class Plan:
    """One edit of one machine directory, being planned."""

    def __init__(self, machine: Path | str) -> None:
        self.root = Path(machine)
        check_root(self.root)
        if not self.root.name.endswith(MACHINE_SUFFIX):
            raise EditError(f"{self.root}: not a machine directory (NAME.machine)")
        self.before: dict[str, bytes | None] = {}
        self.writes: dict[str, bytes | None] = {}
        raw = self.read(MACHINE_YAML)
        if raw is None:
            raise EditError(f"{self.root} has no machine.yaml")
        self.yaml = YamlDoc(_text(raw, self.root / MACHINE_YAML), MACHINE_YAML)
        self.yaml_changed = False
        self._layout: YamlDoc | None = None
        self.layout_changed = False
        self._index()

    # -- files ------------------------------------------------------------------------------
    def read(self, rel: str) -> bytes | None:
        """The bytes of a file as this plan sees it (its own writes included)."""
        if rel in self.writes:
            return self.writes[rel]
        if rel not in self.before:
            self.before[rel] = read_plain(self.root, rel)
        return self.before[rel]

    def text(self, rel: str) -> str | None:
        data = self.read(rel)
        return None if data is None else _text(data, self.root / rel)

    def write(self, rel: str, data: bytes | str | None) -> None:
        self.read(rel)  # its `before`
        self.writes[rel] = data.encode("utf-8") if isinstance(data, str) else data

    def change(self, summary: str) -> Change:
        if self.yaml_changed:
            self.write(MACHINE_YAML, self.yaml.dump())
        if self.layout_changed and self._layout is not None:
            self.write(LAYOUT_FILE, self._layout.dump())
        writes = {k: v for k, v in self.writes.items() if v != self.before.get(k)}
        return Change(self.root, writes, {k: self.before.get(k) for k in writes}, summary)

    def exists(self, rel: str) -> bool:
        return self.read(rel) is not None

    # -- machine.yaml's structure -------------------------------------------------------------
    def _index(self) -> None:
        """The states as machine.yaml lists them; EditError for a shape no edit can work on
        (llfsm check says what is wrong; the editor edits the text instead)."""
        doc = self.yaml.data
        if not isinstance(doc, CommentedMap) or not isinstance(doc.get("states"), CommentedSeq):
            raise EditError(f"{self.root / MACHINE_YAML}: no `states` list; fix it first (llfsm check)")
        self.states: CommentedSeq = doc["states"]
        self.by_name: dict[str, CommentedMap] = {}
        for i, st in enumerate(self.states):
            name = st.get("name") if isinstance(st, CommentedMap) else None
            if not isinstance(name, str):
                where = f"{self.root / MACHINE_YAML}:{line_of(st) or line_of(self.states)}"
                raise EditError(f"{where}: state {i} has no name; fix it first (llfsm check)")
            ts = st.get("transitions")
            if ts is not None and not isinstance(ts, CommentedSeq):
                where = f"{self.root / MACHINE_YAML}:{line_of(st, 'transitions')}"
                raise EditError(f"{where}: `transitions` of {name} is not a list; fix it first (llfsm check)")
            self.by_name.setdefault(name, st)

    @property
    def names(self) -> list[str]:
        return [str(st["name"]) for st in self.states]

    def state(self, name: object, what: str = "state") -> CommentedMap:
        """The state named `name` (a valid name: checked first), or EditError."""
        check_name(name, what)
        st = self.by_name.get(str(name))
        if st is None:
            raise EditError(f"{self.root.name} has no state {name}")
        return st

    def fresh(self, name: object, what: str = "state name") -> str:
        """A valid name no state has yet, or EditError."""
        check_name(name, what)
        if name in self.by_name:
            raise EditError(f"{self.root.name} already has a state {name}")
        return str(name)

    def entries(self, name: str) -> list[Any]:
        ts = self.by_name[name].get("transitions")
        return list(ts) if ts is not None else []

    def rearrange(self, name: str, order: list[int | None], new: dict[int, Any] | None = None) -> None:
        """The state's transitions as `order` says: `order[j]` is the old position of the entry
        now at j, None for a new one (from `new`).  Entries keep their comments; the list keeps
        its style; no transitions left means no `transitions:` (an accepting state, as END is
        written)."""
        st = self.by_name[name]
        ts = st.get("transitions")
        old = list(ts) if ts is not None else []
        items = [old[i] if i is not None else (new or {})[j] for j, i in enumerate(order)]
        self.yaml_changed = True
        if not items:
            if "transitions" in st:
                del st["transitions"]
            return
        if ts is None:
            block = any(isinstance(e, CommentedMap) for e in items)
            st["transitions"] = CommentedSeq(items) if block else flow_seq(items)
            return
        comments = dict(ts.ca.items)
        del ts[:]
        ts.extend(items)
        ts.ca.items.clear()
        ts.ca.items.update({j: comments[i] for j, i in enumerate(order) if i is not None and i in comments})

    def reorder(self, source: str, order: list[int | None], new: Any = None, new_target: str = "") -> None:
        """`source`'s transitions in a new order (`rearrange`), each guard file with its
        transition (`place_guards`); `new`, the entry of the one new transition (None in
        `order`), goes to `new_target`."""
        entries = self.entries(source)
        old = self.guards(source)
        targets = [target_of(entries[i]) if i is not None else new_target for i in order]
        self.rearrange(source, order, {order.index(None): new} if None in order else None)
        self.place_guards(source, old, order, targets)

    def index(self, source: str, n: object) -> int:
        """Transition `n` of `source`, checked."""
        count = len(self.entries(source))
        if not isinstance(n, int) or isinstance(n, bool) or not 0 <= n < count:
            have = f"transitions 0 to {count - 1}" if count else "no transitions"
            raise EditError(f"{source} has {have}; there is no transition {n}")
        return n

    def inline_form(self, source: str) -> bool:
        """The guard form a new transition of `source` takes: the state's own if it has
        transitions, else the machine's (inline only where every guard is)."""
        mine = self.entries(source)
        pool = mine or [e for st in self.states for e in (st.get("transitions") or [])]
        return bool(pool) and all(is_inline(e) for e in pool)

    def new_entry(self, source: str, target: str, guard: str | None, inline: bool) -> Any:
        """A transition entry as machine.yaml writes it: a name, or `{to, guard}` inline."""
        if not inline:
            return target
        ts = self.by_name[source].get("transitions")
        flow = ts is not None and is_flow(ts)
        return new_map([("to", target), ("guard", guard)], flow)

    # -- guard files ------------------------------------------------------------------------
    def guards(self, source: str) -> dict[int, bytes | None]:
        """The guard files of `source`'s transitions, by position (None where there is none)."""
        return {i: self.read(guard_file(source, i)) for i in range(len(self.entries(source)))}

    def place_guards(
        self, source: str, old: dict[int, bytes | None], order: list[int | None], targets: list[str]
    ) -> None:
        """Each guard file to its transition's new position: `order[j]` is the old position of
        the transition now at j (None: a new one, whose file, if any, is written apart).  A file
        that moves starts with `# -> TARGET`; one that stays is left as it is."""
        for n in range(max(len(old), len(order))):
            if self.exists(guard_file(source, n)):
                self.write(guard_file(source, n), None)
        for j, i in enumerate(order):
            data = old.get(i) if i is not None else None
            if data is None:
                continue
            if i == j:
                self.write(guard_file(source, j), data)
            else:
                self.write(guard_file(source, j), with_header(_text(data, self.root), targets[j]))
        self.move_labels(source, order)

    # -- layout.yaml ------------------------------------------------------------------------
    def layout(self, create: bool = False) -> YamlDoc | None:
        """layout.yaml as a round-trip document (None without one, unless `create`)."""
        if self._layout is None:
            raw = self.read(LAYOUT_FILE)
            if raw is None and not create:
                return None
            text = _text(raw, self.root / LAYOUT_FILE) if raw is not None else ""
            try:
                self._layout = YamlDoc(text, LAYOUT_FILE)
            except EditError:
                if not create:
                    return None  # a broken layout.yaml is check's to report; structure edits go on
                raise
            if self._layout.data is None:
                self._layout.data = CommentedMap()
            if not isinstance(self._layout.data, CommentedMap):
                if not create:
                    return None
                raise EditError(f"{self.root / LAYOUT_FILE} is not a mapping; fix it first (llfsm check)")
        return self._layout

    def layout_section(self, key: str, create: bool = False) -> CommentedMap | None:
        doc = self.layout(create)
        if doc is None:
            return None
        section = doc.data.get(key)
        if not isinstance(section, CommentedMap):
            if not create:
                return None
            section = doc.data[key] = CommentedMap()
        return section

    def move_labels(self, source: str, order: list[int | None]) -> None:
        """Renumber the transition labels layout.yaml places for `source` after a reorder."""
        labels = self.layout_section("labels")
        mine = labels.get(source) if labels is not None else None
        if labels is None or not isinstance(mine, CommentedMap):
            return
        old = {int(k): v for k, v in mine.items() if str(k).isdigit()}
        moved = {j: old[i] for j, i in enumerate(order) if i is not None and i in old}
        if moved == old:
            return
        mine.clear()
        for j in sorted(moved):
            mine[j] = moved[j]
        if not mine:
            del labels[source]
        self.layout_changed = True

    def rename_in_layout(self, old: str, new: str | None) -> None:
        """A state's entries in layout.yaml under its new name (None: removed)."""
        for key in ("states", "labels"):
            section = self.layout_section(key)
            if section is None or old not in section:
                continue
            if new is None:
                del section[old]
            else:
                keys = list(section.keys())
                section.insert(keys.index(old), new, section.pop(old))
            self.layout_changed = True


def is_inline(entry: Any) -> bool:
    return isinstance(entry, CommentedMap) and "guard" in entry


def target_of(entry: Any) -> str:
    return str(entry.get("to")) if isinstance(entry, CommentedMap) else str(entry)


def _text(data: bytes, where: Path) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise EditError(f"{where} is not UTF-8 text; fix it first (llfsm check)") from None


def listing(root: Path) -> list[str]:
    try:
        return sorted(os.listdir(root))
    except OSError as e:
        raise EditError(f"{root}: cannot list: {e.strerror or e}") from None
