"""Machines on the graph (docs/view.md): each machine's state, structure and control, as ROS means.

For each loaded machine M, a node `/llfsm/M` offers
- `/llfsm/M/state` (std_msgs/msg/String, the current state's name; TRANSIENT_LOCAL, so a late
  subscriber gets the current one at once),
- `/llfsm/M/description` (std_msgs/msg/String holding JSON: states in order, each with its
  transitions in priority order, targets and guard text; initial and suspend state;
  TRANSIENT_LOCAL),
- `/llfsm/M/suspend`, `/llfsm/M/resume`, `/llfsm/M/restart` (std_srvs/srv/Trigger), which
  schedule the command exactly as the macros do: pending until M's next ringlet;
- the variables machine.yaml lists under `parameters:` as parameters of the node, typed by
  their annotations: a set (`llfsm param set /llfsm/M gain 2.0`, `ros2 param set`, an override
  from `-p` or `--params-file`) gives the variable its value at the start of M's next ringlet
  (Arrangement.set_variables), never in the middle of one; a get shows the variable's value,
  changes made by M's own code included (docs/parameters.md).

Everything goes through the public `ros` API, so it works on any transport.  It joins the
graph with the bus (the first `ros.init()`, a `--node`, or a machine declaring `parameters:`):
a run that never uses the bus never pays for one.

Cost: states are published from scheduler events (a tracer), and that tracer is installed
only while some state topic has a reader; otherwise the scheduler runs its plain loop and a
state change costs nothing at all.  When a reader joins, the current state is published first,
so what the reader is handed is never stale.
"""

from __future__ import annotations

import json
import time
from typing import TYPE_CHECKING, Any, cast

from ..msgs.std_msgs.msg import String
from ..msgs.std_srvs.srv import Trigger
from ..runtime.context import RunContext, activate
from ..runtime.machine import RESTART, RESUME, SUSPEND, Machine
from ..runtime.readout import description
from ..runtime.trace import Tee, Tracer
from .node import Node
from .parameters import Parameter, ParameterDescriptor
from .qos import DurabilityPolicy, QoSProfile

if TYPE_CHECKING:
    from ..runtime.scheduler import Arrangement
    from .bus import Bus, Topic

#: The namespace of the machines' nodes: /llfsm/M/state and so on.
NAMESPACE = "/llfsm"
#: Latched, as a ROS user expects of a state or a description topic.
LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: How often a run on DDS looks for another run of one of its machines (seconds of run time).
WATCH_PERIOD = 0.5


def enable(ctx: RunContext) -> None:
    """Put the run's machines on the graph as soon as its bus is initialised (now, if it is).

    Call once the Arrangement exists (it registers itself in `ctx.arrangement`)."""
    arr = cast("Arrangement | None", ctx.arrangement)  # held by its port, below the scheduler
    if arr is None or ctx.machine_graph is not None:
        return
    bus = ctx.bus
    if bus is not None and bus.initialised:
        attach(arr, cast("Bus", bus))
    else:
        ctx.on_init.append(lambda b: attach(arr, b))


def attach(arr: Arrangement, bus: Bus) -> MachineGraph:
    """Create the nodes, topics and services of every machine of `arr` on `bus` (once)."""
    graph = arr.ctx.machine_graph
    if not isinstance(graph, MachineGraph):
        prev = activate(arr.ctx)
        try:
            graph = arr.ctx.machine_graph = MachineGraph(arr, bus)
        finally:
            activate(prev)
    return graph


def _with_start(desc: dict[str, Any], clock: Any) -> dict[str, Any]:
    """The description with `started`, the wall time (seconds since the epoch) of the run's
    time 0 when the run keeps wall time, so that `llfsm view` in another process shows the
    run's own times (a state's sample carries its wall time); a run on the sim clock has none."""
    read = getattr(clock, "read", None)
    if getattr(clock, "kind", None) != "wall" or read is None:
        return desc
    return {**desc, "started": round((time.time_ns() - read()) / 1e9, 6)}


class _Entry:
    """One machine's publishers and what was last published."""

    __slots__ = ("last", "listened", "machine", "state_pub")

    def __init__(self, machine: Machine, state_pub: Any) -> None:
        self.machine = machine
        self.state_pub = state_pub
        self.last: str | None = None
        self.listened = False


