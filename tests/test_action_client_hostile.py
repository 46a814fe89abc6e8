"""An llfsm action client beside a peer that publishes anything on the action's status and
feedback topics (SPEC §18): status arrays of 300,000 entries, arrays that declare more entries
than they hold, feedback of 8 MB for goals that are not the client's.  The client's own goal
still gets all its feedback and its result, and its memory stays near what the samples
themselves take (a status array decoded as messages took hundreds of MB per sample).  The peer
is a real DDS process in a private network namespace, writing bytes of its own making."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest
from dds_netns import RAW_PEER, NetNamespace, finish

pytestmark = pytest.mark.dds

TRAIL = "int32 target\n---\nint32 total\n---\nint32[] trail\n"

#: A server of /trail: feedback [i] every 50 ms for i < target, then the result.
SERVER = textwrap.dedent(
    """
    import time
    from llfsm import ros
    from llfsm.msgs.llfsm_trail_msgs.action import Trail
    from llfsm.ros2cli.endpoints import hidden_node

    def execute(goal):
        for i in range(goal.request.target):
            goal.publish_feedback(Trail.Feedback(trail=[i]))
            yield 0.05
        goal.succeed()
        return Trail.Result(total=goal.request.target)

    with hidden_node("trail_server") as (node, graph):
        ros.ActionServer(node, Trail, "/trail", execute)
        print("serving", flush=True)
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            node._bus.spin_once(50_000_000)
    """
)

#: The peer: huge and broken status arrays (a status of 99 in every entry), huge feedback for
#: goals of nobody, over and over.
PEER = RAW_PEER + textwrap.dedent(
    """
    import os
    from llfsm.msgs.action_msgs.msg import GoalStatusArray
    from llfsm.msgs.llfsm_trail_msgs.action import Trail
    kept = (Policy.History.KeepLast(8),)
    latched = (Policy.Durability.TransientLocal, Policy.History.KeepLast(8))
    status = writer("rt/trail/_action/status", GoalStatusArray, *latched)
    feedback = writer("rt/trail/_action/feedback", Trail.Impl.FeedbackMessage, *kept)
    N = 300_000
    # the first entry: id, stamp, status; every next one: id, 3 bytes of padding, stamp, status
    huge = (HEAD + struct.pack("<I", N) + os.urandom(16) + bytes(8) + b"\\x63"
            + (os.urandom(16) + bytes(11) + b"\\x63") * (N - 1))
    broken = HEAD + struct.pack("<I", 1_000_000) + bytes(12)
    M = 2_000_000
    fat = HEAD + os.urandom(16) + struct.pack("<I", M) + bytes(4 * M)
    print("flooding", flush=True)
    while True:
        write(status, huge)
        write(status, broken)
        write(feedback, fat)
        time.sleep(0.05)
    """
)

#: The client: one goal of 30 steps, its feedback and result, and its peak memory.
CLIENT = textwrap.dedent(
    """
    import json, resource, time
    from llfsm import ros
    from llfsm.msgs.llfsm_trail_msgs.action import Trail
    from llfsm.ros2cli.endpoints import hidden_node

    with hidden_node("trail_client") as (node, graph):
        client = ros.ActionClient(node, Trail, "/trail")
        assert client.wait_for_server(timeout_sec=30.0)
        heard = []
        sent = client.send_goal_async(Trail.Goal(target=30), lambda m: heard.append(list(m.feedback.trail)))
        assert ros.spin_until_future_complete(node, sent, timeout_sec=30.0) == ros.FutureReturnCode.SUCCESS
        result = sent.result().get_result_async()
        assert ros.spin_until_future_complete(node, result, timeout_sec=60.0) == ros.FutureReturnCode.SUCCESS
        # the feedback is a topic and the result a service: the last feedback may come after the
        # result (under load 11 of 30 did), so the client listens on until it has all, or 30 s
        deadline = time.monotonic() + 30
        while len(heard) < 30 and time.monotonic() < deadline:
            ros.spin_once(node, timeout_sec=0.1)
        print(json.dumps({"status": result.result().status, "total": result.result().result.total,
                          "heard": heard, "handle": sent.result().status,
                          "max_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}), flush=True)
    """
)


def test_a_client_reads_its_own_goal_through_a_peers_flood(netns: NetNamespace, tmp_path: Path) -> None:
    (tmp_path / "llfsm_trail_msgs" / "action").mkdir(parents=True)
    (tmp_path / "llfsm_trail_msgs" / "action" / "Trail.action").write_text(TRAIL)
    env = {"LLFSM_INTERFACE_PATH": str(tmp_path), "PYTHONUNBUFFERED": "1"}
    server = netns.python(SERVER, env=env)
    peer = netns.python(PEER, env=env)
    assert peer.stdout is not None and peer.stdout.readline().strip() == "flooding"
    status, out, err = finish(netns.python(CLIENT, env=env), 120)
    assert status == 0, err[-3000:]
    got = json.loads(out.strip().splitlines()[-1])
    assert (got["status"], got["total"], got["handle"]) == (4, 30, 4)
    assert got["heard"] == [[i] for i in range(30)]  # its own feedback, all of it, nobody else's
    # the samples themselves (Cyclone's copies, the payload taken) are 8 MB each; decoded as
    # messages one status array alone took several hundred MB
    assert got["max_rss_mib"] < 250, got["max_rss_mib"]
    assert "Traceback" not in err
    # (the arrays that declare more than they hold never get here: Cyclone drops them in C)
    peer.kill()
    server.kill()
