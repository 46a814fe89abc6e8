"""The shape of the package, as docs/architecture.md draws it, checked from the source text.

`lint-imports` (make lint, [tool.importlinter] in pyproject.toml) holds the layers; these tests
hold what it does not: an import deferred into a function says why on its line or just above it
(a deferred import is for start-up or an optional dependency, never to hide a cycle), no two
modules import each other at module level, and README's layout block names what the tree holds.
All of it is read with `ast` and `tokenize`: nothing of llfsm is imported.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import REPO

PACKAGE = REPO / "llfsm"
#: Words that say why an import waits for its function.
REASON = re.compile(r"deferred|start-up|startup|optional", re.IGNORECASE)
#: Generated message modules (llfsm/msgs/PKG/msg|srv|action/): the interface toolchain writes them.
GENERATED = re.compile(r"^msgs/[a-z0-9_]+/(msg|srv|action)/")


def modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if not GENERATED.match(p.relative_to(PACKAGE).as_posix()))


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def comments(source: str) -> dict[int, str]:
    """Line number -> the comment on that line."""
    found: dict[int, str] = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            found[tok.start[0]] = tok.string
    return found


def _is_type_checking(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and (
        (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
        or (isinstance(node.test, ast.Attribute) and node.test.attr == "TYPE_CHECKING")
    )


_BODIES = ("body", "orelse", "finalbody", "handlers")


class _Imports:
    """The imports of one module: at module level, and deferred into functions, each deferred
    one with the comments that explain it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.source = path.read_text(encoding="utf-8")
        self.lines = self.source.splitlines()
        self.tree = ast.parse(self.source, str(path))
        self.comments = comments(self.source)
        self.parent: dict[ast.AST, tuple[ast.AST, list[ast.stmt]]] = {}
        for node in ast.walk(self.tree):
            for field in _BODIES:
                body = getattr(node, field, None)
                if isinstance(body, list):
                    for child in body:
                        self.parent[child] = (node, body)

    def walk(self, node: ast.AST, in_function: bool = False) -> Iterator[tuple[ast.Import | ast.ImportFrom, bool]]:
        """Every import with whether it runs inside a function; TYPE_CHECKING blocks skipped."""
        for child in ast.iter_child_nodes(node):
            if _is_type_checking(child):
                for extra in child.orelse:  # `else:` of TYPE_CHECKING runs
                    yield from self.walk_one(extra, in_function)
                continue
            yield from self.walk_one(child, in_function)

    def walk_one(self, node: ast.AST, in_function: bool) -> Iterator[tuple[ast.Import | ast.ImportFrom, bool]]:
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node, in_function
            return
        inside = in_function or isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
        yield from self.walk(node, inside)

    def _comment_above(self, line: int) -> list[str]:
        """The block of comment-only lines directly above `line`."""
        out = []
        n = line - 1
        while n >= 1 and self.lines[n - 1].strip().startswith("#"):
            out.append(self.comments.get(n, ""))
            n -= 1
        return out

    def explanation(self, node: ast.stmt) -> list[str]:
        """The comments that speak for an import: on its lines, on the lines of the imports
        grouped with it (consecutive statements), and the comment block above the group or above
        the block the group opens (an `if`/`try` whose first statements the imports are)."""
        found: list[str] = []
        first = node
        if node in self.parent:
            _, body = self.parent[node]
            i = body.index(node)
            while i > 0 and isinstance(body[i - 1], ast.Import | ast.ImportFrom):
                i -= 1
            first = body[i]
            j = i
            while j < len(body) and isinstance(body[j], ast.Import | ast.ImportFrom):
                stmt = body[j]
                found += [self.comments[n] for n in range(stmt.lineno, (stmt.end_lineno or stmt.lineno) + 1)
                          if n in self.comments]  # fmt: skip
                j += 1
        found += self._comment_above(first.lineno)
        owner = self.parent.get(first)
        while owner is not None and not isinstance(owner[0], ast.FunctionDef | ast.AsyncFunctionDef | ast.Module):
            block, body = owner
            if body and body[0] is not first:
                break
            if isinstance(block, ast.stmt):
                found += [self.comments[block.lineno]] if block.lineno in self.comments else []
                found += self._comment_above(block.lineno)
            first = block  # type: ignore[assignment]
            owner = self.parent.get(block)
        return found


def deferred_imports() -> Iterator[tuple[Path, ast.Import | ast.ImportFrom, list[str]]]:
    for path in modules():
        imports = _Imports(path)
        for node, in_function in imports.walk(imports.tree):
            if in_function:
                yield path, node, imports.explanation(node)


