"""What `llfsm run` does once its arguments are parsed: load the arrangement and run it with
the ringlet scheduler, beside the bus.

Free of click, so that the start-up fast path (llfsm.cli.main with llfsm.cli.run_args.parse)
can run a machine without importing it; the click command (llfsm.cli.run) calls `run` too.
"""

from __future__ import annotations

import os
import sys

from ._base import EXIT_ERRORS, echo, fail

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any

    from ..ros.bus import Bus
    from ..runtime import RunContext


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
    web: str | None = None,
    transport: str = "inproc",
    record: str | None = None,
    record_topics: tuple[str, ...] = (),
    storage: str = "mcap",
    play: str | None = None,
    play_topics: tuple[str, ...] = (),
    play_rate: float = 1.0,
    native: bool = False,
) -> None:
    """Run the targets with these options (the keywords of llfsm.cli.run_args.RUN_OPTIONS);
    ends the process with the run's exit status."""
    from ..runtime import Arrangement, ArrangementError, RunContext, SimClock, Tracer, WallClock, signals_handled
    from ..targets import InvalidMachine, MachineLoadError, TargetError, load

    if period is not None and period <= 0:
        fail("--period must be greater than 0")
    if not targets and not nodes and not echoes:
        fail("nothing to run: give a machine (TARGET), or --node NAME / --echo TOPIC to run on their own")
    if transport == "dds" and clock == "sim":
        fail(
            "--clock sim cannot be used with --transport dds: DDS peers live on the wall clock (their messages "
            "come in real time), so simulated time would neither keep pace with them nor be reproducible"
        )
    if native and not os.environ.get("LLFSM_NATIVE"):
        _run_native(targets)  # compiles (or finds) the native build, then runs in a fresh process
    from ..idl.paths import add_search_path  # not llfsm.msgs: a run without messages never imports it

    for t in targets:  # user interfaces (PKG/msg/*.msg) beside or above the machines import too
        folder = os.path.realpath(t)  # realpath: no error on a loop
        for _ in range(4):
            parent = os.path.dirname(folder)
            if parent == folder:
                break
            folder = parent
            add_search_path(folder)
    classes = []
    for t in targets:
        try:
            classes.append(load(t))
        except TargetError as e:
            fail(str(e))
        except InvalidMachine as e:
            from ..lang.diagnostics import format_text

            echo(format_text(e.diagnostics), nl=False)
            fail(f"{t}: the machine has errors; nothing was run")
        except MachineLoadError as e:
            echo(e.report.format(), nl=False)
            sys.exit(EXIT_ERRORS)
    the_clock = SimClock(period or 1_000_000) if clock == "sim" else WallClock(idle, period)
    ctx = RunContext(the_clock)
    if image and not image.lower().endswith((".png", ".svg")):
        fail(f"--image {image}: the picture is written as .png or .svg")
    if (image or view) and "turtlesim" not in nodes:
        fail("--image and --view draw the turtle simulator: add --node turtlesim")
    if view and (why := _no_display()) is not None:
        fail(why)
    web_address = _web_address(web) if web is not None else None
    # the watchdog ends a run stuck in a C call (llfsm.runtime.watchdog): forked here, with the
    # machines loaded and before the transport, the bus, the nodes or the page start a thread
    watchdog = _start_watchdog(classes, grace if classes else 0)
    try:
        if transport != "inproc":
            ctx.extras["transport"] = _open_transport(transport)
        bags = _open_bags(record, record_topics, storage, play, play_topics, play_rate) if (record or play) else None
        uses_bus = bool(nodes or remaps or params or echoes or introspect or web or transport != "inproc" or bags)
        bus = _start_bus(ctx, targets, nodes, remaps, params, echoes, image, view) if uses_bus else None
        if bags is not None and bus is not None:
            _attach_bags(bags, bus)
        trace_out = None
        if trace_file:
            from ..outputs import OutputError, StreamedOutput

            try:
                trace_out = StreamedOutput(trace_file, what="--trace")  # write errors kept, not raised mid-run
            except OutputError as e:
                fail(str(e), EXIT_ERRORS)
        tracer = Tracer(verbose=sys.stderr if verbose else None, jsonl=trace_out) if (verbose or trace_out) else None  # type: ignore[arg-type]
        try:
            try:
                arr = Arrangement(
                    classes, context=ctx, keep_accepting=keep_accepting, tracer=tracer, suspended=suspended
                )
                arr.watchdog = watchdog
            except ArrangementError as e:
                fail(str(e))
            except BaseException as exc:  # a variable initialiser raised: machine code may raise anything
                from ..runtime.errors import passes_through, report_for

                rep = None if passes_through(exc) else report_for(exc)
                if rep is None:
                    raise
                echo(rep.format(), nl=False)
                sys.exit(EXIT_ERRORS)
            _machines_on_graph(ctx)
            if classes:
                arr.on_interrupt = lambda grace: echo(
                    f"llfsm: interrupted; machines have {grace / 1e9:g} s of run time to finish "
                    "(interrupt again to stop now)",
                )
            else:  # nodes on their own (SPEC 4): they run until interrupted or --duration
                arr.serve_forever = True
                grace = 0
            if transport != "inproc":  # other processes can resume machines (SPEC 8): all suspended is no end
                arr.end_when_suspended = False
            web_server = _start_web(web_address, arr, bus) if web_address is not None and bus is not None else None
            try:
                with signals_handled(arr):
                    result = arr.run(duration, grace)
            finally:
                if web_server is not None:
                    web_server.stop()
        finally:
            # a named output that could not be written whole is an error, never a silent success
            failed_outputs: list[str] = list(ctx.extras.get("output_errors", ()))
            if trace_out is not None and (trace_error := trace_out.finish()) is not None:
                failed_outputs.append(trace_error)
            bag_error = bags.close() if bags is not None else None  # the bag is closed whatever happened
        sys.stdout.flush()
        if result.error is not None:
            echo(result.error.format(), nl=False)
        if introspect and bus is not None:
            echo(_graph_text(bus.graph()), nl=False)
        for message in failed_outputs:
            echo(f"llfsm: {message}")
        sys.exit(result.status if result.status or not (failed_outputs or bag_error) else EXIT_ERRORS)
    finally:
        if watchdog is not None:
            watchdog.close()  # it ends with the run, never after it


