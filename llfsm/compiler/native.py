"""Native builds (`--native`): the runtime and a build's machine modules compiled ahead of time
with mypyc, in one compile, into the llfsm cache.

The generated modules and the runtime stay plain, typed Python; mypyc turns them into C
extension modules that do the same thing faster.  One build is one mypyc invocation: every
machine module of the build plus the runtime modules on the hot path (machine, gate,
scheduler, clock, context) make one group, so a machine class and the scheduler that calls its
ringlets are compiled against each other.  A machine whose code mypyc cannot compile (its type checker
refuses it, usually) is dropped from the group with one warning naming the user's file and
line, and runs as plain Python beside the compiled ones.

The result lives in `<cache>/native/<key>`, where the key covers the runtime's source, every
module's text and the machine folder it leads to, the Python version and the mypyc version, so
an unchanged build is found again without compiling.  A process uses it by starting with
`LLFSM_NATIVE=<that folder>` in its environment: `llfsm.runtime` then imports its compiled
modules from there (see llfsm/runtime/__init__.py), which is why `llfsm run --native` starts
the run in a fresh process.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..machinedir import source_ref
from ..runtime.errors import _display
from ..runtime.generated import HEADER_LINES, SOURCE_LINE, map_line, source_dir_of, source_map_in
from ..templating import comment_text

#: The runtime modules a native build compiles: everything a round touches.
RUNTIME_MODULES = ("machine", "gate", "scheduler", "clock", "context")
#: Environment variable naming the native build a process runs with.
ENV = "LLFSM_NATIVE"
MANIFEST = "manifest.json"
#: How a generated module's header names its machine folder.
SOURCE_KEY = SOURCE_LINE.encode("ascii")

_ERROR = re.compile(r"^(?P<file>[^:\n]+):(?P<line>\d+):(?:\d+:)? error: (?P<msg>.*)$", re.M)

_MYPY_INI = """\
[mypy]
# only the listed files are compiled; whatever they import that is not llfsm's runtime is Any
follow_imports = skip
follow_imports_for_stubs = False
ignore_missing_imports = True
warn_unused_ignores = False
allow_redefinition = True
disable_error_code = annotation-unchecked

[mypy-llfsm.runtime.*]
follow_imports = silent
"""


class NativeUnavailable(Exception):
    """No mypyc or no C compiler: --native cannot work on this machine."""


@dataclass
class NativeBuild:
    """A finished native build: the folder to run with, which modules were compiled, and one
    warning per machine that stays plain Python."""

    folder: Path
    #: module file (as given to build) -> name of its compiled module, None if it stays plain
    modules: dict[str, str | None] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    cached: bool = False


def module_key(module: Path) -> str:
    """How a manifest names a module (llfsm.targets looks modules up the same way): by its text
    and the machine folder it leads to.  A module names that folder relative to its own, so two
    copies of a project have modules of the same text; their compiled code would name the files
    of whichever copy was compiled first in its error reports."""
    h = hashlib.sha256(module.read_bytes())
    h.update(b"\0" + os.fsencode(source_dir_of(str(module)) or ""))
    return h.hexdigest()[:32]


def _from_manifest(folder: Path, modules: list[Path], base: str) -> NativeBuild | None:
    """The build in `folder`, if it holds every one of `modules` (same runtime, same text)."""
    try:
        data = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if data.get("base") != base:
        return None
    out = NativeBuild(folder, cached=True)
    for m in modules:
        h = module_key(m)
        if h not in data["modules"]:
            return None
        out.modules[str(m)] = data["modules"][h]
        out.warnings += data["warnings"].get(h, [])
    return out


def available() -> str | None:
    """Why --native cannot work here, or None when it can."""
    try:
        import mypyc  # noqa: F401  # deferred: optional dependency (llfsm[native])
    except ImportError:
        return "mypyc is not installed (pip install 'llfsm[native]')"
    cc = (sysconfig.get_config_var("CC") or "cc").split()[0]
    if shutil.which(cc) is None and shutil.which("cc") is None:
        return f"no C compiler ({cc}) on PATH"
    include = sysconfig.get_paths().get("include", "")
    if not Path(include, "Python.h").exists():
        return f"the Python headers are missing ({include}/Python.h)"
    return None


def _runtime_dir() -> Path:
    return Path(__file__).resolve().parent.parent / "runtime"


def _mypyc_version() -> str:
    from mypy.version import __version__  # deferred: optional dependency (llfsm[native])

    return __version__


def base_key() -> str:
    """The runtime's source, the Python version and the mypyc version."""
    h = hashlib.sha256()
    h.update(f"{sys.version}\0{sys.platform}\0{_mypyc_version()}\0".encode())
    for f in sorted(_runtime_dir().glob("*.py")):
        h.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()[:24]


