"""Resolve what `llfsm run` is given into machine classes.

A target is a machine directory (compiled into a cache, never into the source tree), a built
module (`build/ping.py`), or `PKG/NAME` of a package installed by colcon (found through
AMENT_PREFIX_PATH).  The compiler is imported only when a cached module is missing or stale,
so a warm start pays for stat-ing the machine's files (hashing them only when they changed
recently) and nothing more.

The run's path through this module (`load` of a machine directory or a built module) imports
neither pathlib nor hashlib nor importlib.util: each is a tenth of `llfsm run`'s start-up.  The
functions that return a Path (`resolve`, `compiled_module_for`) import it.
"""

from __future__ import annotations

import os
import sys
import zlib  # not hashlib: zlib is a builtin module, hashlib a tenth of a run's start-up
from importlib.machinery import ModuleSpec, SourceFileLoader

from . import fingerprint
from .cachedir import cache_dir, preferred_root
from .cachedir import problem as cache_problem
from .machinedir import MACHINE_SUFFIX
from .runtime.errors import ErrorReport, passes_through, report_for
from .runtime.generated import source_dir_of
from .runtime.machine import Machine

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from pathlib import Path
    from types import ModuleType


class TargetError(Exception):
    """A target that cannot be found or is not something llfsm can run (exit status 2)."""


class InvalidMachine(Exception):
    """A machine directory that fails validation (exit status 2), with its diagnostics."""

    def __init__(self, diagnostics: list) -> None:
        super().__init__(f"{len(diagnostics)} problem(s)")
        self.diagnostics = diagnostics


class MachineLoadError(Exception):
    """Machine code raised while its module was imported (a bad include): exit status 1."""

    def __init__(self, report: ErrorReport) -> None:
        super().__init__(report.exception)
        self.report = report


def _path_str(p: str) -> str:
    """str(Path(p)), without pathlib: repeated and trailing slashes and `.` parts dropped."""
    lead = "//" if p.startswith("//") and not p.startswith("///") else "/" if p.startswith("/") else ""
    return lead + "/".join(x for x in p.split("/") if x and x != ".") or "."


def _name(p: str) -> str:
    """Path(p).name, without pathlib."""
    parts = [x for x in p.split("/") if x and x != "."]
    return parts[-1] if parts else ""


def _cache_key(machine_dir: str) -> str:
    """The machine's folder in the cache: named after its real path (zlib's checksums, not
    hashlib's: a different key only costs a compile, and hashlib costs every run's start-up)."""
    b = os.fsencode(os.path.realpath(machine_dir))
    return f"{zlib.crc32(b):08x}{zlib.adler32(b):08x}"


def compiled_module_for(machine_dir: Path) -> Path:
    """The cached module of a machine directory, compiled first if missing or stale."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    return Path(_compiled_module(os.fspath(machine_dir)))


def _compiled_module(machine_dir: str) -> str:
    out = cache_dir(preferred_root(), _cache_key(machine_dir))  # a folder of ours that no one else can write
    name = _name(machine_dir)
    module = os.path.join(out, f"{name.removesuffix(MACHINE_SUFFIX)}.py")
    trusted = cache_problem(module, directory=False) is None
    if trusted and fingerprint.unchanged_since_record(machine_dir, module):
        return module  # the warm run: the files look exactly as when the module was last found fresh
    try:
        fp: str | None = fingerprint.machine_fingerprint(machine_dir, out)  # hashes the files
        fresh = fingerprint.module_fingerprint(module) == fp
    except OSError:
        fp, fresh = None, False
    untrusted = fresh and not trusted
    if untrusted:
        fresh = False  # not written by us for us: compile again (the atomic write replaces it)
    if fresh:
        assert fp is not None
        fingerprint.record_fresh(machine_dir, module, fp)
        return module
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    from .compiler.build import build_machine  # deferred: start-up (a warm run needs no compiler)

    try:
        outcome = build_machine(Path(machine_dir), Path(out), force=untrusted)
    except OSError as e:
        raise TargetError(
            f"{_path_str(machine_dir)}: cannot write its compiled module into {out}: {e.strerror or e}"
        ) from None
    if outcome.status == "failed" or outcome.module is None:
        raise InvalidMachine(outcome.diagnostics)
    if outcome.fingerprint:
        fingerprint.record_fresh(machine_dir, os.fspath(outcome.module), outcome.fingerprint)
    return os.fspath(outcome.module)


def find_installed(spec: str) -> Path:
    """`PKG/NAME` -> the machine installed by colcon under some prefix of AMENT_PREFIX_PATH."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    pkg, _, name = spec.partition("/")
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for prefix in prefixes:
        share = Path(prefix) / "share" / pkg
        for candidate in (share / "llfsm" / f"{name}.py", share / "machine" / f"{name}{MACHINE_SUFFIX}"):
            if candidate.exists():
                return candidate
    if not prefixes:
        where = "AMENT_PREFIX_PATH is not set: did you `source install/setup.bash`?"
    else:
        machines = _installed_machines(prefixes, pkg)
        if machines:
            hint = _did_you_mean(name, machines)
            where = f"package {pkg} has: {', '.join(sorted(machines))}{hint}"
        else:
            packages = _installed_packages(prefixes)
            hint = _did_you_mean(pkg, packages)
            where = f"no package {pkg} with machines under {', '.join(prefixes)}{hint}"
    local = Path(spec + MACHINE_SUFFIX)
    if local.is_dir():
        where = f"did you mean the folder {local}?"
    raise TargetError(f"{spec}: no installed machine {name!r} in package {pkg!r} ({where})")


