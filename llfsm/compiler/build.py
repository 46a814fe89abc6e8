"""Builds: validation first, an incremental skip when nothing changed (a content fingerprint in
the module header), and atomic writes, so an interrupted build never leaves half a module."""

from __future__ import annotations

import contextlib
import os
import secrets
import signal
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from ..discover import machine_name_of
from ..fingerprint import machine_fingerprint, module_fingerprint

if TYPE_CHECKING:
    from ..diagnostics import Diagnostic

# -- builds ------------------------------------------------------------------------------------


@dataclass
class BuildOutcome:
    path: Path  # machine directory
    module: Path | None
    status: str  # compiled | unchanged | failed
    diagnostics: list[Diagnostic] = field(default_factory=list)
    name: str = ""


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


def build_machine(path: Path, out_dir: Path, force: bool = False) -> BuildOutcome:
    """Compile one machine into out_dir/NAME.py unless the module there is already up to date."""
    name = machine_name_of(path)
    target = out_dir / f"{name}.py"
    try:
        fp = machine_fingerprint(path)
    except OSError:
        fp = ""
    if not force and fp and module_fingerprint(target) == fp:
        return BuildOutcome(path, target, "unchanged", name=name)
    # only now the checker and the code generator (pydantic, yaml, jinja2): warm builds skip them
    from ..check import check_machine
    from .generate import CompileError, compile_machine

    checked = check_machine(path)
    if not checked.ok:
        return BuildOutcome(path, None, "failed", checked.diagnostics, name=name)
    try:
        source = compile_machine(checked, fp)
    except CompileError as e:
        return BuildOutcome(path, None, "failed", checked.diagnostics + e.diagnostics, name=name)
    write_atomic(target, source)
    return BuildOutcome(path, target, "compiled", checked.diagnostics, name=name)


#: From this many machines to compile on, `build_all` spreads the work over worker processes.
PARALLEL_FROM = 32


def _build_or_error(path: Path, out_dir: Path, force: bool) -> BuildOutcome | str:
    """build_machine in a worker: an output that cannot be written comes back as its message."""
    try:
        return build_machine(path, out_dir, force)
    except OSError as e:
        return str(e.strerror or e)


def build_all(
    paths: Sequence[Path], out_dir: Path, force: bool = False, jobs: int | None = None
) -> Iterator[BuildOutcome | str]:
    """build_machine for each path, in order (a str for an output that cannot be written).

    Machines whose module is up to date are found in this process (a fingerprint each); the
    rest are compiled by worker processes, one per core, when there are many of them."""
    stale = []
    for path in paths:
        if not force:
            target = out_dir / f"{machine_name_of(path)}.py"
            try:
                fp = machine_fingerprint(path)
            except OSError:
                fp = ""
            if fp and module_fingerprint(target) == fp:
                continue
        stale.append(path)
    if jobs is None:
        jobs = (os.cpu_count() or 1) if len(stale) >= PARALLEL_FROM else 1
    results: Iterator[BuildOutcome | str]
    if jobs > 1 and len(stale) > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        from ..check import check_machine  # noqa: F401 (imported once, before the workers fork)
        from .generate import compile_machine  # noqa: F401

        ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx)
        chunk = max(1, len(stale) // (jobs * 8))
        results = pool.map(_build_or_error, stale, [out_dir] * len(stale), [force] * len(stale), chunksize=chunk)
    else:
        pool = None
        results = (_build_or_error(p, out_dir, force) for p in stale)
    try:
        todo = set(stale)
        for path in paths:
            if path in todo:
                yield next(results)
            else:
                yield BuildOutcome(
                    path, out_dir / f"{machine_name_of(path)}.py", "unchanged", name=machine_name_of(path)
                )
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
