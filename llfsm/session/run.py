"""`Session`: one `llfsm run`, everything that opens beside the machines opened in one place, in
one order, and closed whatever happens (the order: llfsm.session's docstring).
"""

from __future__ import annotations

import os
import sys

from ..interface_path import add_search_path
from ..runtime import Arrangement, ArrangementError, RunContext, SimClock, Tracer, WallClock, signals_handled
from ..runtime.context import activate
from ..runtime.errors import passes_through, report_for
from ..runtime.inputs import TOPIC
from ..runtime.scheduler import check_names
from ..runtime.watchdog import Watchdog
from ..targets import InvalidMachine, MachineLoadError, TargetError, load
from .errors import MachineFailed, OutputFailed, RunOutcome, UsageError
from .options import RunOptions

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any, Protocol

    from ..bag import RunBags
    from ..debug.debugger import Debugger
    from ..debug.prompt import Prompt
    from ..outputs import StreamedOutput
    from ..ros.bus import Bus
    from ..ros.logging import LogSettings
    from ..ros.transports.base import Transport
    from ..runtime.machine import Machine
    from ..sim.world import TurtleWorld

    class Stoppable(Protocol):
        def stop(self) -> None: ...

    class WebPage(Protocol):
        """The web view of a session (docs/view.md), as llfsm.cli hands it in: llfsm.web is a layer
        above the session, so the session knows the page by this alone."""

        #: Worth running with no machine and no node (`llfsm view`: the page of the DDS graph).
        runs_alone: bool

        def check(self) -> None:
            """Raise UsageError if the page cannot be served (no aiohttp, a bad address)."""

        def source(self, session: Session) -> object:
            """What the page shows; called with the run's context active and its bus up."""

        def serve(self, source: object) -> Stoppable:
            """Start serving on a thread, and tell the user where; UsageError if it cannot."""


def _stderr_line(text: str) -> None:
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


