"""Hostile peers on a shared DDS domain (issue 18, "Untrusted peers" 4 and 5): any process on the
domain can publish anything, and no reader of llfsm's may die of it or grow without bound.

The peers here are separate processes in a private network namespace (tests/dds_netns.py),
written with the `cyclonedds` package directly: they take llfsm's IdlStruct classes only to
name the ROS types (so Cyclone matches them with llfsm's readers), and write raw bytes of their
own making with `ddspy_write`, as a peer of any vendor could put on the wire.

- `PEER` publishes samples that are not UTF-8 where a string is (a `std_msgs/msg/String` and
  a latched `ros_discovery_info` whose node name is not UTF-8), and good ones beside them, so a
  reader that drops the bad ones with a warning still has something to show.
- `FLOOD` publishes as fast as it can: sequences whose declared length is huge, strings that
  are huge in earnest, truncated samples, on many writers and topics at once.
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from dds_netns import RAW_PEER as PRELUDE
from dds_netns import NetNamespace, Watched, finish
from helpers import REPO, Run

pytest.importorskip("cyclonedds", reason="the DDS transport needs the cyclonedds package")

from llfsm.ros.transports.dds import MAX_INCOMPATIBLE_WARNINGS  # after the skip: it needs cyclonedds

#: Bad and good Strings on /chatter, and a latched ros_discovery_info naming two nodes, one of
#: them with a name that is not UTF-8 (the sample as a whole cannot be decoded).
PEER = PRELUDE + textwrap.dedent(
    """
    latched = (Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
    info = writer("ros_discovery_info", ParticipantEntitiesInfo, *latched)
    gid = dp.get_guid().bytes
    good_node = string(b"/") + bytes(2) + string(b"good_node") + bytes(2) + struct.pack("<II", 0, 0)
    # namespace "/" (6 bytes, 2 of padding), name (18 bytes, 2 of padding), no readers, no writers
    node = string(b"/") + bytes(2) + string(b"bad_\\xff\\xfe_node") + bytes(2) + struct.pack("<II", 0, 0)
    if "info" in sys.argv:  # a node name that is not UTF-8 (else a good one: the graph verbs work)
        write(info, HEAD + gid + struct.pack("<I", 1) + node)
    else:
        write(info, HEAD + gid + struct.pack("<I", 1) + good_node)
    chatter = writer("rt/chatter", String)
    i = 0
    while True:
        write(chatter, HEAD + string(b"x" * (i % 7) + b"not utf-8: \\xff\\xfe\\xfd"))  # each error its own text
        write(chatter, HEAD + string(f"good {i}".encode()))
        i += 1
        time.sleep(0.05)
    """
)


def llfsm(ns: NetNamespace, *args: str | os.PathLike[str], timeout: float = 60) -> Run:
    """`llfsm ARGS` in the namespace, to its end."""
    status, out, err = finish(ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], cwd=REPO), timeout)
    return Run(status, out, err)


def peer(ns: NetNamespace, code: str, *args: str) -> subprocess.Popen[str]:
    """A hostile peer in the namespace until the test ends (its output dropped)."""
    return ns.popen([sys.executable, "-c", code, *args], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def wait_until_seen(ns: NetNamespace, topic: str, timeout: float = 40) -> None:
    """Until `topic list` shows the peer's topic (discovery takes its time)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if topic in llfsm(ns, "topic", "list").stdout.splitlines():
            return
        time.sleep(0.2)
    raise AssertionError(f"{topic} never appeared")


# -- 4. a sample that cannot be decoded is dropped with one warning, by every reader --------------


@pytest.mark.dds
def test_echo_drops_samples_that_are_not_utf8_and_prints_the_good_ones(netns: NetNamespace) -> None:
    peer(netns, PEER)
    wait_until_seen(netns, "/chatter")
    p = Watched(netns.popen([sys.executable, "-m", "llfsm", "topic", "echo", "/chatter", "--timeout", "20"], cwd=REPO))
    p.wait_for(r"^data: good", stream="out", count=5)  # not a fixed time: a start-up takes seconds under load
    p.wait_for(r"/chatter: dropped")
    status, out, err = p.finish(30, signal.SIGINT)
    assert status in (0, 130), err
    assert "Traceback" not in err, err
    assert out.count("data: good") >= 5, (out, err)
    assert "not utf-8" not in out
    warnings = [line for line in err.splitlines() if "/chatter: dropped" in line]
    assert len(warnings) == 1, err  # once for the topic and the peer, not once per sample
    assert "std_msgs/msg/String" in warnings[0] and "participant" in warnings[0]


@pytest.mark.dds
def test_echo_once_skips_a_bad_sample(netns: NetNamespace) -> None:
    peer(netns, PEER)
    wait_until_seen(netns, "/chatter")
    r = llfsm(netns, "topic", "echo", "/chatter", "std_msgs/msg/String", "--once", "--timeout", "20")
    assert r.status == 0, r.stderr
    assert r.stdout.startswith("data: good"), r.stdout


@pytest.mark.dds
@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (("node", "list"), None),
        (("topic", "list"), "/chatter"),
        (("topic", "list", "-t"), "/chatter [std_msgs/msg/String]"),
        (("topic", "info", "/chatter", "-v"), "Type: std_msgs/msg/String"),
        (("service", "list"), None),
    ],
)
def test_graph_verbs_survive_a_discovery_info_that_is_not_utf8(
    netns: NetNamespace, args: tuple[str, ...], needle: str | None
) -> None:
    peer(netns, PEER, "info")
    wait_until_seen(netns, "/chatter")  # discovery (its time is not what is tested here)
    r = llfsm(netns, *args)
    assert r.status in (0, 1), r.stderr  # 1: nothing to list (the peer has no service)
    assert "Traceback" not in r.stderr, r.stderr
    if needle is not None:
        assert needle in r.stdout, r.stdout
    assert r.stderr.count("ros_discovery_info: dropped") <= 1, r.stderr


