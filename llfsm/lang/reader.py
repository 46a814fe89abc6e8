"""Read a machine directory into a `Machine` model, with a diagnostic for what cannot be read.

The reader looks at bytes, YAML nodes and `ast` trees only; it never imports or runs user code,
because `llfsm check` runs on untrusted pull requests.  Whatever it is given (binary files,
alias bombs, deep nesting, symlinks out of the directory), it returns diagnostics, never raises.

sources.py reads the directory's files and parses their Python (`_Files`); this module reads
machine.yaml on top of it (`_Reader`) and makes the model.
"""

from __future__ import annotations

import ast
import os
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from .. import yamlfile
from ..machinedir import LAYOUT_FILE, machine_name_of, refused_link
from .diagnostics import Diagnostic, diag
from .files import GUARD_RE, SECTION_RE, guard_file
from .model import (
    IMPLICIT_SUSPENDED,
    SECTIONS,
    Code,
    Input,
    Loc,
    Machine,
    MachineParameter,
    State,
    Transition,
    Variable,
)
from .sources import MAX_CODE_DEPTH, MAX_FILE_BYTES, _Files

__all__ = [  # with the limits sources.py holds, still named here
    "INPUT_KEYS",
    "MAX_CODE_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_YAML_DEPTH",
    "YAML_LOADER",
    "ReadResult",
    "compose",
    "read_machine",
    "structure_refusal",
]

MAX_YAML_DEPTH = 32
#: libyaml's C parser when PyYAML has it (about ten times faster), else the pure-Python one.
YAML_LOADER = yamlfile.LOADER


@dataclass
class ReadResult:
    """What the reader could make of a directory.  `machine` is None when machine.yaml is unusable."""

    path: Path
    machine: Machine | None
    diagnostics: list[Diagnostic] = field(default_factory=list)
    trees: dict[str, ast.Module] = field(default_factory=dict)  # file name -> parsed code
    orphans: list[str] = field(default_factory=list)  # state code files matching no state
    #: file name -> the bytes read (a build fingerprints them without reading them again)
    raw: dict[str, bytes] = field(default_factory=dict)
    #: the inline guards, by the name their file would have (the key of their tree in `trees`)
    inline: dict[str, Code] = field(default_factory=dict)
    #: layout.yaml's text, if the directory has one (llfsm.lang.layout_file reads it; a build never)
    layout_text: str | None = None


