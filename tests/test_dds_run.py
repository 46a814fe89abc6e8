"""`llfsm run --transport dds`: machines and nodes in separate processes, on ROS 2's wire.

Every test runs its processes in one private network namespace (dds_netns.py); nothing leaves
the machine and every process has a timeout.  These are real processes talking over Cyclone DDS:
no mocks.
"""

from __future__ import annotations

import re
import signal
import sys
import time
from pathlib import Path

import pytest
from dds_netns import NetNamespace, Watched, finish, interrupt, until_shown
from helpers import MACHINES, llfsm_process, write_machine

#: Peers that vanish without saying goodbye are noticed after the lease: 1 s instead of 10 s.
SHORT_LEASE = {
    "CYCLONEDDS_URI": "<CycloneDDS><Domain><Discovery><LeaseDuration>1s</LeaseDuration></Discovery></Domain>"
    "</CycloneDDS>"
}


def poses(yaml_text: str) -> list[tuple[float, float]]:
    """(x, y) of each turtlesim/msg/Pose printed by --echo."""
    out = []
    for block in yaml_text.split("---\n"):
        x = re.search(r"^x: (\S+)$", block, re.M)
        y = re.search(r"^y: (\S+)$", block, re.M)
        if x and y:
            out.append((float(x.group(1)), float(y.group(1))))
    return out


def test_sim_clock_with_dds_is_a_usage_error_saying_why() -> None:
    run = llfsm_process("run", "--transport", "dds", "--clock", "sim", MACHINES / "ros2_ping_pong.machine")
    assert run.status == 2
    assert "--clock sim cannot be used with --transport dds" in run.stderr
    assert "wall clock" in run.stderr and "Traceback" not in run.stderr


def test_llfsm_transport_variable_chooses_the_transport() -> None:
    import os

    env = {**os.environ, "LLFSM_TRANSPORT": "dds"}
    run = llfsm_process("run", "--clock", "sim", "--node", "turtlesim", "--duration", "0.1", env=env)
    assert run.status == 2 and "--clock sim cannot be used with --transport dds" in run.stderr


