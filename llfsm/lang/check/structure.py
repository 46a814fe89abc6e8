"""Rules on the machine's shape: its directory's name, its states and transitions as
machine.yaml declares them, the shape of each guard, the files that belong to nothing, which
states can be reached, and the suspend state (LF010-LF014, LF020-LF024, LF101-LF104, LF107).
"""

from __future__ import annotations

import ast

from ...machinedir import MACHINE_SUFFIX, machine_name_of
from ..files import guard_file, header_target
from ..layout_file import placement
from ..model import MAX_MACHINE_NAME, Code, Machine, State, is_valid_name
from ..positions import node_col
from .checking import Checking
from .scan import guard_semicolon


def machine_name(c: Checking) -> None:
    """LF010, LF014: the directory is NAME.machine, NAME an identifier short enough for a build."""
    name = machine_name_of(c.path)
    if not c.path.name.endswith(MACHINE_SUFFIX):
        c.add(
            "LF010",
            "machine.yaml",
            1,
            1,
            f"the directory {c.path.name!r} must be named NAME.machine (NAME is the machine's name)",
        )
    elif not is_valid_name(name):
        c.add("LF010", "machine.yaml", 1, 1, f"machine name {name!r} must be a Python identifier and not a keyword")
    elif len(name) > MAX_MACHINE_NAME:
        c.add(
            "LF014",
            "machine.yaml",
            1,
            1,
            f"machine name {name[:20]}... is {len(name)} characters long; at most {MAX_MACHINE_NAME} "
            "fit the file names a build writes",
        )


def states(c: Checking, m: Machine) -> None:
    """LF011, LF012, LF020-LF022, and each transition's guard (`guard`), in the order declared."""
    seen: dict[str, State] = {}
    names = {s.name for s in m.states}
    declared = [s.name for s in m.states if not s.implicit]  # what "did you mean" offers
    for s in m.states:
        if s.implicit:
            continue
        if not is_valid_name(s.name):
            c.at("LF011", s.loc, f"state name {s.name!r} must be a Python identifier and not a keyword")
        if s.name in seen:
            c.at("LF012", s.loc, f"state {s.name} is declared twice (first at line {seen[s.name].loc.line})")
        else:
            seen[s.name] = s
        for t in s.transitions:
            if t.target not in names:
                c.at(
                    "LF020",
                    t.loc,
                    f"transition {t.index} of {s.name} goes to unknown state {t.target!r}"
                    + c.suggest.did_you_mean(t.target, declared),
                )
            guard(c, s, t.index, t.guard)
    if m.initial not in names:
        c.at(
            "LF021",
            m.initial_loc,
            f"initial state {m.initial!r} is not a state of this machine" + c.suggest.did_you_mean(m.initial, declared),
        )
    if m.suspended not in names:
        c.at(
            "LF022",
            m.suspended_loc,
            f"suspend state {m.suspended!r} is not a state of this machine"
            + c.suggest.did_you_mean(m.suspended, declared),
        )