def build_key(modules: list[Path], base: str) -> str:
    """Content (each module's `module_key`) + Python version + mypyc version: the same key means
    the same compiled result."""
    h = hashlib.sha256(base.encode())
    for m in sorted(modules, key=_stage_name):
        h.update(_stage_name(m).encode() + b"\0" + module_key(m).encode() + b"\0")
    return h.hexdigest()[:24]


def _stage_name(module: Path) -> str:
    """The compiled module's name: never the name of a module users import (`time`, `json`)."""
    return f"_llfsm_native_{module.stem}"


def native_build(modules: list[Path], root: Path, say: Callable[[str], None] | None = None) -> NativeBuild:
    """Compile `modules` (generated machine modules) and the runtime into root/native/<key>,
    or find that build already there.  `say` is told what a compile is doing when one starts
    (each try of it): the command shows it while mypyc works, which takes seconds a machine."""
    why = available()
    if why is not None:
        raise NativeUnavailable(why)
    names = [_stage_name(m) for m in modules]
    if len(set(names)) != len(names):
        raise NativeUnavailable("two machines of the build have the same name")
    base = base_key()
    key = build_key(modules, base)
    native = root / "native"
    folder = native / key
    found = _from_manifest(folder, modules, base)
    if found is not None:
        return found
    for other in sorted(native.glob(f"*/{MANIFEST}")) if native.is_dir() else ():  # a bigger build
        found = _from_manifest(other.parent, modules, base)
        if found is not None:
            return found
    folder.mkdir(parents=True, exist_ok=True)
    with open(native / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one compile per key, even with two builds at once
        found = _from_manifest(folder, modules, base)
        if found is not None:
            return found
        result, per_module = _compile(modules, folder, native / "mypy-cache", say)
        data = {
            "base": base,
            "modules": {module_key(m): result.modules[str(m)] for m in modules},
            "warnings": {module_key(m): w for m, w in per_module.items()},
        }
        (folder / MANIFEST).write_text(json.dumps(data, indent=1), encoding="utf-8")
        return result


def _stage(modules: list[Path], folder: Path) -> dict[str, Path]:
    """Copy the runtime (as llfsm/runtime) and the modules into the folder; staged name -> path."""
    shutil.rmtree(folder / "llfsm", ignore_errors=True)
    rt = folder / "llfsm" / "runtime"
    rt.mkdir(parents=True)
    (folder / "llfsm" / "__init__.py").write_text("", encoding="utf-8")
    for f in _runtime_dir().glob("*.py"):
        shutil.copyfile(f, rt / f.name)
    staged = {}
    for m in modules:
        target = folder / f"{_stage_name(m)}.py"
        target.write_bytes(_rebased(m, folder))
        staged[_stage_name(m)] = target
    (folder / "mypy.ini").write_text(_MYPY_INI, encoding="utf-8")
    return staged


def _rebased(module: Path, folder: Path) -> bytes:
    """The module's text for its copy in `folder`: the same lines, but the `# Source:` line names
    the machine folder relative to the copy (a module names it relative to its own folder), so
    that errors in the compiled code, whose frames point at the copy, still name the user's files."""
    data = module.read_bytes()
    machine = source_dir_of(str(module))
    if machine is None:
        return data
    lines = data.split(b"\n")
    for i, line in enumerate(lines[:HEADER_LINES]):
        if line.startswith(SOURCE_KEY):
            lines[i] = SOURCE_KEY + comment_text(source_ref(machine, folder)).encode("ascii")
            break
    return b"\n".join(lines)


def _run_mypyc(files: list[Path], folder: Path, mypy_cache: Path) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "mypyc", "--config-file", str(folder / "mypy.ini"), "--cache-dir", str(mypy_cache)]
    env = dict(os.environ)
    env.pop(ENV, None)
    return subprocess.run(
        [*cmd, *map(str, files)], cwd=folder, env=env, capture_output=True, text=True, timeout=1800, check=False
    )


