"""The debugger over the graph (docs/debug.md, "Over the graph"): the same control as the prompt
and the page, as services of the run, so that another process (`llfsm view`, a script,
`llfsm service call`, `ros2 service call`) pauses, steps, continues and reads variables.

On each machine's node `/llfsm/M` (llfsm.ros.control), beside suspend/resume/restart:

    /llfsm/M/pause, /continue, /step, /step_round    std_srvs/srv/Trigger (the whole run)
    /llfsm/M/variables                               llfsm_msgs/srv/GetVariables (M as YAML)
    /llfsm/M/set_variable                            llfsm_msgs/srv/SetVariable (paused only)
    /llfsm/M/breakpoint                              llfsm_msgs/srv/SetBreakpoint
    /llfsm/M/debug                                   llfsm_msgs/msg/DebugState (latched; on DDS)

Every machine of a run offers the run's control: a client that knows one machine of a run can
pause the run.  The callbacks run on the scheduler's thread, between rounds while the run runs
and in the pause loop while it stands (`answers` says which requests a paused run answers: the
machines' control, parameter and debug services).
"""

from __future__ import annotations

from typing import Any

from ..msgs.llfsm_msgs.msg import DebugState
from ..msgs.llfsm_msgs.srv import GetVariables, SetBreakpoint, SetVariable
from ..msgs.std_srvs.srv import Trigger
from ..ros.control import LATCHED, NAMESPACE
from ..ros.transports.base import ServiceView
from .debugger import CONTINUE, ROUND, STEP, DebugError, Debugger
from .variables import as_yaml


def answers(server: ServiceView) -> bool:
    """Whether a paused run answers a request to `server`: the machines' nodes' services
    (control, parameters, the debugger's) and every node's parameter services."""
    return server.srv_name.startswith(NAMESPACE + "/") or server.type._TYPE.startswith("rcl_interfaces/srv/")


def offer(debugger: Debugger, graph: Any, topic: bool = True) -> None:
    """The debug services and (with `topic`) the state topic on each machine's node of `graph`
    (a llfsm.ros.control.MachineGraph; None: the run has no machines on the graph)."""
    if graph is None:
        return
    pubs = []
    for m, node in zip(debugger.arr.machines, graph.nodes, strict=True):
        name = m.NAME
        node.create_service(Trigger, "~/pause", _trigger(debugger, "pause", f"{NAMESPACE}/{name}/pause"))
        for verb, mode in (("continue", CONTINUE), ("step", STEP), ("step_round", ROUND)):
            node.create_service(Trigger, f"~/{verb}", _trigger(debugger, mode, f"{NAMESPACE}/{name}/{verb}"))
        node.create_service(GetVariables, "~/variables", _variables(debugger, name))
        node.create_service(SetVariable, "~/set_variable", _set_variable(debugger, name))
        node.create_service(SetBreakpoint, "~/breakpoint", _breakpoint(debugger))
        if topic:
            pubs.append(node.create_publisher(DebugState, "~/debug", LATCHED))
    if not pubs:
        return

    def publish(d: Debugger) -> None:
        s = d.status()
        msg = DebugState(
            paused=s["paused"],
            where=s["where"],
            reason=s["reason"],
            machine=s["machine"] or "",
            round=max(0, s["round"]),
            time=float(s["t"]),
            breakpoints=list(s["breaks"]),
        )
        for pub in pubs:
            pub.publish(msg)

    debugger.listeners.append(publish)
    publish(debugger)


def _trigger(debugger: Debugger, mode: str, service: str) -> Any:
    def serve(request: Any, response: Any) -> Any:
        try:
            if mode == "pause":
                if debugger.paused:
                    response.message = f"already {debugger.where()}"
                else:
                    debugger.pause(f"{service} called")
                    response.message = "pausing at the next ringlet boundary"
            else:
                response.message = debugger.resume(mode)
            response.success = True
        except DebugError as e:
            response.success, response.message = False, str(e)
        return response

    return serve


def _variables(debugger: Debugger, name: str) -> Any:
    def serve(request: Any, response: Any) -> Any:
        response.paused = debugger.paused
        response.yaml = as_yaml(debugger.read(name)[name])
        return response

    return serve


def _set_variable(debugger: Debugger, name: str) -> Any:
    def serve(request: Any, response: Any) -> Any:
        try:
            response.message = debugger.set_value(name, request.name.strip(), request.value)
            response.success = True
        except DebugError as e:
            response.success, response.message = False, str(e)
        return response

    return serve


def _breakpoint(debugger: Debugger) -> Any:
    def serve(request: Any, response: Any) -> Any:
        try:
            if request.enable:
                bp = debugger.add_break(request.expression, where="breakpoint")
                response.message = f"breakpoint {bp.number}: {bp.text}"
            else:
                gone = debugger.remove_break(text=request.expression)
                response.message = f"removed breakpoint {', '.join(str(b.number) for b in gone)}"
            response.success = True
        except DebugError as e:
            response.success, response.message = False, str(e)
        response.breakpoints = [b.text for b in debugger.breaks.items]
        return response

    return serve