class _Reader(_Files):
    # -- yaml ----------------------------------------------------------------------------
    def yaml_tree(self, text: str) -> yaml.Node | None:
        node, refusal = compose(text)
        if refusal is not None:
            self.report(refusal[0], "machine.yaml", refusal[1], refusal[2], refusal[3])
        return node

    def structure_error(self, node: yaml.Node | None, msg: str) -> None:
        line, col = (node.start_mark.line + 1, node.start_mark.column + 1) if node is not None else (1, 1)
        self.report("LF004", "machine.yaml", line, col, msg)

    def mapping(self, node: yaml.Node, what: str, keys: tuple[str, ...]) -> dict[str, yaml.Node] | None:
        if not isinstance(node, yaml.MappingNode):
            self.structure_error(node, f"{what} must be a mapping")
            return None
        out: dict[str, yaml.Node] = {}
        for k, v in node.value:
            if not isinstance(k, yaml.ScalarNode):
                self.structure_error(k, f"keys of {what} must be plain words")
                continue
            if k.value not in keys:
                self.structure_error(k, f"unknown key `{k.value}` in {what} (expected one of: {', '.join(keys)})")
                continue
            if k.value in out:
                self.structure_error(k, f"duplicate key `{k.value}` in {what}")
                continue
            out[k.value] = v
        return out

    def scalar(self, node: yaml.Node | None, what: str) -> str | None:
        """The text of a scalar as written (so `ON` stays the name ON); None for null or missing."""
        if node is None:
            return None
        if not isinstance(node, yaml.ScalarNode):
            self.structure_error(node, f"{what} must be a single word, not a {_kind(node)}")
            return None
        if not node.style and node.value in ("", "~"):
            return None  # `initial:` left empty means the default; `null` is a name like any other
        return str(node.value)

    # -- the whole directory ---------------------------------------------------------------
    def run(self) -> ReadResult:
        name = machine_name_of(self.path)
        result = ReadResult(self.path, None, self.diags, self.trees, raw=self.raw, inline=self.inline)
        refused = refused_link(self.path)
        if refused is not None:  # the directory itself: nothing in it is read
            self.diags.append(diag("LF037", self.path, 1, 1, refused))
            return result
        if not (self.path / "machine.yaml").exists() and not (self.path / "machine.yaml").is_symlink():
            self.report("LF001", "machine.yaml", 1, 1, f"{self.path} has no machine.yaml")
            return result
        text = self.read("machine.yaml")
        if text is None:
            return result
        if not text.strip():
            self.structure_error(None, "machine.yaml is empty: it needs at least a `states` list")
            return result
        root = self.yaml_tree(text)
        if root is None:
            return result
        self.yaml_lines = text.split("\n")
        top = self.mapping(
            root, "machine.yaml", ("description", "initial", "suspended", "states", "inputs", "parameters")
        )
        if top is None:
            return result
        states_node = top.get("states")
        if states_node is None:
            self.structure_error(root, "machine.yaml has no `states` list")
            return result
        if not isinstance(states_node, yaml.SequenceNode) or not states_node.value:
            self.structure_error(states_node, "`states` must be a non-empty list of states")
            return result

        try:
            entries = sorted(os.listdir(self.path))
        except OSError as e:
            self.report("LF002", ".", 1, 1, f"cannot list {self.path}: {e.strerror or e}")
            return result
        entry_set = set(entries)

        states: list[State] = []
        for snode in states_node.value:
            fields = self.mapping(snode, "a state", ("name", "transitions"))
            if fields is None:
                continue
            if "name" not in fields:
                self.structure_error(snode, "every state needs a `name`")
                continue
            sname = self.scalar(fields["name"], "a state name")
            if sname is None:
                if isinstance(fields["name"], yaml.ScalarNode):
                    self.structure_error(fields["name"], "a state name cannot be empty")
                continue
            sloc = _mark_loc(fields["name"])
            targets: list[_Target] = []
            tnode = fields.get("transitions")
            if tnode is not None and not (isinstance(tnode, yaml.ScalarNode) and tnode.tag.endswith("null")):
                if not isinstance(tnode, yaml.SequenceNode):
                    self.structure_error(tnode, f"`transitions` of {sname} must be a list of state names")
                else:
                    for position, t in enumerate(tnode.value):
                        target = self.transition(sname, position, t)
                        if target is not None:
                            targets.append(target)
            states.append(self.state(sname, sloc, targets, entry_set))

        if not states:
            return result
        names = [s.name for s in states]
        initial = self.scalar(top.get("initial"), "`initial`") or names[0]
        suspended = self.scalar(top.get("suspended"), "`suspended`")
        if suspended is None:
            suspended = IMPLICIT_SUSPENDED
            if IMPLICIT_SUSPENDED not in names:
                # not declared, but its State_SUSPENDED_* files (OnEntry, OnResume...) still count
                implicit = self.state(IMPLICIT_SUSPENDED, Loc(file="machine.yaml"), [], entry_set)
                states.append(implicit.model_copy(update={"implicit": True}))
        description = None
        if "description" in top:
            d = top["description"]
            description = d.value if isinstance(d, yaml.ScalarNode) else None
            if description is None:
                self.structure_error(d, "`description` must be text")

        inputs = self.inputs(top["inputs"]) if "inputs" in top else []
        if LAYOUT_FILE in entry_set:
            result.layout_text = self.read(LAYOUT_FILE)
            self.raw.pop(LAYOUT_FILE, None)  # no part of the build's fingerprint
        includes = self.code_file("Includes.py", entry_set)
        variables, variables_file = self.variables("Variables.py") if "Variables.py" in entry_set else ([], None)

        # transitions per state (the first of duplicates): linear in files plus transitions
        counts: dict[str, int] = {}
        for s in states:
            counts.setdefault(s.name, len(s.transitions))
        for entry in entries:
            m = SECTION_RE.match(entry) or GUARD_RE.match(entry)
            if m and m["state"] not in counts:
                result.orphans.append(entry)
            elif m and "n" in m.groupdict():
                n, count = m["n"], counts[m["state"]]
                # `Transition_01` is no transition's file; int() of a long digit string raises
                if (n != "0" and n.startswith("0")) or len(n) > len(str(count)) or int(n) >= count:
                    result.orphans.append(entry)

        result.machine = Machine(
            name=name,
            path=self.path,
            description=description,
            initial=initial,
            suspended=suspended,
            states=states,
            includes=includes,
            variables=variables,
            variables_file=variables_file,
            inputs=inputs,
            initial_loc=_mark_loc(top["initial"]) if "initial" in top else Loc(file="machine.yaml"),
            suspended_loc=_mark_loc(top["suspended"]) if "suspended" in top else Loc(file="machine.yaml"),
            parameters=self.parameters(top.get("parameters")),
        )
        return result

    def transition(self, state: str, position: int, node: yaml.Node) -> _Target | None:
        """An entry of `transitions:`: a target's name, or `{to: TARGET, guard: EXPR}`."""
        guard = None
        if isinstance(node, yaml.MappingNode):
            keys = self.mapping(node, f"transition {position} of {state}", ("to", "guard"))
            if keys is None:
                return None
            if "to" not in keys:
                self.structure_error(node, f"transition {position} of {state} needs `to:`, the state it goes to")
                return None
            guard = keys.get("guard")
            if guard is not None and not isinstance(guard, yaml.ScalarNode):
                self.structure_error(guard, f"the guard of transition {position} of {state} must be text")
                return None
            if guard is not None and not guard.value.strip():
                self.structure_error(
                    guard,
                    f"the guard of transition {position} of {state} is empty: write an expression, or leave "
                    f"`guard` out and write it in {guard_file(state, position)}",
                )
                return None
            node = keys["to"]
        tname = self.scalar(node, "a transition target")
        if tname is None:
            if isinstance(node, yaml.ScalarNode):  # `[~, END]`: never dropped in silence
                self.structure_error(
                    node, f"transition {position} of {state} has no target (`~` or empty); name a state"
                )
            return None
        return tname, _mark_loc(node), guard

    def inline_guard(self, state: str, index: int, node: yaml.ScalarNode) -> Code:
        """An inline guard as a Code under its file's name, with where its text is in machine.yaml."""
        name = guard_file(state, index)
        start, end = node.start_mark, node.end_mark
        origin = Loc(file="machine.yaml", line=start.line + 1, column=start.column + 1)
        block_column = None
        exact = False
        if node.style in ("|", ">"):
            # the text starts on the line after the indicator, at the block's indentation
            below = self.yaml_lines[start.line + 1] if start.line + 1 < len(self.yaml_lines) else ""
            column = len(below) - len(below.lstrip(" ")) + 1
            origin = Loc(file="machine.yaml", line=start.line + 2, column=column)
            block_column = column if node.style == "|" else None  # `>` folds lines: only the start is sure
        elif start.line == end.line:
            quoted = node.style in ("'", '"')
            raw = self.yaml_lines[start.line][start.column : end.column] if start.line < len(self.yaml_lines) else ""
            inner = raw[1:-1] if quoted else raw
            exact = inner == node.value
            if quoted:
                origin = Loc(file="machine.yaml", line=origin.line, column=origin.column + 1)
        code = Code(
            file=name, text=node.value, loc=Loc(file=name), origin=origin, block_column=block_column, exact=exact
        )
        self.inline[name] = code
        return code

    def inputs(self, node: yaml.Node) -> list[Input]:
        """`inputs:`, a mapping of input name to its keys.  What the keys say (types, values,
        bindings) is judged by the checker (llfsm.lang.check.inputs); here only the shape."""
        if isinstance(node, yaml.ScalarNode) and node.tag.endswith("null"):
            return []
        if not isinstance(node, yaml.MappingNode):
            self.structure_error(node, "`inputs` must be a mapping of input names to their type, default...")
            return []
        out: list[Input] = []
        seen: set[str] = set()
        for knode, value in node.value:
            key = self.scalar(knode, "an input name")
            if key is None:
                continue
            if key in seen:
                self.structure_error(knode, f"input {key} is declared twice")
                continue
            seen.add(key)
            keys = self.mapping(value, f"input {key}", INPUT_KEYS)
            if keys is None:
                continue
            if "type" not in keys:
                self.structure_error(value, f"input {key} needs a `type` (bool, int, float or str)")
                continue
            values: dict[str, object] = {}
            for k, vnode in keys.items():
                if k == "domain":
                    if not isinstance(vnode, yaml.SequenceNode):
                        self.structure_error(vnode, f"`domain` of input {key} must be a list of values")
                        continue
                    items = [self.value(item, f"a value of the domain of {key}") for item in vnode.value]
                    if all(v is not _NOT_A_SCALAR for v in items):
                        values[k] = items
                elif k == "default":
                    v = self.value(vnode, f"the default of {key}")
                    if v is not _NOT_A_SCALAR:
                        values[k] = v
                else:
                    text = self.scalar(vnode, f"`{k}` of input {key}")
                    if text is not None:
                        values[k] = text
            if "type" not in values:
                continue
            locs = {k: _mark_loc(v) for k, v in keys.items()}
            try:
                out.append(Input(name=key, loc=_mark_loc(knode), locs=locs, **values))  # type: ignore[arg-type]
            except ValueError:  # a value that is not a bool, number or string (a date, null...)
                self.structure_error(value, f"input {key}: default and domain hold booleans, numbers or strings")
        return out

    def value(self, node: yaml.Node, what: str) -> object:
        """A scalar as YAML types it (`false` a bool, `1.5` a float, `"1"` a string)."""
        if not isinstance(node, yaml.ScalarNode):
            self.structure_error(node, f"{what} must be a single value, not a {_kind(node)}")
            return _NOT_A_SCALAR
        try:
            value = yaml.constructor.SafeConstructor().construct_object(node)
        except (yaml.YAMLError, ValueError, OverflowError):
            self.structure_error(node, f"{what} is not a value YAML can read")
            return _NOT_A_SCALAR
        if not isinstance(value, bool | int | float | str):
            self.structure_error(node, f"{what} must be a boolean, a number or a string")
            return _NOT_A_SCALAR
        return value

    def parameters(self, node: yaml.Node | None) -> list[MachineParameter]:
        """`parameters:`, a list of variable names, each with where it is written (check's rule
        module `parameters` says whether each is a variable that can be one)."""
        if node is None or (isinstance(node, yaml.ScalarNode) and not node.style and node.value in ("", "~")):
            return []
        if not isinstance(node, yaml.SequenceNode):
            self.structure_error(node, "`parameters` must be a list of machine variable names")
            return []
        out = []
        for item in node.value:
            name = self.scalar(item, "a parameter")
            if name is not None:
                out.append(MachineParameter(name=name, loc=_mark_loc(item)))
            elif isinstance(item, yaml.ScalarNode):
                self.structure_error(item, "an entry of `parameters` is empty; name a machine variable")
        return out

    def state(self, name: str, loc: Loc, targets: list[_Target], entries: set[str]) -> State:
        sections: dict[str, Code] = {}
        for sec in SECTIONS:
            code = self.code_file(f"State_{name}_{sec}.py", entries)
            if code is not None:
                sections[sec] = code
        variables: list[Variable] = []
        variables_file = None
        vname = f"State_{name}_Variables.py"
        if vname in entries:
            variables, variables_file = self.variables(vname)
        transitions = []
        for i, (target, tloc, inline) in enumerate(targets):
            fname = guard_file(name, i)
            if inline is None:
                guard = self.code_file(fname, entries)
            else:
                guard = self.inline_guard(name, i, inline)
                self.parse(fname, guard.text)
            file_too = inline is not None and fname in entries
            transitions.append(Transition(index=i, target=target, guard=guard, loc=tloc, file_too=file_too))
        return State(
            name=name,
            transitions=transitions,
            sections=sections,
            variables=variables,
            variables_file=variables_file,
            loc=loc,
        )


