"""What `llfsm verify` is given, loaded: machine targets as `llfsm run` takes them, or a
verification file `NAME.verify.yaml` (docs/verify.md, "Verification files").

Each machine is checked as `llfsm check` checks it (a machine with errors is not explored),
read for what verify refuses (llfsm.verify.refuse), and loaded as `llfsm run` loads it
(llfsm.targets: the same cache, the same compiled module), so what is explored is what runs.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..lang.check import check_machine
from ..lang.diagnostics import Diagnostic, Severity, diag
from ..machinedir import MACHINE_SUFFIX
from ..props.atoms import MachineInfo
from ..props.file import VERIFY_SUFFIX as VERIFY_SUFFIX  # re-exported: the CLI's and tests' names
from ..props.file import Environment, FileError, VerifyFile
from ..props.file import PropertySource as PropertySource
from ..props.file import read_verify_file as read_file
from ..targets import InvalidMachine, MachineLoadError, TargetError, find_installed, load
from .explorer import Loaded
from .refuse import refusals


class VerifyError(Exception):
    """Bad input (exit status 2), or machine code that raised while loading (status 1): the
    message, and the diagnostics to print before it."""

    def __init__(self, message: str, diagnostics: list[Diagnostic] | None = None, status: int = 2) -> None:
        super().__init__(message)
        self.message = message
        self.diagnostics = diagnostics or []
        self.status = status
        self.details = ""


def read_verify_file(path: Path) -> VerifyFile:
    """A NAME.verify.yaml (llfsm.props.file); VerifyError (status 2) for anything wrong with it."""
    try:
        return read_file(path)
    except FileError as e:
        raise VerifyError(str(e)) from None


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


def load_arrangement(
    targets: list[str], environment: Environment | None = None, bounds: dict[str, float] | None = None
) -> Loaded:
    """The arrangement of `targets`, in load order, checked and read; VerifyError otherwise.
    `environment` (a verification file's) is what the machines may call and read instead of
    being refused; `bounds` where the exploration stops going further."""
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
        found = refusals(result.machine, result.read.trees, d, environment)
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
    return Loaded(classes, models, cuts, paths, environment if environment else None, dict(bounds or {}))


def machine_infos(loaded: Loaded) -> dict[str, MachineInfo]:
    """What properties may name of each machine."""
    out = {}
    for k, (cls, model) in enumerate(zip(loaded.classes, loaded.models, strict=True)):
        variables = tuple(v.name for v in model.variables) + tuple(i.name for i in model.inputs)
        out[cls.NAME] = MachineInfo(k, cls.NAME, tuple(cls.STATES), variables)
    return out