class MachineGraph(Tracer):
    """The machines' nodes, and the tracer that publishes their states while someone listens."""

    def __init__(self, arr: Arrangement, bus: Bus) -> None:
        super().__init__()
        self.arr = arr
        self.bus = bus
        #: The tracer the run had (-v, --trace) while this one is not installed.
        self._own_tracer: Tracer | None = None
        self._installed = False
        self.entries: list[_Entry] = []
        self.nodes: list[Node] = []
        for m in arr.machines:
            node = Node(m.NAME, namespace=NAMESPACE)
            self.nodes.append(node)
            desc = node.create_publisher(String, "~/description", LATCHED)
            desc.publish(String(data=json.dumps(_with_start(description(type(m)), arr.ctx.clock))))
            entry = _Entry(m, node.create_publisher(String, "~/state", LATCHED))
            self.entries.append(entry)
            self._publish(entry, m.STATES[m._state])
            entry.state_pub._topic.on_readers.append(lambda topic, joining, e=entry: self._readers(e, topic, joining))
            for verb in (SUSPEND, RESUME, RESTART):
                node.create_service(Trigger, f"~/{verb}", self._service(m, verb))
            entry.listened = entry.state_pub.get_subscription_count() > 0
            if m.PARAMETERS:
                _declare_variables(arr, m, node)
        #: Readers in other processes come and go unannounced (a DDS transport): there, states
        #: are always published, so the writer's kept sample is current for a late joiner.
        self.always = bool(getattr(getattr(bus, "transport", None), "remote", False))
        if self.always:
            for entry in self.entries:
                entry.listened = True
            if self.nodes:
                self._watch_twins()
        self._update_tracer()

    # -- another run of the same machine --------------------------------------------------------
    def _watch_twins(self) -> None:
        """Say, once per machine, when another run on the domain runs a machine of the same name:
        the two then share /llfsm/M's topics and services, so a command reaches both, which a
        user who started the same machine twice by mistake would not guess.  The graph's nodes
        (ros_discovery_info, as `ros2 node list` reads it) are looked at every WATCH_PERIOD."""
        dp = getattr(self.bus.transport, "dp", None)
        if dp is None:
            return
        try:
            # deferred: optional dependency (cyclonedds); only a run on the DDS transport looks
            from .transports.dds_graph import Graph

            def say(text: str) -> None:  # what a peer sent that could not be read
                self.nodes[0].get_logger().warning(text)

            graph = Graph(dp, say=say)
        except Exception:  # the graph reader is a courtesy: the run goes on without it
            return
        ours = {node.get_fully_qualified_name(): node for node in self.nodes}
        told: set[str] = set()

        def look() -> None:
            try:
                graph.update()
                others = {n.full_name for n in graph.nodes(include_hidden=True)}
            except Exception:
                return
            for name in sorted((others & ours.keys()) - told):
                told.add(name)
                machine = name.rsplit("/", 1)[1]
                ours[name].get_logger().warning(
                    f"another run on this ROS domain runs a machine named {machine} too: the two share "
                    f"{name}/state, {name}/description and {name}/suspend|resume|restart, so a command "
                    f"reaches both (`llfsm view` shows them apart); rename one to tell them apart"
                )

        self.nodes[0].create_timer(WATCH_PERIOD, look)

    # -- publishing -----------------------------------------------------------------------------
    def _publish(self, entry: _Entry, name: str) -> None:
        entry.last = name
        entry.state_pub.publish(String(data=name))

    def _readers(self, entry: _Entry, topic: Topic, joining: bool) -> None:
        """A subscription joins (before it is handed the latched state) or leaves a state topic."""
        if joining:
            m = entry.machine
            current = m.STATES[m._state]
            if entry.last != current:  # changed while no one listened: bring the latched value up to date
                self._publish(entry, current)
            entry.listened = True
        else:
            entry.listened = self.always or bool(topic.readers) or bool(topic.taps)
        self._update_tracer()

    def _update_tracer(self) -> None:
        """Install this tracer while any state topic has a reader; take it away when none has."""
        want = any(e.listened for e in self.entries)
        if want == self._installed:
            return
        arr = self.arr
        if want:
            self._own_tracer = arr.tracer
            arr.set_tracer(self if arr.tracer is None else Tee(arr.tracer, self))
        else:
            arr.set_tracer(self._own_tracer)
        self._installed = want

    # -- scheduler events (only while installed) -----------------------------------------------------
    def transition(self, m: Machine, source: int, target: int, index: int) -> None:
        entry = self.entries[m._id]
        if entry.listened:
            name = m.STATES[m._state]
            if m._state == m.SUSPENDED and entry.last == name:
                return  # a transition into the suspend state: the suspend event has just told it
            self._publish(entry, name)

    def command(self, kind: str, m: Machine, state: int) -> None:
        entry = self.entries[m._id]
        if entry.listened:
            self._publish(entry, m.STATES[state])

    # -- control services ------------------------------------------------------------------------------
    def _service(self, m: Machine, verb: str) -> Any:
        arr = self.arr

        def serve(request: Any, response: Any) -> Any:
            reason = refusal(m, verb)
            response.success = reason is None
            if reason is None:
                arr.command(m.NAME, verb)
                response.message = f"{verb} of {m.NAME} pending until its next ringlet"
            else:
                response.message = reason
            return response

        return serve