@pytest.mark.dds
def test_node_list_still_lists_the_good_nodes(netns: NetNamespace) -> None:
    netns.popen(
        [sys.executable, "-m", "llfsm", "run", "--transport", "dds", "--node", "turtlesim", "--duration", "60s"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wait_until_seen(netns, "/turtle1/pose")
    peer(netns, PEER, "info")
    wait_until_seen(netns, "/chatter")
    r = llfsm(netns, "node", "list")
    assert r.status == 0, r.stderr
    assert "/turtlesim" in r.stdout.splitlines(), (r.stdout, r.stderr)
    assert "bad_" not in r.stdout
    assert r.stderr.count("ros_discovery_info: dropped") == 1, r.stderr


@pytest.mark.dds
def test_hz_counts_the_good_samples(netns: NetNamespace) -> None:
    peer(netns, PEER)
    wait_until_seen(netns, "/chatter")
    p = Watched(netns.popen([sys.executable, "-m", "llfsm", "topic", "hz", "/chatter"], cwd=REPO))
    p.wait_for(r"^average rate:", stream="out")  # not a fixed time: a start-up takes seconds under load
    p.wait_for(r"/chatter: dropped")
    status, out, err = p.finish(30, signal.SIGINT)
    assert status in (0, 130), err
    assert "Traceback" not in err, err
    assert "average rate:" in out, (out, err)
    assert err.count("/chatter: dropped") == 1, err


@pytest.mark.dds
def test_bag_record_keeps_the_good_samples(netns: NetNamespace, tmp_path: Path) -> None:
    peer(netns, PEER)
    wait_until_seen(netns, "/chatter")
    bag = tmp_path / "bag"
    p = Watched(netns.popen([sys.executable, "-m", "llfsm", "bag", "record", "/chatter", "-o", bag], cwd=REPO))
    p.wait_for(r"/chatter: dropped")  # it has heard the peer (a fixed time raced with its start-up under load)
    status, _out, err = p.finish(30, signal.SIGINT)
    assert status in (0, 130), err
    assert "Traceback" not in err, err
    assert err.count("/chatter: dropped") == 1, err
    r = llfsm(netns, "bag", "info", bag)
    assert r.status == 0, r.stderr
    assert "/chatter" in r.stdout, r.stdout


# -- 5. a flooding peer costs bounded memory and never stalls a run's rounds ------------------------

#: A peer publishing as fast as it can: on the topics the machine reads, from many writers, good
#: samples, samples that are not UTF-8, sequences and strings whose declared length is far
#: beyond the sample, truncated samples, and (every few rounds) strings huge in earnest; beside
#: them many topics nobody reads and many latched machine descriptions (each endpoint a record
#: in every peer's discovery).
FLOOD = PRELUDE + textwrap.dedent(
    """
    from llfsm.msgs.std_msgs.msg import Float64MultiArray
    N_WRITERS, N_TOPICS, N_DESCRIPTIONS, HUGE = (int(a) for a in sys.argv[1:5])
    latched = (Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
    others = [writer(f"rt/flood/t{i}", String) for i in range(N_TOPICS)]
    description = '{"states": [' + ",".join(f'{{"name": "S{i}"}}' for i in range(5000)) + "]}"
    descriptions = [writer(f"rt/llfsm/fake{i}/description", String, *latched) for i in range(N_DESCRIPTIONS)]
    for w in descriptions:
        write(w, HEAD + string(description.encode()))
    strings = [writer("rt/flood", String) for _ in range(N_WRITERS)]
    # huge samples need a writer that keeps them until they are acknowledged: one that keeps only
    # its last sample drops a huge one (still being sent in fragments) at its next write
    kept = (Policy.History.KeepLast(8),)
    huge_writers = [writer("rt/flood", String, *kept) for _ in range(4)]
    arrays = [writer("rt/flood_seq", Float64MultiArray) for _ in range(N_WRITERS)]
    good = HEAD + string(b"ok")
    bads = [HEAD + string(b"x" * n + b"\\xff") for n in range(1024)]  # each error its own text
    long_string = HEAD + struct.pack("<I", 0xFFFFFFF0) + b"short\\0\\0\\0"  # declares 4 GiB
    truncated = HEAD + struct.pack("<I", 1000) + b"abc"
    huge = HEAD + string(b"x" * HUGE)
    # Float64MultiArray: no dimensions, data_offset 0, then the data (8-aligned)
    long_array = HEAD + struct.pack("<IIII", 0, 0, 0x7FFFFFFF, 0) + bytes(16)  # declares 16 GiB
    array = HEAD + struct.pack("<IIII", 0, 0, 4096, 0) + bytes(8 * 4096)
    print("flooding", flush=True)
    i = 0
    while True:
        for w in strings:
            write(w, good)
            write(w, bads[i % len(bads)])
            write(w, long_string)
            write(w, truncated)
        for w in arrays:
            write(w, long_array)
            write(w, array)
        write(others[i % N_TOPICS], good)
        write(huge_writers[i % len(huge_writers)], huge)
        i += 1
    """
)

#: A peer making and deleting endpoints as fast as it can: best-effort writers on /flood, which
#: the machine's reliable subscription cannot match (each one is an "incompatible QoS" event).
CHURN = PRELUDE + textwrap.dedent(
    """
    print("churning", flush=True)
    topic = Topic(dp, "rt/flood", dds_type(String))
    while True:
        w = DataWriter(dp, topic, qos=Qos(Policy.Reliability.BestEffort, XCDR1))
        time.sleep(0.002)
        w.__del__()
    """
)

#: A machine that publishes its count every few milliseconds on /ticks, with a PUSH subscription
#: to /flood and a PULL one to /flood_seq (what the peer floods).
FLOODED_STATES = {"INITIAL": [("TICK", "True")], "TICK": [("TOCK", "True")], "TOCK": [("TICK", "after_ms(5)")]}
FLOODED_CODE = {
    "INITIAL_OnEntry": textwrap.dedent(
        """
        ros.init()
        node = ros.Node("flooded")
        ticks = node.create_publisher(String, "ticks", 10)
        pull = node.create_subscription(Float64MultiArray, "flood_seq", None, 10)
        push = node.create_subscription(String, "flood", lambda m: None, 10)
        """
    ),
    "TICK_OnEntry": "count += 1\npull.take()\nticks.publish(String(data=str(count)))",
}
FLOODED_VARIABLES = (
    "count: int = 0\nnode: ros.Node\nticks: ros.Publisher\npull: ros.Subscription\npush: ros.Subscription\n"
)
FLOODED_INCLUDES = "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Float64MultiArray, String\n"


#: The flood: writers on each flooded topic, topics nobody reads, and the size of the strings
#: that are huge in earnest.
FLOOD_WRITERS, FLOOD_TOPICS, HUGE = 50, 1000, 8 << 20
#: The memory a flooded reader may take: its subscription (depth 10) holds the largest samples
#: several times over (Cyclone's history and reassembly, the payloads taken, the decoded
#: messages, the callback's queue, the allocator's slack), and nothing else grows.
BOUND_MIB = 64 + 6 * 10 * (HUGE >> 20)
#: How much more the last third of the flood may take than the rest (no steady growth; the
#: allocator keeps some freed blocks of huge samples, in steps: `topic hz` was seen 130 MiB up
#: once, so the margin is wide; a leak of the flood's 8 MiB samples would take gigabytes).
GROWTH_MIB = 256


def rss_mib(pid: int) -> float:
    """The resident memory of a process, from /proc."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise AssertionError(f"no VmRSS for {pid}")


def count_now(ns: NetNamespace) -> int:
    """The machine's count as it publishes it on /ticks."""
    r = llfsm(ns, "topic", "echo", "/ticks", "std_msgs/msg/String", "--once", "--timeout", "30", timeout=90)
    assert r.status == 0, r.stderr
    return int(r.stdout.split("data:")[1].split()[0].strip("'\""))


@pytest.mark.dds
def test_a_flooding_peer_neither_stalls_a_run_nor_grows_its_memory(netns: NetNamespace, tmp_path: Path) -> None:
    """A run whose subscriptions a peer floods keeps its rounds going (the count it publishes
    keeps rising) and its memory bounded (RSS from /proc, by a generous bound: what the
    subscriptions' depth lets Cyclone and the bus hold of the largest samples, and no steady
    growth in the last third of the flood); `topic hz` on the flooded topic too.
    Stderr is a pipe read only at the end, as under `2>&1 | less`: a reader that said something
    per sample would block on it."""
    from helpers import write_machine

    machine = write_machine(
        tmp_path, "flooded", FLOODED_STATES, FLOODED_CODE, variables=FLOODED_VARIABLES, includes=FLOODED_INCLUDES
    )
    run = netns.popen(
        [sys.executable, "-m", "llfsm", "run", "--transport", "dds", machine, "--duration", "300s"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    first = count_now(netns)
    hz = netns.popen(
        [sys.executable, "-m", "llfsm", "topic", "hz", "/flood", "--timeout", "60"],  # TOPIC...: no type
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    time.sleep(2)
    procs = {"run": run, "topic hz": hz}
    before = {name: rss_mib(p.pid) for name, p in procs.items()}
    flood = netns.popen([sys.executable, "-c", FLOOD, *map(str, (FLOOD_WRITERS, FLOOD_TOPICS, 100, HUGE))], cwd=REPO)
    assert flood.stdout is not None and flood.stdout.readline().strip() == "flooding"
    churn = netns.popen([sys.executable, "-c", CHURN], cwd=REPO)
    assert churn.stdout is not None and churn.stdout.readline().strip() == "churning"
    rss: dict[str, list[float]] = {name: [] for name in procs}
    stop = threading.Event()

    def watch() -> None:
        while not stop.wait(0.5):
            for name, p in procs.items():
                if p.poll() is None:
                    rss[name].append(rss_mib(p.pid))

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    counts = [first]
    try:
        for _ in range(6):
            time.sleep(3)
            for name, p in [*procs.items(), ("flooding peer", flood), ("churning peer", churn)]:
                assert p.poll() is None, f"{name} ended: {p.communicate()[1][-3000:]}"
            counts.append(count_now(netns))
    finally:
        stop.set()
        watcher.join()
    print(f"counts {counts}; RSS MiB before {before}, during", {n: [round(v) for v in r] for n, r in rss.items()})
    assert all(b > a for a, b in itertools.pairwise(counts)), counts  # the rounds go on
    for name, values in rss.items():
        third = len(values) // 3
        assert max(values) < before[name] + BOUND_MIB, (name, before[name], values)
        assert max(values[-third:]) < max(values[:-third]) + GROWTH_MIB, (name, values)
    flood.kill()
    churn.kill()
    for name, p in procs.items():
        p.send_signal(2)
        _, err = p.communicate(timeout=30)
        assert "Traceback" not in err and "internal error" not in err, (name, err[-3000:])
        assert err.count("/flood: dropped a") <= 1, (name, err[-3000:])  # one peer: one warning
        assert err.count("incompatible QoS") <= MAX_INCOMPATIBLE_WARNINGS + 1, (name, err[-3000:])


#: Requests to turtlesim's /spawn on rmw_cyclonedds's wire (client id, sequence number, then
#: x, y, theta and the name), the name not UTF-8; on argv[1] the number to send.
BAD_REQUESTS = PRELUDE + textwrap.dedent(
    """
    from llfsm.msgs._dds import request_type
    from llfsm.msgs.turtlesim.srv import Spawn
    qos = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), Policy.History.KeepLast(100), XCDR1)
    w = DataWriter(dp, Topic(dp, "rq/spawnRequest", request_type(Spawn)), qos=qos)
    while not w.get_matched_subscriptions():
        time.sleep(0.05)
    for seq in range(int(sys.argv[1])):
        name = b"t" * (seq % 9) + b"\\xff\\xfe"  # each error its own text
        write(w, HEAD + struct.pack("<Qq3f", 7, seq, 1.0, 1.0, 0.0) + string(name))
        time.sleep(0.01)
    print("sent", flush=True)
    time.sleep(1)  # reliable: the last ones are acknowledged before the participant goes
    """
)


@pytest.mark.dds
def test_a_service_drops_requests_it_cannot_decode_and_answers_the_next(netns: NetNamespace) -> None:
    sim = netns.popen(
        [sys.executable, "-m", "llfsm", "run", "--transport", "dds", "--node", "turtlesim", "--duration", "90s"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    wait_until_seen(netns, "/turtle1/pose")
    bad = netns.popen([sys.executable, "-c", BAD_REQUESTS, "50"], cwd=REPO)
    status, out, err = finish(bad, 60)
    assert status == 0 and out.strip() == "sent", err
    r = llfsm(netns, "service", "call", "/spawn", "turtlesim/srv/Spawn", "{x: 2.0, y: 2.0, name: good}")
    assert r.status == 0, r.stderr
    assert "name='good'" in r.stdout, r.stdout
    sim.send_signal(2)
    _, err = sim.communicate(timeout=30)
    assert "Traceback" not in err, err[-3000:]
    assert err.count("/spawn: dropped a request") == 1, err[-3000:]  # fifty bad requests, one peer


def test_warnings_about_undecodable_samples_are_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    """One line per peer, at most MAX_WARNED_PEERS peers remembered, then one line for the rest:
    a peer making writers (or participants) by the thousand neither floods the log nor grows
    the reader's memory."""
    from types import SimpleNamespace

    from llfsm.msgs._dds import from_cdr
    from llfsm.msgs.std_msgs.msg import String
    from llfsm.ros.transports import dds_read

    bad = b"\0\1\0\0" + (3).to_bytes(4, "little") + b"\xff\xfe\0"
    good = b"\0\1\0\0" + (3).to_bytes(4, "little") + b"ok\0"
    batch = [(bad, SimpleNamespace(publication_handle=h % 500)) for h in range(5000)]
    batch.append((good, SimpleNamespace(publication_handle=1)))
    monkeypatch.setattr(dds_read, "take_raw", lambda reader, n=dds_read.TAKE_BATCH: batch)

    class Gone:  # every writer has left by the time its sample is looked at
        def get_matched_publication_data(self, handle: int) -> None:
            raise RuntimeError("gone")

    said: list[str] = []
    samples = dds_read.Samples(Gone(), lambda data: from_cdr(data, String), "/t", "a std_msgs/msg/String", said.append)
    assert [m.data for m, _ in samples.take()] == ["ok"]
    assert samples.dropped == 5000
    assert len(said) == dds_read.MAX_WARNED_PEERS + 1, said[-3:]
    assert said[0].startswith("/t: dropped a sample that is not a std_msgs/msg/String (from writer 0x0): ")
    assert said[-1].endswith("theirs are dropped without further warnings")
    assert len(samples._warned) == dds_read.MAX_WARNED_PEERS
    samples.take()
    assert len(said) == dds_read.MAX_WARNED_PEERS + 1  # the same peers again: nothing more said