def guard(c: Checking, s: State, index: int, code: Code | None) -> None:
    """LF023, LF024: a guard exists (in its file or inline) and is one expression; LF070: not
    in both places; LF071: its file's `# -> TARGET` names its target; LF103, LF104: constant
    guards."""
    t = s.transitions[index]
    fname = guard_file(s.name, index)
    if code is None:
        if fname not in c.read.trees and fname not in c.unreadable:
            c.at(
                "LF023",
                t.loc,
                f"transition {index} of {s.name} has no guard: write it in {fname}, "
                f"or inline in machine.yaml (`{{to: {t.target}, guard: EXPR}}`)",
            )
        return
    if t.file_too:
        c.at(
            "LF070",
            code.origin or t.loc,
            f"the guard of transition {index} of {s.name} is written twice, here and in {fname}; keep one "
            "(delete the file, or the inline `guard:`)",
        )
    if not code.inline:
        named = header_target(code.text)
        if named is not None and named != t.target:
            col = code.text.index(named) + 1
            c.add(
                "LF071",
                fname,
                1,
                col,
                f"{fname} says `# -> {named}` but transition {index} of {s.name} goes to {t.target}: was "
                "`transitions:` reordered by hand? Each guard file stays at its position; move it with its "
                "transition (`llfsm transition move`), or correct the comment",
            )
    what_guard = f"the guard of transition {index} of {s.name}" if code.inline else f"guard {fname}"
    tree = c.read.trees.get(fname)
    if tree is None:
        return  # a syntax error, already reported
    if len(tree.body) != 1 or not isinstance(tree.body[0], ast.Expr):
        where = tree.body[1] if len(tree.body) > 1 else (tree.body[0] if tree.body else None)
        line, col = (where.lineno, node_col(code.text, where)) if where is not None else (1, 1)
        what = "is empty" if not tree.body else "must be exactly one Python expression"
        c.add("LF024", fname, line, col, f"{what_guard} {what}, such as `after_ms(500)`")
        return
    expr = tree.body[0].value
    if isinstance(expr, ast.Tuple):
        # `a, b` is always true, and `if a, b:` is not even Python
        c.add(
            "LF024",
            fname,
            expr.lineno,
            node_col(code.text, expr),
            f"{what_guard} is a tuple, which is always true; join conditions with `and` or `or`",
        )
        return
    semicolon = guard_semicolon(code.text)
    if semicolon is not None:
        c.add("LF024", fname, *semicolon, f"{what_guard} must be one expression, without `;`")
        return
    if isinstance(expr, ast.Constant):
        if not expr.value:
            if "# UNTRANSLATED" not in code.text:  # `llfsm import`'s stand-in: LF080 says it once
                c.add("LF103", fname, 1, 1, f"{what_guard} is always false: transition {index} never fires")
        elif s.name not in c.always_true:  # the first true guard silences all later ones
            c.always_true.add(s.name)
            for later in s.transitions[index + 1 :]:
                c.add(
                    "LF104",
                    "machine.yaml",
                    later.loc.line,
                    later.loc.column,
                    f"transition {later.index} of {s.name} is never evaluated: "
                    f"transition {index} before it is always true",
                )


def layout(c: Checking, m: Machine) -> None:
    """LF073: layout.yaml is not of its form (at its line); LF072: it places a state or a
    transition label the machine does not have (left from a rename or a removal by hand)."""
    placed, problems = placement(c.read)
    c.diagnostics.extend(problems)
    if placed is None:
        return
    states = {s.name: s for s in m.states if not s.implicit}
    for name, loc in placed.state_locs.items():
        if name not in states:
            c.at("LF072", loc, f"layout.yaml places state {name}, which the machine does not have; it is ignored")
    for (name, index), loc in placed.label_locs.items():
        if name not in states or index >= len(states[name].transitions):
            c.at(
                "LF072",
                loc,
                f"layout.yaml places the label of transition {index} of {name}, which the machine does not have; "
                "it is ignored",
            )


def orphans(c: Checking) -> None:
    """LF101: state code files that match no state or transition of machine.yaml."""
    for orphan in c.read.orphans:
        c.add("LF101", orphan, 1, 1, f"{orphan} belongs to no state or transition of machine.yaml; it is ignored")


def reachability(c: Checking, m: Machine) -> None:
    """LF102: states no path of transitions leads to from the initial state.  A misspelt
    target (already LF020) is followed to the state it was meant for, so that one typo gives
    one diagnostic rather than one more for each state behind it."""
    names = {s.name: s for s in m.states}
    if m.initial not in names:
        return
    seen = {m.initial}
    todo = [m.initial]
    meant: dict[str, str | None] = {}  # a misspelt target -> the state it was meant for
    while todo:
        for t in names[todo.pop()].transitions:
            target: str | None = t.target
            if target not in names:  # already LF020: follow it where it was meant to go
                if t.target not in meant:
                    close = c.suggest.close(t.target, names)
                    meant[t.target] = close[0] if close else None
                target = meant[t.target]
            if target is not None and target not in seen:
                seen.add(target)
                todo.append(target)
    for s in m.states:
        if s.name not in seen and s.name != m.suspended and not s.implicit:
            c.at("LF102", s.loc, f"state {s.name} cannot be reached from the initial state {m.initial}")


def suspend_state(c: Checking, m: Machine) -> None:
    """LF107: a suspended machine gets no ringlets and leaves by OnResume: some of its code never runs."""
    s = next((s for s in m.states if s.name == m.suspended), None)
    if s is None:
        return
    for t in s.transitions:
        c.at(
            "LF107",
            t.loc,
            f"transition {t.index} of the suspend state {s.name} never fires: a "
            "suspended machine gets no ringlets; resume() or restart() moves it on",
        )
    for sec in ("Internal", "OnExit", "OnSuspend"):
        if sec in s.sections and not s.sections[sec].is_empty:
            c.add(
                "LF107",
                s.sections[sec].file,
                1,
                1,
                f"{sec} of the suspend state {s.name} never runs "
                "(a suspended machine gets no ringlets and leaves it through OnResume)",
            )
