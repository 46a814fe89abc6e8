"""Reliability over DDS across processes, in a private network namespace (dds_netns.py): a
best-effort llfsm publisher reaches a best-effort llfsm subscriber in another process; a
reliable subscriber does not match a best-effort publisher (as in ROS 2) and says so once, as
rclpy's default QoS event handler does; the endpoints carry the reliability they asked for.
"""

from __future__ import annotations

import textwrap
import time

import pytest
from dds_netns import NetNamespace, finish

pytestmark = pytest.mark.dds

pytest.importorskip("cyclonedds")

#: One llfsm run on the DDS transport (wall clock), with its node `NAME`; then the snippet.
_RUN = """
import sys, time
from llfsm import ros
from llfsm.msgs.std_msgs.msg import String
from llfsm.ros.bus import bus_of
from llfsm.ros.transports.dds import DdsTransport
from llfsm.runtime import RunContext, WallClock
from llfsm.runtime.context import activate

ctx = RunContext(WallClock())
transport = DdsTransport(0)
ctx.transport = transport
activate(ctx)
bus = bus_of(ctx)
bus.initialised = True
node = ros.Node(NAME)

def spin(seconds, until=lambda: False):
    end = time.monotonic() + seconds
    while time.monotonic() < end and not until():
        bus.spin_once(20_000_000)
"""

PUBLISHER = """
pub = node.create_publisher(String, "/scan_like", ros.qos_profile_sensor_data)
spin(8, until=lambda: pub.get_subscription_count() >= 1)   # the best-effort reader matches
spin(1)  # the reliable one has been discovered by now too: it still does not match
print("matched", pub.get_subscription_count(), flush=True)
for i in range(40):
    pub.publish(String(data=f"m{i}"))
    spin(0.05)
transport.close()
"""

SUBSCRIBER = """
got = []
sub = node.create_subscription(String, "/scan_like", lambda m: got.append(m.data), QOS)
spin(12, until=lambda: len(got) >= 5)
print("got", len(got), flush=True)
transport.close()
"""


def _code(name: str, body: str, **consts: str) -> str:
    consts_code = "".join(f"{k} = {v}\n" for k, v in consts.items())
    return f"NAME = {name!r}\n" + textwrap.dedent(_RUN) + consts_code + textwrap.dedent(body)


def test_best_effort_reaches_best_effort_and_a_reliable_reader_is_told_it_cannot_match(netns: NetNamespace) -> None:
    best = netns.python(_code("best", SUBSCRIBER, QOS="ros.qos_profile_sensor_data"))
    strict = netns.python(_code("strict", SUBSCRIBER, QOS="ros.QoSProfile(depth=10)"))
    pub = netns.python(_code("sensor", PUBLISHER))
    code, out, err = finish(pub, 40)
    assert code == 0, err
    assert out.strip() == "matched 1", (out, err)  # only the best-effort reader matched
    code, out, err = finish(best, 40)
    assert code == 0, err
    assert out.startswith("got ") and int(out.split()[1]) >= 5, (out, err)
    code, out, err = finish(strict, 40)
    assert code == 0, err
    assert out.strip() == "got 0", (out, err)
    warning = (
        "[strict]: New publisher discovered on topic '/scan_like', offering incompatible QoS. "
        "No messages will be received from it. Last incompatible policy: RELIABILITY"
    )
    assert err.count(warning) == 1 and "[WARN]" in err, err


IDLE_PUBLISHER = """
pub = node.create_publisher(String, "/scan_like", ros.qos_profile_sensor_data)
keep_all = ros.QoSProfile(depth=1, history=ros.HistoryPolicy.KEEP_ALL)
sub = node.create_subscription(String, "/scan_like", None, keep_all)
print("ready", flush=True)
spin(25)
transport.close()
"""


def test_topic_info_verbose_shows_the_reliability_and_history_llfsm_endpoints_asked_for(netns: NetNamespace) -> None:
    """As `ros2 topic info -v` prints them: the publisher BEST_EFFORT, KEEP_LAST (5)."""
    holder = netns.python(_code("sensor", IDLE_PUBLISHER))
    assert holder.stdout is not None and holder.stdout.readline().strip() == "ready"
    deadline = time.monotonic() + 30
    while True:
        code, out, err = finish(netns.llfsm("topic", "info", "/scan_like", "-v"), 30)
        if ("Subscription count: 1" in out and "Publisher count: 1" in out) or time.monotonic() > deadline:
            break
        time.sleep(0.3)
    assert code == 0, err
    publisher, subscription = out.split("Endpoint type: PUBLISHER")[1].split("Endpoint type: SUBSCRIPTION")
    assert "  Reliability: BEST_EFFORT\n  History (Depth): KEEP_LAST (5)\n  Durability: VOLATILE\n" in publisher, out
    assert "  Reliability: RELIABLE\n  History (Depth): KEEP_ALL\n" in subscription, out
    holder.kill()
