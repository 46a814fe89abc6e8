"""Builds: validation first, an incremental skip when nothing changed (a content fingerprint in
the module header), and atomic writes, so an interrupted build never leaves half a module."""

from __future__ import annotations

import ast
import contextlib
import gc
import hashlib
import json
import os
import secrets
import signal
import sys
import threading
import time
from collections.abc import Generator, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..cachedir import cache_root
from ..fingerprint import RACY_NS, compiler_id, machine_fingerprint, module_fingerprint, stat_signature
from ..machinedir import machine_name_of, source_ref
from ..workers import die_with_parent, usable_cores

if TYPE_CHECKING:
    from ..lang.diagnostics import Diagnostic

# -- builds ------------------------------------------------------------------------------------


@dataclass
class BuildOutcome:
    path: Path  # machine directory
    module: Path | None
    status: str  # compiled | unchanged | failed
    diagnostics: list[Diagnostic] = field(default_factory=list)
    name: str = ""
    fingerprint: str = ""  # of the machine's files, as written into the module
    signature: str = ""  # _StatCache.signature, when the worker took it (before reading)
    #: helper modules the machine imports from beside its folder, when the module is written
    #: elsewhere (a run of the module imports them from there: `llfsm build` says so)
    helpers: list[Path] = field(default_factory=list)


#: Signals held back while a module is written: Ctrl-C, `kill` and a closed terminal.
_DEFERRED = frozenset(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold back interrupting signals until the block ends.

    A Ctrl-C (KeyboardInterrupt) can strike between any two bytecodes, and a SIGTERM with its
    default action kills the process on the spot, either of which could leave a temporary
    file behind.  Blocked signals stay pending and take effect as soon as the write is done.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # the current mask first, without changing it: an interrupt that lands between the two
    # calls then finds nothing blocked, and the `finally` always knows what to restore
    old = signal.pthread_sigmask(signal.SIG_BLOCK, ())
    try:
        signal.pthread_sigmask(signal.SIG_BLOCK, _DEFERRED)
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def write_atomic_bytes(target: Path, data: bytes) -> None:
    """Write via a temporary file in the same folder and rename: readers see old or new, never half."""
    target.parent.mkdir(parents=True, exist_ok=True)
    # named before it exists, so that the cleanup can remove it whenever an interrupt lands
    tmp = target.parent / f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    with _signals_deferred():
        try:
            fd = os.open(tmp, flags, 0o666)  # the umask applies, as for any file the user writes
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, target)  # atomic for every reader; no fsync: a build can be redone
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise


def write_atomic(target: Path, text: str) -> None:
    write_atomic_bytes(target, text.encode("utf-8"))


def build_machine(path: Path, out_dir: Path, force: bool = False, fp: str | None = None) -> BuildOutcome:
    """Compile one machine into out_dir/NAME.py unless the module there is already up to date
    (`fp`: the machine's fingerprint, when the caller has it already)."""
    name = machine_name_of(path)
    target = out_dir / f"{name}.py"
    if fp is None and not force and target.exists():
        try:
            fp = machine_fingerprint(path, out_dir)
        except OSError:
            fp = ""
    if not force and fp and module_fingerprint(target) == fp:
        return BuildOutcome(path, target, "unchanged", name=name, fingerprint=fp)
    # deferred: start-up (the checker and the code generator import pydantic, yaml and jinja2;
    # a warm build, and a warm `llfsm run`, which imports this module to compile, skip them)
    from ..lang.check import check_machine
    from .generate import CompileError, compile_machine

    checked = check_machine(path)
    if not checked.ok:
        return BuildOutcome(path, None, "failed", checked.diagnostics, name=name)
    if not fp:  # no module to compare with: hash the bytes the checker has read
        try:
            fp = machine_fingerprint(path, out_dir, checked.read.raw)
        except OSError:
            fp = ""
    try:
        source = compile_machine(checked, fp, source_ref(path, out_dir))
    except CompileError as e:
        return BuildOutcome(path, None, "failed", checked.diagnostics + e.diagnostics, name=name)
    write_atomic(target, source)
    helpers = helpers_of(path, checked.read.trees, out_dir)
    return BuildOutcome(path, target, "compiled", checked.diagnostics, name=name, fingerprint=fp, helpers=helpers)


#: Most helper files followed from a machine's imports (a helper's own imports are followed too).
MAX_HELPERS = 100


def helpers_of(machine_dir: Path, trees: dict[str, ast.Module], out_dir: Path) -> list[Path]:
    """The helper modules (`NAME.py`, or a package folder) beside `machine_dir` that its code
    imports, and those they import in turn, when the module goes to another folder: a run of
    the module finds them beside the machine folder while it is there (llfsm.targets), and
    elsewhere only if they are copied beside the module.  Read as text (`ast`), never run."""
    beside = machine_dir.parent
    try:
        if os.path.samefile(beside, out_dir):
            return []
    except OSError:
        pass
    found: dict[str, Path] = {}
    todo = [name for tree in trees.values() for name in _imported_tops(tree)]
    while todo and len(found) < MAX_HELPERS:
        name = todo.pop(0)
        if name in found or not name.isidentifier():
            continue
        file = beside / f"{name}.py"
        if file.is_file():
            found[name] = file
            try:
                todo += _imported_tops(ast.parse(file.read_bytes()))
            except (OSError, SyntaxError, ValueError, RecursionError, MemoryError):
                pass  # the run reports a helper that does not import; the build only names it
        elif (beside / name / "__init__.py").is_file():
            found[name] = beside / name
    return sorted(found.values())


