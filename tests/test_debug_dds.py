"""The debugger over ROS 2's wire (docs/debug.md, "Over the graph"): a run on DDS paused, read,
set and continued by another process through its debug services, and its state topic.  Real
processes in a private network namespace (dds_netns.py)."""

from __future__ import annotations

import json
import textwrap

import pytest
from dds_netns import NetNamespace, finish, start_view
from helpers import MACHINES

pytestmark = pytest.mark.dds

#: The other process: one hidden node, the run's services called in turn; what it saw, as JSON.
CONTROLLER = textwrap.dedent(
    """
    import json, time
    from llfsm.msgs.llfsm_msgs.msg import DebugState
    from llfsm.msgs.llfsm_msgs.srv import GetVariables, SetBreakpoint, SetVariable
    from llfsm.msgs.std_srvs.srv import Trigger
    from llfsm.ros.executor import spin_until_future_complete
    from llfsm.ros2cli.endpoints import hidden_node

    NS = "/llfsm/ros2_ping_pong"
    seen, states = {}, []
    with hidden_node("_debug_probe") as (node, graph):
        node.create_subscription(DebugState, NS + "/debug", lambda m: states.append(m.paused), 10)

        def call(srv, service, **fields):
            client = node.create_client(srv, NS + "/" + service)
            client.wait_for_service(timeout_sec=20)
            future = client.call_async(srv.Request(**fields))
            spin_until_future_complete(node, future, timeout_sec=10)
            return future.result()

        time.sleep(2.5)  # the count has reached 1 or 2
        seen["pause"] = call(Trigger, "pause").message
        first = call(GetVariables, "variables")
        time.sleep(1.5)  # paused: nothing runs, not even the run clock
        second = call(GetVariables, "variables")
        seen["read"] = [first.paused, first.yaml, second.yaml]
        seen["bad"] = call(SetVariable, "set_variable", name="count", value="lots").message
        seen["set"] = call(SetVariable, "set_variable", name="count", value="41").message
        seen["break"] = call(SetBreakpoint, "breakpoint", expression="ros2_ping_pong.count == 43", enable=True).message
        seen["continue"] = call(Trigger, "continue").message
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:  # the breakpoint pauses it again
            time.sleep(0.1)
            if call(GetVariables, "variables").paused:
                break
        seen["at_break"] = call(GetVariables, "variables").yaml
        seen["again"] = call(Trigger, "continue").message
        seen["running"] = not call(GetVariables, "variables").paused  # also spins: the state topic's last sample
        seen["states"] = states
    print(json.dumps(seen))
    """
)


def test_a_dds_run_is_paused_read_set_and_continued_from_another_process(netns: NetNamespace) -> None:
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "14")
    probe = netns.python(CONTROLLER)
    status, out, err = finish(probe, 60)
    run_status, run_out, run_err = finish(run, 60)
    assert status == 0, err
    seen = json.loads(out)
    assert seen["pause"] == "pausing at the next ringlet boundary"
    paused, first, second = seen["read"]
    assert paused and first == second  # nothing ran while it was paused
    assert "state: " in first and "time_in_state: " in first and "variables:\n  count: " in first
    assert "count is int: 'lots' is a string, not an int" in seen["bad"]
    assert seen["set"] == "ros2_ping_pong.count = 41"
    assert seen["break"] == "breakpoint 1: ros2_ping_pong.count == 43"
    assert "count: 43" in seen["at_break"]
    assert seen["continue"] == seen["again"] == "continuing"
    assert seen["running"]
    assert seen["states"][0] is False and True in seen["states"] and seen["states"][-1] is False
    assert run_status == 0, run_err
    published = run_out + run_err
    assert "The count is 42'" in published and "The count is 43'" in published and "The count is 4'" not in published


#: What the page's controls send to `llfsm view`, from inside the namespace: the view's answers.
VIEW_CLIENT = textwrap.dedent(
    """
    import http.client, json, sys, time
    port = int(sys.argv[1])

    def post(what, **data):
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=15)
        conn.request("POST", "/api/debug/" + what, json.dumps(data), {"Content-Type": "application/json"})
        r = conn.getresponse()
        return r.status, json.loads(r.read())

    seen = {}
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # until the view has found the machine and its services answer
        status, answer = post("variables", machine="ros2_ping_pong")
        if status == 200:
            break
        time.sleep(0.3)
    seen["pause"] = post("pause", machine="ros2_ping_pong")
    first = post("variables", machine="ros2_ping_pong")[1]
    time.sleep(1.5)
    second = post("variables", machine="ros2_ping_pong")[1]
    seen["paused"] = [first["paused"], first["machine"], second["machine"]]
    seen["set"] = post("set", machine="ros2_ping_pong", name="count", value="41")
    seen["frame"] = post("frame", machine="ros2_ping_pong", back=0)
    seen["continue"] = post("continue", machine="ros2_ping_pong")
    time.sleep(2.5)
    seen["after"] = post("variables", machine="ros2_ping_pong")[1]
    print(json.dumps(seen))
    """
)


def test_llfsm_view_pauses_reads_sets_and_continues_a_run_of_another_process(netns: NetNamespace) -> None:
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "40")
    view, url, _err = start_view(netns, "--duration", "40")
    port = url.rstrip("/").rsplit(":", 1)[1]
    client = netns.python(VIEW_CLIENT.replace("sys.argv[1]", repr(port)))
    status, out, err = finish(client, 90)
    view.terminate()
    run.terminate()
    finish(view, 20)
    finish(run, 20)
    assert status == 0, err
    seen = json.loads(out)
    assert seen["pause"] == [200, {"success": True, "message": "pausing at the next ringlet boundary"}]
    paused, first, second = seen["paused"]
    assert paused and first == second and "count" in first["variables"]  # nothing ran while paused
    assert seen["set"] == [200, {"success": True, "message": "ros2_ping_pong.count = 41"}]
    assert seen["frame"][0] == 400 and "no history crosses the graph" in seen["frame"][1]["message"]
    assert seen["continue"][1]["message"] == "continuing"
    assert seen["after"]["machine"]["variables"]["count"] > 41 and not seen["after"]["paused"]
