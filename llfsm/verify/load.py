"""What `llfsm verify` is given, loaded: machine targets as `llfsm run` takes them, or a
verification file `NAME.verify.yaml` (docs/verify.md, "Verification files").

Each machine is checked as `llfsm check` checks it (a machine with errors is not explored),
read for what verify refuses (llfsm.verify.refuse), and loaded as `llfsm run` loads it
(llfsm.targets: the same cache, the same compiled module), so what is explored is what runs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..lang.check import check_machine
from ..lang.diagnostics import Diagnostic, Severity, diag
from ..lang.reader import YAML_LOADER
from ..machinedir import MACHINE_SUFFIX
from ..targets import InvalidMachine, MachineLoadError, TargetError, find_installed, load
from .explorer import Loaded
from .props import KINDS, MachineInfo
from .refuse import refusals

#: The suffix of a verification file.
VERIFY_SUFFIX = ".verify.yaml"
#: Keys of a verification file besides `machines` and `properties`: defaults for the options.
FILE_OPTIONS = ("period", "interrupt", "max_states")


class VerifyError(Exception):
    """Bad input (exit status 2), or machine code that raised while loading (status 1): the
    message, and the diagnostics to print before it."""

    def __init__(self, message: str, diagnostics: list[Diagnostic] | None = None, status: int = 2) -> None:
        super().__init__(message)
        self.message = message
        self.diagnostics = diagnostics or []
        self.status = status
        self.details = ""


@dataclass
class PropertySource:
    kind: str
    text: Any  # str, or a list of two for leads_to
    name: str | None = None
    where: str = "--property"


@dataclass
class VerifyFile:
    path: Path
    machines: list[str]
    properties: list[PropertySource]
    options: dict[str, Any] = field(default_factory=dict)


def read_verify_file(path: Path) -> VerifyFile:
    """A NAME.verify.yaml: `machines:` (paths relative to the file, in load order),
    `properties:` (each a mapping of one kind to its text, and an optional `name`), and
    optionally `period`, `interrupt`, `max_states` (what the options of the same names say)."""

    def fail(node: yaml.Node | None, message: str) -> VerifyError:
        line = node.start_mark.line + 1 if node is not None else 1
        return VerifyError(f"{path}:{line}: {message}")

    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise VerifyError(f"{path}: cannot be read: {getattr(e, 'strerror', None) or e}") from None
    if len(text) > 1 << 20:
        raise VerifyError(f"{path}: larger than 1 MiB")
    try:
        for ev in yaml.parse(text, Loader=YAML_LOADER):
            if isinstance(ev, yaml.AliasEvent) or getattr(ev, "anchor", None):
                raise fail(None, "anchors and aliases are not allowed in a verification file")
        root = yaml.compose(text, Loader=YAML_LOADER)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        raise VerifyError(f"{path}:{mark.line + 1 if mark else 1}: invalid YAML: {e.problem or e.context}") from None
    except (yaml.YAMLError, RecursionError) as e:
        raise VerifyError(f"{path}: invalid YAML: {type(e).__name__}") from None
    if not isinstance(root, yaml.MappingNode):
        raise fail(root, "a verification file is a mapping with `machines:` and `properties:`")
    top: dict[str, yaml.Node] = {}
    for k, v in root.value:
        key = k.value if isinstance(k, yaml.ScalarNode) else None
        if key not in ("machines", "properties", *FILE_OPTIONS):
            raise fail(k, f"unknown key {key!r} (machines, properties, {', '.join(FILE_OPTIONS)})")
        top[key] = v
    mnode = top.get("machines")
    if not isinstance(mnode, yaml.SequenceNode) or not mnode.value:
        raise fail(mnode or root, "`machines:` lists the machines to load, in load order")
    machines = []
    for m in mnode.value:
        if not isinstance(m, yaml.ScalarNode) or not m.value:
            raise fail(m, "each machine is a path (relative to this file) or PKG/NAME")
        p = path.parent / m.value
        machines.append(os.path.normpath(p) if p.exists() or not _looks_installed(m.value) else m.value)
    props: list[PropertySource] = []
    pnode = top.get("properties")
    if pnode is not None and not (isinstance(pnode, yaml.ScalarNode) and pnode.tag.endswith("null")):
        if not isinstance(pnode, yaml.SequenceNode):
            raise fail(pnode, "`properties:` is a list")
        for item in pnode.value:
            if not isinstance(item, yaml.MappingNode):
                raise fail(item, f"a property is a mapping of one kind ({', '.join(KINDS)}) to its text")
            name = None
            found: tuple[str, Any] | None = None
            for k, v in item.value:
                key = k.value if isinstance(k, yaml.ScalarNode) else None
                if key == "name":
                    name = v.value if isinstance(v, yaml.ScalarNode) else None
                    if not name:
                        raise fail(v, "a property's name is text")
                elif key in KINDS:
                    if found is not None:
                        raise fail(k, f"a property has one kind; this one has {found[0]} and {key}")
                    if isinstance(v, yaml.ScalarNode):
                        found = (key, v.value)
                    elif isinstance(v, yaml.SequenceNode) and key == "leads_to":
                        found = (key, [x.value if isinstance(x, yaml.ScalarNode) else None for x in v.value])
                    else:
                        raise fail(v, f"the text of a {key} property")
                else:
                    raise fail(k, f"unknown key {key!r} in a property (name, or one of {', '.join(KINDS)})")
            if found is None:
                raise fail(item, f"a property needs one of {', '.join(KINDS)}")
            props.append(PropertySource(found[0], found[1], name, f"{path}:{item.start_mark.line + 1}"))
    options: dict[str, Any] = {}
    for key in FILE_OPTIONS:
        node = top.get(key)
        if node is not None:
            if not isinstance(node, yaml.ScalarNode):
                raise fail(node, f"`{key}` is a single value")
            options[key] = yaml.safe_load(node.value) if key != "period" else node.value
    return VerifyFile(path, machines, props, options)


def _looks_installed(target: str) -> bool:
    return target.count("/") == 1 and not target.endswith((".py", MACHINE_SUFFIX))


def machine_dir(target: str) -> Path | None:
    """The machine directory a target stands for: itself, the folder a built module was built
    from (its `Source:` line), or the installed package's machine."""
    p = Path(target)
    if p.is_dir():
        return p
    if p.is_file() and p.suffix == ".py":
        from ..runtime.generated import source_dir_of  # deferred: start-up (only a built module needs it)

        src = source_dir_of(str(p))
        return Path(src) if src is not None and os.path.isdir(src) else None
    if _looks_installed(target):
        try:
            found = find_installed(target)
        except TargetError:
            return None
        return found if found.is_dir() else machine_dir(str(found))
    return None


