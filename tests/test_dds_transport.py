"""The DDS transport inside one process: two runs (two RunContexts, two participants) on a
domain with discovery OFF, which Cyclone still connects within its process.  Nothing touches the
network, so these run anywhere cyclonedds installs; they check what a ROS 2 peer would see (the
names, QoS, USER_DATA and ros_discovery_info) and the bus API on top (PUSH, PULL, services,
TIMEOUT rules) against real Cyclone entities.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

pytest.importorskip("cyclonedds")

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
from cyclonedds.core import Policy, Qos

from llfsm import ros
from llfsm.msgs import _dds
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.rmw_dds_common.msg import ParticipantEntitiesInfo
from llfsm.msgs.std_msgs.msg import String
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.ros.bus import Bus, bus_of
from llfsm.ros.transports.dds import DdsTransport
from llfsm.runtime import RunContext, WallClock
from llfsm.runtime.context import activate

pytestmark = pytest.mark.dds  # Cyclone DDS participants (in this process)

DOMAIN = 98


class Run:
    """One llfsm run: a context, its DDS transport and its bus."""

    def __init__(self) -> None:
        self.ctx = RunContext(WallClock())
        self.transport = DdsTransport(DOMAIN)
        self.ctx.transport = self.transport
        self.bus: Bus = bus_of(self.ctx)
        self.bus.initialised = True

    def __enter__(self) -> Run:
        self._prev = activate(self.ctx)
        return self

    def __exit__(self, *exc: object) -> None:
        activate(self._prev)

    def node(self, name: str) -> ros.Node:
        with self:
            return ros.Node(name)


@pytest.fixture
def runs(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[], Run]]:
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF")  # this process only
    made: list[Run] = []

    def make() -> Run:
        made.append(Run())
        return made[-1]

    yield make
    for r in made:
        r.transport.close()


def spin_until(cond: Callable[[], Any], *runs: Run, timeout: float = 5.0) -> bool:
    """Spin every run until cond() holds (wall time, as DDS needs)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for r in runs:
            r.bus.spin_once(5_000_000)
        if cond():
            return True
    return False


def test_push_and_pull_across_two_runs(runs: Callable[[], Run]) -> None:
    a, b = runs(), runs()
    with a:
        pub = a.node("talker").create_publisher(String, "chatter", 10)
    heard: list[str] = []
    with b:
        listener = b.node("listener")
        listener.create_subscription(String, "/chatter", lambda m: heard.append(m.data), 10)
        pull = listener.create_subscription(String, "chatter", None, 10)
    assert spin_until(lambda: pub.get_subscription_count() == 2, a, b)  # two remote readers
    for i in range(3):
        pub.publish(String(data=f"hello {i}"))
    assert spin_until(lambda: len(heard) == 3, a, b)
    assert heard == ["hello 0", "hello 1", "hello 2"]
    assert pull.count == 3 and pull.latest.data == "hello 2"
    assert pull.take().data == "hello 2" and pull.take() is None


def test_a_run_does_not_hear_its_own_messages_twice(runs: Callable[[], Run]) -> None:
    a, b = runs(), runs()
    with a:
        node = a.node("both")
        pub = node.create_publisher(String, "echo", 10)
        heard: list[str] = []
        node.create_subscription(String, "echo", lambda m: heard.append(m.data), 10)
    with b:
        b.node("other").create_subscription(String, "echo", None, 10)
    assert spin_until(lambda: pub.get_subscription_count() == 2, a, b)  # one local, one remote
    pub.publish(String(data="once"))
    spin_until(lambda: False, a, timeout=0.3)
    assert heard == ["once"]


def test_services_across_runs_and_the_timeout_rules(runs: Callable[[], Run]) -> None:
    a, b = runs(), runs()
    with a:
        a.node("server").create_service(
            Trigger, "/greet", lambda req, resp: Trigger.Response(success=True, message="hi")
        )
    with b:
        node = b.node("client")
        client = node.create_client(Trigger, "/greet")
        nobody = node.create_client(Trigger, "/nobody")
        t0 = time.monotonic()
        assert (
            ros.spin_until_future_complete(node, nobody.call_async(Trigger.Request())) is ros.FutureReturnCode.TIMEOUT
        )
        assert time.monotonic() - t0 < 0.5  # sent to nobody: TIMEOUT at once, never a hang
        assert not nobody.wait_for_service(timeout_sec=0.2)
    assert spin_until(client.service_is_ready, a, b)
    with b:
        future = client.call_async(Trigger.Request())
        code = ros.spin_until_future_complete(node, future, timeout_sec=0.01)  # a's executor has not run
        assert code is ros.FutureReturnCode.TIMEOUT and not future.done()
    assert spin_until(future.done, a, b)
    assert future.result() == Trigger.Response(success=True, message="hi")


def test_a_call_to_a_run_that_leaves_ends_in_timeout(runs: Callable[[], Run]) -> None:
    a, b = runs(), runs()
    with a:
        a.node("server").create_service(Trigger, "/greet", lambda req, resp: resp)
    with b:
        node = b.node("client")
        client = node.create_client(Trigger, "/greet")
    assert spin_until(client.service_is_ready, a, b)
    with b:
        future = client.call_async(Trigger.Request())  # a never spins: no answer
        a.transport.close()  # the server's run ends
        t0 = time.monotonic()
        code = ros.spin_until_future_complete(node, future, timeout_sec=10)
    assert code is ros.FutureReturnCode.TIMEOUT
    assert time.monotonic() - t0 < 2.0