def test_every_deferred_import_says_why() -> None:
    """An import inside a function hides a dependency from start-up, which is the only reason
    to have one (or an optional dependency that may be missing): the comment on its line, or
    just above it (or its group, or the `if`/`try` it opens), says so with `deferred:`,
    `start-up` or `optional`."""
    unexplained = []
    count = 0
    for path, node, said in deferred_imports():
        count += 1
        if not any(REASON.search(c) for c in said):
            line = ast.get_source_segment(path.read_text(encoding="utf-8"), node) or ""
            unexplained.append(f"{path.relative_to(REPO)}:{node.lineno}: {line.splitlines()[0]}")
    assert count > 50, "the walk found too few deferred imports to be looking at llfsm"
    assert not unexplained, (
        "deferred imports without a reason (add `# deferred: start-up (...)` or `# deferred: optional "
        "dependency`, or import at module level):\n" + "\n".join(unexplained)
    )


def _resolve(importer: str, is_package: bool, node: ast.Import | ast.ImportFrom, known: set[str]) -> set[str]:
    """The llfsm modules an import statement names (not their parent packages: importing
    `llfsm.ros.bus` from inside llfsm.ros is not a cycle with llfsm.ros)."""
    out: set[str] = set()
    if isinstance(node, ast.Import):
        for alias in node.names:
            name = alias.name
            while name and name not in known:
                name = name.rpartition(".")[0]
            if name:
                out.add(name)
        return out
    if node.level:
        base = importer if is_package else importer.rpartition(".")[0]
        for _ in range(node.level - 1):
            base = base.rpartition(".")[0]
        target = f"{base}.{node.module}" if node.module else base
    else:
        target = node.module or ""
    submodules = {f"{target}.{alias.name}" for alias in node.names} & known
    out |= submodules
    if target in known and len(submodules) < len(node.names):  # a name the module itself defines
        out.add(target)
    return out


def module_graph(deferred: bool = False) -> dict[str, set[str]]:
    """Module -> the llfsm modules it imports when it is imported (module level: neither function
    bodies nor TYPE_CHECKING blocks), or with `deferred`, also those its functions import."""
    paths = {module_name(p): p for p in modules()}
    known = set(paths)
    graph: dict[str, set[str]] = {}
    for name, path in paths.items():
        imports = _Imports(path)
        edges: set[str] = set()
        for node, in_function in imports.walk(imports.tree):
            if deferred or not in_function:
                edges |= _resolve(name, path.name == "__init__.py", node, known)
        graph[name] = edges - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, without recursion)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work: list[tuple[str, Iterator[str]]] = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in graph:
                    continue
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    component.append(top)
                    if top == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_cycle_finder_finds_a_cycle() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_an_import_names_the_modules_it_runs_not_their_package() -> None:
    known = {"p", "p.a", "p.b", "p.c"}
    imports = [ast.parse(text).body[0] for text in ("from . import a, b", "from .c import X", "from . import VALUE")]
    assert [_resolve("p.x", False, node, known) for node in imports] == [{"p.a", "p.b"}, {"p.c"}, {"p"}]  # type: ignore[arg-type]


def test_no_import_cycle_at_module_level() -> None:
    graph = module_graph()
    assert len(graph) > 100 and graph["llfsm.session"], "the graph should hold every module and its imports"
    assert "llfsm.runtime.scheduler" in graph["llfsm.runtime"]
    found = cycles(graph)
    assert not found, "modules that import each other at module level:\n" + "\n".join(" <-> ".join(c) for c in found)


#: The one door from run time to the toolchain (docs/architecture.md): the import hook compiles a
#: user's interface package on its first import.  Nothing in idl/ imports the hook back; this only
#: keeps a cycle through it from being reported twice should one appear.
DOORS = {("llfsm.msgs._finder", "llfsm.idl.package")}


def test_no_import_cycle_hidden_behind_a_deferred_import() -> None:
    """A deferred import is for start-up, never to break a cycle: with the imports of function
    bodies counted too (not those for annotations only), the modules still form no cycle."""
    graph = module_graph(deferred=True)
    assert "llfsm.idl.package" in graph["llfsm.msgs._finder"], "the door is a deferred import: it must be seen"
    for importer, imported in DOORS:
        graph[importer].discard(imported)
    found = cycles(graph)
    assert not found, "modules that import each other (deferred imports counted):\n" + "\n".join(
        " <-> ".join(c) for c in found
    )


def test_the_runtime_reads_bottom_up_even_for_type_checkers() -> None:
    """runtime/ is what every generated module imports: its modules import one another in one
    direction only, counting every import (those under TYPE_CHECKING, for annotations, and those
    deferred into functions too).  What a lower module knows of a higher one it knows through
    runtime/protocols.py (the arrangement's port, the machine's port)."""
    paths = {module_name(p): p for p in modules() if module_name(p).startswith("llfsm.runtime.")}
    known = set(paths)
    graph = {
        name: {
            m
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.Import | ast.ImportFrom)
            for m in _resolve(name, path.name == "__init__.py", node, known)
        }
        - {name}
        for name, path in paths.items()
    }
    # trace.py imports machine.py for its annotations only: the walk must see such imports
    assert "llfsm.runtime.machine" in graph["llfsm.runtime.trace"]
    found = cycles(graph)
    assert not found, "runtime modules that import each other, annotations counted:\n" + "\n".join(
        " <-> ".join(c) for c in found
    )


