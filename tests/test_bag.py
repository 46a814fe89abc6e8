"""Bags (SPEC §9): `--record` writes rosbag2 bags that other readers read, `--play` publishes a
bag into a run, `llfsm bag info` prints what `ros2 bag info` prints.

Recorded bags are read back with two readers llfsm does not write with: mcap-ros2-support's
(MCAP, decoding with the definitions embedded in the file) and rosbags' (both storages).
"""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from helpers import MACHINES, REPO, driver, llfsm, llfsm_process, run_sim, write_machine
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

# -- helpers -----------------------------------------------------------------------------------------


def expected_drive(n_messages: int) -> list[tuple[int, float, float, str]]:
    """(time ns, linear.x, angular.z, chat text) of the driver's first messages."""
    out = []
    for k in range(n_messages):
        n = k + 1
        out.append((1_000_000 + k * 102_000_000, 1.0 + n % 3, 0.5 * (n % 5 - 2), f"step {n}"))
    return out


class McapMessage:
    """One message as mcap-ros2-support decodes it (with the definition embedded in the file)."""

    def __init__(self, schema: object, channel: object, message: object, ros_msg: object) -> None:
        self.schema, self.channel, self.ros_msg = schema, channel, ros_msg
        self.log_time_ns = message.log_time  # type: ignore[attr-defined]


def read_ros2_messages(path: str) -> list[McapMessage]:
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [McapMessage(*x) for x in reader.iter_decoded_messages(log_time_order=True)]


def rosbags_messages(bag: Path) -> dict[str, list[tuple[int, object]]]:
    """topic -> [(timestamp, decoded message)] with rosbags' reader."""
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([bag]) as r:
        for c, t, data in r.messages():
            out.setdefault(c.topic, []).append((t, r.deserialize(data, c.msgtype)))
    return out


def raw_messages(bag: Path) -> dict[str, list[tuple[int, bytes]]]:
    """topic -> [(timestamp, CDR bytes)] with rosbags' reader."""
    out: dict[str, list[tuple[int, bytes]]] = {}
    with AnyReader([bag]) as r:
        for c, t, data in r.messages():
            out.setdefault(c.topic, []).append((t, bytes(data)))
    return out


def read_metadata(bag: Path) -> dict:
    return yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]


def one_clear_line(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.startswith("llfsm:")]
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


# -- recording -----------------------------------------------------------------------------------------


