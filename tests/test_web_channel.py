"""The page's channel (protocol 1, docs/view.md "The page's channel"; llfsm/web/channel.py) and
what a source hands it (SPEC §18, issue 28 items 4 and 10): a hello with everything, then only
what changed; every part bounded, the rest counted; topics with no endpoints but the page's own
forgotten and the page's readers of them deleted; parameter events of a flood of node names
neither held without bound nor sent.  In process, under the sim clock."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llfsm import ros
from llfsm.msgs.rcl_interfaces.msg import ParameterEvent
from llfsm.msgs.std_msgs.msg import String
from llfsm.ros.bus import Bus
from llfsm.runtime import Arrangement, RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.targets import load
from llfsm.web.channel import MAX_TOPIC_ROWS, PROTOCOL, Channel, Mirror, state_of
from llfsm.web.parameters import MAX_EVENT_NAME
from llfsm.web.source import MAX_EVENT_NODES, RunSource, dumps

# -- the channel --------------------------------------------------------------------------------------


def test_a_delta_carries_what_changed_and_nothing_when_nothing_did() -> None:
    ch = Channel()
    a = state_of(t=1.0, topics=[{"name": "/a", "count": 1}, {"name": "/b", "count": 5}], topics_total=7)
    hello = ch.reset(a)
    assert hello["topics"] == {
        "upsert": [{"name": "/a", "count": 1}, {"name": "/b", "count": 5}],
        "remove": [],
        "total": 7,
    }
    assert ch.delta(a) is None  # the same state: no message at all
    b = state_of(t=1.0, topics=[{"name": "/a", "count": 2}, {"name": "/c", "count": 0}], topics_total=7)
    d = ch.delta(b)
    assert d == {
        "type": "delta",
        "seq": 1,
        "topics": {"upsert": [{"name": "/a", "count": 2}, {"name": "/c", "count": 0}], "remove": ["/b"], "total": 7},
    }
    assert ch.delta(
        state_of(t=1.5, topics=[{"name": "/a", "count": 2}, {"name": "/c", "count": 0}], topics_total=7)
    ) == {
        "type": "delta",
        "seq": 2,
        "header": {"t": 1.5, "clock": "wall", "source": "run", "ended": False},
    }


_row = st.fixed_dictionaries({"name": st.sampled_from(["/a", "/b", "/c", "/d"]), "count": st.integers(0, 3)})
_debug = st.one_of(
    st.none(),
    st.builds(
        lambda paused, variables: {"paused": paused, "variables": variables},
        st.booleans(),
        st.dictionaries(
            st.sampled_from(["m1", "m2", "m3"]), st.dictionaries(st.sampled_from(["x", "y"]), st.integers(0, 2))
        ),
    ),
)
_state = st.builds(
    lambda t, topics, machines, events, world, debug: state_of(
        t=t,
        topics=topics,
        machines=[{"name": n, "state": s} for n, s in machines.items()],
        param_events=events,
        world=world,
        debug=debug,
    ),
    st.sampled_from([0.0, 1.0]),
    st.lists(_row, max_size=4, unique_by=lambda r: r["name"]),
    st.dictionaries(st.sampled_from(["m1", "m2"]), st.sampled_from(["A", "B"])),
    st.dictionaries(st.sampled_from(["/n1", "/n2"]), st.integers(0, 2)),
    st.sampled_from([None, "<svg/>"]),
    _debug,
)


@settings(deadline=None, max_examples=100)
@given(st.lists(_state, min_size=1, max_size=6))
def test_a_page_that_applies_the_messages_holds_the_last_state(states: list[dict[str, Any]]) -> None:
    """Whatever the states, a mirror fed the hello then the deltas holds the last state, rows
    and counts alike (the page's script does what the Mirror does)."""
    ch = Channel()
    page = Mirror()
    page.apply({"type": "hello", "protocol": PROTOCOL, "snapshot": ch.reset(states[0])})
    for s in states[1:]:
        d = ch.delta(s)
        if d is not None:
            page.apply(d)
    last = states[-1]
    held = page.state()
    assert {r["name"]: r for r in held["topics"]} == last["topics"]
    assert {r["name"]: r for r in held["machines"]} == last["machines"]
    assert held["world"] == last["world"]
    assert held["debug"] == last["debug"]  # the variables of machines that changed, merged
    assert {k: v for k, v in held["param_events"].items() if k in last["param_events"]} == last["param_events"]


def test_the_debuggers_part_carries_the_variables_of_the_machines_that_changed() -> None:
    ch = Channel()
    many = {f"m{i:03d}": {"count": 0} for i in range(200)}
    hello = ch.reset(state_of(debug={"paused": True, "variables": many}))
    assert hello["debug"]["variables"] == many
    d = ch.delta(state_of(debug={"paused": False, "variables": {**many, "m007": {"count": 1}}}))
    assert d is not None and d["debug"] == {"paused": False, "variables": {"m007": {"count": 1}}}
    gone = {k: v for k, v in many.items() if k != "m001"} | {"m007": {"count": 1}}
    d = ch.delta(state_of(debug={"paused": False, "variables": gone}))
    assert d is not None and d["debug"]["variables"] == {"m001": None}


def test_a_page_of_another_protocol_is_told_so() -> None:
    with pytest.raises(ValueError, match="protocol 2 is not 1"):
        Mirror().apply({"type": "hello", "protocol": 2, "snapshot": {}})


# -- what a source hands the channel -----------------------------------------------------------------


@pytest.fixture
def source(bus: Bus) -> Iterator[RunSource]:
    arr = Arrangement([], context=bus.ctx)
    yield RunSource(arr, bus)


def drain(bus: Bus) -> None:
    """What the page handed the scheduler's thread (readers made and deleted), done."""
    for _ in range(3):
        bus.clock.now += 1_000_000
        bus.spin_some()


def test_the_topics_table_is_bounded_and_readers_are_made_for_its_rows_only(bus: Bus, source: RunSource) -> None:
    node = ros.Node("many")
    base = source.state()["topics_total"]  # the nodes' own: /parameter_events, /rosout
    pubs = [node.create_publisher(String, f"/t{i:04d}", 1) for i in range(MAX_TOPIC_ROWS + 300)]
    state = source.state()
    drain(bus)
    state = source.state()
    assert len(state["topics"]) == MAX_TOPIC_ROWS and state["topics_total"] == base + MAX_TOPIC_ROWS + 300
    assert len(source._readers) <= MAX_TOPIC_ROWS
    # the topics of the rows shown go, the next ones come in their place; the page's readers follow
    for p in pubs[:250]:
        node.destroy_publisher(p)
    source.state()
    drain(bus)
    state = source.state()
    assert "/t0000" not in state["topics"] and "/t0300" in state["topics"]
    assert state["topics_total"] == base + 250
    assert not any(name.startswith("/t00") for name in source._readers)  # deleted, not kept for ever
    assert bus.topics["/t0000"].readers == []  # nothing of the page's holds it


def test_a_flood_of_parameter_events_is_held_bounded_and_sent_only_for_listed_nodes(
    bus: Bus, source: RunSource
) -> None:
    node = ros.Node("flooder")
    events = node.create_publisher(ParameterEvent, "/parameter_events", 10_000)
    for i in range(MAX_EVENT_NODES + 500):
        events.publish(ParameterEvent(node=f"/fake_{i}"))
        if i % 90 == 0:  # the page's reader keeps the last 100
            drain(bus)
    events.publish(ParameterEvent(node="/" + "x" * (MAX_EVENT_NAME + 1)))
    events.publish(ParameterEvent(node="/flooder"))
    drain(bus)
    assert len(source.param_events) == MAX_EVENT_NODES and "/flooder" not in source.param_events  # full
    assert all(len(name) <= MAX_EVENT_NAME for name in source.param_events)
    source.graph()  # the nodes the page lists: this process's
    state = source.state()
    assert set(state["param_events"]) <= {"/flooder", "/many"}  # not the ten thousand others


def test_two_hundred_machines_in_one_run_send_only_the_machine_that_moved(tmp_path: Path) -> None:
    """Issue 28 item 10: 200 machines in one process were sent whole 13 times a second (245-290
    KB each).  Now, after the hello, each sample's delta carries the one machine that changed
    state: a row of a few hundred bytes, however many idle machines stand beside it."""
    from helpers import write_machine

    idle = load(str(write_machine(tmp_path, "idle", {"A": [("B", "False")], "B": None})))
    blink = load(str(write_machine(tmp_path, "blink", {"A": [("B", "after_ms(1)")], "B": [("A", "after_ms(1)")]})))
    classes = [blink, *(type(idle)(f"idle{i:03d}", (idle,), {"NAME": f"idle{i:03d}"}) for i in range(199))]
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        arr = Arrangement(classes, context=ctx)
        ros.init()
        source = RunSource(arr, ros.bus_of())
        ch, page = Channel(), Mirror()
        hello = ch.reset(source.state())
        page.apply({"type": "hello", "protocol": PROTOCOL, "snapshot": hello})
        deltas = []
        for k in range(1, 6):
            arr.run(duration_ns=7_000_000 * k)  # an odd number of toggles: blink's state changes
            deltas.append(ch.delta(source.state()))
            assert deltas[-1] is not None
            held = page.apply(deltas[-1])
            assert held is not None and held["machines"][0]["state"] == blink.STATES[arr.machines[0]._state]
    finally:
        activate(prev)
    assert len(hello["machines"]["upsert"]) == 200 and len(dumps(hello)) > 20_000
    assert [[row["name"] for row in d["machines"]["upsert"]] for d in deltas] == [["blink"]] * 5
    assert max(len(dumps(d)) for d in deltas) < 2_000, [len(dumps(d)) for d in deltas]