#: What each contract of [tool.importlinter] governs: the package (or container) whose every module
#: and subpackage the contract names (`layers`, `modules`, `forbidden_modules`), but for those
#: it leaves out on purpose, each with why.  A new contract needs its entry here.
GOVERNED: dict[str, tuple[str, dict[str, str]]] = {
    "layers": ("llfsm", {}),
    "transports": ("llfsm.ros", {"llfsm.ros.transports": "the transports themselves, the contract's source"}),
    "transport-kinds": (
        "llfsm.ros.transports",
        {
            "llfsm.ros.transports.base": "what every transport implements and sees of the bus",
            "llfsm.ros.transports.dds_config": "a part of the dds transport",
            "llfsm.ros.transports.dds_entities": "a part of the dds transport",
            "llfsm.ros.transports.dds_graph": "a part of the dds transport",
            "llfsm.ros.transports.dds_read": "a part of the dds transport",
            "llfsm.ros.transports.dds_services": "a part of the dds transport",
            "llfsm.ros.transports.dds_topics": "a part of the dds transport",
        },
    ),
    "verb-groups": (
        "llfsm.ros2cli",
        {
            "llfsm.ros2cli.arguments": "shared by the verb groups: names and VALUES",
            "llfsm.ros2cli.discovery": "shared by the verb groups: the DDS graph",
            "llfsm.ros2cli.endpoints": "shared by the verb groups: their own readers and nodes",
            "llfsm.ros2cli.lookup": "shared by the verb groups: TYPE strings to classes",
        },
    ),
    "cli-verbs": (
        "llfsm.cli",
        {
            "llfsm.cli._commands": "registers every command on the group",
            "llfsm.cli._exits": "shared: how a command ends, without click",
            "llfsm.cli._launch": "shared by `llfsm launch`'s click command and its fast path",
            "llfsm.cli._group": "shared: the click group and what commands share on click's side",
            "llfsm.cli._ros2": "shared by the ros2-style verb groups",
            "llfsm.cli._run": "shared by `llfsm run`'s click command and its fast path",
            "llfsm.cli._web": "shared by `llfsm run --web` and `llfsm view`",
            "llfsm.cli.run_args": "`llfsm run`'s fast path, shared with its click command",
        },
    ),
    "renderers": (
        "llfsm.diagram",
        {
            "llfsm.diagram.description": "what a published description must be before it is drawn",
            "llfsm.diagram.layout": "where svg places what it draws (and the web's graph)",
            "llfsm.diagram.ordering": "a part of layout: the order within its ranks",
            "llfsm.diagram.text": "labels shared by mermaid and dot: not a drawing",
        },
    ),
}


def children(package: str) -> set[str]:
    """The modules and subpackages directly in `package` (not __init__)."""
    folder = REPO.joinpath(*package.split("."))
    out = {f"{package}.{p.stem}" for p in folder.glob("*.py") if p.name != "__init__.py"}
    out |= {f"{package}.{d.name}" for d in folder.iterdir() if d.is_dir() and any(d.glob("*.py"))}
    return out


def named_by(contract: dict[str, object]) -> set[str]:
    """The modules a contract names in its list: a layers contract's layers (in its container),
    an independence contract's modules, a forbidden contract's forbidden modules."""
    if contract["type"] == "layers":
        (container,) = contract["containers"]  # type: ignore[misc]
        layers: list[str] = contract["layers"]  # type: ignore[assignment]
        return {f"{container}.{m.strip()}" for layer in layers for m in re.split(r"[|:]", layer)}
    key = "modules" if contract["type"] == "independence" else "forbidden_modules"
    return set(contract[key])  # type: ignore[call-overload]