def _as_type(value: object, type_: Parameter.Type) -> object:
    """The variable's value as its parameter holds it: an int where a float is annotated (`gain:
    float = 2`) is that float; a tuple is a list."""
    if type_ is Parameter.Type.DOUBLE and type(value) is int:
        return float(value)
    if type_ is Parameter.Type.DOUBLE_ARRAY and isinstance(value, list | tuple):
        return [float(v) if type(v) is int else v for v in value]
    if isinstance(value, tuple):
        return list(value)
    return value


def _declare_variables(arr: Arrangement, m: Machine, node: Node) -> None:
    """M's `parameters:` on its node: declared statically typed from the annotations, with the
    run's overrides applied through the scheduler like any later set."""
    names = {name for name, _ in m.PARAMETERS}
    types = {name: Parameter.Type[kind] for name, kind in m.PARAMETERS}
    overridden: dict[str, object] = {}
    for name, type_ in types.items():
        current = _as_type(getattr(m, name), type_)
        descriptor = ParameterDescriptor(description=f"variable {name} of machine {m.NAME}", type=int(type_))
        declared = node.declare_parameter(name, current if type_.check(current) else type_, descriptor)
        if declared.type_ is not Parameter.Type.NOT_SET and declared.value != current:
            overridden[name] = _own(declared.value)
    if overridden:
        arr.set_variables(m.NAME, overridden)

    def apply(params: list[Parameter]) -> None:
        values = {p.name: _own(p.value) for p in params if p.name in names}
        if values:
            arr.set_variables(m.NAME, values)

    def refresh() -> None:
        """What M's own code did to a variable shows in a get (unless a set is still pending)."""
        pending = arr._variables.get(m._id, {})
        for name in names:
            if name in pending:
                continue
            value = _as_type(getattr(m, name), types[name])
            held = node._parameters.get(name)
            if held is not None and held.value != value and types[name].check(value):
                node._parameters[name] = Parameter(name, types[name], value)

    node.add_post_set_parameters_callback(apply)
    node._refresh_parameters = refresh


def _own(value: object) -> object:
    """A list for the machine of its own (machine code may change it in place)."""
    return list(value) if isinstance(value, list) else value


def refusal(m: Machine, verb: str) -> str | None:
    """Why `verb` makes no sense for `m` now (None: it does), judged on the state the machine
    will be in once the command already pending, if any, has been applied."""
    pending = m._pending
    finished = m._finished and pending != RESTART
    suspended = pending == SUSPEND or (m._suspended and pending not in (RESUME, RESTART))
    if verb == RESTART:
        return None  # always meaningful: also brings a finished machine back
    if finished:
        return f"{m.NAME} has finished; only restart brings it back"
    if verb == SUSPEND and suspended:
        return f"{m.NAME} is already suspended"
    if verb == RESUME and not suspended:
        return f"{m.NAME} is not suspended"
    return None