@pytest.mark.dds
def test_wall_turtle_in_one_process_backs_off_the_walls_of_turtlesim_in_another(netns: NetNamespace) -> None:
    sim = Watched(netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--node", "turtle_sensor_poster"))
    echo = Watched(netns.llfsm("run", "--transport", "dds", "--echo", "/turtle1/pose", "--node", "teleop"))
    echo.wait_for(r"^theta: ", stream="out")  # turtlesim is up and the echo hears it
    bot = Watched(netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_wall_turtle_bot.machine", "-v"))
    # Ctrl-C once it has backed off a wall (counted from its start, a time would race with a
    # start-up that takes seconds under load); Ctrl-C rather than --duration: a --duration ending
    # inside a pose request would cut that request short (TIMEOUT, then SERVICE_FAILS), as it
    # does in process; after Ctrl-C the bot takes its `not ros.ok()` transitions to END
    bot.wait_for(r"- ros2_wall_turtle_bot - BACK\b")
    bot_status, _, bot_err = bot.finish(120, signal.SIGINT)
    _, echo_out, echo_err = echo.finish(120, signal.SIGINT)
    sim_status, _, sim_err = sim.finish(120, signal.SIGINT)
    assert bot_status == 0 and sim_status == 0, bot_err + sim_err  # END reached: a normal end
    assert "Traceback" not in bot_err + sim_err + echo_err
    states = re.findall(r"- ros2_wall_turtle_bot - (\w+)", bot_err)
    assert "TEST" in states, "the pose service never answered across processes"
    assert "BACK" in states, "the turtle never came near a wall to back off from"
    assert "SERVICE_FAILS" not in states, bot_err
    assert states[-1] == "END", bot_err
    assert "I hit the wall" not in sim_err, "the turtle hit a wall: the bot did not back off in time"
    seen = poses(echo_out)
    assert len(seen) > 100, "--echo in a third process saw too few poses"
    xs, ys = [p[0] for p in seen], [p[1] for p in seen]
    assert max(abs(x - 5.544445) for x in xs) + max(abs(y - 5.544445) for y in ys) > 2, "the turtle did not move"
    assert all(0.0 < v < 11.088889 for v in xs + ys), "the turtle left the arena"


@pytest.mark.dds
def test_ping_pong_is_heard_by_another_process(netns: NetNamespace) -> None:
    listener = Watched(netns.llfsm("run", "--transport", "dds", "--echo", "/pingpong", "--node", "teleop"))
    talker = Watched(netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine"))
    listener.wait_for(
        r"^data: The count is", stream="out", count=2
    )  # both ends up: a start-up takes seconds under load
    t_status, _, t_err = talker.finish(120, signal.SIGINT)
    l_status, out, l_err = listener.finish(120, signal.SIGINT)
    assert t_status == 0 and l_status == 0, t_err + l_err
    counts = [int(n) for n in re.findall(r"^data: The count is (\d+)$", out, re.M)]
    assert len(counts) >= 2, out + l_err
    assert counts == sorted(counts) and len(set(counts)) == len(counts)  # in order, once each


SPAWNER = """\
ros.init()
node = ros.Node("spawner")
client = node.create_client(Spawn, "/spawn")
ready = client.wait_for_service(timeout_sec=8.0)
future = client.call_async(Spawn.Request(x=2.0, y=3.0, theta=0.5, name="visitor"))
code = ros.spin_until_future_complete(node, future, timeout_sec=5.0)
name = future.result().name if future.done() else None
node.get_logger().info(f"ready={ready} code={code} name={name}")
"""


@pytest.mark.dds
def test_a_service_call_across_processes(netns: NetNamespace, tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "spawner",
        {"INITIAL": [("END", "True")], "END": None},
        code={"INITIAL_OnEntry": SPAWNER},
        includes="from llfsm import ros\nfrom llfsm.msgs.turtlesim.srv import Spawn\n",
    )
    sim = Watched(netns.llfsm("run", "--transport", "dds", "--node", "turtlesim"))
    sim.wait_for(r"Spawning turtle \[turtle1\]")  # the client waits 8 s for /spawn: count them from here
    client = netns.llfsm("run", "--transport", "dds", m, "--duration", "30")
    c_status, _, c_err = finish(client, 120)
    s_status, _, s_err = sim.finish(120, signal.SIGINT)
    assert c_status == 0, c_err
    assert "ready=True code=SUCCESS name=visitor" in c_err
    assert "Spawning turtle [visitor] at x=[2.000000], y=[3.000000], theta=[0.500000]" in s_err
    assert s_status == 0 and "Traceback" not in s_err  # turtlesim on its own ends at Ctrl-C, as ros2 run's does


DOOMED_SERVER = """\
ros.init()
node = ros.Node("doomed")
node.create_service(Trigger, "/doomed", lambda request, response: os.kill(os.getpid(), signal.SIGKILL))
"""

CALLER = """\
ros.init()
node = ros.Node("caller")
nobody = node.create_client(Trigger, "/nobody")
t0 = time.monotonic()
code = ros.spin_until_future_complete(node, nobody.call_async(Trigger.Request()))
node.get_logger().info(f"nobody: {code} after {time.monotonic() - t0:.1f} s")
client = node.create_client(Trigger, "/doomed")
ready = client.wait_for_service(timeout_sec=8.0)
t0 = time.monotonic()
code = ros.spin_until_future_complete(node, client.call_async(Trigger.Request()))
node.get_logger().info(f"doomed: ready={ready} {code} after {time.monotonic() - t0:.1f} s")
"""


@pytest.mark.dds
def test_no_server_and_a_server_that_dies_mid_call_end_in_timeout_not_a_hang(
    netns: NetNamespace, tmp_path: Path
) -> None:
    includes = "import os, signal, time\nfrom llfsm import ros\nfrom llfsm.msgs.std_srvs.srv import Trigger\n"
    server = write_machine(
        tmp_path,
        "doomed",
        {"INITIAL": [("END", "not ros.ok()")], "END": None},
        code={"INITIAL_OnEntry": DOOMED_SERVER},
        includes=includes,
    )
    caller = write_machine(
        tmp_path,
        "caller",
        {"INITIAL": [("END", "True")], "END": None},
        code={"INITIAL_OnEntry": CALLER},
        includes=includes,
    )
    srv = netns.llfsm("run", "--transport", "dds", server, "--duration", "20", env=SHORT_LEASE)
    cli = netns.llfsm("run", "--transport", "dds", caller, "--duration", "20", env=SHORT_LEASE)
    status, _, err = finish(cli, 120)
    s_status, _, _ = finish(srv, 120)
    assert status == 0, err
    assert s_status == -signal.SIGKILL  # the server really died inside its callback
    nobody = re.search(r"nobody: (\w+) after ([\d.]+) s", err)
    assert nobody and nobody.group(1) == "TIMEOUT" and float(nobody.group(2)) < 1.0, err
    doomed = re.search(r"doomed: ready=True (\w+) after ([\d.]+) s", err)
    assert doomed and doomed.group(1) == "TIMEOUT", err
    assert float(doomed.group(2)) < 8.0, "the caller waited far beyond the peer's lease"


FLOOD_SETUP = """\
ros.init()
node = ros.Node("flood")
publisher_ = node.create_publisher(String, "flood", 10)
"""
PUBLISHER = """\
count += 1
message.data = f"flood {count}"
publisher_.publish(message)
"""


@pytest.mark.dds
def test_a_machine_publishing_while_the_transport_shuts_down_ends_cleanly(netns: NetNamespace, tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "flood",
        {"INITIAL": [("PUBLISH", "True")], "PUBLISH": [("PUBLISH", "True")], "END": None},
        code={
            "INITIAL_OnEntry": FLOOD_SETUP,
            "PUBLISH_OnEntry": PUBLISHER,
        },
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
        variables="count: int = 0\nmessage: String = String()\nnode: ros.Node\npublisher_: ros.Publisher\n",
    )
    listener = Watched(netns.llfsm("run", "--transport", "dds", "--echo", "/flood", "--node", "teleop"))
    flood = netns.llfsm("run", "--transport", "dds", m, "--duration", "120")
    listener.wait_for(r"^data: flood", stream="out")
    interrupt(flood, 0.5)  # Ctrl-C while it publishes as fast as it can
    status, _, err = finish(flood, 120)
    l_status, _, l_err = listener.finish(120, signal.SIGINT)
    assert status == 130, err  # the machine never reaches END; after the grace the run stops
    assert "Traceback" not in err and "Error" not in err, err
    assert l_status == 0 and "Traceback" not in l_err  # nodes on their own: an interrupt is their end


#: The node each `--node` starts, as `node list` shows it.
NODE_NAMES = {"turtlesim": "/turtlesim", "turtle_sensor_poster": "/turtle_sensor_poster", "teleop": "/teleop_turtle"}


@pytest.mark.dds
@pytest.mark.parametrize("node", list(NODE_NAMES))
def test_a_node_on_its_own_runs_until_interrupted(netns: NetNamespace, node: str) -> None:
    p = netns.llfsm("run", "--transport", "dds", "--node", node)
    # on the graph, so past its start-up: a SIGTERM before the run is under way is Python's own
    # (-15), and a fixed time raced with a start-up that takes seconds under load
    until_shown(netns, "node", "list", needle=NODE_NAMES[node])
    assert p.poll() is None, f"--node {node} on its own ended by itself"
    p.send_signal(signal.SIGTERM)
    status, _, err = finish(p, 120)
    assert status == 0, err  # as `ros2 run turtlesim turtlesim_node` and machine runs end (issue 27, item 10)
    assert "Traceback" not in err


def test_a_node_on_its_own_runs_for_its_duration_in_process_too() -> None:
    t0 = time.monotonic()
    run = llfsm_process("run", "--node", "turtlesim", "--duration", "1.5", timeout=30)
    assert run.status == 0 and "Spawning turtle [turtle1]" in run.stderr
    assert time.monotonic() - t0 >= 1.5


if sys.platform != "linux":  # pragma: no cover
    pytestmark = pytest.mark.skip(reason="the DDS tests use Linux network namespaces")


WAITER = """\
ros.init()
node = ros.Node("patient")
found = node.create_client(Trigger, "/never").wait_for_service(timeout_sec=120.0)
node.get_logger().info(f"found={found} ok={ros.ok()}")
"""


@pytest.mark.dds
def test_ctrl_c_ends_a_long_wait_for_a_service_on_dds(netns: NetNamespace, tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "patient",
        {"INITIAL": [("END", "not ros.ok()")], "END": None},
        code={"INITIAL_OnEntry": WAITER},
        includes="from llfsm import ros\nfrom llfsm.msgs.std_srvs.srv import Trigger\n",
    )
    p = Watched(netns.llfsm("run", "--transport", "dds", m, "-v"))
    p.wait_for(r"- patient +- INITIAL\b")  # under way (a time from its start races with a slow start-up)
    time.sleep(1.0)  # across processes: into the wait
    t0 = time.monotonic()
    p.p.send_signal(signal.SIGINT)
    # the wait's own answer, not the process's end (closing DDS took 20 s under load): long
    # before its 120 s
    p.wait_for(r"found=")
    assert time.monotonic() - t0 < 20, "the wait ignored Ctrl-C"
    status, _, err = p.finish(60)
    assert "found=False ok=False" in err, err
    assert status == 0 and "Traceback" not in err  # the machine took its `not ros.ok()` to END


#: A user's own Cyclone configuration (it comes after llfsm's, so it wins): no multicast at all.
NO_MULTICAST = {
    "CYCLONEDDS_URI": "<CycloneDDS><Domain><General><AllowMulticast>false</AllowMulticast></General></Domain>"
    "</CycloneDDS>"
}


@pytest.mark.dds
@pytest.mark.parametrize(
    ("talker_env", "listener_env", "hears"),
    [
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, True),
        ({**NO_MULTICAST, "ROS_STATIC_PEERS": "127.0.0.1"}, {**NO_MULTICAST, "ROS_STATIC_PEERS": "127.0.0.1"}, True),
        ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF"}, {}, False),
        ({"ROS_DOMAIN_ID": "3"}, {"ROS_DOMAIN_ID": "4"}, False),
    ],
    ids=["localhost", "user-config-and-static-peer", "off", "other-domain"],
)
def test_discovery_follows_the_ros_variables(
    netns: NetNamespace, talker_env: dict[str, str], listener_env: dict[str, str], hears: bool
) -> None:
    # a listener that hears is stopped once it has (its start-up takes seconds under load: a
    # window counted from it raced); one that must not hear listens for a window of the talker's
    windows = () if hears else ("--duration", "6")
    listener = Watched(netns.llfsm("run", "--transport", "dds", "--echo", "/pingpong", *windows, env=listener_env))
    talker = Watched(
        netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", *windows, env=talker_env)
    )
    if hears:
        listener.wait_for(r"^data: The count is", stream="out")
    stop = signal.SIGINT if hears else None
    t_status, _, t_err = talker.finish(120, stop)
    l_status, out, l_err = listener.finish(120, stop)
    assert t_status == 0 and l_status == 0, t_err + l_err
    assert ("data: The count is" in out) is hears, out + l_err