def load_arrangement(targets: list[str]) -> Loaded:
    """The arrangement of `targets`, in load order, checked and read; VerifyError otherwise."""
    if not targets:
        raise VerifyError("nothing to verify: give machines (TARGET...) or a NAME.verify.yaml")
    models = []
    cuts = []
    paths = []
    diags: list[Diagnostic] = []
    for t in targets:
        d = machine_dir(t)
        if d is None:
            if Path(t).exists() or _looks_installed(t):
                diags.append(
                    diag("LF203", t, 1, 1, f"{t}: verify reads the machine's directory, which cannot be found")
                )
                continue
            raise VerifyError(f"{t}: no such machine directory, module or installed PKG/NAME")
        result = check_machine(d)
        errors = [x for x in result.diagnostics if x.severity is Severity.ERROR]
        if errors or result.machine is None:
            diags.extend(errors)
            continue
        found = refusals(result.machine, result.read.trees, d)
        diags.extend(found.diagnostics)
        models.append(result.machine)
        cuts.append(found.cuts)
        paths.append(str(d))
    if diags:
        raise VerifyError(f"{len(diags)} problem(s): nothing was explored", sorted(diags, key=Diagnostic.sort_key))
    classes = []
    for t in targets:
        try:
            classes.append(load(t))
        except TargetError as e:
            raise VerifyError(str(e)) from None
        except InvalidMachine as e:
            raise VerifyError(f"{t}: the machine has errors; nothing was explored", e.diagnostics) from None
        except MachineLoadError as e:
            err = VerifyError("a machine's module raised while it was loaded", status=1)
            err.details = e.report.format()
            raise err from None
    names = [c.NAME for c in classes]
    for n in names:
        if names.count(n) > 1:
            raise VerifyError(f"machine {n} is loaded twice; an arrangement addresses machines by name")
    return Loaded(classes, models, cuts, paths)


def machine_infos(loaded: Loaded) -> dict[str, MachineInfo]:
    """What properties may name of each machine."""
    out = {}
    for k, (cls, model) in enumerate(zip(loaded.classes, loaded.models, strict=True)):
        variables = tuple(v.name for v in model.variables) + tuple(i.name for i in model.inputs)
        out[cls.NAME] = MachineInfo(k, cls.NAME, tuple(cls.STATES), variables)
    return out
