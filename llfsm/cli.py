"""The `llfsm` command.

Each command imports what it needs when it runs: `llfsm run` must start fast and never load
the compiler's libraries when its cached modules are fresh.  Every failure the user can cause
ends in a one-line-per-problem message and an exit status (1 or 2), never a traceback.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click

from . import __version__

if TYPE_CHECKING:
    from .ros.bus import Bus
    from .runtime import RunContext

EXIT_OK, EXIT_ERRORS, EXIT_USAGE = 0, 1, 2


def fail(message: str, status: int = EXIT_USAGE) -> NoReturn:
    click.echo(f"llfsm: {message}", err=True)
    sys.exit(status)


class Duration(click.ParamType):
    """Seconds (`0.5`) or a number with a unit (`500ms`, `2s`), as nanoseconds."""

    name = "duration"

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> int:
        if isinstance(value, int):
            return value
        from .runtime.clock import parse_duration

        try:
            return parse_duration(str(value))
        except ValueError as e:
            self.fail(str(e), param, ctx)


DURATION = Duration()


def _quiet_broken_pipe() -> NoReturn:
    """Our reader went away (`llfsm run ... | head -1`): end quietly, as `cat` would."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())  # later flushes (and interpreter exit) write nowhere
        except (OSError, ValueError):
            pass
    sys.exit(EXIT_OK)


