"""`llfsm import`: bring clfsm (MiEditLLFSM) machines into llfsm (docs/import.md)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ._group import EXIT_ERRORS, EXIT_OK, _existing, cli, fail


@cli.command(name="import")
@click.argument("paths", nargs=-1, required=True)
@click.option(
    "-o", "--output", "out", default=".", show_default=True, help="The folder that receives the NAME.machine folders."
)
@click.option("--format", "fmt", type=click.Choice(["text", "json"]), default="text", show_default=True)
@click.option("--force", is_flag=True, help="Replace llfsm machines already in the output folder.")
def import_(paths: tuple[str, ...], out: str, fmt: str, force: bool) -> None:
    """Import clfsm machine directories (NAME.machine, or folders holding them).

    The structure is carried over exactly and the C++ translated where it is clear; what is
    not is kept as `# UNTRANSLATED` lines that `llfsm check` reports.  Nothing of the clfsm
    machines is executed.  Exit status: 0 every machine imported (even with lines left), 1 a
    machine could not be read or written (the others are still written), 2 bad usage.
    """
    # deferred: start-up (every command module is imported when `llfsm` starts; the importer
    # and its parser only when `import` runs)
    from ..importer import ParserMissing, import_machines
    from ..importer.report import format_json, format_text

    roots = _existing(paths)
    target = Path(out)
    if target.name.endswith(".machine"):
        fail(f"-o {out}: name the folder that receives NAME.machine folders, not a machine")
    if target.exists() and not target.is_dir():
        fail(f"-o {out}: not a folder")
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        fail(f"-o {out}: cannot be made ({e.strerror})")
    try:
        reports = import_machines(roots, target, force)
    except ParserMissing as e:
        fail(str(e))
    click.echo(format_json(reports) if fmt == "json" else format_text(reports), nl=False)
    sys.exit(EXIT_ERRORS if any(r.error for r in reports) else EXIT_OK)
