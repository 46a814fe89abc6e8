"""`llfsm build`: compile machines into importable modules (incremental, atomic)."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from ..compiler.build import BuildOutcome

from ._group import EXIT_ERRORS, EXIT_OK, _existing, cli, fail, progress

# -- build -------------------------------------------------------------------------------------


@cli.command()
@click.argument("paths", nargs=-1)
@click.option(
    "-o",
    "--output",
    "out",
    type=click.Path(file_okay=False),
    default="build/llfsm",
    show_default=True,
    help="Folder that receives NAME.py for each machine.",
)
@click.option("--force", is_flag=True, help="Rewrite modules even when they are up to date.")
@click.option("-q", "--quiet", is_flag=True, help="No progress lines.")
@click.option("--native", is_flag=True, help="Also compile the modules and the runtime with mypyc (docs/native.md).")
@click.option(
    "-j", "--jobs", type=int, default=None, help="Worker processes (default: one per core from 32 stale machines on)."
)
def build(
    paths: tuple[str, ...], out: str, force: bool, quiet: bool, native: bool = False, jobs: int | None = None
) -> None:
    """Compile machines into importable modules (incremental; atomic writes).

    With no PATH, every machine below the current folder (e.g. a package root) is built.
    """
    # deferred: start-up (every command module is imported when `llfsm` starts)
    from ..compiler.build import build_all, terminated_as_exception
    from ..lang.discover import find_machines

    roots = _existing(paths) if paths else [Path(".")]
    machines = [m for r in roots for m in find_machines(r)]
    if not machines:
        fail(f"no NAME.machine directories found in {', '.join(paths) or 'the current folder'}")
    names: dict[str, Path] = {}
    for m in machines:
        name = m.name.removesuffix(".machine")
        if name in names:
            fail(f"{m} and {names[name]} would both be built as {name}.py")
        names[name] = m
    if jobs is not None and jobs < 1:
        fail("--jobs must be at least 1")
    out_dir = Path(out)
    outcomes = build_all(machines, out_dir, force, jobs)
    with terminated_as_exception(), contextlib.closing(outcomes):  # an interrupt stops the workers first
        failed = _report(machines, outcomes, out_dir, quiet)
    if native and not failed:
        _native(sorted((out_dir / f"{name}.py").resolve() for name in names), quiet)
    sys.exit(EXIT_ERRORS if failed else EXIT_OK)


def _report(machines: list[Path], outcomes: Iterable[BuildOutcome | str], out_dir: Path, quiet: bool) -> int:
    """One progress line per machine (in order), diagnostics of failures; the number failed."""
    failed = 0
    for i, (path, outcome) in enumerate(zip(machines, outcomes, strict=True), 1):
        if isinstance(outcome, str):  # the output cannot be written: not the machine's fault, still a failure
            failed += 1
            target = out_dir / f"{path.name.removesuffix('.machine')}.py"
            progress(f"llfsm: cannot write {target}: {outcome}\n")
            continue
        if outcome.status == "failed":
            from ..lang.diagnostics import format_text  # deferred: start-up (failures only)

            failed += 1
            progress(format_text(outcome.diagnostics))
        if not quiet:
            where = f" -> {outcome.module}" if outcome.module else ""
            progress(f"[{i}/{len(machines)}] {outcome.name}: {outcome.status}{where}\n")
            if outcome.helpers and outcome.module is not None:
                progress(_helpers_note(outcome.helpers, outcome.module))
    return failed


def _helpers_note(helpers: list[Path], module: Path) -> str:
    """What a built module needs besides itself: the helper modules beside its machine folder,
    found there by a run of the module as long as they stay; copied beside it, anywhere."""
    names = ", ".join(str(h) for h in helpers)
    return (
        f"    imports helper modules {names}: a run of {module} finds them there; "
        f"to run it elsewhere, copy them beside it\n"
    )


def _native(modules: list[Path], quiet: bool) -> None:
    """One mypyc compile for every module of the build (cached in the llfsm cache)."""
    # deferred: start-up (--native only)
    from ..cachedir import cache_root
    from ..compiler.native import NativeUnavailable, native_build
    from ..progress import Status

    try:
        with Status().doing("native") as say:
            nb = native_build(modules, cache_root(), say)
    except NativeUnavailable as e:
        fail(f"--native: {e}")
    for w in nb.warnings:
        progress(w + "\n")
    if not quiet:
        done = sum(1 for v in nb.modules.values() if v)
        how = "found in the cache" if nb.cached else "compiled"
        progress(f"native: {done} of {len(modules)} machines {how} ({nb.folder})\n")