def _start_watchdog(classes: list[Any], grace: int) -> Any:
    """The run's watchdog, or None where there can be none (no fork)."""
    from ..runtime.watchdog import Watchdog

    return Watchdog.start(grace, classes)


def _open_bags(
    record: str | None,
    record_topics: tuple[str, ...],
    storage: str,
    play: str | None,
    play_topics: tuple[str, ...],
    play_rate: float,
) -> Any:
    """The bag to play (read and checked now) and the bag to record (created now), or fail."""
    from ..bag import BagError, RunBags

    try:
        return RunBags(
            record,
            record_topics,
            storage,
            play,
            play_topics,
            play_rate,
            report=lambda text: echo(f"llfsm: {text}"),
        )
    except BagError as e:
        fail(str(e))


def _open_transport(name: str) -> Any:
    """The run's transport; a missing package or a bad ROS_* variable is a usage error."""
    from ..ros.transports.inproc import make

    try:
        return make(name)
    except (ImportError, ValueError) as e:
        fail(str(e))


def _attach_bags(bags: Any, bus: Bus) -> None:
    from ..bag import BagError

    try:
        bags.attach(bus)
    except BagError as e:
        bags.close()
        fail(f"--play {e}")


def _run_native(targets: tuple[str, ...]) -> None:
    """`--native`: build the targets' modules natively (one compile, cached), then start the
    same command again with LLFSM_NATIVE set, so that the compiled runtime is the one imported.
    Returns only when nothing could be compiled (the run then goes on as plain Python)."""
    from pathlib import Path

    from ..cachedir import cache_root
    from ..compiler.native import ENV, NativeUnavailable, native_build
    from ..targets import InvalidMachine, MachineLoadError, TargetError, resolve

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
        echo(w)
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
    from pathlib import Path

    from ..nodes import NodeError, NodeOptions, start
    from ..nodes.echo import echo as echo_topic
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
                echo_topic(bus, topic)
        except (InvalidNameError, ValueError) as e:
            fail(str(e))
        if nodes:
            bus.init()  # the nodes are up: ros.ok() is true from the first round
        options = NodeOptions(image=Path(image) if image else None, view=view)
        for name in dict.fromkeys(nodes):
            try:
                start(name, ctx, options)
            except NodeError as e:
                fail(str(e))
        return bus
    finally:
        activate(prev)


def _no_display() -> str | None:
    """Why --view cannot open a window, or None.  Without a display SDL falls back to drawing
    off-screen, and the user would wait for a window that never appears."""
    if not sys.platform.startswith("linux"):
        return None  # macOS and Windows always have their own display
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("SDL_VIDEODRIVER"):
        return None  # a display, or a video driver chosen on purpose (dummy: off-screen, for tests)
    return (
        "--view opens a window, but there is no display (neither DISPLAY nor WAYLAND_DISPLAY is set); "
        "use --image FILE.png for a picture, or SDL_VIDEODRIVER=dummy to draw off-screen on purpose"
    )


def _web_address(text: str) -> tuple[str, int]:
    from ..web import INSTALL_HINT, WebUnavailable, server_class

    try:
        server_class()
    except WebUnavailable:
        fail(f"--web: {INSTALL_HINT}")
    from ..web.server import AddressError, parse_address

    try:
        return parse_address(text)
    except AddressError as e:
        fail(str(e))


def _start_web(address: tuple[str, int], arr: Any, bus: Bus) -> Any:
    """--web: the page's server on its own thread, the bus up (so the machines' control
    services exist), and a run that waits, rather than ends, when every machine is suspended:
    the page can resume them."""
    from ..runtime.context import activate
    from ..web.source import RunSource

    prev = activate(arr.ctx)
    try:
        bus.init()
        source = RunSource(arr, bus)
    finally:
        activate(prev)
    arr.end_when_suspended = False
    return _serve_web(source, address)


def _serve_web(source: Any, address: tuple[str, int]) -> Any:
    """Start the page's server for a source (a run, or the DDS graph for `llfsm view`) and print
    its address: one line holding `http://` (SPEC 10)."""
    from ..web.server import AddressError, WebServer

    server = WebServer(source, *address)
    try:
        url = server.start()
    except AddressError as e:
        fail(str(e))
    echo(f"llfsm: web view at {url}")
    return server


def _machines_on_graph(ctx: RunContext) -> None:
    """SPEC §8: the machines' state topics and control services join the graph with the bus
    (now if it is up, else at the first `ros.init()`); a run that never uses the bus never
    imports it."""
    bus = ctx.extras.get("bus")
    if bus is not None and bus.initialised:
        from ..ros.control import enable

        enable(ctx)
    else:
        ctx.extras.setdefault("on_init", []).append(lambda bus: _enable(ctx))


def _enable(ctx: RunContext) -> None:
    from ..ros.control import enable

    enable(ctx)


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
