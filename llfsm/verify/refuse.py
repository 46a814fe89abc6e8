"""What verify refuses to explore, found before exploring, from the machines' text alone
(docs/verify.md, "What verify refuses"; docs/rules.md, LF200-LF203).

Exploring runs the compiled ringlets on snapshots, many times over and in any order, so code
whose effect depends on the world rather than on the configuration would make the explored
structure a fiction: randomness, the wall clock, files and the terminal, threads, reads of the
bus (subscriptions, services, spin calls, timers with callbacks), parameters.  Each place is one
diagnostic with its file and line and the advice to make what it reads an input.  The list is
of what llfsm knows to read the world; a helper module of the user's, imported by Includes.py,
is not looked into (docs/verify.md says so).

The same pass reads each state's `after*` thresholds (`cuts`): the constants its guards and
sections name, which cut the time spent in the state into the intervals abstract time explores.
A threshold that is not a constant number is refused (LF201) in both time modes: with one, no
finite set of intervals (nor a cap on the time kept) is known to be enough.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..lang.diagnostics import Diagnostic, diag
from ..lang.model import Code, Machine
from ..lang.positions import node_col

#: after* and the run clock's units per argument unit (as llfsm.runtime.machine computes them).
AFTER_SCALE = {"after": 1_000_000_000, "after_ms": 1_000_000, "after_us": 1_000}

_INPUT_ADVICE = "make what it reads an input (`inputs:` in machine.yaml, bound to a topic at run time)"
_ENVIRONMENT_ADVICE = (
    ', or declare the service or topic under `environment:` in a verification file (docs/verify.md, "The environment")'
)

#: Modules whose every use reads the world (imported by Includes.py or in a section).
_MODULES: dict[str, str] = {
    "random": "randomness",
    "secrets": "randomness",
    "uuid": "randomness",
    "time": "the wall clock",
    "datetime": "the wall clock",
    "threading": "a thread",
    "_thread": "a thread",
    "multiprocessing": "another process",
    "concurrent": "a thread",
    "asyncio": "an event loop",
    "subprocess": "another process",
    "socket": "the network",
    "select": "the network",
    "selectors": "the network",
    "signal": "a signal",
    "urllib": "the network",
    "http": "the network",
    "requests": "the network",
    "pathlib": "a file",
    "shutil": "a file",
    "tempfile": "a file",
    "glob": "a file",
    "sqlite3": "a file",
    "fileinput": "a file",
}

#: Builtins that read the world or run text as code.
_BUILTINS: dict[str, str] = {
    "open": "a file",
    "input": "the terminal",
    "eval": "text run as code",
    "exec": "text run as code",
    "compile": "text run as code",
    "__import__": "an import at run time",
    "breakpoint": "the debugger",
}

#: Attributes of `os` and `sys` that read the world (other uses, `os.path.join`, are fine).
_OS: dict[str, str] = {
    name: "the environment or a file"
    for name in (
        "environ", "getenv", "urandom", "listdir", "scandir", "stat", "lstat", "getcwd", "times", "getpid",
        "read", "open", "system", "popen", "walk", "exists", "isfile", "isdir", "getmtime", "getsize", "fork",
        "kill", "getrandom", "stdin", "argv", "cpu_count", "getloadavg",
    )
}  # fmt: skip

#: Methods and attributes of the bus that read it, wait on it, or run callbacks verify never runs.
_BUS: dict[str, str] = {
    "create_subscription": "a subscription, what arrives on a topic",
    "create_client": "a service client, what a server answers",
    "create_service": "a service, its callback runs when a peer calls",
    "create_timer": "a timer, its callback runs between rounds",
    "take": "a message taken from a subscription",
    "latest": "the newest message of a subscription",
    "spin": "a spin call, callbacks, waiting",
    "spin_once": "a spin call, callbacks, waiting",
    "spin_until_future_complete": "a spin call, callbacks, waiting",
    "call_async": "a service call",
    "call": "a service call",
    "wait_for_service": "a wait for a server",
    "service_is_ready": "whether a server is up",
    "get_subscription_count": "how many subscribers there are",
    "get_publisher_count": "how many publishers there are",
    "get_clock": "the run clock",
    "declare_parameter": "a parameter, set from outside",
    "declare_parameters": "a parameter, set from outside",
    "get_parameter": "a parameter, set from outside",
    "get_parameters": "a parameter, set from outside",
    "get_parameter_or": "a parameter, set from outside",
    "has_parameter": "a parameter, set from outside",
    "add_on_set_parameters_callback": "a parameter callback",
    # actions (llfsm.ros.action): goals, feedback and results come from a peer
    "ActionClient": "an action client, what a server answers",
    "ActionServer": "an action server, goals a peer sends",
    "send_goal_async": "an action goal, what a server answers",
    "send_goal": "an action goal, what a server answers",
    "server_is_ready": "whether an action server is up",
    "wait_for_server": "a wait for an action server",
    "get_result_async": "an action result, what a server answers",
    "get_result": "an action result, what a server answers",
    "cancel_goal_async": "an action cancel, what a server answers",
    "cancel_goal": "an action cancel, what a server answers",
}

#: Classes of the bus whose objects read the world: refused where they are called (`ros.ActionClient(...)`,
#: `ActionClient(...)`), not where they annotate a variable (`client: ros.ActionClient`).
_BUS_CLASSES = ("ActionClient", "ActionServer")

#: Sections whose after* verify follows: those that run in a ringlet of the state itself.
_TIMED_SECTIONS = ("OnEntry", "Internal", "OnExit")


@dataclass
class Refusals:
    """What the static pass found for one machine: its diagnostics, and per state index the
    sorted cut points (ns, integers >= 0) of its after* thresholds."""

    diagnostics: list[Diagnostic] = field(default_factory=list)
    cuts: list[tuple[int, ...]] = field(default_factory=list)


def refusals(m: Machine, trees: dict[str, ast.Module], path: Path, environment: Any = None) -> Refusals:
    """LF200, LF201, LF202 for one machine (a model the checker passed, with its trees); what
    `environment` (llfsm.props.file.Environment) declares is explored, not refused."""
    out = Refusals()
    allowed = _allowed(environment)

    def report(code: str, file: str, node: ast.AST, message: str) -> None:
        where = next((c for c in _codes(m) if c.file == file), None)
        text = where.text if where is not None else ""
        col = node_col(text, node) if text and isinstance(node, ast.expr | ast.stmt) else 1
        line = getattr(node, "lineno", 1)
        loc = where.place(line, col) if where is not None else None  # an inline guard is in machine.yaml
        if loc is not None:
            file, line, col = loc.file, loc.line, loc.column
        out.diagnostics.append(diag(code, path / file, line, col, message))

    # names an import binds to what reads the world, wherever they are used (SPEC 16)
    imported: dict[str, tuple[str, str]] = {}
    for code in _codes(m):
        tree = trees.get(code.file)
        if tree is not None:
            for name, what in _world_names(tree):
                imported.setdefault(name, (what, f"{code.file}:{getattr(tree, 'lineno', 1)}"))
    for code in _codes(m):
        tree = trees.get(code.file)
        if tree is None:
            continue
        for node, what in _world_reads(tree, allowed):
            advice = _ENVIRONMENT_ADVICE if any(w in what for w in ("service", "subscription", "spin")) else ""
            report("LF200", code.file, node, f"{what}: verify cannot explore this faithfully; {_INPUT_ADVICE}{advice}")
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and node.id in imported:
                what, _where = imported[node.id]
                report(
                    "LF200",
                    code.file,
                    node,
                    f"`{node.id}` ({what}, imported in Includes.py or this file): verify cannot explore this "
                    f"faithfully; {_INPUT_ADVICE}",
                )
    for i in m.inputs:
        if i.type != "bool" and not i.domain:
            out.diagnostics.append(
                diag(
                    "LF202",
                    path / "machine.yaml",
                    i.loc.line,
                    i.loc.column,
                    f"input {i.name} ({i.type}) has no domain: list the values verify explores (`domain: [...]`)",
                )
            )
    timed = {c.file for s in m.states for n, c in s.sections.items() if n in _TIMED_SECTIONS}
    timed |= {t.guard.file for s in m.states for t in s.transitions if t.guard is not None}
    for s in m.states:
        cuts: set[int] = set()
        files = [c for n, c in s.sections.items() if n in _TIMED_SECTIONS]
        files += [t.guard for t in s.transitions if t.guard is not None]
        for code in files:
            tree = trees.get(code.file)
            if tree is None:
                continue
            for node, threshold, problem in _afters(tree):
                if problem is not None:
                    report("LF201", code.file, node, problem)
                elif threshold is not None and threshold >= 0:
                    cuts.add(math.floor(threshold))
        out.cuts.append(tuple(sorted(cuts)))
    for code in _codes(m):
        tree = trees.get(code.file)
        if tree is None or code.file in timed:
            continue
        for node, _threshold, _problem in _afters(tree):
            where = "OnSuspend and OnResume" if "_On" in code.file else code.file
            report(
                "LF201",
                code.file,
                node,
                f"{node.func.id if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) else 'after*'} "
                f"in {where} cannot be followed by verify: after* measures the time since the state was entered, "
                "which verify follows in a state's guards, OnEntry, Internal and OnExit only",
            )
    return out


def _codes(m: Machine) -> Iterator[Code]:
    """Every code file of the machine."""
    for c in (m.includes, m.variables_file):
        if c is not None:
            yield c
    for s in m.states:
        if s.variables_file is not None:
            yield s.variables_file
        yield from s.sections.values()
        for t in s.transitions:
            if t.guard is not None:
                yield t.guard


def _dotted(node: ast.AST) -> list[str]:
    """`a.b.c` as ["a", "b", "c"]; [] for anything else."""
    parts: list[str] = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return parts[::-1]
    return []


#: What an environment makes explorable (llfsm.verify.environment): services, subscriptions.
_SERVICE_CALLS = frozenset({"call_async", "call", "spin_until_future_complete", "wait_for_service", "service_is_ready"})
_READS = frozenset({"take", "latest"})


def _allowed(environment: Any) -> dict[str, set[str]]:
    """What the environment declares: {"create_client": names, "create_subscription": topics}."""
    out: dict[str, set[str]] = {"create_client": set(), "create_subscription": set()}
    if environment:
        out["create_client"] = {n.lstrip("/") for n in environment.services}
        out["create_subscription"] = {n.lstrip("/") for n in environment.topics}
    return out


def _declared(node: ast.Call, names: set[str]) -> bool:
    """Whether a `create_client(T, "name")` / `create_subscription(T, "topic", ...)` names a
    declared service or topic (its name written as a string)."""
    arg = (
        node.args[1]
        if len(node.args) > 1
        else next((k.value for k in node.keywords if k.arg in ("srv_name", "topic")), None)
    )
    return isinstance(arg, ast.Constant) and isinstance(arg.value, str) and arg.value.lstrip("/~").lstrip("/") in names


def _world_names(tree: ast.AST) -> Iterator[tuple[str, str]]:
    """(name, what it reads) for each name an import in `tree` binds to a module that reads the world."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                top = a.name.split(".")[0]
                if top in _MODULES:
                    yield (a.asname or top), _MODULES[top]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            top = node.module.split(".")[0]
            if top in _MODULES:
                for a in node.names:
                    yield (a.asname or a.name), _MODULES[top]


