"""`action list|info|send_goal`: actions of the ROS graph as `ros2 action` lists, describes and
calls them (docs/actions.md, "From the command line").

The graph finds actions as rcl_action does, from their feedback topics (llfsm/ros/action/
names.py): a topic `<action>/_action/feedback` whose type is `<pkg>/action/<Name>_FeedbackMessage`;
its publishers' nodes serve the action, its subscribers' nodes are clients.  `send_goal` is an
action client of a hidden node of llfsm's bus on the DDS transport, as `ros2 action send_goal`
is rclpy's; Ctrl-C while the goal runs cancels it, as ros2's does.
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

from ..msgs import to_yaml
from ..ros import ActionClient, FutureReturnCode, spin_until_future_complete
from ..ros.action import status
from ..ros.action.names import action_of_feedback, action_type
from ..ros.transports.dds_graph import Graph, message_type
from . import NOT_FOUND, SPIN_TIME, TIMEOUT, CliError
from .arguments import full_name, parse_values
from .discovery import discovered, where
from .endpoints import hidden_node
from .lookup import action_class, use_working_directory

#: How long `send_goal` waits for the server to answer a cancel request after Ctrl-C.
CANCEL_TIMEOUT = 5.0


def actions(graph: Graph) -> dict[str, list[str]]:
    """Action name -> its types (sorted), from the feedback topics the graph shows."""
    out: dict[str, set[str]] = {}
    for topic, types in graph.topics(include_hidden=True).items():
        name = action_of_feedback(topic)
        if name is not None:
            out.setdefault(name, set()).update(action_type(t) for t in types)
    return {n: sorted(t) for n, t in sorted(out.items())}


def list_(*, show_types: bool = False, count: bool = False, spin_time: float = SPIN_TIME) -> str:
    """What `ros2 action list` prints after `spin_time` seconds of discovery."""
    with discovered(spin_time) as graph:
        found = actions(graph)
    if count:
        return f"{len(found)}\n"
    if not found:
        raise CliError(f"no actions found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{name} [{', '.join(types)}]\n" if show_types else f"{name}\n" for name, types in found.items())


def info(action: str, *, show_types: bool = False, count: bool = False, spin_time: float = SPIN_TIME) -> str:
    """What `ros2 action info` prints: the action's clients and servers, by node."""
    name = full_name(action, "action")
    feedback = f"{name}/_action/feedback"
    with discovered(spin_time) as graph:
        graph.settle()  # the nodes of the endpoints
        sides = []
        for kind in ("subscription", "publisher"):  # clients read feedback, servers write it
            nodes: dict[str, set[str]] = {}
            for e in graph.topic_endpoints(feedback, kind):
                node = graph.node_of(e.gid)
                fqn = node.full_name if node is not None else "_NODE_NAME_UNKNOWN_"
                nodes.setdefault(fqn, set()).add(action_type(message_type(e.type_name)))
            sides.append(nodes)
    out = [f"Action: {name}\n"]
    for title, nodes in zip(("Action clients", "Action servers"), sides, strict=True):
        out.append(f"{title}: {len(nodes)}\n")
        if count:
            continue
        for fqn, types in sorted(nodes.items()):
            out.append(f"    {fqn} [{', '.join(sorted(types))}]\n" if show_types else f"    {fqn}\n")
    return "".join(out)


def send_goal(
    action: str,
    type_text: str,
    values: str = "{}",
    *,
    feedback: bool = False,
    timeout: float = TIMEOUT,
    out: TextIO | None = None,
) -> None:
    """`ros2 action send_goal`: send the goal, print its acceptance, feedback (with
    `feedback`) and result.  No server within `timeout`, or no acceptance within `timeout`, or
    a server that goes away before the result: exit status 1.  The result itself may take as
    long as the goal does.  Ctrl-C (KeyboardInterrupt) cancels a goal still running, then goes
    on as an interrupt."""
    out = out or sys.stdout
    name = full_name(action, "action")
    use_working_directory()
    action_type_ = action_class(type_text)
    goal, _stamps = parse_values(action_type_.Goal, values)
    pkg, _, action_name = action_type_._TYPE.split("/")
    with hidden_node(f"_llfsm_cli_send_goal_{pkg}_{action_name}") as (node, graph):
        client = ActionClient(node, action_type_, name)

        def say(text: str) -> None:
            out.write(text)
            out.flush()

        def on_feedback(message: Any) -> None:
            say(f"Feedback:\n    {to_yaml(message.feedback)}\n")

        say("Waiting for an action server to become available...\n")
        _wait_for_server(graph, client, name, action_type_, timeout)
        say(f"Sending goal:\n     {to_yaml(goal)}\n")
        sent = client.send_goal_async(goal, on_feedback if feedback else None)
        if spin_until_future_complete(node, sent, timeout_sec=timeout) is not FutureReturnCode.SUCCESS:
            raise CliError(f"action '{name}' did not answer the goal within {timeout:g} s", NOT_FOUND)
        handle = sent.result()
        if not handle.accepted:
            say("Goal was rejected.\n")
            return
        say(f"Goal accepted with ID: {status.text(handle.goal_id.uuid)}\n\n")
        result = handle.get_result_async()
        try:
            code = spin_until_future_complete(node, result)
        except KeyboardInterrupt:
            if handle.status in (status.ACCEPTED, status.EXECUTING):
                _cancel(node, handle, say)
            raise
        if code is not FutureReturnCode.SUCCESS or result.result() is None:
            raise CliError(f"action '{name}' went away before the goal finished", NOT_FOUND)
        answer = result.result()
        say(f"Result:\n    {to_yaml(answer.result)}\n")
        say(f"Goal finished with status: {status.name(answer.status)}\n")


def _cancel(node: Any, handle: Any, say: Any) -> None:
    """ros2's `finally` block: cancel the goal and say how it went."""
    say("Canceling goal...\n")
    future = handle.cancel_goal_async()
    if spin_until_future_complete(node, future, timeout_sec=CANCEL_TIMEOUT) is not FutureReturnCode.SUCCESS:
        raise CliError(f"the action server did not answer the cancel request within {CANCEL_TIMEOUT:g} s", 1)
    response = future.result()
    if len(response.goals_canceling) == 0:
        raise CliError("Failed to cancel goal", 1)
    if len(response.goals_canceling) > 1:
        raise CliError("More than one goal canceled", 1)
    if bytes(response.goals_canceling[0].goal_id.uuid) != bytes(handle.goal_id.uuid):
        raise CliError("Canceled goal with incorrect goal ID", 1)
    say("Goal canceled.\n")


def _wait_for_server(graph: Graph, client: ActionClient, name: str, action_type_: Any, timeout: float) -> None:
    """Once the client sees a server; a server of another type is said at once; none within
    `timeout`: exit status 1 (ros2 would wait for ever)."""
    deadline = time.monotonic() + timeout
    while not client.server_is_ready():
        client._bus.spin_once(50_000_000)
        graph.update()
        types = actions(graph).get(name)
        if types and action_type_._TYPE not in types:
            raise CliError(f"action '{name}' has type {', '.join(types)}, not {action_type_._TYPE}", NOT_FOUND)
        if time.monotonic() >= deadline:
            raise CliError(f"action server '{name}' not available within {timeout:g} s ({where()})", NOT_FOUND)