class Session:
    """One run's machines and everything opened beside them.  Attributes are None (or empty)
    until `run` opens them, and stay None when the options do not ask for them."""

    def __init__(
        self,
        options: RunOptions,
        *,
        web: WebPage | None = None,
        say: Callable[[str], None] | None = None,
    ) -> None:
        """Check the options alone (UsageError); nothing is loaded or opened yet."""
        self.options = options
        #: The page `--web` serves (given by the command line, which reads options.web).
        self.web = web
        #: Writes a line for the user while the run goes on (stderr unless told otherwise).
        self.say: Callable[[str], None] = say if say is not None else _stderr_line
        self.classes: list[type[Machine]] = []
        self.ctx: RunContext | None = None
        self.watchdog: Watchdog | None = None
        self.transport: Transport | None = None
        self.bags: RunBags | None = None
        self.bus: Bus | None = None
        #: `--param` overrides, (node or None, name) -> value, as the bus's nodes read them.
        self.parameters: dict[tuple[str | None, str], Any] = {}
        #: The `--node` nodes by name, in the order they started.
        self.nodes: dict[str, object] = {}
        self.trace_out: StreamedOutput | None = None
        self.tracer: Tracer | None = None
        self.arrangement: Arrangement | None = None
        self.web_server: Stoppable | None = None
        #: The run's debugger (llfsm.debug), when it has one (`debugs`).
        self.debugger: Debugger | None = None
        self.prompt: Prompt | None = None
        #: `--log-level` and `--log-file`, read by _check_options (None without them).
        self.log_settings: LogSettings | None = None
        self._check_options()

    # -- checks before anything opens ---------------------------------------------------------------
    def _check_options(self) -> None:
        o = self.options
        if o.period is not None and o.period <= 0:
            raise UsageError("--period must be greater than 0")
        if not o.targets and not o.nodes and not o.echoes and not (self.web is not None and self.web.runs_alone):
            raise UsageError(
                "nothing to run: give a machine (TARGET), or --node NAME / --echo TOPIC to run on their own"
            )
        if o.log_levels or o.log_file:
            from ..ros.logging import LogSettings  # deferred: start-up (only a run given them reads them)

            try:
                self.log_settings = LogSettings(o.log_levels, o.log_file)
            except ValueError as e:
                raise UsageError(str(e)) from None
        if o.transport == "dds" and o.clock == "sim":
            raise UsageError(
                "--clock sim cannot be used with --transport dds: DDS peers live on the wall clock (their messages "
                "come in real time), so simulated time would neither keep pace with them nor be reproducible"
            )

    def _load(self) -> None:
        """The machines' classes, in command-line order; user interfaces (PKG/msg/*.msg) beside
        or above the machines import too."""
        for t in self.options.targets:
            folder = os.path.realpath(t)  # realpath: no error on a loop
            for _ in range(4):
                parent = os.path.dirname(folder)
                if parent == folder:
                    break
                folder = parent
                add_search_path(folder)
        for t in self.options.targets:
            try:
                self.classes.append(load(t))
            except TargetError as e:
                raise UsageError(str(e)) from None
            except InvalidMachine as e:
                from ..lang.diagnostics import format_text  # deferred: start-up (error path only)

                raise UsageError(
                    f"{t}: the machine has errors; nothing was run", details=format_text(e.diagnostics)
                ) from None
            except MachineLoadError as e:
                raise MachineFailed(e.report) from None
        try:  # before any node or transport starts: nothing else is said or opened for nothing
            check_names(self.classes, self.options.suspended)
        except ArrangementError as e:
            raise UsageError(str(e)) from None

    def _check_outputs(self) -> None:
        o = self.options
        if o.image and not o.image.lower().endswith((".png", ".svg")):
            raise UsageError(f"--image {o.image}: the picture is written as .png or .svg")
        if (o.image or o.view) and "turtlesim" not in o.nodes:
            raise UsageError("--image and --view draw the turtle simulator: add --node turtlesim")
        if o.view and (why := _no_display()) is not None:
            raise UsageError(why)
        if self.web is not None:
            self.web.check()

    # -- the run --------------------------------------------------------------------------------
    def run(self) -> RunOutcome:
        """Load, open, run and close (see the module's docstring for the order).  Returns how
        the run ended; raises SessionError when it could not start."""
        o = self.options
        self._load()
        self._check_breaks()
        self.ctx = RunContext(SimClock(o.period or 1_000_000) if o.clock == "sim" else WallClock(o.idle, o.period))
        self._check_outputs()
        # the watchdog ends a run stuck in a C call (llfsm.runtime.watchdog): started here, with
        # the machines loaded and before the transport, the bus, the nodes or the page start a thread
        self.watchdog = Watchdog.start(o.grace if self.classes else 0, self.classes)
        try:
            return self._run(self.ctx)
        finally:
            if self.watchdog is not None:
                self.watchdog.close()  # it ends with the run, never after it

    def _run(self, ctx: RunContext) -> RunOutcome:
        o = self.options
        ran = False
        failed_outputs: list[str] = []
        bag_error: str | None = None
        if self.log_settings is not None:  # before any node: the bus takes them when it is initialised
            settings = self.log_settings
            ctx.on_init.append(lambda bus: settings.apply(bus, self.say, o.verbose))
        try:
            if o.transport != "inproc":
                self.transport = self._open_transport()
                ctx.transport = self.transport
            if o.record or o.play:
                self.bags = self._open_bags()
            if self.uses_bus:
                self.bus = self._open_bus(ctx)
                if self.bags is not None:
                    self._attach_bags(self.bags, self.bus)
            if o.trace_file:
                self.trace_out = self._open_trace(o.trace_file)
            if o.verbose or self.trace_out is not None:
                # a StreamedOutput writes text as a file does (IO[str] is more than the tracer uses)
                self.tracer = Tracer(verbose=sys.stderr if o.verbose else None, jsonl=self.trace_out)
            arr = self.arrangement = self._arrange(ctx)
            self._machines_on_graph(ctx)
            if self.binds_inputs and self.bus is not None:
                self._bind_inputs(arr, self.bus)
            grace = o.grace
            if self.classes:
                arr.on_interrupt = lambda grace: self.say(
                    f"llfsm: interrupted; machines have {grace / 1e9:g} s of run time to finish "
                    "(interrupt again to stop now)",
                )
            else:  # nodes on their own (docs/turtlesim.md): they run until interrupted or --duration
                arr.serve_forever = True
                grace = 0
            if o.transport != "inproc":  # other processes can resume machines (docs/view.md): all suspended is no end
                arr.end_when_suspended = False
            monitor = self._open_monitor(arr) if o.monitor or o.monitor_properties else None
            # the monitor says its verdicts as the run goes, the last ones as it ends
            if self.debugs:
                self.debugger = self._open_debugger(arr, pause_on_violation=monitor is not None)
                if monitor is not None and o.on_violation == "pause":
                    monitor.pause = self.debugger.monitor_paused
            if self.web is not None and self.bus is not None:
                self.web_server = self._open_web(self.web, ctx, self.bus, arr)
            try:
                with signals_handled(arr):
                    ran = True  # from here the run's end hooks (ctx.at_end) close what the nodes and bus opened
                    result = arr.run(o.duration, grace)
                if result.reason == "interrupted" and (left := _unfinished(arr)):
                    self.say(f"llfsm: the grace time ({grace / 1e9:g} s) ran out before {left} finished")
            finally:
                if self.web_server is not None:
                    self.web_server.stop()
                if self.prompt is not None:
                    self.prompt.close()
        finally:
            # a named output that could not be written whole is an error, never a silent success
            failed_outputs += ctx.output_errors
            if self.trace_out is not None and (trace_error := self.trace_out.finish()) is not None:
                failed_outputs.append(trace_error)
            if self.bags is not None:
                bag_error = self.bags.close()  # the bag is closed whatever happened
            if not ran and self.transport is not None:
                self.transport.close()  # a run that never began: peers see us leave now
        graph = self.bus.graph() if o.introspect and self.bus is not None else None
        return RunOutcome(result, failed_outputs, bag_error, graph)

    # -- the steps ------------------------------------------------------------------------------
    def _open_transport(self) -> Transport:
        """A missing package or a bad ROS_* variable is a usage error."""
        # deferred: start-up (the factory is only needed beside the in-process bus; dds is heavy)
        from ..ros.transports import make

        try:
            return make(self.options.transport)
        except (ImportError, ValueError) as e:
            raise UsageError(str(e)) from None

    def _open_bags(self) -> RunBags:
        """The bag to play (read and checked now) and the bag to record (created now)."""
        from ..bag import BagError, RunBags  # deferred: start-up (a run without bags never imports them)

        o = self.options
        try:
            return RunBags(
                o.record,
                o.record_topics,
                o.storage,
                o.play,
                o.play_topics,
                o.play_rate,
                report=lambda text: self.say(f"llfsm: {text}"),
            )
        except BagError as e:
            raise UsageError(str(e)) from None

    def _open_bus(self, ctx: RunContext) -> Bus:
        """The bus, its remaps and parameters, the --echo readers and the --node nodes, set up
        before any machine runs, so that turtle1 exists and no message is missed."""
        # deferred: start-up (a run that never uses the bus never imports it, nor the messages)
        from pathlib import Path

        from ..nodes import NodeError, NodeOptions, start
        from ..nodes.echo import echo as echo_topic
        from ..ros import InvalidNameError, Remap, bus_of
        from ..ros.parameters import ParameterException

        o = self.options
        prev = activate(ctx)
        try:
            bus = self.bus = bus_of(ctx)
            try:
                bus.remaps = [Remap.parse(r) for r in o.remaps]
                self._set_parameters(bus)
                for topic in o.echoes:
                    echo_topic(bus, topic)
            except (InvalidNameError, ValueError) as e:
                raise UsageError(str(e)) from None
            if o.nodes or o.params or o.params_files or self.binds_inputs or self.has_parameters:
                # the nodes (and the input readers) are up (ros.ok() is true from the first round),
                # and the machines' nodes will be too: their parameters are set before their first
                # ringlet, and a machine that declares parameters is on the graph without a ros.init()
                bus.init()
            options = NodeOptions(image=Path(o.image) if o.image else None, view=o.view)
            for name in dict.fromkeys(o.nodes):
                try:
                    self.nodes[name] = start(name, ctx, options)
                except NodeError as e:
                    raise UsageError(str(e)) from None
                except ParameterException as e:
                    raise UsageError(parameter_refused(e, f"--node {name}")) from None
            return bus
        finally:
            activate(prev)

    def _set_parameters(self, bus: Bus) -> None:
        """`-p [NODE:]NAME:=VALUE` and `--params-file FILE`: the overrides nodes read when they
        declare a parameter (llfsm/ros/parameter_files.py), all read and checked here, before
        any node or machine starts.  UsageError naming the file and line of a bad one."""
        o = self.options
        if not (o.params or o.params_files):
            return
        # deferred: start-up (only a run given parameters reads their text, with yaml)
        from ..ros.parameter_files import ParameterTextError, node_pattern, parse_param, read_params_file

        try:
            for path in o.params_files:
                for key, values in read_params_file(path):
                    bus.parameter_files.append((node_pattern(key), values))
            for text in o.params:
                node, name, value = parse_param(text)
                self.parameters[(node, name)] = value
                bus.parameters[(node, name)] = value
                bus.parameter_origins[(node, name)] = f"-p {text}"
        except ParameterTextError as e:
            raise UsageError(str(e)) from None

    def _attach_bags(self, bags: RunBags, bus: Bus) -> None:
        from ..bag import BagError  # deferred: start-up (loaded with the bags already)

        try:
            bags.attach(bus)
        except BagError as e:
            raise UsageError(f"--play {e}") from None

    def _open_trace(self, path: str) -> StreamedOutput:
        from ..outputs import OutputError, StreamedOutput  # deferred: start-up (only with --trace)

        try:
            return StreamedOutput(path, what="--trace")  # write errors kept, not raised mid-run
        except OutputError as e:
            raise OutputFailed(str(e)) from None

    def _arrange(self, ctx: RunContext) -> Arrangement:
        o = self.options
        try:
            arr = Arrangement(
                self.classes, context=ctx, keep_accepting=o.keep_accepting, tracer=self.tracer, suspended=o.suspended
            )
        except ArrangementError as e:
            raise UsageError(str(e)) from None
        except BaseException as exc:  # a variable initialiser raised: machine code may raise anything
            rep = None if passes_through(exc) else report_for(exc)
            if rep is None:
                raise
            raise MachineFailed(rep) from None
        arr.watchdog = self.watchdog
        return arr

    def _machines_on_graph(self, ctx: RunContext) -> None:
        """The machines' state topics and control services (docs/view.md) join the graph with the bus
        (now if it is up, else at the first `ros.init()`)."""
        bus = ctx.bus
        if bus is not None and bus.initialised:
            _enable(ctx)
        else:
            ctx.on_init.append(lambda bus: _enable(ctx))

    def _bind_inputs(self, arr: Arrangement, bus: Bus) -> None:
        """SPEC 11: each input bound to a topic reads its field from the newest message there,
        through a PULL reader on the machine's node, opened before the first round."""
        from ..ros.inputs import BindError, bind  # deferred: start-up (only machines with bound inputs)

        prev = activate(arr.ctx)
        try:
            bind(arr, bus, where=lambda m: _machine_yaml_of(m, self.options.targets))
        except BindError as e:
            raise UsageError(str(e)) from None
        finally:
            activate(prev)

    def _open_monitor(self, arr: Arrangement) -> Any:
        """--monitor, --monitor-property (docs/monitor.md): the properties judged at the ringlet
        boundaries where they can change, said on stderr and /llfsm/monitor as the run goes and
        as it ends; a bad one is a usage error."""
        # deferred: start-up (a run without a monitor never imports the property language)
        from pathlib import Path

        from ..monitor import Monitor, MonitorError, property_source
        from ..props.file import FileError, read_verify_file

        o = self.options
        try:
            sources = read_verify_file(Path(o.monitor)).properties if o.monitor else []
            sources += [property_source(t) for t in o.monitor_properties]
            monitor = Monitor(sources, self.classes, o.on_violation, self.say)
        except (FileError, MonitorError) as e:
            raise UsageError(str(e)) from None
        monitor.attach(arr, self.bus)
        return monitor

    def _check_breaks(self) -> None:
        """`--break`: every expression is checked against the loaded machines before anything
        opens (a typo is a usage error, exit 2, not a breakpoint that never fires)."""
        if not self.options.breaks:
            return
        # deferred: start-up (a run without breakpoints never imports the property language)
        from ..debug.breakpoints import BreakError, compile_break
        from ..props.atoms import infos_of

        infos = infos_of(self.classes)
        for text in self.options.breaks:
            try:
                compile_break(text, infos, "--break")
            except BreakError as e:
                raise UsageError(str(e)) from None

    @property
    def debugs(self) -> bool:
        """Whether the run has a debugger: asked for (--paused, --break, --history,
        --debug-prompt, --on-violation pause), for the page (it pauses, steps and keeps a
        history), or on ROS 2's wire (other processes pause and step it, docs/debug.md)."""
        o = self.options
        return bool(
            o.paused
            or o.breaks
            or o.history
            or o.debug_prompt
            or (o.on_violation == "pause" and (o.monitor or o.monitor_properties))
            or self.web is not None
            or o.transport != "inproc"
        )

    def _open_debugger(self, arr: Arrangement, pause_on_violation: bool) -> Debugger:
        """The debugger (docs/debug.md): breakpoints, history, the prompt on the terminal when
        something may pause the run and no page is there to continue it (or --debug-prompt),
        and its services with the machines' control services."""
        # deferred: start-up (a run without the debugger never imports it)
        from ..debug.debugger import DebugError, Debugger
        from ..debug.history import PAGE_DEFAULT

        o = self.options
        history = o.history or (PAGE_DEFAULT if self.web is not None else None)
        debugger = Debugger(arr, history=history, say=self.say)
        for text in o.breaks:
            try:
                debugger.add_break(text, where="--break")
            except DebugError as e:  # checked before the run: this is for the record
                raise UsageError(str(e)) from None
        if o.paused:
            debugger.pause("--paused")
        pauses = o.paused or o.breaks or (pause_on_violation and o.on_violation == "pause")
        if o.debug_prompt or (pauses and self.web is None):
            from ..debug.prompt import Prompt  # deferred: start-up (only a run with the prompt reads the terminal)

            self.prompt = Prompt(debugger, alone=self.web is None)
        if self.bus is not None:
            self._debug_on_graph(debugger, self.bus)
        else:  # a machine may start the bus itself (its first ros.init()): then
            arr.ctx.on_init.append(lambda bus: self._debug_on_graph(debugger, bus))
        return debugger

    def _debug_on_graph(self, debugger: Debugger, bus: Bus) -> None:
        """The debugger answers the bus's control services while paused, and offers its own
        next to them as soon as the machines are on the graph, on either transport; its state
        topic only on ROS 2's wire (in one process, a pause publishes nothing on the run's own
        bus, so that a recorded bag stays the same)."""
        from ..debug.services import answers, offer  # deferred: start-up (with the debugger only)

        debugger.attach_bus(bus, lambda: bus.spin_control(answers))
        remote = bus.transport.remote
        ctx = debugger.arr.ctx
        if ctx.machine_graph is not None:
            offer(debugger, ctx.machine_graph, topic=remote)
        else:
            ctx.on_init.append(lambda _bus: offer(debugger, ctx.machine_graph, topic=remote))

    def _open_web(self, web: WebPage, ctx: RunContext, bus: Bus, arr: Arrangement) -> Stoppable:
        """--web: the page's server on its own thread, the bus up (so the machines' control
        services exist), and a run that waits, rather than ends, when every machine is
        suspended: the page can resume them."""
        prev = activate(ctx)
        try:
            bus.init()
            source = web.source(self)
        finally:
            activate(prev)
        arr.end_when_suspended = False
        return web.serve(source)

    # -- what the session is asked for ----------------------------------------------------------------
    @property
    def uses_bus(self) -> bool:
        """Whether the run opens the bus before its machines start (a machine alone gets one at its
        first `ros.init()`, and a run that never calls it never imports the bus)."""
        o = self.options
        return bool(
            o.nodes
            or o.remaps
            or o.params
            or o.params_files
            or o.echoes
            or o.introspect
            or self.web is not None
            or o.transport != "inproc"
            or o.record
            or o.play
            or self.binds_inputs
            or self.has_parameters
        )

    @property
    def binds_inputs(self) -> bool:
        """Whether a machine binds an input to a topic (SPEC 11): the run then opens the bus."""
        return any(entry[TOPIC] is not None for cls in self.classes for entry in cls.INPUTS)

    @property
    def has_parameters(self) -> bool:
        """Whether a machine declares `parameters:` (SPEC 12): they are parameters of its node
        /llfsm/M, so the run opens the bus, whether or not the machine's code calls ros.init()."""
        return any(cls.PARAMETERS for cls in self.classes)

    @property
    def world(self) -> TurtleWorld | None:
        """The turtle simulator's world (`--node turtlesim`), for the web view to draw live."""
        return getattr(self.nodes.get("turtlesim"), "world", None)