def _imported_tops(tree: ast.AST) -> list[str]:
    """The top-level module names a tree imports absolutely, at any depth."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name.split(".")[0] for a in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            out.append(node.module.split(".")[0])
    return out


#: From this many machines to compile on, `build_all` spreads the work over worker processes.
PARALLEL_FROM = 32


def _build_or_error(
    path: Path, out_dir: Path, force: bool, fp: str | None = None, sign: bool = False
) -> BuildOutcome | str:
    """build_machine in a worker: an output that cannot be written comes back as its message.
    `sign`: take the machine's stat signature first (before anything is read, so that an edit
    during the build is seen next time), here rather than serially in the parent."""
    sig = _StatCache.signature(path) if sign else ""
    try:
        outcome = build_machine(path, out_dir, force, fp)
    except OSError as e:
        return str(e.strerror or e)
    outcome.signature = sig
    return outcome


def build_all(
    paths: Sequence[Path], out_dir: Path, force: bool = False, jobs: int | None = None
) -> Generator[BuildOutcome | str, None, None]:
    """build_machine for each path, in order (a str for an output that cannot be written).

    Machines whose module is up to date are found in this process (a fingerprint each); the
    rest are compiled by worker processes, one per core, when there are many of them.  A
    machine whose files have the same names, sizes, modification times and inodes as at its last
    build (recorded in the llfsm cache) is not even read again."""
    stats = _StatCache(out_dir)
    stale: list[Path] = []
    fps: list[str | None] = []
    sigs: dict[Path, str | None] = {}
    for path in paths:
        target = out_dir / f"{machine_name_of(path)}.py"
        known = stats.known.get(str(path))
        old = module_fingerprint(target)
        # with neither a record nor a module, the worker that builds the machine signs it
        sig = stats.signature(path) if known is not None or old is not None else None
        if not force and sig and known == [sig, old]:
            stats.keep(path, sig)
            continue
        fp: str | None = None
        if old is not None and not force:  # a module to compare with: hash the machine's files
            try:
                fp = machine_fingerprint(path, out_dir)
            except OSError:
                fp = ""
            if fp and old == fp:
                stats.record(path, sig or "", fp)
                continue
        stale.append(path)
        fps.append(fp)
        sigs[path] = sig  # taken before anything was read: an edit during the build is seen next time
    if jobs is None:  # the cores this process may use (taskset, a container's cpuset), as check does
        jobs = usable_cores() if len(stale) >= PARALLEL_FROM else 1
    results: Iterator[BuildOutcome | str]
    pool = None
    safe: _SafePoints | None = None
    if jobs > 1 and len(stale) > 1:
        # deferred: start-up (a build of a few machines never starts worker processes); the
        # compiler is imported once here, before the workers fork, rather than by each of them
        import multiprocessing

        from ..lang.check import check_machine  # noqa: F401
        from .generate import compile_machine  # noqa: F401

        compiler_id()  # read once here, not by every worker
        ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
        gc.freeze()  # the workers' collector leaves the inherited objects alone: fewer pages copied
        with _signals_deferred():  # an interrupt never lands between two forks: every worker is known
            pool = ctx.Pool(jobs, initializer=_worker_init, initargs=(os.getpid(),))
            safe = _SafePoints()  # before the signals held back meanwhile arrive
        chunk = max(1, len(stale) // (jobs * 8))
        work = [(p, out_dir, force, fp, sigs[p] is None) for p, fp in zip(stale, fps, strict=True)]
        results = _results_of(pool.imap(_build_chunk, [work[i : i + chunk] for i in range(0, len(work), chunk)]), safe)
    else:
        results = (_build_or_error(p, out_dir, force, fp, sigs[p] is None) for p, fp in zip(stale, fps, strict=True))
    try:
        todo = set(stale)
        for path in paths:
            if path in todo:
                outcome = next(results)
                if isinstance(outcome, BuildOutcome) and outcome.status != "failed":
                    stats.record(path, sigs[path] or outcome.signature, outcome.fingerprint)
                yield outcome
            else:
                yield BuildOutcome(
                    path, out_dir / f"{machine_name_of(path)}.py", "unchanged", name=machine_name_of(path)
                )
    except BaseException:
        if safe is not None:
            safe.restore()
        if pool is not None:  # Ctrl-C, SIGTERM: stop the workers (each finishes the module it writes)
            pool.terminate()
            pool = None
        raise
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    stats.save()
    if safe is not None:  # an interrupt that came after the last result: taken now, all written
        safe.take()
        safe.restore()


def _results_of(batches: Any, safe: _SafePoints) -> Iterator[BuildOutcome | str]:
    """The outcomes of the workers' batches in order (`batches`: Pool.imap's iterator), waited
    for in short steps that take any interrupt noted meanwhile (see _SafePoints)."""
    import multiprocessing  # deferred: start-up (only a parallel build waits for workers)

    while True:
        safe.take()
        try:
            batch = batches.next(timeout=0.05)
        except multiprocessing.TimeoutError:
            continue
        except StopIteration:
            return
        yield from batch


class _SafePoints:
    """While workers build, an interrupting signal (Ctrl-C, SIGTERM, SIGHUP) only notes itself,
    and the loop that waits for results raises it at a safe point, by its own handler.  Raised
    where it lands, a KeyboardInterrupt can strike inside the finaliser of one of
    multiprocessing's pipes, where Python prints "Exception ignored" with a traceback and drops
    it: the build would go on as if nobody had pressed Ctrl-C.  Installed on first use, in the
    main thread only (elsewhere signals are not this thread's to handle)."""

    def __init__(self) -> None:
        self.pending: int | None = None
        self.old: dict[int, Any] = {}
        if threading.current_thread() is threading.main_thread():
            for s in _DEFERRED:
                self.old[s] = signal.signal(s, self._note)

    def _note(self, signum: int, _frame: object) -> None:
        if self.pending is None:
            self.pending = signum

    def take(self) -> None:
        """Raise the noted signal here (its handler runs as if it had just arrived)."""
        if self.pending is not None:
            signum, self.pending = self.pending, None
            self.restore()
            signal.raise_signal(signum)

    def restore(self) -> None:
        for s, h in self.old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
        self.old = {}


def _build_chunk(work: list[tuple[Path, Path, bool, str | None, bool]]) -> list[BuildOutcome | str]:
    return [_build_or_error(*args) for args in work]


def _worker_init(parent: int | None = None) -> None:
    """Workers leave Ctrl-C to the parent (no traceback from each of them); the parent stops
    them with SIGTERM, which write_atomic_bytes holds back until a module is whole.  A parent
    killed outright (SIGKILL, the OOM killer) sends them SIGTERM too, as check's workers end."""
    if parent is not None:
        die_with_parent(parent, signal.SIGTERM)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "pthread_sigmask"):  # forked while the parent held signals back
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _DEFERRED)


