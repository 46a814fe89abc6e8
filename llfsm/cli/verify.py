"""`llfsm verify`: explore an arrangement and judge properties (docs/verify.md)."""

from __future__ import annotations

import sys

import click

from .. import __version__
from ._group import DURATION, cli, fail, write_output


@cli.command()
@click.argument("targets", nargs=-1, required=True)
@click.option(
    "--property",
    "properties",
    multiple=True,
    metavar="KIND:TEXT",
    help="A property: always, never, reachable, eventually, leads_to, ctl or ltl, then its text "
    '(`never: state(p) == "CRIT" and state(q) == "CRIT"`).  Repeatable.',
)
@click.option(
    "--period", type=DURATION, default=None, help="Explore `--clock sim --period P` exactly (default: abstract time)."
)
@click.option("--interrupt", is_flag=True, default=None, help="ros.ok() may fall once, before any ringlet.")
@click.option(
    "--max-states", type=int, default=None, help="Stop past this many configurations (default 1,000,000): exit 3."
)
@click.option(
    "--max-memory",
    metavar="SIZE",
    default=None,
    help="Stop past this much memory in use (200MB, 2GB; default: half of what this process may use): exit 3.",
)
@click.option(
    "--hash-compact",
    is_flag=True,
    help="Keep each configuration as a 64-bit hash only (about 60 bytes each; the chance of a collision is printed).",
)
@click.option(
    "--counterexample",
    "counterexample_dir",
    type=click.Path(file_okay=False),
    help="Write the first counterexample's inputs bound to topics as a rosbag2 bag in DIR (with --period).",
)
@click.option(
    "--export",
    "exports",
    type=(click.Choice(["promela", "smv", "dot"]), click.Path(dir_okay=False)),
    multiple=True,
    metavar="promela|smv|dot FILE",
    help="Write the explored structure and the properties as a SPIN or NuSMV model, or draw it.",
)
@click.option(
    "--format", "fmt", type=click.Choice(["text", "json", "github", "sarif"]), default="text", show_default=True
)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the report to FILE instead of stdout.")
@click.option("-q", "--quiet", is_flag=True, help="No progress and no summary on stderr.")
@click.option("-v", "--witnesses", is_flag=True, help="Also show the path to what a reachable (or EF) property found.")
def verify(
    targets: tuple[str, ...],
    properties: tuple[str, ...],
    period: int | None,
    interrupt: bool | None,
    max_states: int | None,
    max_memory: str | None,
    hash_compact: bool,
    counterexample_dir: str | None,
    exports: tuple[tuple[str, str], ...],
    fmt: str,
    output: str | None,
    quiet: bool,
    witnesses: bool,
) -> None:
    """Explore every reachable configuration of an arrangement and judge properties.

    TARGET: machines as `llfsm run` takes them (in load order), or a NAME.verify.yaml that lists
    the machines and the properties.  Exit status: 0 every property holds, 1 one fails (or
    machine code raised), 2 bad input or code verify cannot explore, 3 the state limit or the
    memory bound.
    """
    # deferred: start-up (every command module is imported when `llfsm` starts)
    from pathlib import Path

    from ..lang.diagnostics import render as render_diagnostics
    from ..props.kinds import KINDS
    from ..runtime.clock import parse_duration
    from ..verify.explorer import Options
    from ..verify.judge import verify as run_verification
    from ..verify.load import VERIFY_SUFFIX, PropertySource, VerifyError, load_arrangement, read_verify_file
    from ..verify.memory import parse_size
    from ..verify.report import render

    sources: list[PropertySource] = []
    machines: list[str] = []
    file_options: dict[str, object] = {}
    environment = None
    bounds: dict[str, float] = {}
    try:
        for t in targets:
            if t.endswith(VERIFY_SUFFIX):
                vf = read_verify_file(Path(t))
                machines += vf.machines
                sources += vf.properties
                file_options.update(vf.options)
                if vf.environment:
                    environment = vf.environment
                bounds.update(vf.bounds)
            else:
                machines.append(t)
        for text in properties:
            kind, sep, body = text.partition(":")
            if not sep or kind.strip() not in KINDS:
                fail(f"--property {text!r}: write KIND:TEXT, KIND one of {', '.join(KINDS)}")
            sources.append(PropertySource(kind.strip(), body.strip()))
        if period is None and "period" in file_options:
            try:
                period = parse_duration(str(file_options["period"]))
            except ValueError as e:
                fail(f"period in the verification file: {e}")
        if period is not None and period <= 0:
            fail("--period must be greater than 0")
        if interrupt is None:
            interrupt = bool(file_options.get("interrupt", False))
        if max_states is None:
            ms = file_options.get("max_states", 1_000_000)
            if not isinstance(ms, int) or isinstance(ms, bool):
                fail("max_states in the verification file must be a whole number")
            max_states = ms
        if max_states < 1:
            fail("--max-states must be at least 1")
        memory: int | None = None
        size = max_memory if max_memory is not None else file_options.get("max_memory")
        if size is not None:
            try:
                memory = parse_size(str(size))
            except ValueError as e:
                fail(f"--max-memory: {e}" if max_memory is not None else f"max_memory in the verification file: {e}")
        if counterexample_dir is not None:
            if period is None:
                fail("--counterexample writes a bag replayed with `llfsm run --clock sim --period P`: give --period P")
            from ..verify.replay import ReplayError, check_folder  # deferred: start-up (only with the option)

            try:
                check_folder(counterexample_dir)
            except ReplayError as e:
                fail(f"--counterexample {counterexample_dir}: {e}")
        loaded = load_arrangement(machines, environment, bounds)
        options = Options(period=period, interrupt=bool(interrupt), max_states=max_states, hash_compact=hash_compact)
        options.max_memory = memory
        show = None if quiet else _progress()
        result = run_verification(
            loaded, sources, options, show, keep_graph=bool(exports), judging=None if show is None else show.judging
        )
        if show is not None:
            show.done()
    except VerifyError as e:
        if e.diagnostics:
            click.echo(render_diagnostics(e.diagnostics, fmt, __version__), nl=False)
        if e.details:
            click.echo(e.details, nl=False, err=True)
        click.echo(f"llfsm: {e.message}", err=True)
        sys.exit(e.status)
    for kind, path in exports:
        from ..verify.export import write_export  # deferred: start-up (only --export writes one)

        try:
            data = write_export(kind, result)
        except ValueError as e:
            fail(str(e))
        write_output(path, data.encode("utf-8"), f"--export {kind}")
    report = render(result, fmt, __version__, witnesses)
    if output:
        write_output(output, report.encode("utf-8"), "-o")
    else:
        click.echo(report, nl=False)
    sys.stdout.flush()  # the report first, whatever happens to the bag, and before the summary
    if counterexample_dir is not None:
        from ..verify.replay import ReplayError, write_counterexample  # deferred: start-up (only with the option)

        try:
            said = write_counterexample(result, counterexample_dir)
        except ReplayError as e:
            click.echo(f"llfsm: --counterexample: {e}", err=True)
            said = None
        if said and not quiet:
            click.echo(f"llfsm: {said}", err=True)
    if not quiet:
        extra = ""
        if hash_compact and result.configurations:
            n = result.configurations
            extra = f"; hash compaction: chance of a collision about {n * n / 2**65:.1e}"
        failed = sum(o.verdict == "fails" for o in result.outcomes)
        click.echo(
            f"verified {len(result.outcomes)} propert{'y' if len(result.outcomes) == 1 else 'ies'}: "
            f"{failed} failed; {result.configurations:,} configurations, {result.steps:,} steps, "
            f"{result.seconds:.2f} s{extra}",
            err=True,
        )
    sys.exit(result.status)


class _progress:
    """The exploration's progress (the explorer reports about every second) on the status line
    of llfsm.progress: rewritten each second on a terminal; in a log, a line after 2 s, then
    every 10 s."""

    def __init__(self) -> None:
        # deferred: start-up (every command module is imported when `llfsm` starts)
        from ..progress import Status

        self.status = Status(log_after=2.0, log_every=10.0)

    def __call__(self, explored: int, queue: int, seconds: float) -> None:
        rate = explored / seconds if seconds else 0
        line = f"llfsm verify: {explored:,} configurations ({rate:,.0f}/s), queue {queue:,}, {seconds:.0f} s"
        self.status.progress(line, seconds)

    def judging(self, name: str, nodes: int, states: int, seconds: float) -> None:
        """An `ltl:` property judged on the explored structure: its product with the automaton."""
        line = f"llfsm verify: judging {name}: {nodes:,} product states ({states:,} automaton states), {seconds:.0f} s"
        self.status.progress(line, seconds)

    def done(self) -> None:
        self.status.clear()