def test_recorded_mcap_reads_back_with_two_other_readers(tmp_path: Path) -> None:
    bag = tmp_path / "drive"
    r = run_sim(driver(tmp_path), "--node", "turtlesim", "--duration", "1s", "--record", bag)
    assert r.status == 0, r.stderr
    mcap_file = bag / "drive_0.mcap"
    assert sorted(p.name for p in bag.iterdir()) == ["drive_0.mcap", "metadata.yaml"]
    want = expected_drive(10)  # 1 ms ... 919 ms

    # mcap-ros2-support: decodes with the definitions embedded in the file
    by_topic: dict[str, list] = {}
    for m in read_ros2_messages(str(mcap_file)):
        by_topic.setdefault(m.channel.topic, []).append(m)
        assert m.schema.encoding == "ros2msg" and m.channel.message_encoding == "cdr"
    # (and the machine's /llfsm/driver/... topics, where the run publishes them)
    assert sorted(t for t in by_topic if not t.startswith("/llfsm/")) == [
        "/chat",
        "/rosout",  # turtlesim's log lines, as every node's
        "/turtle1/cmd_vel",
        "/turtle1/color_sensor",
        "/turtle1/pose",
    ]
    twists = by_topic["/turtle1/cmd_vel"]
    assert [(m.log_time_ns, m.ros_msg.linear.x, m.ros_msg.angular.z) for m in twists] == [w[:3] for w in want]
    assert [(m.log_time_ns, m.ros_msg.data) for m in by_topic["/chat"]] == [(w[0], w[3]) for w in want]
    poses = by_topic["/turtle1/pose"]
    assert [m.log_time_ns for m in poses] == [16_000_000 * k for k in range(1, 63)]  # turtlesim: every 16 ms
    assert poses[0].schema.name == "turtlesim/msg/Pose"
    assert twists[0].schema.name == "geometry_msgs/msg/Twist"
    assert "\n" + "=" * 80 + "\nMSG: geometry_msgs/Vector3\n" in twists[0].schema.data.decode()

    # rosbags: same topics, types, counts, values and times, through metadata.yaml
    got = rosbags_messages(bag)
    assert {k: len(v) for k, v in got.items()} == {k: len(v) for k, v in by_topic.items()}
    assert [(t, m.linear.x, m.angular.z) for t, m in got["/turtle1/cmd_vel"]] == [w[:3] for w in want]
    assert abs(got["/turtle1/pose"][-1][1].x - poses[-1].ros_msg.x) == 0

    # channels carry what rosbag2 puts there; the summary is complete
    with open(mcap_file, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
    assert header.profile == "ros2"
    assert summary is not None and summary.statistics.message_count == sum(len(v) for v in by_topic.values())
    for ch in summary.channels.values():
        assert ch.metadata["topic_type_hash"].startswith("RIHS01_")
        assert "reliability: reliable" in ch.metadata["offered_qos_profiles"]
    hashes = {ch.topic: ch.metadata["topic_type_hash"] for ch in summary.channels.values()}
    # rosidl's hash of geometry_msgs/msg/Twist (the same in Iron, Jazzy and Rolling)
    assert hashes["/turtle1/cmd_vel"] == "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"


def test_metadata_yaml_is_laid_out_as_rosbag2_writes_it(tmp_path: Path) -> None:
    bag = tmp_path / "meta"
    only = ("--record-topic", "/turtle1/cmd_vel", "--record-topic", "/chat")
    assert run_sim(driver(tmp_path), "--duration", "250ms", "--record", bag, *only).status == 0
    text = (bag / "metadata.yaml").read_text()
    hash_twist = "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
    assert text.startswith(
        "rosbag2_bagfile_information:\n"
        "  version: 9\n"
        "  storage_identifier: mcap\n"
        "  duration:\n"
        "    nanoseconds: 204000000\n"
        "  starting_time:\n"
        "    nanoseconds_since_epoch: 1000000\n"
        "  message_count: 6\n"
        "  topics_with_message_count:\n"
        "    - topic_metadata:\n"
        "        name: /turtle1/cmd_vel\n"
        "        type: geometry_msgs/msg/Twist\n"
        "        serialization_format: cdr\n"
        "        offered_qos_profiles:\n"
        "          - history: unknown\n"
        "            depth: 0\n"
        "            reliability: reliable\n"
        "            durability: volatile\n"
        "            deadline:\n"
        "              sec: 9223372036\n"
        "              nsec: 854775807\n"
    )
    assert f"        type_description_hash: {hash_twist}\n      message_count: 3\n" in text
    assert text.endswith(
        '  compression_format: ""\n'
        '  compression_mode: ""\n'
        "  relative_file_paths:\n"
        "    - meta_0.mcap\n"
        "  files:\n"
        "    - path: meta_0.mcap\n"
        "      starting_time:\n"
        "        nanoseconds_since_epoch: 1000000\n"
        "      duration:\n"
        "        nanoseconds: 204000000\n"
        "      message_count: 6\n"
        "  custom_data:\n"
        "    llfsm.clock: sim\n"
        "  ros_distro: jazzy\n"
    )
    # the MCAP file carries the same metadata, as rosbag2_storage_mcap writes it
    with open(bag / "meta_0.mcap", "rb") as f:
        records = list(make_reader(f).iter_metadata())
    assert [m.name for m in records] == ["rosbag2"]
    inner = yaml.safe_load(records[0].metadata["serialized_metadata"])
    assert inner == read_metadata(bag)


def test_sqlite3_storage_reads_back(tmp_path: Path) -> None:
    bag = tmp_path / "lite"
    only = ("--record-topic", "/turtle1/cmd_vel", "--record-topic", "/chat")
    assert run_sim(driver(tmp_path), "--duration", "1s", "--record", bag, "--storage", "sqlite3", *only).status == 0
    assert sorted(p.name for p in bag.iterdir()) == ["lite_0.db3", "metadata.yaml"]
    meta = read_metadata(bag)
    assert meta["storage_identifier"] == "sqlite3" and meta["message_count"] == 20
    got = rosbags_messages(bag)
    want = expected_drive(10)
    assert [(t, m.linear.x, m.angular.z) for t, m in got["/turtle1/cmd_vel"]] == [w[:3] for w in want]
    assert [(t, m.data) for t, m in got["/chat"]] == [(w[0], w[3]) for w in want]
    db = sqlite3.connect(bag / "lite_0.db3")
    try:
        defs = dict(db.execute("SELECT topic_type, encoding FROM message_definitions"))
        topics = {row[0]: row[1] for row in db.execute("SELECT name, type_description_hash FROM topics")}
    finally:
        db.close()
    assert defs == {"geometry_msgs/msg/Twist": "ros2msg", "std_msgs/msg/String": "ros2msg"}
    assert topics["/chat"] == "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_two_sim_runs_give_the_same_bag_byte_for_byte(tmp_path: Path, storage: str) -> None:
    m = driver(tmp_path)
    bags = []
    for run in ("a", "b"):
        (tmp_path / run).mkdir()
        bag = tmp_path / run / "same"
        r = run_sim(m, "--node", "turtlesim", "--duration", "2s", "--record", bag, "--storage", storage)
        assert r.status == 0, r.stderr
        bags.append(bag)
    files = sorted(p.name for p in bags[0].iterdir())
    assert files == sorted(p.name for p in bags[1].iterdir())
    for name in files:
        assert (bags[0] / name).read_bytes() == (bags[1] / name).read_bytes(), name
    assert raw_messages(bags[0]) == raw_messages(bags[1])


def test_a_sim_run_waits_for_a_writer_that_falls_behind(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Under the sim clock a run can make messages faster than the writer stores them: past the
    high-water mark of bytes waiting, the run waits for the writer between rounds (memory stays
    bounded), and the bag is the same as a run that never waited."""
    from llfsm.bag import recorder

    waits: list[int] = []
    original = recorder.Recorder._backpressure

    def spy(self: recorder.Recorder) -> None:
        before = self.waited
        original(self)
        waits.append(self.waited - before)

    monkeypatch.setattr(recorder.Recorder, "_backpressure", spy)
    m = driver(tmp_path)
    bags = []
    for run, high_water in (("free", recorder.HIGH_WATER), ("held", 100)):
        monkeypatch.setattr(recorder, "HIGH_WATER", high_water)
        waits.clear()
        (tmp_path / run).mkdir()
        bag = tmp_path / run / "same"
        r = run_sim(m, "--node", "turtlesim", "--duration", "3s", "--record", bag)
        assert r.status == 0, r.stderr
        bags.append(bag)
        assert len(waits) >= 29  # a look every 100 ms of run time
        assert (sum(waits) > 0) == (run == "held"), waits
    for name in sorted(p.name for p in bags[0].iterdir()):
        assert (bags[0] / name).read_bytes() == (bags[1] / name).read_bytes(), name


def test_record_topic_selects_topics(tmp_path: Path) -> None:
    bag = tmp_path / "some"
    r = run_sim(
        driver(tmp_path), "--node", "turtlesim", "--duration", "500ms", "--record", bag, "--record-topic", "chat"
    )
    assert r.status == 0, r.stderr
    assert list(rosbags_messages(bag)) == ["/chat"]


def test_wall_clock_timestamps_are_epoch_times(tmp_path: Path) -> None:
    bag = tmp_path / "wall"
    # Three messages 100 ms apart, then the machine ends the run itself: a fixed duration of wall
    # time saw no message at all on a machine loaded to 100 (the recorder's start took it all).
    m = write_machine(
        tmp_path,
        "three",
        {"INITIAL": [("SAY", "True")], "SAY": [("END", "n >= 3"), ("SAY", "after_ms(100)")], "END": None},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('three')\nchat = node.create_publisher(String, '/chat', 10)\n"
            ),
            "SAY_OnEntry": "n += 1\nchat.publish(String(data=f'step {n}'))\n",
        },
        variables="n: int = 0\nchat: ros.Publisher\nnode: ros.Node\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )
    before = time.time_ns()
    assert llfsm("run", m, "--duration", "120s", "--record", bag).status == 0
    after = time.time_ns()
    times = [t for t, _ in rosbags_messages(bag)["/chat"]]
    assert len(times) >= 2 and before <= times[0] < times[-1] <= after
    assert "custom_data: ~" in (bag / "metadata.yaml").read_text()


# -- playing --------------------------------------------------------------------------------------------

KEYS = "\x1b[A\x1b[A\x1b[C\x1b[A\x1b[D\x1b[A\x1b[A\x1b[C\x1b[C\x1b[A"


def test_teleop_session_replayed_into_the_follower_reproduces_its_picture(tmp_path: Path) -> None:
    """Record turtle1 driven from the keyboard (teleop) with the follower chasing it, then play
    only /turtle1/cmd_vel into turtlesim and the follower: the same picture, the same poses;
    and recording the replay gives the same messages again (record -> play -> record)."""
    follower = MACHINES / "turtle_follower.machine"
    common = ("run", "--clock", "sim", follower, "--node", "turtlesim", "--duration", "8s")
    first = llfsm_process(*common, "--node", "teleop", "--record", tmp_path / "a", "--image", tmp_path / "a.png",
                          input=KEYS, cwd=tmp_path)  # fmt: skip
    assert first.status == 0, first.stderr
    second = llfsm_process(*common, "--play", tmp_path / "a", "--play-topic", "/turtle1/cmd_vel",
                           "--record", tmp_path / "b", "--image", tmp_path / "b.png", cwd=tmp_path)  # fmt: skip
    assert second.status == 0, second.stderr
    a, b = raw_messages(tmp_path / "a"), raw_messages(tmp_path / "b")
    assert len(a["/turtle1/cmd_vel"]) == KEYS.count("\x1b")
    assert a == b  # every topic: the same messages at the same times, turtle2's chase included
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def test_play_rate_scales_time(tmp_path: Path) -> None:
    assert run_sim(driver(tmp_path), "--duration", "1s", "--record", tmp_path / "a").status == 0
    empty = write_machine(tmp_path, "idle", {"A": [("A", "False")]})
    r = run_sim(empty, "--duration", "1s", "--play", tmp_path / "a", "--play-rate", "2", "--record", tmp_path / "b")
    assert r.status == 0, r.stderr
    a, b = raw_messages(tmp_path / "a")["/chat"], raw_messages(tmp_path / "b")["/chat"]
    ms = 1_000_000  # at the first executor pass (one per 1 ms round) at or after half the time
    assert [-(-t // 2 // ms) * ms for t, _ in a] == [t for t, _ in b]
    assert [t for t, _ in b][:3] == [1_000_000, 52_000_000, 103_000_000]
    assert [d for _, d in a] == [d for _, d in b]


def _foreign_bag(path: Path, storage: str, with_definition: bool = True, reading_topic: str = "/weather") -> None:
    """A bag as ROS 2 tools write it (rosbags' writer): wall-clock times, a Twist topic and a
    type llfsm has no class for (its definition travels in the bag)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg("float64 celsius\nstring where\nint32[] history\n", "weather_msgs/msg/Reading"))
    Twist = store.types["geometry_msgs/msg/Twist"]
    Vector3 = store.types["geometry_msgs/msg/Vector3"]
    Reading = store.types["weather_msgs/msg/Reading"]
    import numpy as np

    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        tw = w.add_connection("/turtle1/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        if with_definition:
            rd = w.add_connection(reading_topic, "weather_msgs/msg/Reading", typestore=store)
        else:
            rd = w.add_connection(reading_topic, "weather_msgs/msg/Reading", msgdef="", rihs01="RIHS01_" + "0" * 64)
        t0 = 1_700_000_000_000_000_000
        for k in range(3):
            twist = Twist(linear=Vector3(x=float(k + 1), y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.5))
            w.write(tw, t0 + k * 200_000_000, store.serialize_cdr(twist, "geometry_msgs/msg/Twist"))
            reading = Reading(celsius=20.5 + k, where="roof", history=np.array([k, k + 1], dtype=np.int32))
            w.write(rd, t0 + k * 200_000_000 + 50_000_000, store.serialize_cdr(reading, "weather_msgs/msg/Reading"))


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_bags_written_by_ros_tools_play_unknown_types_built_from_the_bag(tmp_path: Path, storage: str) -> None:
    _foreign_bag(tmp_path / "ros", storage)
    idle = write_machine(tmp_path, "idle", {"A": [("A", "False")]})
    r = run_sim(idle, "--duration", "1s", "--play", tmp_path / "ros", "--echo", "/weather", "--record", tmp_path / "re")
    assert r.status == 0, r.stderr
    docs = [yaml.safe_load(d) for d in r.stdout.split("---\n") if d.strip()]
    assert docs == [{"celsius": 20.5 + k, "where": "roof", "history": [k, k + 1]} for k in range(3)]
    got = rosbags_messages(tmp_path / "re")
    # times relative to the bag's start, which becomes the run's start (published at the first pass after it)
    assert [t for t, _ in got["/turtle1/cmd_vel"]] == [1_000_000, 200_000_000, 400_000_000]
    assert [t for t, _ in got["/weather"]] == [50_000_000, 250_000_000, 450_000_000]
    assert [m.linear.x for _, m in got["/turtle1/cmd_vel"]] == [1.0, 2.0, 3.0]


# -- llfsm bag info ------------------------------------------------------------------------------------


def test_bag_info_prints_what_ros2_bag_info_prints(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    try:
        _foreign_bag(tmp_path / "ros", "mcap")
        size = (tmp_path / "ros" / "ros.mcap").stat().st_size
        r = llfsm("bag", "info", tmp_path / "ros")
    finally:
        monkeypatch.delenv("TZ")
        time.tzset()
    assert r.status == 0
    assert r.stdout == (
        "\n"
        "Files:             ros.mcap\n"
        f"Bag size:          {size / 1024:.1f} KiB\n"
        "Storage id:        mcap\n"
        "ROS Distro:        rosbags\n"
        "Duration:          0.450000000s\n"
        "Start:             Nov 14 2023 22:13:20.000000000 (1700000000.000000000)\n"
        "End:               Nov 14 2023 22:13:20.450000000 (1700000000.450000000)\n"
        "Messages:          6\n"
        "Topic information: Topic: /turtle1/cmd_vel | Type: geometry_msgs/msg/Twist | Count: 3 | "
        "Serialization Format: cdr\n"
        "                   Topic: /weather | Type: weather_msgs/msg/Reading | Count: 3 | Serialization Format: cdr\n"
        "Service:           0\n"
        "Service information: \n"
    )


# -- bad input -----------------------------------------------------------------------------------------


def test_bad_bags_and_folders_are_one_clear_line(tmp_path: Path) -> None:
    m = driver(tmp_path)
    (tmp_path / "exists").mkdir()
    (tmp_path / "a_file").write_text("x")
    (tmp_path / "corrupt").mkdir()
    (tmp_path / "corrupt" / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    assert run_sim(m, "--duration", "1s", "--record", tmp_path / "good").status == 0
    cut = tmp_path / "cut"
    cut.mkdir()
    (cut / "metadata.yaml").write_text((tmp_path / "good" / "metadata.yaml").read_text().replace("good_0", "cut_0"))
    (cut / "cut_0.mcap").write_bytes((tmp_path / "good" / "good_0.mcap").read_bytes()[:700])
    _foreign_bag(tmp_path / "nodef", "mcap", with_definition=False)
    _foreign_bag(tmp_path / "wrong", "mcap", reading_topic="/turtle1/pose")
    cases = [
        (["--record", tmp_path / "exists"], 2, "output folder"),
        (["--record", tmp_path / "a_file" / "bag"], 2, "Not a directory"),
        (["--play", tmp_path / "missing"], 2, "no such bag"),
        (["--play", tmp_path / "corrupt"], 2, "cannot read the bag"),
        (["--play", cut], 2, "cut"),
        (["--play", tmp_path / "nodef"], 2, "weather_msgs/msg/Reading"),
        (["--play", tmp_path / "good", "--play-topic", "/nothing"], 2, "no topic /nothing"),
        (["--play", tmp_path / "wrong", "--node", "turtlesim"], 2, "already carries turtlesim/msg/Pose"),
    ]
    for args, status, text in cases:
        r = llfsm_process("run", "--clock", "sim", m, "--duration", "10ms", *args)
        line = one_clear_line(r.stderr)
        assert r.status == status and text in line, (args, r.stderr)
    assert not (tmp_path / "a_file" / "bag").exists()
    for bag, text in ((tmp_path / "missing", "no such bag"), (tmp_path / "corrupt", "not rosbag2 metadata")):
        r = llfsm_process("bag", "info", bag)
        assert r.status == 1 and text in one_clear_line(r.stderr)


def _spawn(*args: str | os.PathLike[str], cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "llfsm", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )


def test_the_writer_joins_records_cut_between_frames(tmp_path: Path) -> None:
    """The run sends what it has in pieces of a size, cutting records anywhere (even inside a
    header): the bag holds every message, whole, in order."""
    import io
    import json

    from llfsm.bag._writer_process import FRAME, RECORD, serve
    from llfsm.bag.typesupport import TypeSupport
    from llfsm.bag.writer import qos_profile
    from llfsm.msgs.std_msgs.msg import String

    ts = TypeSupport()
    definition, type_hash = ts.definition("std_msgs/msg/String")
    cdr = ts.serializer(String)
    topic = {"id": 1, "topic": "/chat", "type": "std_msgs/msg/String", "definition": definition}
    topic.update(hash=type_hash, qos=[qos_profile()])
    stream = b"".join(
        RECORD.pack(1, 1000 * k, len(d)) + d for k, d in enumerate(cdr(String(data="x" * k)) for k in range(40))
    )
    frames = [(b"T", json.dumps(topic).encode())]
    for a, b in zip([0, 3, 17, 18, 100, 101, 700], [3, 17, 18, 100, 101, 700, len(stream)], strict=True):
        frames.append((b"M", stream[a:b]))
    frames += [(b"S", b"\x00"), (b"C", b"")]
    inp = io.BytesIO(b"".join(FRAME.pack(kind, len(data)) + data for kind, data in frames))
    out = io.BytesIO()
    assert serve(str(tmp_path / "cut"), "mcap", inp, out) == 0
    assert json.loads(out.getvalue().splitlines()[-1]) == {"ok": True, "count": 40}
    got = rosbags_messages(tmp_path / "cut")["/chat"]
    assert [(t, m.data) for t, m in got] == [(1000 * k, "x" * k) for k in range(40)]  # type: ignore[attr-defined]


@pytest.mark.parametrize("signum", ["SIGINT", "SIGTERM"])
def test_interrupted_recording_is_a_closed_readable_bag(tmp_path: Path, signum: str) -> None:
    import signal

    m = write_machine(tmp_path, "tick", {"A": [("A", "after_ms(20)")]}, {"A_OnEntry": "print('tick', flush=True)"})
    p = _spawn("run", m, "--node", "turtlesim", "--grace", "100ms", "--record", tmp_path / "cut", cwd=tmp_path)
    try:
        assert p.stdout is not None
        for _ in range(15):  # 300 ms of recording at least
            assert p.stdout.readline().strip() == "tick"
        p.send_signal(getattr(signal, signum))
        _out, err = p.communicate(timeout=30)
    finally:
        p.kill()
    assert "Traceback" not in err
    meta = read_metadata(tmp_path / "cut")
    got = rosbags_messages(tmp_path / "cut")
    assert meta["message_count"] == sum(len(v) for v in got.values()) >= 30
    n = sum(1 for _ in read_ros2_messages(str(tmp_path / "cut" / "cut_0.mcap")))
    assert n == meta["message_count"]


def _mount_small_disk(where: Path) -> bool:
    where.mkdir()
    if os.geteuid() != 0:
        return False
    return (
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(where)], capture_output=True).returncode
        == 0
    )


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_full_disk_is_one_message_a_failed_status_and_a_readable_bag(tmp_path: Path, storage: str) -> None:
    disk = tmp_path / "disk"
    if not _mount_small_disk(disk):
        pytest.skip("needs root to mount a small tmpfs")
    try:
        ping = MACHINES / "ros2_ping_pong.machine"
        r = llfsm_process("run", "--clock", "sim", ping, "--node", "turtlesim", "--duration", "120s",
                          "--record", disk / "full", "--storage", storage, cwd=REPO)  # fmt: skip
        line = one_clear_line(r.stderr)
        assert r.status == 1
        assert "the disk is full" in line and "closed with the" in line
        kept = int(line.split("closed with the ")[1].split()[0])
        meta = read_metadata(disk / "full")
        got = rosbags_messages(disk / "full")
        assert kept == meta["message_count"] == sum(len(v) for v in got.values()) > 1000
        # what is kept is the start of the run, without a gap
        poses = [t for t, _ in got["/turtle1/pose"]]
        assert poses == [16_000_000 * k for k in range(1, len(poses) + 1)]
        if storage == "mcap":
            assert sum(1 for _ in read_ros2_messages(str(disk / "full" / "full_0.mcap"))) == kept
    finally:
        subprocess.run(["umount", str(disk)], check=False)


def test_a_killed_run_still_leaves_a_closed_bag(tmp_path: Path) -> None:
    """kill -9 gives the run no chance to close anything: the writer process sees its pipe
    close and closes the bag with everything it was sent."""
    import signal

    m = write_machine(tmp_path, "tick", {"A": [("A", "after_ms(20)")]}, {"A_OnEntry": "print('tick', flush=True)"})
    p = _spawn("run", m, "--node", "turtlesim", "--record", tmp_path / "killed", cwd=tmp_path)
    try:
        assert p.stdout is not None
        for _ in range(50):  # a second of recording
            assert p.stdout.readline().strip() == "tick"
        p.send_signal(signal.SIGKILL)
        p.communicate(timeout=30)
    finally:
        p.kill()
    meta = {}
    for _ in range(200):  # the writer process closes the bag on its own, shortly after
        time.sleep(0.05)
        try:
            meta = read_metadata(tmp_path / "killed")
        except (yaml.YAMLError, TypeError):  # being rewritten right now
            continue
        if meta["message_count"]:
            break
    got = rosbags_messages(tmp_path / "killed")
    assert meta["message_count"] == sum(len(v) for v in got.values()) > 0
    assert len(read_ros2_messages(str(tmp_path / "killed" / "killed_0.mcap"))) == meta["message_count"]


def test_player_loops_over_the_bag(tmp_path: Path) -> None:
    """`bag play --loop` (the player in process, under the sim clock): the bag again from the
    start once its last message is out, keeping the bag's spacing."""
    from llfsm import ros
    from llfsm.bag.player import Player
    from llfsm.msgs.std_msgs.msg import String
    from llfsm.ros.bus import bus_of
    from llfsm.runtime import RunContext, SimClock
    from llfsm.runtime.context import activate

    assert run_sim(driver(tmp_path), "--duration", "250ms", "--record", tmp_path / "a").status == 0  # 1, 103, 205 ms
    player = Player(str(tmp_path / "a"), ["/chat"], loop=True)
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        player.attach(bus)
        heard: list[tuple[int, str]] = []
        ros.Node("ear").create_subscription(String, "/chat", lambda m: heard.append((bus.clock.now, m.data)), 10)
        for _ in range(700):
            bus.clock.now += 1_000_000
            bus.spin_some()
    finally:
        activate(prev)
    assert [d for _, d in heard] == ["step 1", "step 2", "step 3"] * 3 + ["step 1"]
    # each pass starts where the last ended, with the bag's own spacing (its first message at 1 ms)
    assert [t // 1_000_000 for t, _ in heard] == [1, 103, 205, 206, 308, 410, 411, 513, 615, 616]