def _installed_machines(prefixes: list[str], pkg: str) -> set[str]:
    """The machines a package installs: share/PKG/llfsm/NAME.py and share/PKG/machine/NAME.machine."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    out: set[str] = set()
    for prefix in prefixes:
        share = Path(prefix) / "share" / pkg
        out.update(p.stem for p in _listing(share / "llfsm") if p.suffix == ".py")
        out.update(
            p.name.removesuffix(MACHINE_SUFFIX) for p in _listing(share / "machine") if p.name.endswith(MACHINE_SUFFIX)
        )
    return out


def _installed_packages(prefixes: list[str]) -> set[str]:
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    return {
        p.name
        for prefix in prefixes
        for p in _listing(Path(prefix) / "share")
        if (p / "llfsm").is_dir() or (p / "machine").is_dir()
    }


def _listing(folder: Path, limit: int = 2000) -> list[Path]:
    """A folder's entries (at most `limit`: a hint must not cost a scan of a huge folder)."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    try:
        with os.scandir(folder) as it:
            return [Path(e.path) for _, e in zip(range(limit), it, strict=False)]
    except OSError:
        return []


def _did_you_mean(name: str, choices: set[str] | list[str]) -> str:
    import difflib  # deferred: start-up (only a target that names nothing needs it)

    close = difflib.get_close_matches(name, sorted(choices), n=3, cutoff=0.6)
    return f"; did you mean {' or '.join(close)}?" if close else ""


def _not_found(target: str) -> str:
    """What to say about a target that names nothing: the NAME.machine folder it probably meant,
    or close names of machines and modules beside it."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    p = Path(target)
    bare = p.name.removesuffix(MACHINE_SUFFIX).removesuffix(".py")
    for guess in (p.with_name(bare + MACHINE_SUFFIX), p.with_name(bare + ".py")):
        if guess != p and guess.exists():
            return f"{target}: no such machine directory or module; did you mean {guess}?"
    folder = p.parent
    names = {e.name for e in _listing(folder) if e.name.endswith((MACHINE_SUFFIX, ".py"))}
    stems = {n.removesuffix(MACHINE_SUFFIX).removesuffix(".py"): n for n in names}
    import difflib  # deferred: start-up (only a target that names nothing needs it)

    close = difflib.get_close_matches(bare, sorted(stems), n=3, cutoff=0.6)
    hint = f"; did you mean {' or '.join(str(folder / stems[c]) for c in close)}?" if close else ""
    return f"{target}: no such machine directory, module or installed PKG/NAME{hint}"


def resolve(target: str) -> Path:
    """The module file to load for a target."""
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    return Path(_resolve(target))


def _resolve(target: str) -> str:
    """resolve(), as a str: the run's own path (no pathlib)."""
    p = _path_str(target)
    if os.path.isdir(p):
        if _name(p).endswith(MACHINE_SUFFIX) or os.path.exists(os.path.join(p, "machine.yaml")):
            return _compiled_module(p)
        raise TargetError(f"{target}: a directory, but not a NAME.machine directory")
    if os.path.isfile(p):
        if os.path.splitext(_name(p))[1] == ".py":
            return p
        raise TargetError(f"{target}: not a machine directory or a built module (.py)")
    if target.count("/") == 1 and not target.startswith((".", "/")) and not target.endswith((".py", MACHINE_SUFFIX)):
        found = find_installed(target)
        return _compiled_module(os.fspath(found)) if found.is_dir() else os.fspath(found)
    raise TargetError(_not_found(target))


def helper_folder(target: str) -> Path | None:
    """Where a machine's helper modules live: the folder that holds NAME.machine (or the built
    module).  Its modules can be imported from Includes.py without setting PYTHONPATH."""
    folder = _helper_folder(target)
    if folder is None:
        return None
    from pathlib import Path  # deferred: start-up (the run's own path has no Path)

    return Path(folder)


def _helper_folder(target: str) -> str | None:
    p = _path_str(target)
    if os.path.exists(p):
        return os.path.dirname(os.path.realpath(p))
    if target.count("/") == 1:
        try:
            return os.fspath(find_installed(target).parent)
        except TargetError:
            return None
    return None


