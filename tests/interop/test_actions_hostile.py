"""A peer that piles goals on an llfsm action server and cancels them all at once (SPEC §18,
issue 28): an rclpy process (Fast DDS) against an llfsm run (Cyclone DDS) where a machine
serves the action in the PULL form, one goal at a time, beside a 10 Hz machine that publishes
its wall time and holds a client of the same action (so it reads every status array).  The
peer fills the server past its limit, cancels every goal with one request, and reads the 10 Hz
machine's own timestamps: the longest gap between two of them is how long the run stood still.
(rcl_action publishes the whole status array once per goal it moves: a cancel of 990 goals
stalled such a run 3.4 s.)"""

from __future__ import annotations

import itertools
import json
import shutil
from pathlib import Path

import pytest
from helpers import write_machine

from interop.ros2env import VENV_ROS, llfsm_command, requires_ros, ros_command, run_together

pytestmark = [pytest.mark.interop, pytest.mark.dds, requires_ros]

# The peer: reads /tick and the status array, sends goals in batches (an llfsm server's replies
# do not reach a Fast DDS client, docs/actions.md, so the status array says what was accepted)
# until the server holds 1000 and has refused more, then one cancel of every goal (no id, no
# stamp), then watches for 4 s.
_PEER = r"""
import json, time, rclpy
from rclpy.action import ActionClient
from rclpy.node import Node
from action_msgs.msg import GoalStatusArray
from action_msgs.srv import CancelGoal
from std_msgs.msg import Float64
from test_msgs.action import Fibonacci

rclpy.init()
node = Node("hostile_peer")
ticks, statuses = [], []
node.create_subscription(Float64, "/tick", lambda m: ticks.append(m.data), 100)
def heard(array):
    statuses.append([s.status for s in array.status_list])
node.create_subscription(GoalStatusArray, "/fibonacci/_action/status", heard, 10)
client = ActionClient(node, Fibonacci, "fibonacci")
cancel = node.create_client(CancelGoal, "/fibonacci/_action/cancel_goal")
assert client.wait_for_server(timeout_sec=30.0)
assert cancel.wait_for_service(timeout_sec=30.0)
def spin(seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.01)
def held():
    return sum(1 for s in (statuses[-1] if statuses else []) if s in (1, 2, 3))
spin(1.0)
started = ticks[-1] if ticks else None
sent = 0
deadline = time.monotonic() + 60
while held() < 1000 and time.monotonic() < deadline:
    for _ in range(10):
        client.send_goal_async(Fibonacci.Goal(order=1))
    sent += 10
    spin(0.03)
for _ in range(3):  # past the limit: refused
    client.send_goal_async(Fibonacci.Goal(order=1))
spin(0.5)
most = max((sum(1 for x in s if x in (1, 2, 3)) for s in statuses), default=0)
cancel_at = ticks[-1] if ticks else None
cancel.call_async(CancelGoal.Request())
spin(4.0)
after = [s for s in statuses[-1]] if statuses else []
print(json.dumps({"sent": sent, "held": most, "ticks": ticks, "started": started, "cancel_at": cancel_at,
                  "ended": time.time(), "after": after}), flush=True)
"""


def machines(root: Path) -> list[Path]:
    server = write_machine(
        root,
        "slow_server",
        {
            "INITIAL": [("IDLE", "True")],
            "IDLE": [("STEP", "server.waiting > 0")],
            "STEP": [("CANCELED", "goal.is_cancel_requested"), ("DONE", "after_ms(1000)")],
            "DONE": [("IDLE", "True")],
            "CANCELED": [("IDLE", "True")],
        },
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('slow_server')\n"
                "server = ros.ActionServer(node, Fibonacci, '/fibonacci', None,\n"
                "    cancel_callback=lambda handle: ros.CancelResponse.ACCEPT)\n"
            ),
            "STEP_OnEntry": "goal = server.take()",
            "DONE_OnEntry": "goal.succeed(Fibonacci.Result())",
            "CANCELED_OnEntry": "goal.canceled(Fibonacci.Result())",
        },
        variables="node: object = None\nserver: object = None\ngoal: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.test_msgs.action import Fibonacci\n",
    )
    ticker = write_machine(
        root,
        "ticker",
        {"INITIAL": [("TICK", "True")], "TICK": [("TICK", "after_ms(100)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('ticker')\npub = node.create_publisher(Float64, '/tick', 10)\n"
                "watch = ros.ActionClient(node, Fibonacci, '/fibonacci')  # reads every status array\n"
            ),
            "TICK_OnEntry": "pub.publish(Float64(data=time.time()))",
        },
        variables="node: object = None\npub: object = None\nwatch: object = None\n",
        includes=(
            "import time\nfrom llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Float64\n"
            "from llfsm.msgs.test_msgs.action import Fibonacci\n"
        ),
    )
    return [server, ticker]


def test_a_cancel_of_a_thousand_goals_leaves_a_10_hz_machine_at_its_rate(tmp_path: Path) -> None:
    for kind in ("msg", "action"):  # test_msgs as a user's package, from the wheel's own files
        (tmp_path / "test_msgs" / kind).mkdir(parents=True)
        for f in sorted((VENV_ROS / "share" / "test_msgs" / kind).glob(f"*.{kind}")):
            shutil.copy(f, tmp_path / "test_msgs" / kind / f.name)
    env = {"LLFSM_INTERFACE_PATH": str(tmp_path)}
    run = llfsm_command(["run", "--transport", "dds", *map(str, machines(tmp_path)), "--duration", "120"], env)
    llfsm, peer = run_together([run, ros_command(_PEER)], timeout=150, stop_after_first=1)
    assert peer.returncode == 0, peer.stderr + llfsm.stderr
    out = json.loads(peer.stdout.strip().splitlines()[-1])
    assert out["held"] == 1000, out["held"]  # the limit, not every goal sent
    assert "holds 1000 unfinished goals, the most it keeps" in llfsm.stderr, llfsm.stderr
    assert llfsm.stderr.count("unfinished goals") == 1
    # every goal was canceled by the one request (the machine ends them as it takes them)
    assert out["after"] and set(out["after"]) <= {3, 5} and out["after"].count(5) > 0, out["after"][:20]
    # the machine's own stamps, from before the first goal to the end of the watch (same host,
    # same clock): the longest time it published nothing
    ticks = [t for t in out["ticks"] if t >= out["started"]] + [out["ended"]]
    gaps = [b - a for a, b in itertools.pairwise(ticks)]
    assert max(gaps) < 1.0, f"the 10 Hz machine stood still {max(gaps):.2f} s"
    assert "Traceback" not in llfsm.stderr