#: A transition as machine.yaml names it: its target, where, and its inline guard's node if any.
_Target = tuple[str, Loc, yaml.ScalarNode | None]

#: The keys of an input under `inputs:` (SPEC 11, docs/machine-format.md).
INPUT_KEYS = ("type", "default", "domain", "topic", "msg", "field")
_NOT_A_SCALAR = object()


def read_machine(path: str | Path) -> ReadResult:
    """Read one machine directory.  Never raises for anything the directory holds."""
    return _Reader(Path(path)).run()


# -- helpers ---------------------------------------------------------------------------------


def _mark_loc(node: yaml.Node) -> Loc:
    return Loc(file="machine.yaml", line=node.start_mark.line + 1, column=node.start_mark.column + 1)


def _kind(node: yaml.Node) -> str:
    return {"MappingNode": "mapping", "SequenceNode": "list"}.get(type(node).__name__, "value")


_Refusal = tuple[str, int, int, str]


#: machine.yaml's words for what llfsm.yamlfile refuses: (rule, message).
_YAML_WORDS = {
    "alias": ("LF005", "anchors and aliases are not allowed in machine.yaml"),
    "depth": ("LF004", f"machine.yaml nests deeper than {MAX_YAML_DEPTH} levels"),
    "syntax": ("LF003", "invalid YAML: {detail}"),
}


def compose(text: str, loader: type | None = None) -> tuple[yaml.Node | None, _Refusal | None]:
    """The YAML tree of `text` (machine.yaml, layout.yaml), or None and why (llfsm.yamlfile:
    anchors, aliases and deep nesting refused before a tree is built, the library's own limits,
    LF003 where the text stops being YAML).  `loader`: YAML_LOADER, as it is when called."""
    try:
        return yamlfile.compose(text, MAX_YAML_DEPTH, loader or YAML_LOADER), None
    except yamlfile.Refused as e:
        return None, _refusal(e)


def structure_refusal(text: str, loader: type) -> _Refusal | None:
    """(code, line, column, message) when machine.yaml uses anchors or nests too deep, found on
    the event stream, before any tree is built; yaml.YAMLError where it is not YAML."""
    found = yamlfile.scan(text, MAX_YAML_DEPTH, loader)
    return None if found is None else _refusal(found)


def _refusal(e: yamlfile.Refused) -> _Refusal:
    code, message = _YAML_WORDS[e.kind]
    return code, e.line, e.column, message.format(detail=e.detail)
