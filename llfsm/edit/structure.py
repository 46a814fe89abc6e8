"""The structure operations (SPEC 13): states and transitions added, renamed, moved, retargeted,
removed; guards, the initial and the suspend state set.  Each is a planner: it reads the machine
directory and returns a Change (llfsm.edit.change), or raises EditError with the one line the
user sees, having built no path from a name it has not checked.

Guards stay with their transitions: a transition's guard file is renamed with it when its
position changes (and starts with `# -> TARGET` once llfsm has written it), an inline guard
moves with its entry.  A new transition takes its state's guard form (or the machine's).
"""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Any

from ruamel.yaml.comments import CommentedMap
from ruamel.yaml.scalarstring import LiteralScalarString

from ..compiler.rewrite import apply as apply_edits
from ..lang.bindings import Edit
from ..lang.files import GUARD_RE, SECTION_RE, guard_file, header, header_target, state_files, with_header
from ..lang.positions import source_lines
from ..lang.reader import MAX_FILE_BYTES
from ..machinedir import machine_name_of
from .change import Change, EditError
from .plan import Plan, is_inline, listing, target_of

#: What a transition's guard is when none is given: it always fires (clfsm's editor's `true`).
DEFAULT_GUARD = "True"


def state_add(machine: Path, name: str, *, after: str | None = None) -> Change:
    """A new state with no transitions (an accepting one until it has some), after `after`
    (default: last)."""
    p = Plan(machine)
    name = p.fresh(name)
    pos = len(p.states) if after is None else p.states.index(p.state(after, "state")) + 1
    _refuse_files_of(p, name)
    entry = CommentedMap([("name", name)])
    _rearrange_states(p, [*range(pos), None, *range(pos, len(p.states))], entry)
    return p.change(f"added state {name}")


def state_rename(machine: Path, old: str, new: str) -> Change:
    """`old` becomes `new`: its entry, every transition that targets it, `initial` and
    `suspended`, its files, its places in layout.yaml, and state-name comparisons in code
    (`state_name() == "OLD"`)."""
    p = Plan(machine)
    st = p.state(old)
    new = p.fresh(new, "new name")
    _refuse_files_of(p, new)
    _rename_literals(p, old, new)
    st["name"] = new
    doc = p.yaml.data
    for key in ("initial", "suspended"):
        if doc.get(key) == old:
            doc[key] = new
    moved = {}
    for name, entry in list(p.by_name.items()):
        ts = entry.get("transitions") or []
        for j, e in enumerate(ts):
            if target_of(e) != old:
                continue
            if isinstance(e, CommentedMap):
                e["to"] = new
            else:
                ts[j] = new
            text = p.text(guard_file(name, j))
            if text is not None and header_target(text) == old:
                p.write(guard_file(name, j), with_header(text, new))
    for j in range(len(p.entries(old))):
        moved[guard_file(old, j)] = guard_file(new, j)
    for f in state_files(old):
        moved[f] = f.replace(f"State_{old}_", f"State_{new}_", 1)
    targets = [target_of(e) for e in p.entries(old)]
    for src, dst in moved.items():
        data = p.read(src)
        if data is not None:
            guard = GUARD_RE.match(dst)
            p.write(dst, with_header(p.text(src) or "", targets[int(guard["n"])]) if guard else data)
            p.write(src, None)
    p.by_name[new] = p.by_name.pop(old)
    p.rename_in_layout(old, new)
    p.yaml_changed = True
    change = p.change("")
    return Change(change.root, change.writes, change.before, f"renamed state {old} to {new} ({_files(change)})")


def state_remove(machine: Path, name: str) -> Change:
    """`name`, its files, and the transitions into it (the other guards renumbered with their
    transitions).  The initial state is refused."""
    p = Plan(machine)
    p.state(name)
    doc = p.yaml.data
    initial = doc.get("initial") or p.names[0]
    if initial == name:
        raise EditError(f"{name} is the initial state of {p.root.name}; make another state initial first")
    if doc.get("suspended") == name:
        del doc["suspended"]
    into = 0
    for other in p.names:
        if other == name:
            continue
        entries = p.entries(other)
        keep = [i for i, e in enumerate(entries) if target_of(e) != name]
        if len(keep) != len(entries):
            into += len(entries) - len(keep)
            p.reorder(other, list(keep))
    for j in range(len(p.entries(name))):
        p.write(guard_file(name, j), None)
    for f in state_files(name):
        p.write(f, None)
    _rearrange_states(p, [i for i, st in enumerate(p.states) if st is not p.by_name[name]])
    p.rename_in_layout(name, None)
    change = p.change("")
    extra = f" and {into} transition{'s' if into != 1 else ''} into it" if into else ""
    return Change(change.root, change.writes, change.before, f"removed state {name}{extra} ({_files(change)})")