def _native_module(module_path: str | Path) -> str | None:
    """The compiled module of a built module in this process's native build (LLFSM_NATIVE),
    or None: no native build, or one that left this machine plain Python."""
    folder = os.environ.get("LLFSM_NATIVE")
    if not folder:
        return None
    import json  # deferred: start-up (only a native run reads the manifest)

    try:
        with open(os.path.join(folder, "manifest.json"), encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError):
        return None
    try:
        with open(module_path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    import hashlib  # deferred: start-up (only a native run names modules by their hash)

    key = hashlib.sha256(data)  # as compiler.native.module_key, without importing the compiler
    key.update(b"\0" + os.fsencode(source_dir_of(os.fspath(module_path)) or ""))
    return manifest.get("modules", {}).get(key.hexdigest()[:32])


def load_class(module_path: str | Path) -> type[Machine]:
    """Import a built module and return its machine class."""
    native = _native_module(module_path)
    if native is not None:
        import importlib  # deferred: start-up (only a native run imports modules by name)

        module = importlib.import_module(native)
        found = [
            v
            for v in vars(module).values()
            if isinstance(v, type) and issubclass(v, Machine) and v is not Machine and v.__module__ == native
        ]
        if len(found) == 1:
            return found[0]
    path = os.fspath(module_path)
    key = f"{zlib.crc32(os.fsencode(os.path.realpath(path))):08x}"  # the same name in every run
    mod_name = f"llfsm_machine_{os.path.splitext(_name(path))[0]}_{key}"
    module, loader = _new_module(mod_name, path)
    sys.modules[mod_name] = module
    try:
        loader.exec_module(module)
    except SyntaxError as e:
        sys.modules.pop(mod_name, None)
        raise TargetError(f"{module_path}:{e.lineno}: not a valid module: {e.msg}") from None
    except BaseException as exc:  # an include may raise anything, SystemExit too
        sys.modules.pop(mod_name, None)
        if passes_through(exc):
            raise
        rep = report_for(exc)
        if rep is None:
            raise TargetError(f"{module_path}: import failed: {type(exc).__name__}: {exc}") from None
        raise MachineLoadError(rep) from None
    classes = [
        v
        for v in vars(module).values()
        if isinstance(v, type) and issubclass(v, Machine) and v is not Machine and v.__module__ == mod_name
    ]
    if len(classes) != 1:
        raise TargetError(f"{module_path}: not an llfsm machine module (found {len(classes)} machine classes)")
    return classes[0]


def _new_module(name: str, path: str) -> tuple[ModuleType, SourceFileLoader]:
    """What importlib.util.spec_from_file_location and module_from_spec make of a source file,
    from importlib.machinery alone (importlib.util imports contextlib and functools), and its
    loader."""
    loader = SourceFileLoader(name, path)
    spec = ModuleSpec(name, loader, origin=path)
    spec.has_location = True
    module = type(sys)(name)
    module.__spec__ = spec
    module.__loader__ = loader
    module.__package__ = ""
    module.__file__ = path
    module.__cached__ = spec.cached  # type: ignore[attr-defined]  # set by the import system; typeshed omits it
    return module, loader


def helper_folders(target: str, module: str) -> list[str]:
    """The folders a machine's helper modules are imported from, in order: the folder that
    holds NAME.machine (or the built module), and for a built or installed module also the
    folder that holds the machine folder it was built from, where `import helpers` found
    `helpers.py` when the machine itself was run (docs/machine-format.md, "Helper modules")."""
    folders = []
    first = _helper_folder(target)
    if first is not None:
        folders.append(first)
    if not os.path.isdir(_path_str(target)):  # a built module, or PKG/NAME: not compiled from a folder here
        machine = source_dir_of(module)
        if machine is not None and os.path.isdir(machine):
            beside = os.path.dirname(os.path.realpath(machine))
            if beside not in folders:
                folders.append(beside)
    return folders


def load(target: str) -> type[Machine]:
    module = _resolve(target)
    folders = helper_folders(target, module)
    for folder in folders:
        if folder not in sys.path:
            # last: a helper never hides an installed module of the same name (a `yaml.py` beside
            # the machines stays a helper for them, pyyaml stays pyyaml)
            sys.path.append(folder)
    try:
        return load_class(module)
    except MachineLoadError as e:
        e.report.exception += _missing_helper_hint(e.report.exception, folders, module)
        raise


def _missing_helper_hint(exception: str, folders: list[str], module: str) -> str:
    """Where llfsm looked for a module an include could not import: a helper module (a built
    module copied away from the machine folder it was built from), or an interface package."""
    prefix = "ModuleNotFoundError: No module named '"
    if not exception.startswith(prefix):
        return ""
    name = exception[len(prefix) :].split("'")[0]
    if name.startswith("llfsm.msgs.") and name.count(".") == 2:
        return (
            f" (no interface package {name.split('.')[2]!r}: llfsm looks among the packages it ships, in the "
            "folders above the machine, in LLFSM_INTERFACE_PATH and in share/ of AMENT_PREFIX_PATH)"
        )
    if "." in name:
        return ""
    where = " and ".join(folders) or "nowhere"
    return (
        f" (not installed; llfsm looks for helper modules in {where}: copy {name}.py beside "
        f"{os.path.basename(module)}, or install it)"
    )