def _world_reads(tree: ast.AST, allowed: dict[str, set[str]] | None = None) -> Iterator[tuple[ast.AST, str]]:
    """(node, what it reads) for each place in `tree` that reads the world (less what the
    environment declares, `allowed`)."""
    allowed = allowed or {"create_client": set(), "create_subscription": set()}
    services, topics = bool(allowed["create_client"]), bool(allowed["create_subscription"])
    declared: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            names = allowed.get(node.func.attr)
            if names and _declared(node, names):
                declared.add(id(node.func))
    for node in ast.walk(tree):
        if id(node) in declared:
            continue
        if isinstance(node, ast.Attribute) and (
            (services and node.attr in _SERVICE_CALLS) or (topics and node.attr in _READS)
        ):
            continue
        if isinstance(node, ast.Import):
            for a in node.names:
                top = a.name.split(".")[0]
                if top in _MODULES:
                    yield node, f"`import {a.name}` ({_MODULES[top]})"
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            top = node.module.split(".")[0]
            if top in _MODULES:
                yield node, f"`from {node.module} import ...` ({_MODULES[top]})"
            elif node.module in ("os", "sys", "os.path"):
                for a in node.names:
                    if a.name in _OS:
                        yield node, f"`from {node.module} import {a.name}` ({_OS[a.name]})"
            elif node.module in ("llfsm.runtime", "llfsm.runtime.context"):
                for a in node.names:
                    if a.name == "current":
                        yield node, "`current` (the run context: its clock)"
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _BUILTINS:
            yield node, f"`{node.func.id}()` ({_BUILTINS[node.func.id]})"
        elif isinstance(node, ast.Call) and _called_name(node.func) in _BUS_CLASSES:
            yield node, f"`{_called_name(node.func)}()` ({_BUS[_called_name(node.func)]})"
        elif isinstance(node, ast.Attribute):
            dotted = _dotted(node)
            if len(dotted) >= 2 and dotted[0] in ("os", "sys") and dotted[-1] in _OS:
                yield node, f"`{'.'.join(dotted)}` ({_OS[dotted[-1]]})"
            elif (
                node.attr in _BUS and node.attr not in _BUS_CLASSES
            ):  # a class: only a call (not `x: ros.ActionClient`)
                yield node, f"`.{node.attr}` ({_BUS[node.attr]})"


