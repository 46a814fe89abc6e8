"""How fast messages become DDS payloads and back: llfsm's generated CDR functions beside the
route through cyclonedds' IdlStruct samples (to_dds + cyclonedds' XCDR1 serializer), and rclpy's
serialize_message / deserialize_message (C, from the wheels in .venv-ros, when installed).

    python bench/dds_types.py           prints the table
    python bench/dds_types.py --quick   fewer iterations

Each rate is the median of interleaved repeats (the three ways take turns), in one process per
Python; ratios are llfsm's rate over the other's.  This is what chose the hand-generated CDR
encoder over the IdlStruct route for the transport.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
ROS_PYTHON = REPO / ".venv-ros" / "bin" / "python"

Table = tuple[str, list[str], list[list[str]]]


def _messages() -> dict[str, object]:
    from llfsm.msgs.geometry_msgs.msg import PoseStamped, Twist
    from llfsm.msgs.std_msgs.msg import Float64MultiArray, String

    twist = Twist()
    twist.linear.x, twist.angular.z = 2.0, -1.5
    pose = PoseStamped()
    pose.header.frame_id, pose.pose.position.x = "map", 1.0
    return {
        "Twist": twist,
        "PoseStamped": pose,
        "String (20 chars)": String(data="hello world, again!!"),
        "Float64MultiArray (1000)": Float64MultiArray(data=[float(i) for i in range(1000)]),
    }


# The same messages built with rclpy's classes (only in .venv-ros).
_ROS_MESSAGES = r"""
from geometry_msgs.msg import PoseStamped, Twist
from std_msgs.msg import Float64MultiArray, String
twist = Twist(); twist.linear.x, twist.angular.z = 2.0, -1.5
pose = PoseStamped(); pose.header.frame_id, pose.pose.position.x = "map", 1.0
MESSAGES = {"Twist": twist, "PoseStamped": pose, "String (20 chars)": String(data="hello world, again!!"),
            "Float64MultiArray (1000)": Float64MultiArray(data=[float(i) for i in range(1000)])}
"""

_ROS_BENCH = (
    _ROS_MESSAGES
    + r"""
import json, statistics, sys, time
from rclpy.serialization import serialize_message, deserialize_message
n, repeats = int(sys.argv[1]), int(sys.argv[2])
out = {}
for name, msg in MESSAGES.items():
    data, cls = serialize_message(msg), type(msg)
    enc, dec = [], []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(n):
            serialize_message(msg)
        enc.append(n / (time.perf_counter() - t))
        t = time.perf_counter()
        for _ in range(n):
            deserialize_message(data, cls)
        dec.append(n / (time.perf_counter() - t))
    out[name] = [statistics.median(enc), statistics.median(dec)]
print(json.dumps(out))
"""
)


def _rate(fn: Callable[[], object], n: int) -> float:
    t = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - t)


def measure(n: int, repeats: int) -> dict[str, dict[str, float]]:
    from llfsm.msgs import _dds

    out: dict[str, dict[str, float]] = {}
    for name, msg in _messages().items():
        cls = type(msg)
        idl = _dds.dds_type(cls)
        data = _dds.cdr(msg)
        assert idl.deserialize(data) == _dds.to_dds(msg)  # the same bytes both ways
        ways = {
            "llfsm encode": lambda m=msg: _dds.cdr(m),
            "idl encode": lambda m=msg: _dds.to_dds(m).serialize(use_version_2=False),
            "llfsm decode": lambda d=data, c=cls: _dds.from_cdr(d, c),
            "idl decode": lambda d=data, i=idl, c=cls: _dds.from_dds(i.deserialize(d), c),
        }
        rates: dict[str, list[float]] = {k: [] for k in ways}
        for _ in range(repeats):  # interleaved: each way once per round
            for k, fn in ways.items():
                rates[k].append(_rate(fn, n))
        out[name] = {k: statistics.median(v) for k, v in rates.items()}
    return out


def measure_rclpy(n: int, repeats: int) -> dict[str, list[float]] | None:
    if not ROS_PYTHON.exists():
        return None
    r = subprocess.run(
        [str(ROS_PYTHON), "-c", _ROS_BENCH, str(n), str(repeats)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    return json.loads(r.stdout) if r.returncode == 0 else None


def section(quick: bool = False) -> list[Table]:
    n, repeats = (2000, 3) if quick else (20000, 7)
    ours = measure(n, repeats)
    ros = measure_rclpy(n, repeats)
    rows = []
    for name, r in ours.items():
        rc = ros.get(name) if ros else None
        rows.append(
            [
                name,
                f"{r['llfsm encode']:,.0f}",
                f"{r['idl encode']:,.0f}",
                f"{r['llfsm encode'] / r['idl encode']:.1f}x",
                f"{rc[0]:,.0f}" if rc else "-",
                f"{r['llfsm decode']:,.0f}",
                f"{r['idl decode']:,.0f}",
                f"{r['llfsm decode'] / r['idl decode']:.1f}x",
                f"{rc[1]:,.0f}" if rc else "-",
            ]
        )
    title = (
        f"Messages to XCDR1 payloads and back, per second (median of {repeats} interleaved runs of {n}; "
        "idl = to_dds + cyclonedds' serializer; rclpy = serialize_message in .venv-ros)"
    )
    header = [
        "message",
        "llfsm encode",
        "idl encode",
        "ratio",
        "rclpy encode",
        "llfsm decode",
        "idl decode",
        "ratio",
        "rclpy decode",
    ]
    return [(title, header, rows)]


def render(tables: list[Table]) -> str:
    out = []
    for title, header, rows in tables:
        out += [f"### {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        out += ["| " + " | ".join(row) + " |" for row in rows]
        out.append("")
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    sys.path.insert(0, str(REPO))
    print(render(section(args.quick)))


if __name__ == "__main__":
    main()
