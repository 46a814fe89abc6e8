"""`llfsm run`: load an arrangement and run it with the ringlet scheduler, beside the bus."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from ._common import DURATION, EXIT_ERRORS, cli, fail

if TYPE_CHECKING:
    from ..ros.bus import Bus
    from ..runtime import RunContext


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
@click.option("--native", is_flag=True, help="Run machines compiled with mypyc (see docs/native.md).")
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
    native: bool = False,
) -> None:
    """Run an arrangement of machines, round-robin, in command-line order.

    A TARGET is a NAME.machine directory (compiled into a cache), a built module, or PKG/NAME
    of an installed package.  Exit status: 0 normal end, 1 an exception in machine code,
    2 bad arguments or a machine that fails validation.
    """
    from ..runtime import Arrangement, ArrangementError, RunContext, SimClock, Tracer, WallClock, signals_handled
    from ..targets import InvalidMachine, MachineLoadError, TargetError, load

    if period is not None and period <= 0:
        fail("--period must be greater than 0")
    if native and not os.environ.get("LLFSM_NATIVE"):
        _run_native(targets)  # compiles (or finds) the native build, then runs in a fresh process
    from ..msgs import add_search_path

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
            from ..diagnostics import format_text

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
            from ..runtime import report_for

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


def _run_native(targets: tuple[str, ...]) -> None:
    """`--native`: build the targets' modules natively (one compile, cached), then start the
    same command again with LLFSM_NATIVE set, so that the compiled runtime is the one imported.
    Returns only when nothing could be compiled (the run then goes on as plain Python)."""
    from ..compiler.native import ENV, NativeUnavailable, native_build
    from ..targets import InvalidMachine, MachineLoadError, TargetError, cache_root, resolve

    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if getattr(spec, "name", None) != "llfsm.__main__" and Path(getattr(main, "__file__", "") or "").name != "llfsm":
        fail("--native starts the run in a fresh process: use it from the llfsm command")
    modules = []
    for t in targets:
        try:
            modules.append(resolve(t).resolve())
        except (TargetError, InvalidMachine, MachineLoadError):
            return  # the ordinary path reports it
    try:
        build = native_build(modules, cache_root())
    except NativeUnavailable as e:
        fail(f"--native: {e}")
    for w in build.warnings:
        click.echo(w, err=True)
    if not any(build.modules.values()):
        return
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, [sys.executable, *sys.orig_argv[1:]], {**os.environ, ENV: str(build.folder)})


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
    from ..nodes import NodeError, NodeOptions, start
    from ..nodes.echo import echo
    from ..ros import InvalidNameError, Remap, bus_of, parse_param
    from ..runtime.context import activate

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