def _user_location(module: Path, line: int) -> str:
    """`file:line` in the user's machine for a line of a generated module (the module's own
    line when it is not user code)."""
    mapped = map_line(str(module), line, source_map_in(module.read_text(encoding="utf-8")))
    src = source_dir_of(str(module))
    if mapped is None or src is None:
        return f"{module}:{line}"
    user = os.path.join(src, mapped[0])
    try:
        lines = len(Path(user).read_text(encoding="utf-8").splitlines())
    except (OSError, UnicodeDecodeError):
        lines = 0
    if not 1 <= mapped[1] <= lines:  # a generated line after the user's block, not user code
        return f"{module}:{line}"
    return f"{_display(user)}:{mapped[1]}"


def _compile(
    modules: list[Path], folder: Path, mypy_cache: Path, say: Callable[[str], None] | None = None
) -> tuple[NativeBuild, dict[Path, list[str]]]:
    staged = _stage(modules, folder)
    by_stage = {_stage_name(m): m for m in modules}
    runtime = [folder / "llfsm" / "runtime" / f"{n}.py" for n in RUNTIME_MODULES]
    left = dict(staged)
    warnings: dict[Path, list[str]] = {}
    for attempt in range(3):  # each retry drops the machines mypyc refused
        if say is not None:
            again = "" if attempt == 0 else ", again without the machines it refused"
            say(f"compiling {len(left)} machine(s) and the runtime with mypyc{again}")
        proc = _run_mypyc([*runtime, *left.values()], folder, mypy_cache)
        if proc.returncode == 0:
            break
        refused: dict[str, tuple[int, str]] = {}
        other = []
        for e in _ERROR.finditer(proc.stdout + proc.stderr):
            path = folder / e["file"]  # mypy names files relative to the folder it runs in
            stem = path.stem
            if path.parent.resolve() == folder.resolve() and stem in left:
                refused.setdefault(stem, (int(e["line"]), e["msg"]))
            else:
                other.append(e.group(0))
        if not refused:  # the runtime itself, or the C compiler: nothing compiles natively
            detail = (other or (proc.stderr or proc.stdout).strip().splitlines() or ["unknown error"])[-1]
            return _all_plain(modules, folder, f"the native compile failed ({detail.strip()})")
        for stem, (line, msg) in sorted(refused.items()):
            where = _user_location(left.pop(stem), line)
            warnings[by_stage[stem]] = [
                f"{where}: warning: mypyc cannot compile this machine ({msg}); it runs as plain Python"
            ]
    else:
        return _all_plain(modules, folder, "the native compile kept failing")
    shutil.rmtree(folder / "build", ignore_errors=True)
    result = {str(m): (stem if stem in left else None) for stem, m in by_stage.items()}
    return NativeBuild(folder, result, [w for m in modules for w in warnings.get(m, [])]), warnings


def _all_plain(modules: list[Path], folder: Path, why: str) -> tuple[NativeBuild, dict[Path, list[str]]]:
    """Nothing compiled: every machine runs as plain Python, with one warning saying why."""
    shutil.rmtree(folder / "build", ignore_errors=True)
    for so in folder.rglob("*.so"):
        with contextlib.suppress(OSError):
            so.unlink()
    warning = f"llfsm: warning: {why}; the machines run as plain Python"
    per_module = {m: [warning] if i == 0 else [] for i, m in enumerate(modules)}
    return NativeBuild(folder, {str(m): None for m in modules}, [warning]), per_module
