"""The bus (SPEC §3): rclpy's API over an in-process, deterministic executor."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from helpers import run_sim, write_machine

from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.std_msgs.msg import Int64, String
from llfsm.msgs.std_srvs.srv import SetBool, Trigger
from llfsm.ros.bus import Bus
from llfsm.ros.parameter_files import parse_param
from llfsm.ros.transports.inproc import InProcess
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate


def advance(bus: Bus, ms: int) -> None:
    """What the scheduler does between rounds: move the clock on, then let the executor run."""
    for _ in range(ms):
        bus.clock.now += 1_000_000
        bus.spin_some()


# -- init, ok, shutdown ------------------------------------------------------------------------------


def test_ok_is_false_before_init_and_after_shutdown_or_an_interrupt() -> None:
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        assert not ros.ok()
        with pytest.raises(RuntimeError, match=r"ros\.init"):
            ros.Node("early")
        ros.init()
        ros.init()  # every machine may call it
        assert ros.ok()
        ctx.interrupted = True
        assert not ros.ok()
        ctx.interrupted = False
        ros.shutdown()
        assert not ros.ok()
    finally:
        activate(prev)


# -- names ---------------------------------------------------------------------------------------------


def test_relative_absolute_private_names_and_namespaces(bus: Bus) -> None:
    n = ros.Node("talker", namespace="robot1")
    assert n.get_fully_qualified_name() == "/robot1/talker"
    assert n.create_publisher(String, "chatter", 10).topic_name == "/robot1/chatter"
    assert n.create_publisher(String, "/chatter", 10).topic_name == "/chatter"
    assert n.create_publisher(String, "~/status", 10).topic_name == "/robot1/talker/status"
    assert n.create_publisher(String, "{node}/x", 10).topic_name == "/robot1/talker/x"
    assert n.create_publisher(String, "{ns}/y", 10).topic_name == "/robot1/y"  # rcl: the namespace, absolute
    root = ros.Node("root")
    assert root.create_publisher(String, "turtle1/cmd_vel", 10).topic_name == "/turtle1/cmd_vel"
    assert n.create_client(Trigger, "reset").srv_name == "/robot1/reset"


@pytest.mark.parametrize("bad", ["", "with space", "1st", "a//b", "a/", "a/~b", "~x", "é", "{nope}"])
def test_invalid_topic_names_are_a_clear_error(bus: Bus, bad: str) -> None:
    n = ros.Node("n")
    with pytest.raises(ros.InvalidNameError, match="name"):
        n.create_publisher(String, bad, 10)


@pytest.mark.parametrize(("name", "ns"), [("bad-name", ""), ("1node", ""), ("", ""), ("ok", "bad ns"), ("ok", "/a/1b")])
def test_invalid_node_names_and_namespaces(bus: Bus, name: str, ns: str) -> None:
    with pytest.raises(ros.InvalidNameError):
        ros.Node(name, namespace=ns)


def test_remapping_global_node_specific_and_node_name(bus: Bus) -> None:
    bus.remaps = [
        ros.Remap.parse("teleop:turtle1/cmd_vel:=turtle2/cmd_vel"),
        ros.Remap.parse("/chatter:=/talk"),
        ros.Remap.parse("old:__node:=new"),
    ]
    teleop = ros.Node("teleop")
    other = ros.Node("other")
    assert teleop.create_publisher(Twist, "turtle1/cmd_vel", 1).topic_name == "/turtle2/cmd_vel"
    assert other.create_publisher(Twist, "turtle1/cmd_vel", 1).topic_name == "/turtle1/cmd_vel"
    assert other.create_publisher(String, "chatter", 1).topic_name == "/talk"
    assert ros.Node("old").get_name() == "new"
    with pytest.raises(ros.InvalidNameError):
        ros.Remap.parse("no-arrow")


# -- topics ---------------------------------------------------------------------------------------------


def test_pull_reader_latest_take_count(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(Int64, "numbers", 10)
    reader = n.create_subscription(Int64, "numbers", None, 10)
    assert reader.latest is None and reader.take() is None and reader.count == 0
    for i in range(3):
        pub.publish(Int64(data=i))
    assert reader.latest.data == 2 and reader.count == 3
    assert reader.take().data == 2
    assert reader.take() is None  # nothing new since
    pub.publish(Int64(data=7))
    assert reader.take().data == 7


def test_push_callbacks_run_when_the_executor_spins_not_at_publish(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(String, "chatter", 10)
    heard: list[str] = []
    n.create_subscription(String, "chatter", lambda m: heard.append(m.data), 10)
    pub.publish(String(data="a"))
    pub.publish(String(data="b"))
    assert heard == []
    bus.spin_some()
    assert heard == ["a", "b"]


def test_push_queue_is_bounded_by_qos_depth_dropping_the_oldest(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(Int64, "numbers", 10)
    got: list[int] = []
    sub = n.create_subscription(Int64, "numbers", lambda m: got.append(m.data), ros.QoSProfile(depth=3))
    for i in range(10):
        pub.publish(Int64(data=i))
    bus.spin_some()
    assert got == [7, 8, 9] and sub.count == 10


def test_a_callback_publishing_on_its_own_topic_does_not_loop_forever(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(Int64, "echo", 10)
    seen: list[int] = []

    def again(m: Int64) -> None:
        seen.append(m.data)
        pub.publish(Int64(data=m.data + 1))

    n.create_subscription(Int64, "echo", again, 10)
    pub.publish(Int64(data=0))
    bus.spin_some()
    bus.spin_some()
    assert seen == [0, 1]


def test_subscribers_get_a_copy_so_publishers_may_reuse_their_message(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(Twist, "/turtle1/cmd_vel", 10)
    reader = n.create_subscription(Twist, "/turtle1/cmd_vel", None, 10)
    msg = Twist()
    msg.linear.x = 2.0
    pub.publish(msg)
    msg.linear.x = -5.0  # the seed machines mutate and re-publish one message object
    assert reader.latest.linear.x == 2.0


def test_taps_see_the_message_itself_while_subscribers_still_get_a_copy(bus: Bus) -> None:
    """A tap (what --record uses) takes what it needs during publish(): it is handed the very
    object published, no copy; a subscription on the same topic still gets its own copy, and a
    tap counts as a subscription (turtlesim senses colours while its topic has one)."""
    n = ros.Node("n")
    pub = n.create_publisher(Twist, "/turtle1/cmd_vel", 10)
    seen: list[tuple[object, float]] = []
    bus.add_tap(lambda topic: topic.taps.append(lambda m: seen.append((m, m.linear.x))))
    assert pub.get_subscription_count() == 1
    reader = n.create_subscription(Twist, "/turtle1/cmd_vel", None, 10)
    assert pub.get_subscription_count() == 2
    assert bus.graph()["topics"]["/turtle1/cmd_vel"]["subscriptions"] == 2
    msg = Twist()
    msg.linear.x = 2.0
    pub.publish(msg)
    msg.linear.x = -5.0
    pub.publish(msg)
    assert [x for _, x in seen] == [2.0, -5.0]  # each value as it was published
    assert all(m is msg for m, _ in seen)  # the object itself
    assert reader.latest is not msg and reader.latest.linear.x == -5.0
    assert reader.count == 2


def test_publishing_the_wrong_type_is_a_clear_error(bus: Bus) -> None:
    n = ros.Node("n")
    pub = n.create_publisher(Twist, "/turtle1/cmd_vel", 10)
    with pytest.raises(
        TypeError, match=r"/turtle1/cmd_vel: expected a geometry_msgs/msg/Twist message, got std_msgs/msg/String"
    ):
        pub.publish(String(data="go"))
    with pytest.raises(TypeError, match="already carries geometry_msgs/msg/Twist"):
        n.create_subscription(String, "/turtle1/cmd_vel", None, 10)
    with pytest.raises(TypeError, match="message class"):
        n.create_publisher("Twist", "x", 10)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="QoS depth"):
        n.create_publisher(Twist, "y", 0)


# -- services -------------------------------------------------------------------------------------------


def test_service_call_with_future_and_spin_until_complete(bus: Bus) -> None:
    server = ros.Node("server")

    def handle(req: SetBool.Request, resp: SetBool.Response) -> SetBool.Response:
        resp.success = req.data
        resp.message = "on" if req.data else "off"
        return resp

    server.create_service(SetBool, "switch", handle)
    client_node = ros.Node("client")
    client = client_node.create_client(SetBool, "/switch")
    assert client.service_is_ready() and client.wait_for_service(timeout_sec=1.0)
    done: list[str] = []
    future = client.call_async(SetBool.Request(data=True))
    future.add_done_callback(lambda f: done.append(f.result().message))
    assert not future.done()  # served when the executor spins
    assert ros.spin_until_future_complete(client_node, future) is ros.FutureReturnCode.SUCCESS
    assert future.result().success is True and done == ["on"]
    assert client.call(SetBool.Request(data=False)).message == "off"


def test_a_request_to_a_missing_service_returns_timeout_at_once(bus: Bus) -> None:
    n = ros.Node("n")
    n.create_timer(0.016, lambda: None)  # timers exist, yet nothing could ever answer
    client = n.create_client(Trigger, "/turtle_pose_service")
    assert not client.service_is_ready()
    assert client.wait_for_service() is False
    future = client.call_async(Trigger.Request())
    before = bus.clock.now
    assert ros.spin_until_future_complete(n, future, timeout_sec=None) is ros.FutureReturnCode.TIMEOUT
    assert bus.clock.now == before  # no waiting at all
    assert client.wait_for_service(timeout_sec=0.5) is False
    assert bus.clock.now == before + 500_000_000  # the sim clock moved on, nothing slept


def test_spin_is_interrupted_when_ros_is_not_ok(bus: Bus) -> None:
    n = ros.Node("n")
    n.create_service(Trigger, "t", lambda req, resp: resp)
    future = n.create_client(Trigger, "t").call_async(Trigger.Request())
    bus.ctx.interrupted = True
    assert ros.spin_until_future_complete(n, future) is ros.FutureReturnCode.INTERRUPTED


def test_a_future_completed_by_a_timer_and_the_timeout(bus: Bus) -> None:
    n = ros.Node("n")
    future = ros.Future()
    n.create_timer(0.2, lambda: future.set_result(42))
    assert ros.spin_until_future_complete(n, future, timeout_sec=0.1) is ros.FutureReturnCode.TIMEOUT
    assert bus.clock.now == 100_000_000
    assert ros.spin_until_future_complete(n, future, timeout_sec=1.0) is ros.FutureReturnCode.SUCCESS
    assert future.result() == 42 and bus.clock.now == 200_000_000


def test_a_service_callback_must_return_its_response(bus: Bus) -> None:
    n = ros.Node("n")
    n.create_service(Trigger, "bad", lambda req, resp: None)
    future = n.create_client(Trigger, "bad").call_async(Trigger.Request())
    with pytest.raises(TypeError, match="must return the std_srvs/srv/Trigger_Response"):
        ros.spin_until_future_complete(n, future)
    with pytest.raises(ValueError, match="already has a server"):
        n.create_service(Trigger, "bad", lambda req, resp: resp)


# -- timers, logging, parameters, graph ---------------------------------------------------------------------


def test_timers_run_on_the_run_clock(bus: Bus) -> None:
    n = ros.Node("n")
    ticks: list[int] = []
    t = n.create_timer(0.016, lambda: ticks.append(bus.clock.now // 1_000_000))
    advance(bus, 50)
    assert ticks == [16, 32, 48]
    t.cancel()
    advance(bus, 50)
    assert ticks == [16, 32, 48]
    with pytest.raises(ValueError):
        n.create_timer(0, lambda: None)


def test_logger_prints_rclpy_lines_with_run_time_under_the_sim_clock(
    bus: Bus, capsys: pytest.CaptureFixture[str]
) -> None:
    n = ros.Node("ros_ping_pong", namespace="demo")
    bus.clock.now = 1_500_000_000
    n.get_logger().info("Publishing: 'The count is 0'")
    n.get_logger().debug("hidden")
    n.get_logger().warning("careful", once=True)
    n.get_logger().warning("careful", once=True)
    assert capsys.readouterr().err.splitlines() == [
        "[INFO] [1.500000000] [demo.ros_ping_pong]: Publishing: 'The count is 0'",
        "[WARN] [1.500000000] [demo.ros_ping_pong]: careful",
    ]


def test_parameters_and_overrides(bus: Bus) -> None:
    node, name, value = parse_param("turtlesim:background_r:=10")
    bus.parameters[(node, name)] = value
    bus.parameters[parse_param("verbose:=true")[::2]] = True  # type: ignore[index]
    t = ros.Node("turtlesim")
    assert t.declare_parameter("background_r", 69).value == 10
    assert t.declare_parameter("background_g", 86).value == 86
    assert t.get_parameter("background_r").value == 10
    assert parse_param("x:=1.5")[2] == 1.5 and parse_param("s:=hello")[2] == "hello"


def test_graph_introspection(bus: Bus) -> None:
    n = ros.Node("talker")
    pub = n.create_publisher(String, "chatter", 10)
    n.create_subscription(String, "chatter", None, 10)
    n.create_service(Trigger, "reset", lambda req, resp: resp)
    ros.Node("quiet", start_parameter_services=False)  # as ros2cli's own nodes: no parameter services
    pub.publish(String(data="x"))
    events = {"type": "rcl_interfaces/msg/ParameterEvent", "publishers": 1, "subscriptions": 0, "messages": 0}
    assert bus.graph() == {
        "nodes": ["/quiet", "/talker"],
        "topics": {
            "/chatter": {"type": "std_msgs/msg/String", "publishers": 1, "subscriptions": 1, "messages": 1},
            "/parameter_events": events,  # every node publishes there, as rclpy's do
            # and every node's logger publishes on /rosout (an rclpy node's too, even a quiet one)
            "/rosout": {"type": "rcl_interfaces/msg/Log", "publishers": 2, "subscriptions": 0, "messages": 0},
        },
        "services": {
            "/reset": "std_srvs/srv/Trigger",
            # every node serves its parameters, as rclpy's do (`ros2 service list` shows them)
            **{
                f"/talker/{verb}": f"rcl_interfaces/srv/{srv}"
                for verb, srv in (
                    ("describe_parameters", "DescribeParameters"),
                    ("get_parameter_types", "GetParameterTypes"),
                    ("get_parameters", "GetParameters"),
                    ("list_parameters", "ListParameters"),
                    ("set_parameters", "SetParameters"),
                    ("set_parameters_atomically", "SetParametersAtomically"),
                )
            },
        },
    }


# -- through the command line ------------------------------------------------------------------------------


def _talker(tmp_path: Path, topic: str = "chatter") -> Path:
    return write_machine(
        tmp_path,
        "talker",
        {"INITIAL": [("SAY", "True")], "SAY": [("END", "n == 2"), ("SAY", "after_ms(10)")], "END": None},
        {
            "INITIAL_OnEntry": (
                f"ros.init()\nnode = ros.Node('talker')\npub = node.create_publisher(String, {topic!r}, 10)"
            ),
            "SAY_OnEntry": "n += 1\npub.publish(String(data=f'hello {n}'))",
        },
        variables="n: int = 0\nnode: ros.Node\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )


def test_echo_prints_yaml_documents_and_remap_moves_the_topic(tmp_path: Path) -> None:
    m = _talker(tmp_path)
    r = run_sim(m, "--echo", "/chatter")
    assert r.status == 0, r.stderr
    assert r.stdout == "data: hello 1\n---\ndata: hello 2\n---\n"
    r = run_sim(m, "--remap", "talker:chatter:=/elsewhere", "--echo", "/chatter", "--echo", "elsewhere")
    assert r.stdout == "data: hello 1\n---\ndata: hello 2\n---\n"
    r = run_sim(m, "--remap", "broken")
    assert r.status == 2 and "FROM:=TO" in r.stderr


def test_introspect_lists_nodes_topics_and_services(tmp_path: Path) -> None:
    # --keep-accepting: a machine that finished releases its node (test_lifetimes.py), and this
    # looks at the graph at the end of the run
    r = run_sim(_talker(tmp_path), "--introspect", "--keep-accepting", "--duration", "50ms")
    assert (
        r.stderr.splitlines()
        == [
            "nodes:",
            "  /llfsm/talker",  # SPEC §8: every machine's state and control on the graph
            "  /talker",
            "topics:",
            "  /chatter [std_msgs/msg/String] publishers: 1, subscriptions: 0, messages: 2",
            "  /llfsm/talker/description [std_msgs/msg/String] publishers: 1, subscriptions: 0, messages: 1",
            "  /llfsm/talker/state [std_msgs/msg/String] publishers: 1, subscriptions: 0, messages: 1",
            # every node publishes its parameter events and serves its parameters, as rclpy's do
            "  /parameter_events [rcl_interfaces/msg/ParameterEvent] publishers: 2, subscriptions: 0, messages: 0",
            # and every node's logger publishes on /rosout, as rclpy's do
            "  /rosout [rcl_interfaces/msg/Log] publishers: 2, subscriptions: 0, messages: 0",
            "services:",
            *parameter_services("/llfsm/talker")[:4],
            "  /llfsm/talker/restart [std_srvs/srv/Trigger]",
            "  /llfsm/talker/resume [std_srvs/srv/Trigger]",
            *parameter_services("/llfsm/talker")[4:],
            "  /llfsm/talker/suspend [std_srvs/srv/Trigger]",
            *parameter_services("/talker"),
        ]
    )


def parameter_services(node: str) -> list[str]:
    """`--introspect`'s lines for a node's parameter services, in name order."""
    return [
        f"  {node}/{verb} [rcl_interfaces/srv/{srv}]"
        for verb, srv in (
            ("describe_parameters", "DescribeParameters"),
            ("get_parameter_types", "GetParameterTypes"),
            ("get_parameters", "GetParameters"),
            ("list_parameters", "ListParameters"),
            ("set_parameters", "SetParameters"),
            ("set_parameters_atomically", "SetParametersAtomically"),
        )
    ]


def test_invalid_names_in_machine_code_are_reported_at_the_users_line(tmp_path: Path) -> None:
    m = _talker(tmp_path, topic="bad topic")
    r = run_sim(m)
    assert r.status == 1
    assert "State_INITIAL_OnEntry.py:3: error: InvalidNameError: invalid topic name 'bad topic'" in r.stderr


@pytest.mark.parametrize(
    ("where", "code"),
    [
        ("subscription", "node.create_subscription(String, 'x', lambda m: 1 / 0, 10)"),
        ("timer", "node.create_timer(0.005, lambda: 1 / 0)"),
        (
            "service",
            "node.create_service(Trigger, 's', lambda q, r: 1 / 0)\n"
            "f = node.create_client(Trigger, 's').call_async(Trigger.Request())",
        ),
    ],
)
def test_exceptions_in_callbacks_point_at_the_machine_code_that_defined_them(
    tmp_path: Path, where: str, code: str
) -> None:
    m = write_machine(
        tmp_path,
        "cb",
        {"INITIAL": [("END", "after_ms(50)")], "END": None},
        {
            "INITIAL_OnEntry": (
                f"ros.init()\nnode = ros.Node('cb')\n{code}\nnode.create_publisher(String, 'x', 10).publish(String())"
            )
        },
        variables="node: ros.Node\n",
        includes=(
            "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n"
            "from llfsm.msgs.std_srvs.srv import Trigger\n"
        ),
    )
    r = run_sim(m)
    assert r.status == 1, where
    assert (
        "State_INITIAL_OnEntry.py:3: error: ZeroDivisionError: division by zero (machine cb, state INITIAL, OnEntry)"
        in r.stderr
    )


# -- a remote transport: a reply a poll brings in ends the spin at once -------------------------------


class _OneReplyTransport(InProcess):
    """A transport of another process's server: the request goes out, and the reply arrives with
    the next poll after one wait (as a reply from another process comes in through the wait set).
    It counts the waits: a spin that keeps waiting after the reply came costs every call a whole
    wait (the DDS transport's is 100 ms)."""

    remote = True

    def __init__(self) -> None:
        self.waits = 0
        self.sent: list[Any] = []
        self.arrived = False  # a wait happened since the request went out

    def client(self, cli: Any) -> Any:
        return self

    def ready(self) -> bool:
        return True

    def can_still_answer(self, future: Any) -> bool:
        return True

    def send(self, request: Any, future: Any) -> None:
        self.sent.append(future)
        self.arrived = False

    def poll(self, force: bool = True) -> bool:
        if self.arrived and self.sent:
            self.sent.pop().set_result(Trigger.Response(success=True, message="from afar"))
            return True
        return False

    def wait(self, until_ns: int) -> None:
        self.waits += 1
        self.arrived = True


def test_a_spin_returns_as_soon_as_a_poll_brings_the_reply_in() -> None:
    ctx = RunContext(SimClock())
    transport = ctx.transport = _OneReplyTransport()
    prev = activate(ctx)
    try:
        ros.init()
        node = ros.Node("caller")
        client = node.create_client(Trigger, "/elsewhere")
        for _ in range(3):
            future = client.call_async(Trigger.Request())
            before = transport.waits
            code = ros.spin_until_future_complete(node, future, timeout_sec=5.0)
            assert code is ros.FutureReturnCode.SUCCESS and future.result().message == "from afar"
            assert transport.waits - before == 1  # the one wait the reply came in after, no more
    finally:
        activate(prev)


# -- two nodes of one name ---------------------------------------------------------------------------

_NODE = "from llfsm import ros\n"


def _noder(root: Path, name: str, node: str, states: dict | None = None) -> Path:  # type: ignore[type-arg]
    return write_machine(
        root,
        name,
        states or {"A": [("A", "after_ms(2)")]},
        {"A_OnEntry": f"ros.init()\nnode = ros.Node({node!r})\n"},
        variables="node: ros.Node = None\n",
        includes=_NODE,
    )


WARNING = (
    "llfsm: warning: 2 nodes of this run are named {}: ROS 2 tools cannot tell them apart and their parameter "
    "services clash; give one of them another name or namespace"
)


def test_two_nodes_of_one_name_are_said_once(tmp_path: Path) -> None:
    """Issue 27, item 8: two machines making ros.Node("x") were silent, as was a machine's node
    named like a --node."""
    r = run_sim(_noder(tmp_path, "one", "x"), _noder(tmp_path, "two", "x"), "--duration", "20ms")
    assert r.status == 0, r.stderr
    assert r.stderr.splitlines().count(WARNING.format("/x")) == 1  # once, though both make it again and again
    r = run_sim(_noder(tmp_path, "sim", "turtlesim"), "--node", "turtlesim", "--duration", "5ms")
    assert WARNING.format("/turtlesim") in r.stderr.splitlines()


def test_a_node_made_anew_is_no_twin_of_the_one_it_replaces(tmp_path: Path) -> None:
    # each entry of A makes its node again; the variable drops the old one
    r = run_sim(_noder(tmp_path, "again", "x"), "--duration", "20ms")
    assert r.status == 0 and "warning" not in r.stderr, r.stderr
