"""Content fingerprints for incremental builds, and the stat record that spares a warm run
from hashing.

Deliberately light: `llfsm run DIR.machine` calls it to decide whether the cached module is
fresh, and must not import the compiler to find out that it is.  Importing this module costs
nothing (hashlib and pathlib are imported by the functions that hash); `unchanged_since_record`,
the test of a warm run, only lists and stats files.
"""

from __future__ import annotations

import os
import stat
import time

from . import __version__
from .machinedir import LAYOUT_FILE, refused_link, source_ref

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from pathlib import Path

HEADER_KEY = "# Fingerprint: "
_PKG = os.path.dirname(os.path.abspath(__file__))
#: A file changed this recently (ns) may change again within the same clock tick unseen: a stat
#: record is written only when every file is older than this (git's "racily clean" rule).
RACY_NS = 2_000_000_000
_compiler_id: str | None = None
_compiler_paths: list[str] | None = None


def _compiler_files() -> list[str]:
    """What shapes generated code besides the version: the machine templates and the compiler
    (listed once per process: a warm build stats them for each of its machines)."""
    global _compiler_paths
    if _compiler_paths is None:
        _compiler_paths = _list_compiler_files()
    return _compiler_paths


def _list_compiler_files() -> list[str]:
    """The machine template, the compiler, the front end (lang/) whose reading of a machine the
    compiler generates from, and the generated module's contract (runtime/generated.py)."""
    templates = os.path.join(_PKG, "templates")
    out = sorted(
        os.path.join(templates, n) for n in os.listdir(templates) if n.startswith("machine") and n.endswith(".j2")
    )
    for folder in ("compiler", "lang", os.path.join("lang", "check")):
        d = os.path.join(_PKG, folder)
        out += sorted(os.path.join(d, n) for n in os.listdir(d) if n.endswith(".py") and not n.startswith("."))
    out.append(os.path.join(_PKG, "runtime", "generated.py"))
    return out


def compiler_id() -> str:
    """Changes whenever anything that shapes generated code changes: version, templates, compiler."""
    global _compiler_id
    if _compiler_id is None:
        import hashlib  # deferred: start-up (a warm run never hashes: hashlib is a tenth of it)

        h = hashlib.sha256(__version__.encode())
        for p in _compiler_files():
            h.update(os.path.basename(p).encode())
            with open(p, "rb") as f:
                h.update(f.read())
        _compiler_id = h.hexdigest()[:16]
    return _compiler_id


def machine_fingerprint(path: str | Path, module_dir: str | Path, known: dict[str, bytes] | None = None) -> str:
    """Hash of every regular file of a machine directory (names and bytes), the compiler id,
    and the machine folder as a module built into `module_dir` names it (the one place the
    module's text depends on where things are: machinedir.source_ref).
    `known`: bytes already read (by the checker), by file name: only the others are read.
    (os.path, not pathlib: a run after an edit hashes the files and should not pay for it.)"""
    import hashlib  # deferred: start-up (a warm run never hashes: hashlib is a tenth of it)

    if os.path.islink(path):
        from pathlib import Path  # deferred: start-up (only a linked machine directory needs it)

        if refused_link(Path(path)) is not None:  # never read; the build then reports it (LF037)
            raise OSError(f"{path} is a symlink leading out of its folder")
    h = hashlib.sha256(compiler_id().encode())
    h.update(os.fsencode(source_ref(path, module_dir)))
    with os.scandir(path) as it:  # file types from the listing: no stat per file
        # layout.yaml is where the editor drew the states: it changes nothing a build makes
        entries = sorted((e for e in it if not e.name.startswith(".") and e.name != LAYOUT_FILE), key=lambda e: e.name)
    for e in entries:
        name = e.name
        try:
            regular = e.is_file()
        except OSError:  # as os.path.isfile decides (a symlink loop is no file)
            regular = os.path.isfile(os.path.join(path, name))
        if not regular:
            continue
        p = os.path.join(path, name)
        if known is not None and name in known:
            data = known[name]
        else:
            with open(p, "rb") as f:
                data = f.read()
        h.update(b"\0%s\0%d\0" % (os.fsencode(name), len(data)))
        h.update(data)
    return h.hexdigest()


def module_fingerprint(module: str | os.PathLike[str]) -> str | None:
    """The fingerprint recorded in a generated module's header, if it has one."""
    try:
        with open(module, encoding="utf-8", errors="replace") as f:
            for _ in range(5):
                line = f.readline()
                if line.startswith(HEADER_KEY):
                    return line[len(HEADER_KEY) :].strip()
    except OSError:
        return None
    return None


# -- the stat record of a warm run ---------------------------------------------------------------


def stat_signature(machine_dir: str) -> tuple[str, int] | None:
    """What the machine's files and the compiler look like to stat (names, sizes, times, inodes),
    with the newest change time among them; None when the folder cannot be listed or is a link
    (the hashing path decides about those).  The same files as machine_fingerprint reads."""
    if os.path.islink(machine_dir):
        return None
    lines = [__version__, os.path.abspath(machine_dir)]
    newest = 0
    try:
        with os.scandir(machine_dir) as it:
            entries = sorted((e.name, e.path) for e in it if not e.name.startswith(".") and e.name != LAYOUT_FILE)
        files = entries + [(p, p) for p in _compiler_files()]
    except OSError:
        return None
    for name, path in files:
        try:
            st = os.stat(path)
        except OSError:
            continue  # a dangling link: machine_fingerprint skips it too
        if not stat.S_ISREG(st.st_mode):
            continue
        lines.append(f"{name}\0{st.st_size}\0{st.st_mtime_ns}\0{st.st_ctime_ns}\0{st.st_ino}\0{st.st_dev}")
        newest = max(newest, st.st_ctime_ns, st.st_mtime_ns)
    return "\n".join(lines), newest


def _record_file(module: str) -> str:
    return module + ".stat"


def unchanged_since_record(machine_dir: str, module: str) -> bool:
    """True when the module's fingerprint and the machine's stat signature are those recorded
    by record_fresh: the module is up to date without reading or hashing a file."""
    try:
        with open(_record_file(module), encoding="utf-8", errors="replace") as f:
            recorded = f.read()
    except OSError:
        return False
    fp, _, sig = recorded.partition("\n")
    now = stat_signature(machine_dir)
    return now is not None and sig == now[0] and fp != "" and fp == module_fingerprint(module)


def record_fresh(machine_dir: str, module: str, fp: str) -> None:
    """After the module was found (by hashing) or made up to date: remember the stat signature,
    unless a file changed so recently that a change within the same clock tick could be missed."""
    now = stat_signature(machine_dir)
    if now is None or now[1] > time.time_ns() - RACY_NS:
        return
    record = _record_file(module)
    tmp = f"{record}.{os.getpid()}.tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(f"{fp}\n{now[0]}")
        os.replace(tmp, record)
    except OSError:
        try:
            os.unlink(tmp)
        except OSError:
            pass