def transition_add(
    machine: Path,
    source: str,
    target: str,
    *,
    guard: str | None = None,
    priority: int | None = None,
    inline: bool | None = None,
) -> Change:
    """A transition from `source` to `target` at `priority` (default: last, the lowest), its
    guard `guard` (default: True) in a file, or inline when `inline` (default: the form the
    state's guards, else the machine's, are written in)."""
    p = Plan(machine)
    p.state(source, "source state")
    p.state(target, "target state")
    entries = p.entries(source)
    n = len(entries)
    k = n if priority is None else _priority(priority, n + 1, source)
    text = _guard_text(DEFAULT_GUARD if guard is None else guard)
    form = p.inline_form(source) if inline is None else bool(inline)
    p.reorder(source, [*range(k), None, *range(k, n)], p.new_entry(source, target, _inline_value(text), form), target)
    if not form:
        p.write(guard_file(source, k), header(target) + text + "\n")
    return p.change(f"added transition {k} of {source} to {target}" + (" (guard inline)" if form else ""))


def transition_move(machine: Path, source: str, index: int, to_priority: int) -> Change:
    """Transition `index` of `source` to priority `to_priority`; its guard goes with it."""
    p = Plan(machine)
    p.state(source, "source state")
    entries = p.entries(source)
    i = p.index(source, index)
    k = _priority(to_priority, len(entries), source)
    order: list[int | None] = [j for j in range(len(entries)) if j != i]
    order.insert(k, i)
    p.reorder(source, order)
    return p.change(f"moved transition {i} of {source} (to {target_of(entries[i])}) to priority {k}")


def transition_retarget(machine: Path, source: str, index: int, target: str) -> Change:
    """Transition `index` of `source` goes to `target` instead; its guard stays."""
    p = Plan(machine)
    p.state(source, "source state")
    i = p.index(source, index)
    p.state(target, "target state")
    ts = p.by_name[source]["transitions"]
    was = target_of(ts[i])
    if isinstance(ts[i], CommentedMap):
        ts[i]["to"] = target
    else:
        ts[i] = target
    p.yaml_changed = True
    text = p.text(guard_file(source, i))
    if text is not None:
        p.write(guard_file(source, i), with_header(text, target))
    return p.change(f"transition {i} of {source} goes to {target} (was {was})")


def transition_remove(machine: Path, source: str, index: int) -> Change:
    """Transition `index` of `source` and its guard; the later ones move up with theirs."""
    p = Plan(machine)
    p.state(source, "source state")
    entries = p.entries(source)
    i = p.index(source, index)
    p.reorder(source, [j for j in range(len(entries)) if j != i])
    return p.change(f"removed transition {i} of {source} (to {target_of(entries[i])})")


def set_guard(machine: Path, source: str, index: int, guard: str) -> Change:
    """The guard of transition `index` of `source`, in the form it has (inline or file)."""
    p = Plan(machine)
    p.state(source, "source state")
    i = p.index(source, index)
    text = _guard_text(guard)
    entry = p.by_name[source]["transitions"][i]
    if is_inline(entry):
        entry["guard"] = _inline_value(text)
        p.yaml_changed = True
    else:
        p.write(guard_file(source, i), header(target_of(entry)) + text + "\n")
    return p.change(f"guard of transition {i} of {source} set")


def set_initial(machine: Path, state: str) -> Change:
    p = Plan(machine)
    p.state(state)
    _set_key(p, "initial", state, after=("description",))
    return p.change(f"{state} is the initial state")


def set_suspend(machine: Path, state: str | None) -> Change:
    """The suspend state (`suspended:`); None: none declared (a state named SUSPENDED, else an
    implicit empty one)."""
    p = Plan(machine)
    if state is None:
        if "suspended" in p.yaml.data:
            del p.yaml.data["suspended"]
            p.yaml_changed = True
        return p.change("no suspend state declared")
    p.state(state)
    _set_key(p, "suspended", state, after=("description", "initial"))
    return p.change(f"{state} is the suspend state")


def set_description(machine: Path, text: str | None) -> Change:
    """machine.yaml's `description:` (the editor's "Description"); None or blank removes it.
    Several lines are written as a literal block (`description: |`), as a person would."""
    if text is not None and (not isinstance(text, str) or "\0" in text):
        raise EditError("a description is text without NUL characters")
    p = Plan(machine)
    text = (text or "").strip()
    if not text:
        if "description" in p.yaml.data:
            del p.yaml.data["description"]
            p.yaml_changed = True
        return p.change("no description")
    _set_key(p, "description", LiteralScalarString(text + "\n") if "\n" in text else text, after=())
    return p.change("description written")


# -- helpers ----------------------------------------------------------------------------------------


