"""`llfsm build`: compile machines into importable modules (incremental, atomic)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ._common import EXIT_ERRORS, EXIT_OK, _existing, cli, fail, progress

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
def build(paths: tuple[str, ...], out: str, force: bool, quiet: bool) -> None:
    """Compile machines into importable modules (incremental; atomic writes).

    With no PATH, every machine below the current folder (e.g. a package root) is built.
    """
    from ..compiler.build import build_machine
    from ..discover import find_machines

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
    out_dir = Path(out)
    failed = 0
    for i, path in enumerate(machines, 1):
        try:
            outcome = build_machine(path, out_dir, force=force)
        except OSError as e:  # the output cannot be written: not the machine's fault, still a failure
            failed += 1
            target = out_dir / f"{path.name.removesuffix('.machine')}.py"
            progress(f"llfsm: cannot write {target}: {e.strerror or e}\n")
            continue
        if outcome.status == "failed":
            from ..diagnostics import format_text

            failed += 1
            progress(format_text(outcome.diagnostics))
        if not quiet:
            where = f" -> {outcome.module}" if outcome.module else ""
            progress(f"[{i}/{len(machines)}] {outcome.name}: {outcome.status}{where}\n")
    sys.exit(EXIT_ERRORS if failed else EXIT_OK)