def _called_name(func: ast.expr) -> str:
    """The name a call calls: `f` of `f(...)` and of `a.b.f(...)`."""
    if isinstance(func, ast.Name):
        return func.id
    return func.attr if isinstance(func, ast.Attribute) else ""


def _constant(node: ast.AST) -> float | None:
    """The value of a constant number written with + - * / and parentheses, else None."""
    if isinstance(node, ast.Constant) and isinstance(node.value, int | float) and not isinstance(node.value, bool):
        return node.value
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        v = _constant(node.operand)
        return None if v is None else (-v if isinstance(node.op, ast.USub) else v)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add | ast.Sub | ast.Mult | ast.Div):
        a, b = _constant(node.left), _constant(node.right)
        if a is None or b is None:
            return None
        try:
            if isinstance(node.op, ast.Add):
                return a + b
            if isinstance(node.op, ast.Sub):
                return a - b
            if isinstance(node.op, ast.Mult):
                return a * b
            return a / b
        except (ZeroDivisionError, OverflowError):
            return None
    return None


def _afters(tree: ast.AST) -> Iterator[tuple[ast.AST, float | None, str | None]]:
    """(node, threshold in ns or None, problem or None) for each use of after, after_ms, after_us."""
    calls: set[int] = set()
    nested: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda | ast.ClassDef):
            nested.update(id(n) for n in ast.walk(node) if n is not node)
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in AFTER_SCALE:
            calls.add(id(node.func))
            name = node.func.id
            if id(node) in nested:
                yield node, None, f"{name} inside a function or lambda may run in any state: verify cannot follow it"
                continue
            if len(node.args) != 1 or node.keywords:
                yield node, None, f"{name} takes one number: verify cannot follow this call"
                continue
            value = _constant(node.args[0])
            if value is None or not math.isfinite(value):
                yield (
                    node,
                    None,
                    f"{name} with a threshold that is not a constant number: verify cuts time at the constants a "
                    "state's after* name; write the number",
                )
                continue
            threshold = value * AFTER_SCALE[name]
            yield node, (threshold if math.isfinite(threshold) else None), None
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id in AFTER_SCALE and id(node) not in calls:
            yield node, None, f"{node.id} used other than called directly: verify cannot follow it"