def _endpoints(run: Run, builtin: Any) -> dict[str, Any]:
    """The run's endpoints by topic; for a topic with two (a service's header and bare forms),
    the one carrying USER_DATA `serviceid=`/`clientid=`."""
    reader = BuiltinDataReader(run.transport.dp, builtin)
    spin_until(lambda: False, run, timeout=0.3)
    out: dict[str, Any] = {}
    for s in reader.take(N=200):
        ud = s.qos[Policy.Userdata]
        if s.topic_name not in out or (ud is not None and b"id=" in ud.data):
            out[s.topic_name] = s
    return out


def test_names_types_qos_and_user_data_as_rmw_makes_them(runs: Callable[[], Run]) -> None:
    a = runs()
    with a:
        node = a.node("shape")
        node.create_publisher(Twist, "turtle1/cmd_vel", 7)
        node.create_subscription(String, "~/notes", None, 3)
        node.create_service(Trigger, "reset_me", lambda req, resp: resp)
    pubs = _endpoints(a, BuiltinTopicDcpsPublication)
    subs = _endpoints(a, BuiltinTopicDcpsSubscription)
    twist = pubs["rt/turtle1/cmd_vel"]
    assert twist.type_name == "geometry_msgs::msg::dds_::Twist_"
    assert twist.qos[Policy.Reliability].__class__ is Policy.Reliability.Reliable
    assert twist.qos[Policy.History] == Policy.History.KeepLast(7)
    assert twist.qos[Policy.Durability] == Policy.Durability.Volatile
    assert twist.qos[Policy.Userdata].data == f"typehash={_dds.type_hash(Twist)};".encode()
    assert subs["rt/shape/notes"].qos[Policy.History] == Policy.History.KeepLast(3)
    request_reader = subs["rq/reset_meRequest"]
    assert request_reader.type_name == "std_srvs::srv::dds_::Trigger_Request_"
    assert request_reader.qos[Policy.Userdata].data.startswith(b"serviceid=")
    assert pubs["rr/reset_meReply"].type_name == "std_srvs::srv::dds_::Trigger_Response_"
    info = pubs["ros_discovery_info"]
    assert info.qos[Policy.Durability] == Policy.Durability.TransientLocal
    assert info.qos[Policy.History] == Policy.History.KeepLast(1)


def test_nodes_are_announced_on_ros_discovery_info(runs: Callable[[], Run]) -> None:
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    a, observer = runs(), runs()
    with a:
        # without rclpy's parameter endpoints and rosout, so the lists below are exactly the node's own
        node = ros.Node("announced", start_parameter_services=False, enable_rosout=False)
        pub = node.create_publisher(String, "news", 10)
        sub = node.create_subscription(String, "views", None, 10)
        ros.Node("second", namespace="/ns", start_parameter_services=False, enable_rosout=False)
    dp = observer.transport.dp
    late = Qos(Policy.Reliability.Reliable(10**9), Policy.Durability.TransientLocal, Policy.History.KeepAll)
    # as rmw's graph reader: reliable, transient local, so a late reader still gets the last one
    spin_until(lambda: False, a, timeout=0.3)
    reader = DataReader(dp, Topic(dp, "ros_discovery_info", _dds.dds_type(ParticipantEntitiesInfo)), qos=late)
    infos: list[ParticipantEntitiesInfo] = []

    def got() -> bool:
        infos.extend(_dds.from_dds(s, ParticipantEntitiesInfo) for s in reader.take(N=50) if s.sample_info.valid_data)
        mine = [i for i in infos if bytes(i.gid.data) == a.transport.dp.get_guid().bytes]
        return bool(mine) and len(mine[-1].node_entities_info_seq) == 2

    assert spin_until(got, a, observer)
    latest = [i for i in infos if bytes(i.gid.data) == a.transport.dp.get_guid().bytes][-1]
    nodes = {(n.node_namespace, n.node_name): n for n in latest.node_entities_info_seq}
    assert set(nodes) == {("/", "announced"), ("/ns", "second")}
    announced = nodes[("/", "announced")]
    assert [bytes(g.data) for g in announced.writer_gid_seq] == [pub._remote.writer.get_guid().bytes]
    assert [bytes(g.data) for g in announced.reader_gid_seq] == [sub._remote.reader.get_guid().bytes]
    assert nodes[("/ns", "second")].writer_gid_seq == []


def test_wait_for_service_returns_when_the_server_appears_not_at_its_timeout(runs: Callable[[], Run]) -> None:
    a, b = runs(), runs()
    with b:
        node = b.node("client")
        client = node.create_client(Trigger, "/late")
        assert not client.service_is_ready()
    with a:
        a.node("server").create_service(Trigger, "/late", lambda req, resp: resp)  # a never spins
    with b:
        t0 = time.monotonic()
        assert client.wait_for_service(timeout_sec=20.0)
    assert time.monotonic() - t0 < 10.0  # woken by the match, not by the timeout