class _Terminated(BaseException):
    """SIGTERM while workers build: unwinds like Ctrl-C, so that the workers are stopped."""


@contextlib.contextmanager
def terminated_as_exception() -> Iterator[None]:
    """While a parallel build runs, SIGTERM raises _Terminated instead of killing this process
    outright (which would leave its workers running); afterwards the process ends by SIGTERM."""

    def handler(_signum: int, _frame: object) -> None:
        raise _Terminated

    def unraisable(info: Any) -> None:
        """A signal whose handler ran inside a finalizer (a __del__, a weakref callback) raised
        where Python can only print "Exception ignored in ..." and go on building: say nothing
        and deliver the signal again, so it stops the build at the next bytecode instead."""
        again = {_Terminated: signal.SIGTERM, KeyboardInterrupt: signal.SIGINT}.get(type(info.exc_value))
        if again is None:
            previous_hook(info)
            return
        # a moment later and from another thread (sent from this one, the handler would run at
        # once, still inside the finalizer); if it lands in a finalizer again, this comes again
        later = threading.Timer(0.05, os.kill, args=(os.getpid(), again))
        later.daemon = True
        later.start()

    old = signal.signal(signal.SIGTERM, handler)
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield
    except _Terminated:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        raise
    finally:
        sys.unraisablehook = previous_hook
        signal.signal(signal.SIGTERM, old)


class _StatCache:
    """What each machine's files looked like (names, sizes, mtimes, inodes) when its module was
    last found or made up to date, with that module's fingerprint: a warm build of a thousand
    machines then stats their files instead of reading them.  Kept in the llfsm cache, per
    output folder; any difference (a touched file, another output) falls back to the contents."""

    def __init__(self, out_dir: Path) -> None:
        key = hashlib.sha256(os.fsencode(os.path.abspath(out_dir))).hexdigest()[:16]
        self.file = cache_root() / "buildstat" / f"{key}.json"
        try:
            self.known: dict[str, list[str | None]] = json.loads(self.file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            self.known = {}
        self.now: dict[str, list[str | None]] = {}

    @staticmethod
    def signature(path: Path) -> str:
        """The stat signature that `llfsm run`'s record uses too (fingerprint.stat_signature:
        names, sizes, times, inodes, the compiler's files), hashed; "" when a file changed too
        recently to be trusted (a change within the same clock tick could go unseen)."""
        sig = stat_signature(str(path))
        if sig is None or sig[1] > time.time_ns() - RACY_NS:
            return ""
        return hashlib.sha256(sig[0].encode()).hexdigest()

    def keep(self, path: Path, sig: str) -> None:
        self.now[str(path)] = self.known[str(path)]

    def record(self, path: Path, sig: str, fp: str) -> None:
        if sig and fp:
            self.now[str(path)] = [sig, fp]

    def save(self) -> None:
        if self.now == self.known:
            return
        with contextlib.suppress(OSError):
            write_atomic(self.file, json.dumps(self.now))
