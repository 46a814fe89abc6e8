"""`llfsm check`: validate machine directories without running any of their code."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .. import __version__
from ._group import EXIT_ERRORS, EXIT_OK, _existing, cli, fail, write_output

# -- check -------------------------------------------------------------------------------------


def _enclosing_machines(paths: tuple[str, ...]) -> tuple[str, ...]:
    """A file inside a NAME.machine directory stands for that machine: pre-commit passes the
    files that changed, and a machine is only ever checked whole."""
    out: list[str] = []
    for p in paths:
        path = Path(p)
        if path.is_file():
            p = next((str(d) for d in path.parents if d.name.endswith(".machine") and d.is_dir()), p)
        if p not in out:
            out.append(p)
    return tuple(out)


@cli.command()
@click.argument("paths", nargs=-1, required=True)
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json", "github", "sarif"]),
    default="text",
    show_default=True,
    help="Output format of the diagnostics.",
)
@click.option("--strict", is_flag=True, help="Warnings fail the check too (exit 1).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the report to FILE instead of stdout.")
@click.option("-q", "--quiet", is_flag=True, help="No summary line on stderr.")
@click.option(
    "-j", "--jobs", type=int, default=None, help="Worker processes (default: one per core from 48 machines on, else 1)."
)
def check(paths: tuple[str, ...], fmt: str, strict: bool, output: str | None, quiet: bool, jobs: int | None) -> None:
    """Validate machine directories without running any of their code.

    A PATH is a NAME.machine directory, a folder searched for them, or a file inside a machine
    directory (that machine: pre-commit passes files).  Exit status: 0 clean (warnings allowed
    unless --strict), 1 problems found, 2 bad usage.
    """
    # deferred: start-up (every command module is imported when `llfsm` starts; the checker
    # and its yaml and pydantic only when `check` runs)
    from ..lang.check import diagnose
    from ..lang.diagnostics import Severity, render

    roots = _existing(_enclosing_machines(paths))
    if jobs is not None and jobs < 1:
        fail("--jobs must be at least 1")
    count, diags = diagnose(roots, jobs)
    if not count:
        fail(f"no NAME.machine directories found in {', '.join(paths)}")
    text = render(diags, fmt, __version__)
    if output:
        write_output(output, text.encode("utf-8"), "-o")
    else:
        click.echo(text, nl=False)
    errors = sum(d.severity is Severity.ERROR for d in diags)
    warnings = len(diags) - errors
    if not quiet:
        click.echo(f"checked {count} machine(s): {errors} error(s), {warnings} warning(s)", err=True)
    sys.exit(EXIT_ERRORS if errors or (strict and warnings) else EXIT_OK)