def _unfinished(arr: Arrangement) -> str:
    """The machines of a run that did not finish, each with where it stands: `bot (in TURN)`."""
    return ", ".join(
        f"{m.NAME} ({'suspended in' if m._suspended else 'in'} {m.STATES[m._state]})"
        for m in arr.machines
        if not m._finished
    )


def _machine_yaml_of(m: Machine, targets: tuple[str, ...]) -> str:
    """The machine.yaml an error about `m`'s inputs names: its folder among the targets, else
    the folder its module was built from."""
    for t in targets:
        if os.path.basename(os.path.normpath(t)) == f"{m.NAME}.machine":
            return os.path.join(t, "machine.yaml")
    return os.path.join(m.SOURCE_DIR or f"{m.NAME}.machine", "machine.yaml")


def _enable(ctx: RunContext) -> None:
    # deferred: start-up (a run that never uses the bus never imports it)
    from ..ros.control import enable
    from ..ros.parameters import ParameterException

    try:
        enable(ctx)
    except ParameterException as e:  # an override of a machine's parameter that its variable refuses
        raise UsageError(parameter_refused(e, "a machine's node")) from None


def parameter_refused(e: Exception, who: str) -> str:
    """The one line for an override a node refused: where it was written, then rclpy's words."""
    origin = getattr(e, "origin", None)
    who = getattr(e, "node", None) or who
    return f"{origin}: {who} refused it: {e}" if origin else f"{who}: {e}"


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