class _Group(click.Group):
    """Handles a closed pipe before click does: click would turn it into exit status 1."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except BrokenPipeError:
            _quiet_broken_pipe()


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="llfsm")
def cli() -> None:
    """Logic-labelled finite-state machines: check, build and run them."""


# -- check -------------------------------------------------------------------------------------


def _existing(paths: tuple[str, ...]) -> list[Path]:
    out = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            fail(f"{p}: no such file or directory")
        if not path.is_dir():
            fail(f"{p}: not a machine directory or a folder of machines")
        out.append(path)
    return out


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
    from .check import diagnose
    from .diagnostics import Severity, render

    roots = _existing(_enclosing_machines(paths))
    if jobs is not None and jobs < 1:
        fail("--jobs must be at least 1")
    count, diags = diagnose(roots, jobs)
    if not count:
        fail(f"no NAME.machine directories found in {', '.join(paths)}")
    text = render(diags, fmt, __version__)
    if output:
        from .compiler.build import write_atomic

        write_atomic(Path(output), text)
    else:
        click.echo(text, nl=False)
    errors = sum(d.severity is Severity.ERROR for d in diags)
    warnings = len(diags) - errors
    if not quiet:
        click.echo(f"checked {count} machine(s): {errors} error(s), {warnings} warning(s)", err=True)
    sys.exit(EXIT_ERRORS if errors or (strict and warnings) else EXIT_OK)


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
    from .compiler.build import build_machine
    from .discover import find_machines

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
            click.echo(f"llfsm: cannot write {target}: {e.strerror or e}", err=True)
            continue
        if outcome.status == "failed":
            from .diagnostics import format_text

            failed += 1
            click.echo(format_text(outcome.diagnostics), nl=False, err=True)
        if not quiet:
            where = f" -> {outcome.module}" if outcome.module else ""
            click.echo(f"[{i}/{len(machines)}] {outcome.name}: {outcome.status}{where}", err=True)
    sys.exit(EXIT_ERRORS if failed else EXIT_OK)


# -- run ---------------------------------------------------------------------------------------


@cli.command()
@click.argument("targets", nargs=-1, required=True)
@click.option(
    "-v", "--verbose", is_flag=True, help="clfsm's trace on stderr: a line before each ringlet that enters a state."
)
@click.option("--trace", "trace_file", type=click.Path(dir_okay=False), help="Write every event to FILE.jsonl.")
@click.option(
    "--clock",
    type=click.Choice(["wall", "sim"]),
    default="wall",
    show_default=True,
    help="wall: real time; sim: virtual time, reproducible byte for byte.",
)
@click.option("--period", type=DURATION, help="Round period (time-triggered); sim default 1ms.")
@click.option(
    "--idle",
    type=DURATION,
    default="10ms",
    show_default=True,
    help="Wall clock: sleep after a round in which no transition fired.",
)
@click.option("--duration", type=DURATION, help="End the run after this much run time.")
@click.option(
    "--grace",
    type=DURATION,
    default="1s",
    show_default=True,
    help="After Ctrl-C/SIGTERM, keep running rounds this long so machines can reach END.",
)
@click.option("--suspended", "suspended", multiple=True, metavar="MACHINE", help="Load MACHINE suspended.")
@click.option("--keep-accepting", is_flag=True, help="Keep machines loaded in accepting states.")
@click.option(
    "--node",
    "nodes",
    multiple=True,
    metavar="NAME",
    help="Start a node beside the machines: turtlesim, turtle_sensor_poster, teleop.",
)
@click.option("--remap", "remaps", multiple=True, metavar="[NODE:]FROM:=TO", help="Remap a topic or service name.")
@click.option("--param", "params", multiple=True, metavar="[NODE:]NAME:=VALUE", help="Set a node parameter.")
@click.option("--echo", "echoes", multiple=True, metavar="TOPIC", help="Print the topic's messages as YAML.")
@click.option(
    "--image", type=click.Path(dir_okay=False), help="turtlesim: write the picture (.png or .svg) at the end."
)
@click.option("--view", is_flag=True, help="turtlesim: open a live window (needs pygame).")
@click.option("--introspect", is_flag=True, help="At the end, print the nodes, topics and services on stderr.")
def run(
    targets: tuple[str, ...],
    verbose: bool,
    trace_file: str | None,
    clock: str,
    period: int | None,
    idle: int,
    duration: int | None,
    grace: int,
    suspended: tuple[str, ...],
    keep_accepting: bool,
    nodes: tuple[str, ...] = (),
    remaps: tuple[str, ...] = (),
    params: tuple[str, ...] = (),
    echoes: tuple[str, ...] = (),
    image: str | None = None,
    view: bool = False,
    introspect: bool = False,
) -> None:
    """Run an arrangement of machines, round-robin, in command-line order.

    A TARGET is a NAME.machine directory (compiled into a cache), a built module, or PKG/NAME
    of an installed package.  Exit status: 0 normal end, 1 an exception in machine code,
    2 bad arguments or a machine that fails validation.
    """
    from .runtime import Arrangement, ArrangementError, RunContext, SimClock, Tracer, WallClock, signals_handled
    from .targets import InvalidMachine, MachineLoadError, TargetError, load

    if period is not None and period <= 0:
        fail("--period must be greater than 0")
    from .msgs import add_search_path

    for t in targets:  # user interfaces (PKG/msg/*.msg) beside or above the machines import too
        for folder in list(Path(os.path.realpath(t)).parents)[:4]:  # realpath: no error on a loop
            add_search_path(folder)
    classes = []
    for t in targets:
        try:
            classes.append(load(t))
        except TargetError as e:
            fail(str(e))
        except InvalidMachine as e:
            from .diagnostics import format_text

            click.echo(format_text(e.diagnostics), nl=False, err=True)
            fail(f"{t}: the machine has errors; nothing was run")
        except MachineLoadError as e:
            click.echo(e.report.format(), nl=False, err=True)
            sys.exit(EXIT_ERRORS)
    the_clock = SimClock(period or 1_000_000) if clock == "sim" else WallClock(idle, period)
    ctx = RunContext(the_clock)
    if image and not image.lower().endswith((".png", ".svg")):
        fail(f"--image {image}: the picture is written as .png or .svg")
    if (image or view) and "turtlesim" not in nodes:
        fail("--image and --view draw the turtle simulator: add --node turtlesim")
    uses_bus = bool(nodes or remaps or params or echoes or introspect)
    bus = _start_bus(ctx, targets, nodes, remaps, params, echoes, image, view) if uses_bus else None
    trace_out = None
    if trace_file:
        try:
            trace_out = open(trace_file, "w", encoding="utf-8")  # noqa: SIM115 (closed after the run)
        except OSError as e:
            fail(f"--trace {trace_file}: {e.strerror}")
    tracer = Tracer(verbose=sys.stderr if verbose else None, jsonl=trace_out) if (verbose or trace_out) else None
    try:
        try:
            arr = Arrangement(classes, context=ctx, keep_accepting=keep_accepting, tracer=tracer, suspended=suspended)
        except ArrangementError as e:
            fail(str(e))
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException as exc:  # a variable initialiser raised: machine code may raise anything
            from .runtime import report_for

            rep = report_for(exc)
            if rep is None:
                raise
            click.echo(rep.format(), nl=False, err=True)
            sys.exit(EXIT_ERRORS)
        arr.on_interrupt = lambda grace: click.echo(
            f"llfsm: interrupted; machines have {grace / 1e9:g} s of run time to finish (interrupt again to stop now)",
            err=True,
        )
        with signals_handled(arr):
            result = arr.run(duration, grace)
    finally:
        if trace_out is not None:
            trace_out.close()
    sys.stdout.flush()
    if result.error is not None:
        click.echo(result.error.format(), nl=False, err=True)
    if introspect and bus is not None:
        click.echo(_graph_text(bus.graph()), nl=False, err=True)
    sys.exit(result.status)


def _start_bus(
    ctx: RunContext,
    targets: tuple[str, ...],
    nodes: tuple[str, ...],
    remaps: tuple[str, ...],
    params: tuple[str, ...],
    echoes: tuple[str, ...],
    image: str | None,
    view: bool,
) -> Bus:
    """The bus, its remaps and parameters, the --node nodes and the --echo readers, set up before
    any machine runs, so that turtle1 exists and no message is missed."""
    from .nodes import NodeError, NodeOptions, start
    from .nodes.echo import echo
    from .ros import InvalidNameError, Remap, bus_of, parse_param
    from .runtime.context import activate

    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        try:
            bus.remaps = [Remap.parse(r) for r in remaps]
            for text in params:
                node, name, value = parse_param(text)
                bus.parameters[(node, name)] = value
            for topic in echoes:
                echo(bus, topic)
        except (InvalidNameError, ValueError) as e:
            fail(str(e))
        if nodes:
            bus.initialised = True  # the nodes are up: ros.ok() is true from the first round
        options = NodeOptions(image=Path(image) if image else None, view=view)
        for name in dict.fromkeys(nodes):
            try:
                start(name, ctx, options)
            except NodeError as e:
                fail(str(e))
        return bus
    finally:
        activate(prev)


def _graph_text(graph: dict[str, Any]) -> str:
    out = ["nodes:"] + [f"  {n}" for n in graph["nodes"]] + ["topics:"]
    for name, t in graph["topics"].items():
        out.append(
            f"  {name} [{t['type']}] publishers: {t['publishers']}, subscriptions: {t['subscriptions']}, "
            f"messages: {t['messages']}"
        )
    out.append("services:")
    out += [f"  {name} [{typ}]" for name, typ in graph["services"].items()]
    return "\n".join(out) + "\n"


# -- new ---------------------------------------------------------------------------------------


@cli.group()
def new() -> None:
    """Create a machine or a colcon package from a skeleton."""


@new.command("machine")
@click.argument("name")
@click.option(
    "-d",
    "--dir",
    "directory",
    type=click.Path(file_okay=False),
    default=".",
    show_default=True,
    help="Folder to create NAME.machine in.",
)
@click.option("--description", default=None, help="One line saying what the machine does.")
def new_machine(name: str, directory: str, description: str | None) -> None:
    """A valid machine skeleton: INITIAL -> END."""
    from .scaffold import ScaffoldError, create_machine

    try:
        path = create_machine(Path(directory), name, description)
    except ScaffoldError as e:
        fail(str(e))
    click.echo(f"created {path}")


class _SeveralValues(click.Command):
    """`ros2 pkg create` takes `--dependencies a b c`; a click option takes one value, so the
    words after such an option (up to the next option) are spread into repeated options."""

    several = ("--dependencies", "--machine")

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        out: list[str] = []
        i = 0
        while i < len(args):
            arg = args[i]
            out.append(arg)
            i += 1
            if arg == "--":
                out += args[i:]
                break
            if arg in self.several:
                first = True
                while i < len(args) and (first or not args[i].startswith("-")):
                    if not first:
                        out.append(arg)
                    out.append(args[i])
                    first = False
                    i += 1
        try:
            return super().parse_args(ctx, out)
        except click.MissingParameter as e:
            if e.param is not None and e.param.name == "name" and any(a in self.several for a in args):
                raise click.UsageError(
                    "missing NAME: put it before --dependencies and --machine, which take every word after them",
                    ctx,
                ) from None
            raise


@new.command("package", cls=_SeveralValues)
@click.argument("name")
@click.option(
    "--dependencies",
    multiple=True,
    metavar="D...",
    help="Packages the machines use (std_msgs geometry_msgs ...): <depend> tags in package.xml.",
)
@click.option(
    "--machine",
    "machines",
    multiple=True,
    metavar="M...",
    help="Machines to create in machine/ (default: one named NAME).",
)
@click.option(
    "--license",
    "license_",
    default="TODO: License declaration",
    help="License in package.xml (default, as ros2 pkg create: 'TODO: License declaration'); "
    "a warning unless an ament identifier such as Apache-2.0 or MIT.",
)
@click.option("--description", default=None, help="Description in package.xml.")
@click.option("--maintainer-name", default=None, help="Maintainer (default: your user name).")
@click.option("--maintainer-email", default=None, help="Maintainer's e-mail (default: NAME@todo.todo).")
@click.option(
    "--dir",
    "--destination-directory",
    "directory",
    type=click.Path(file_okay=False),
    default=".",
    show_default=True,
    help="Folder to create the package in: a workspace's src/.",
)
def new_package(
    name: str,
    dependencies: tuple[str, ...],
    machines: tuple[str, ...],
    license_: str,
    description: str | None,
    maintainer_name: str | None,
    maintainer_email: str | None,
    directory: str,
) -> None:
    """A ROS 2 ament_python package of machines that `colcon build` builds.

    Run in a workspace's src/.  It writes NAME/package.xml (format 3), setup.py, setup.cfg,
    resource/NAME, machine/M.machine for each machine and test/.  Then, from the workspace:
    `colcon build`, `source install/setup.bash`, `llfsm run NAME/M`.  NAME comes before the
    options that take several values.
    """
    from .scaffold import ScaffoldError, create_package

    try:
        pkg = create_package(
            Path(directory),
            name,
            dependencies,
            machines,
            license_,
            description,
            maintainer_name,
            maintainer_email,
        )
    except ScaffoldError as e:
        fail(str(e))
    # the summary ros2 pkg create prints, so the two read alike (printed once all is written)
    click.echo("created a new package")
    click.echo(f"package name: {name}")
    click.echo(f"destination directory: {Path(directory).resolve()}")
    click.echo("package format: 3")
    click.echo("version: 0.0.0")
    click.echo(f"description: {pkg.description}")
    click.echo(f"maintainer: {[pkg.maintainer]}")
    click.echo(f"licenses: {[pkg.license]}")
    click.echo("build type: ament_python")
    click.echo(f"dependencies: {pkg.dependencies}")
    click.echo(f"machines: {pkg.machines}")
    rel = Path(directory) / name
    for f in pkg.files:
        if not f.startswith("machine/"):
            click.echo(f"created {rel / f}")
    for m in pkg.machines:
        click.echo(f"created {rel / 'machine' / (m + '.machine')}/")
    for w in pkg.warnings:
        click.echo(f"[WARNING]: {w}", err=True)
    click.echo("next, from the workspace (the folder that holds src/):")
    click.echo(f"  colcon build --packages-select {name}")
    click.echo("  source install/setup.bash")
    click.echo(f"  llfsm run {name}/{pkg.machines[0]}")


# -- graph, schema -------------------------------------------------------------------------------


@cli.command()
@click.argument("path", type=click.Path())
@click.option(
    "--format", "fmt", type=click.Choice(["mermaid", "dot", "svg", "png"]), default="mermaid", show_default=True
)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write to FILE (needed for png).")
def graph(path: str, fmt: str, output: str | None) -> None:
    """The machine's diagram, guards on the arrows."""
    from .check import check_machine
    from .diagnostics import Severity, format_text
    from .graph import GraphError, dot, mermaid, render_image

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
    try:
        data: bytes = (
            mermaid(m).encode() if fmt == "mermaid" else dot(m).encode() if fmt == "dot" else render_image(m, fmt)
        )
    except GraphError as e:
        fail(str(e), EXIT_ERRORS)
    if output:
        from .compiler.build import write_atomic_bytes

        write_atomic_bytes(Path(output), data)
    else:
        sys.stdout.write(data.decode())


@cli.command()
def schema() -> None:
    """JSON Schema of machine.yaml."""
    import json

    from .model import MachineYaml

    click.echo(json.dumps(MachineYaml.model_json_schema(), indent=2))


def main() -> None:
    """Entry point: turns what escapes the commands into a message and a status, not a traceback."""
    try:
        cli.main(prog_name="llfsm", standalone_mode=False)
    except click.exceptions.Exit as e:
        sys.exit(e.exit_code)
    except click.ClickException as e:
        e.show()
        sys.exit(EXIT_USAGE)
    except click.exceptions.Abort:
        sys.exit(130)
    except BrokenPipeError:
        _quiet_broken_pipe()
    except KeyboardInterrupt:
        sys.exit(130)
    except SystemExit:
        raise
    except Exception as exc:  # an llfsm bug: say so plainly
        if os.environ.get("LLFSM_DEBUG"):
            raise
        click.echo(f"llfsm: internal error: {type(exc).__name__}: {exc} (set LLFSM_DEBUG=1 for a traceback)", err=True)
        sys.exit(70)


if __name__ == "__main__":
    main()