def test_every_contract_names_every_module_of_its_package() -> None:
    """A contract whose list leaves a module out does not hold it: a new verb module that nothing
    forbids to import another verb, a new package in no layer.  Every contract of pyproject.toml
    names every module and subpackage of the package it governs (GOVERNED), or GOVERNED says why
    not.  Also run by `make lint`."""
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    contracts = config["tool"]["importlinter"]["contracts"]
    problems = []
    for contract in contracts:
        cid = contract["id"]
        if cid not in GOVERNED:
            problems.append(f"contract {cid!r}: say in GOVERNED of tests/test_architecture.py which package it governs")
            continue
        package, left_out = GOVERNED[cid]
        present = children(package)
        named = named_by(contract)
        key = {"layers": "layers", "independence": "modules"}.get(contract["type"], "forbidden_modules")
        for module in sorted(present - named - set(left_out)):
            problems.append(
                f"{module} is in no list of contract {cid!r}: add it to the contract's `{key}` in pyproject.toml "
                f"([tool.importlinter]), or, if the contract leaves it out on purpose (a module the others share), "
                f"to GOVERNED[{cid!r}] in tests/test_architecture.py, saying why"
            )
        for module in sorted((named | set(left_out)) - present):
            problems.append(f"contract {cid!r} names {module}, which is not a module of {package}")
    assert set(GOVERNED) <= {c["id"] for c in contracts}, "GOVERNED names a contract pyproject.toml does not have"
    assert not problems, "\n".join(problems)


# -- README's layout block ------------------------------------------------------------------------

_FILE = re.compile(r"(?<![\w./-])((?:[\w-]+/)*[\w-]+(?:\.[\w-]+)*\.(?:py|pyi|c|j2|txt|in|md|toml|yaml))(?![\w.])")
_FOLDER = re.compile(r"(?<![\w./-])([\w-]+(?:/[\w-]+)*/)(?![\w])")


def layout_block() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Layout\n", 1)[1]
    block = section.split("```", 2)[1]
    return [line for line in block.splitlines()[1:] if line.strip()]


def layout_entries() -> list[tuple[Path, list[str], list[str]]]:
    """Each entry of the block as (its folder, the files it names, the folders it names).  An entry
    starts at column 0 (a folder or file of the repository) or 2 (of llfsm/); a line indented
    further goes on with the entry above it.  An entry that starts with a file names it and the
    rest of its line in that folder."""
    out: list[tuple[Path, list[str], list[str]]] = []
    for line in layout_block():
        indent = len(line) - len(line.lstrip(" "))
        if indent > 2:
            assert out, f"README layout: a continuation line comes first: {line!r}"
            out[-1][1].extend(_FILE.findall(line))
            out[-1][2].extend(_FOLDER.findall(line))
            continue
        head, _, rest = line.strip().partition(" ")
        base = PACKAGE if indent else REPO
        if head.endswith("/"):
            out.append((base / head, _FILE.findall(rest), _FOLDER.findall(rest)))
        else:
            out.append((base, _FILE.findall(line), _FOLDER.findall(rest)))
    return out


def _named_inside(folder: Path, name: str) -> bool:
    """A file or folder of that relative path somewhere under the folder (ignoring caches)."""
    name = name.rstrip("/")
    return (folder / name).exists() or any(
        "__pycache__" not in p.parts and p.as_posix().endswith("/" + name) for p in folder.rglob(Path(name).name)
    )


def test_every_folder_and_module_the_readme_layout_names_exists() -> None:
    missing = []
    entries = layout_entries()
    assert len(entries) > 10
    for folder, files, folders in entries:
        if not folder.is_dir():
            missing.append(f"{folder.relative_to(REPO)}/")
            continue
        missing += [f"{folder.relative_to(REPO)}/ {n}" for n in files + folders if not _named_inside(folder, n)]
    assert not missing, "README's layout names what is not there:\n" + "\n".join(missing)


def test_the_readme_layout_names_every_package_and_top_level_module() -> None:
    entries = layout_entries()
    folders = {folder.resolve() for folder, _, _ in entries}
    top = {name for folder, files, _ in entries if folder.resolve() == PACKAGE.resolve() for name in files}
    unnamed = [
        f"llfsm/{d.relative_to(PACKAGE)}/"
        for d in sorted(PACKAGE.iterdir())
        if d.is_dir() and any(d.glob("*.py")) and d.resolve() not in folders  # a namespace package too
    ]
    unnamed += [
        f"llfsm/{p.name}" for p in sorted(PACKAGE.glob("*.py")) if p.name != "__init__.py" and p.name not in top
    ]
    assert not unnamed, "README's layout does not name:\n" + "\n".join(unnamed)


@pytest.mark.parametrize(
    ("line", "files", "folders"),
    [
        ("  web/  server.py (x)  static/", ["server.py"], ["static/"]),
        ("  ros/transports/  inproc and dds: base.py", ["base.py"], []),
        ("tests/  `make asan`: _tap.c under ASan/UBSan", ["_tap.c"], []),
        ("  templates/  machine.py.j2 (the module), skeleton/", ["machine.py.j2"], ["skeleton/"]),
    ],
)
def test_the_layout_reader_sees_files_and_folders(line: str, files: list[str], folders: list[str]) -> None:
    rest = line.strip().partition(" ")[2]
    assert _FILE.findall(rest) == files
    assert _FOLDER.findall(rest) == folders
