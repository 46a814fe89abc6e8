"""The web view's graph of nodes and topics, its actions and its parameter editor's values
(issue 21, "In the web view"; docs/view.md), without a browser: what the page is sent."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterator
from typing import Any

import pytest

from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.rcl_interfaces.msg import ParameterType
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.msgs.turtlesim.msg import Pose
from llfsm.ros.parameter_files import guess_value
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.web import parameters as params
from llfsm.web import rosgraph

SVG = "{http://www.w3.org/2000/svg}"


class Fibonacci_SendGoal(Trigger):
    """Stands in for an action's send_goal service type: only its name matters to the graph."""

    _TYPE = "example_interfaces/action/Fibonacci_SendGoal"


@pytest.fixture
def bus() -> Iterator[Any]:
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        yield ros.bus_of()
    finally:
        activate(prev)


def test_the_graph_of_a_process_nodes_topics_arrows_and_actions_by_their_names(bus: Any) -> None:
    teleop = ros.Node("teleop")
    sim = ros.Node("turtlesim")
    page = ros.Node("llfsm_web")
    teleop.create_publisher(Twist, "/turtle1/cmd_vel", 10)
    sim.create_subscription(Twist, "/turtle1/cmd_vel", lambda m: None, 10)
    sim.create_publisher(Pose, "/turtle1/pose", 10)
    page.create_subscription(Pose, "/turtle1/pose", None, 1)
    sim.create_service(Fibonacci_SendGoal, "/fib/_action/send_goal", lambda req, res: res)
    teleop.create_client(Fibonacci_SendGoal, "/fib/_action/send_goal")
    g = rosgraph.from_bus(bus, leave_out=page)
    assert g.nodes == ("/teleop", "/turtlesim")  # the page's own node left out
    assert ("/teleop", "/turtle1/cmd_vel", "pub") in g.edges
    assert ("/turtlesim", "/turtle1/cmd_vel", "sub") in g.edges
    assert ("/turtlesim", "/turtle1/pose", "pub") in g.edges
    assert dict(g.topics)["/turtle1/cmd_vel"] == "geometry_msgs/msg/Twist"
    assert g.data()["actions"] == [
        {
            "name": "/fib",
            "type": "example_interfaces/action/Fibonacci",
            "servers": ["/turtlesim"],
            "clients": ["/teleop"],
        }
    ]
    # what rqt_graph hides by default is left out of the drawing, not out of the lists
    shown = rosgraph.visible(g.merged(rosgraph.RosGraph(("/_hidden",), (("/rosout", "rcl_interfaces/msg/Log"),))))
    assert "/_hidden" not in shown.nodes and all(t != "/rosout" for t, _ in shown.topics)
    assert shown.actions == g.actions


def _parse(svg: str) -> ET.Element:
    return ET.fromstring(svg)


def test_the_drawing_is_rqt_graphs_and_a_peers_names_never_become_markup() -> None:
    evil = '/x<script>alert(1)</script>"'
    g = rosgraph.RosGraph(
        ("/talker", evil),
        (("/chatter", "std_msgs/msg/String"),),
        (("/talker", "/chatter", "pub"), (evil, "/chatter", "sub")),
    )
    root = _parse(rosgraph.svg(g))
    assert {e.tag.removeprefix(SVG) for e in root.iter()} <= {
        "svg",
        "defs",
        "marker",
        "path",
        "g",
        "title",
        "ellipse",
        "rect",
        "text",
    }
    nodes = [e for e in root.iter(f"{SVG}g") if e.get("class") == "ros-node"]
    topics = [e for e in root.iter(f"{SVG}g") if e.get("class") == "ros-topic"]
    assert {n.get("data-node") for n in nodes} == {"/talker", evil}
    assert all(n.find(f"{SVG}ellipse") is not None for n in nodes)
    assert [t.find(f"{SVG}rect") is not None for t in topics] == [True]
    links = {
        (p.get("data-node"), p.get("data-topic"), p.get("class")) for p in root.iter(f"{SVG}path") if p.get("data-node")
    }
    assert links == {("/talker", "/chatter", "link pub"), (evil, "/chatter", "link sub")}
    # publisher -> topic -> subscriber, left to right
    x = {g_.get("data-node") or g_.get("data-topic"): float(g_.find(f"{SVG}text").get("x")) for g_ in nodes + topics}
    assert x["/talker"] < x["/chatter"] < x[evil]


def test_a_big_graph_is_drawn_bounded_and_says_what_it_left_out() -> None:
    n = rosgraph.MAX_DRAWN + 40
    g = rosgraph.RosGraph(
        tuple(f"/n{i}" for i in range(n)),
        tuple((f"/t{i}", "std_msgs/msg/String") for i in range(n)),
        tuple((f"/n{i}", f"/t{i}", "pub") for i in range(n)),
    )
    root = _parse(rosgraph.svg(g))
    drawn = [e for e in root.iter(f"{SVG}g") if e.get("class") in ("ros-node", "ros-topic")]
    assert len(drawn) == rosgraph.MAX_DRAWN
    note = [e.text for e in root.iter(f"{SVG}text") if e.get("class") == "omitted"]
    assert note == [f"{2 * n - rosgraph.MAX_DRAWN:,} more nodes and topics not drawn (at most {rosgraph.MAX_DRAWN})"]


@pytest.mark.parametrize(
    "value",
    [
        2,
        -7,
        2.0,
        0.1,
        1e-20,
        3e300,
        True,
        False,
        "hello",
        "2",
        "2.0",
        "true",
        " padded",
        "it's",
        "",
        [1, 2],
        [1.5, 2.0],
        [True, False],
        ["a", "2"],
    ],
)
def test_a_value_shown_in_the_editor_reads_back_as_itself(value: Any) -> None:
    """What the page shows in a parameter's field, set again unchanged, is the same value
    (`param set` reads it: llfsm.ros.parameter_files.guess_value)."""
    text = params.value_text(value)
    back = guess_value(text)
    assert back == value and type(back) is type(value), (text, back)


def test_the_editor_reads_values_as_param_set_does_and_refuses_a_bad_name() -> None:
    assert params.message("gain", "2").value.type == ParameterType.PARAMETER_INTEGER
    assert params.message("gain", "2.0").value.type == ParameterType.PARAMETER_DOUBLE
    assert params.message("on", "true").value.type == ParameterType.PARAMETER_BOOL
    assert params.message("xs", "[1, 2]").value.type == ParameterType.PARAMETER_INTEGER_ARRAY
    assert params.message("name", "turtle").value.type == ParameterType.PARAMETER_STRING
    assert params.node_name("turtlesim") == "/turtlesim"
    assert params.node_name("/ns/turtlesim") == "/ns/turtlesim"
    with pytest.raises(params.ParameterInputError) as bad:
        params.node_name("/1turtle")
    assert (
        str(bad.value) == "invalid node name '1turtle': use letters, digits and underscores, not starting with a digit"
    )
    with pytest.raises(params.ParameterInputError, match="give the parameter's name"):
        params.message(" ", "2")