def _files(change: Change) -> str:
    n = len(change.writes)
    return f"{n} file{'s' if n != 1 else ''}"


def _priority(value: object, count: int, source: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < count:
        raise EditError(f"priority {value} of {source} is out of range: 0 to {count - 1}")
    return value


def _guard_text(guard: object) -> str:
    if not isinstance(guard, str):
        raise EditError(f"a guard is text, not {type(guard).__name__}")
    if "\0" in guard or len(guard.encode("utf-8", "surrogatepass")) > MAX_FILE_BYTES:
        raise EditError("refused guard: it holds a NUL byte or is larger than 1 MiB")
    text = guard.strip("\n").rstrip()
    if not text.strip():
        raise EditError("a guard cannot be empty: write an expression, such as True or after_ms(100)")
    return text


def _inline_value(text: str) -> Any:
    """An inline guard's YAML value: a block (`|`) when it spans lines, so it reads as written."""
    return LiteralScalarString(text + "\n") if "\n" in text else text


def _set_key(p: Plan, key: str, value: str, after: tuple[str, ...]) -> None:
    doc: CommentedMap = p.yaml.data
    if key in doc:
        doc[key] = value
    else:
        keys = list(doc.keys())
        pos = max((keys.index(k) + 1 for k in after if k in keys), default=0)
        doc.insert(pos, key, value)
    p.yaml_changed = True


def _rearrange_states(p: Plan, order: list[int | None], new: Any = None) -> None:
    """machine.yaml's `states` in a new order (None: the new state), comments kept with theirs."""
    seq = p.states
    old = list(seq)
    comments = dict(seq.ca.items)
    del seq[:]
    seq.extend(old[i] if i is not None else new for i in order)
    seq.ca.items.clear()
    seq.ca.items.update({j: comments[i] for j, i in enumerate(order) if i is not None and i in comments})
    p.yaml_changed = True


def _refuse_files_of(p: Plan, name: str) -> None:
    """A new state's name must not adopt files already there (left by a state removed by hand)."""
    prefix = f"State_{name}_"
    for entry in listing(p.root):
        m = SECTION_RE.match(entry) or GUARD_RE.match(entry)
        if entry.startswith(prefix) and m is not None and m["state"] == name:
            raise EditError(f"{p.root / entry} already exists (it belongs to no state); move it away first")


def _rename_literals(p: Plan, old: str, new: str) -> None:
    """`state_name() == "OLD"` (and `!=`, `in (...)`; `state_name_of("THIS_MACHINE")` alike) in
    the machine's code and inline guards, with the new name: found on the `ast`, written at its
    exact place (a string that is not compared with a state name is left alone)."""
    machine = machine_name_of(p.root)
    for entry in listing(p.root):
        if not (SECTION_RE.match(entry) or GUARD_RE.match(entry)):
            continue
        text = p.text(entry)
        if text is not None and old in text:
            changed = _renamed(text, old, new, machine)
            if changed != text:
                p.write(entry, changed)
    for st in p.states:
        for e in st.get("transitions") or []:
            if is_inline(e) and isinstance(e["guard"], str) and old in e["guard"]:
                changed = _renamed(str(e["guard"]), old, new, machine)
                if changed != str(e["guard"]):
                    e["guard"] = _inline_value(changed.rstrip("\n"))
                    p.yaml_changed = True


def _renamed(text: str, old: str, new: str, machine: str) -> str:
    try:
        tree = ast.parse(text)
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return text  # check reports it; nothing is rewritten in code that does not parse
    edits = []
    lines = source_lines(text)
    for node in ast.walk(tree):
        if not isinstance(node, ast.Compare):
            continue
        sides = [node.left, *node.comparators]
        if not any(_names_a_state(s, machine) for s in sides):
            continue
        for s in sides:
            for c in s.elts if isinstance(s, ast.Tuple | ast.List | ast.Set) else [s]:
                if not (isinstance(c, ast.Constant) and c.value == old and c.end_col_offset is not None):
                    continue
                raw = lines[c.lineno - 1].encode("utf-8")[c.col_offset : c.end_col_offset]
                if c.lineno == c.end_lineno and raw in (f'"{old}"'.encode(), f"'{old}'".encode()):
                    quote = raw[:1].decode()
                    edits.append(Edit(c.lineno, c.col_offset, c.end_col_offset, f"{quote}{new}{quote}"))
    return apply_edits(text, edits)


def _names_a_state(node: ast.AST, machine: str) -> bool:
    """`state_name()`, or `state_name_of("M")` of this machine."""
    if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Name):
        return False
    if node.func.id == "state_name" and not node.args:
        return True
    return (
        node.func.id == "state_name_of"
        and len(node.args) == 1
        and isinstance(node.args[0], ast.Constant)
        and node.args[0].value == machine
    )
