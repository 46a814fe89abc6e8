"""`llfsm graph` and `llfsm schema`: a machine's diagram, and the JSON Schema of machine.yaml."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ._group import EXIT_ERRORS, cli, fail, write_output

# -- graph, schema -------------------------------------------------------------------------------


@cli.command()
@click.argument("path", type=click.Path())
@click.option(
    "--format", "fmt", type=click.Choice(["mermaid", "dot", "svg", "png"]), default="mermaid", show_default=True
)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write to FILE (needed for png).")
def graph(path: str, fmt: str, output: str | None) -> None:
    """The machine's diagram, guards on the arrows: Mermaid or Graphviz text, or SVG and PNG
    drawn by llfsm itself (the web view's drawing; the states where layout.yaml places them)."""
    # deferred: start-up (every command module is imported when `llfsm` starts)
    from ..diagram.dot import dot
    from ..diagram.mermaid import mermaid
    from ..lang.check import check_machine
    from ..lang.diagnostics import Severity, format_text

    p = Path(path)
    if not p.is_dir():
        fail(f"{path}: not a machine directory")
    if fmt == "png" and not output:
        fail("--format png writes binary data: give -o FILE.png")
    result = check_machine(p)
    blocking = [
        d
        for d in result.diagnostics
        if d.severity is Severity.ERROR and d.code in {"LF001", "LF002", "LF003", "LF004", "LF005"}
    ]
    if result.machine is None or blocking:
        click.echo(format_text(result.diagnostics), nl=False, err=True)
        sys.exit(EXIT_ERRORS)
    m = result.machine
    if fmt in ("svg", "png"):
        # deferred: start-up (pydantic, Pillow)
        from ..diagram.description import of_machine
        from ..diagram.svg import standalone, svg
        from ..lang.layout_file import placement

        placed = placement(result.read)[0]
        if placed is None:
            drawn = svg(of_machine(m))
        else:
            drawn = svg(of_machine(m), positions=placed.states, labels=placed.labels)
        if fmt == "png":
            from ..diagram.png import render  # deferred: start-up (Pillow)

            data = render(drawn)
        else:
            data = standalone(drawn).encode()
    else:
        data = (mermaid(m) if fmt == "mermaid" else dot(m)).encode()
    if output:
        write_output(output, data, "-o")
    else:
        sys.stdout.write(data.decode())


@cli.command()
def schema() -> None:
    """JSON Schema of machine.yaml."""
    import json  # deferred: start-up (as above)

    from ..lang.model import MachineYaml  # deferred: start-up (pydantic)

    click.echo(json.dumps(MachineYaml.model_json_schema(), indent=2))
