"""Reliability against real ROS 2 (rclpy from the PyPI wheels in .venv-ros, on Fast DDS): most
sensor drivers publish with `qos_profile_sensor_data` (best effort).  An llfsm machine that
subscribes with `ros.qos_profile_sensor_data` hears such a publisher; a reliable one cannot
match it (as in ROS 2) and says so, as rclpy does.  The other way round too: rclpy hears an
llfsm best-effort publisher with its own sensor-data profile, and its reliable subscription
reports the incompatibility.  Every process runs in one private network namespace."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers import write_machine

from interop.ros2env import llfsm_command, requires_ros, ros_command, run_together

pytestmark = [pytest.mark.interop, pytest.mark.dds, requires_ros]

RCLPY_SENSOR = """
import time, rclpy
from rclpy.qos import qos_profile_sensor_data
from std_msgs.msg import String
rclpy.init()
node = rclpy.create_node("rclpy_sensor")
pub = node.create_publisher(String, "/scan", qos_profile_sensor_data)
best, strict = [], []
node.create_subscription(String, "/llfsm_scan", lambda m: best.append(m.data), qos_profile_sensor_data)
node.create_subscription(String, "/llfsm_scan", lambda m: strict.append(m.data), 10)
end = time.monotonic() + 12
i = 0
while time.monotonic() < end:
    msg = String()
    msg.data = f"scan {i}"
    i += 1
    pub.publish(msg)
    rclpy.spin_once(node, timeout_sec=0.05)
print("RCLPY BEST_EFFORT", len(best), flush=True)
print("RCLPY RELIABLE", len(strict), flush=True)
"""


def sensor_machine(root: Path) -> Path:
    """Subscribes to /scan with the sensor-data profile (and, reliably, a second time), and
    publishes /llfsm_scan best effort every 100 ms; prints what each subscription heard."""
    return write_machine(
        root,
        "sensor",
        {"INITIAL": [("TICK", "True")], "TICK": [("TICK", "after_ms(100)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('llfsm_sensor')\n"
                "scan = node.create_subscription(String, '/scan', None, ros.qos_profile_sensor_data)\n"
                "strict = node.create_subscription(String, '/scan', None, 10)\n"
                "pub = node.create_publisher(String, '/llfsm_scan', ros.qos_profile_sensor_data)\n"
            ),
            "TICK_OnEntry": (
                "n += 1\npub.publish(String(data=f'tick {n}'))\n"
                "got = scan.take()\n"
                "if got is not None:\n    print('HEARD', got.data, flush=True)\n"
                "if strict.count:\n    print('STRICT HEARD', strict.count, flush=True)\n"
            ),
        },
        variables="n: int = 0\nnode: ros.Node\nscan: ros.Subscription\nstrict: ros.Subscription\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )


def test_sensor_data_qos_both_ways_with_rclpy(tmp_path: Path) -> None:
    machine = sensor_machine(tmp_path)
    rclpy_side, llfsm_side = run_together(
        [
            ros_command(RCLPY_SENSOR),
            llfsm_command(["run", "--transport", "dds", str(machine), "--duration", "14"]),
        ],
        timeout=60,
    )
    assert rclpy_side.returncode == 0, rclpy_side.stderr
    assert llfsm_side.returncode == 0, llfsm_side.stderr
    # rclpy's best-effort publisher reaches the llfsm machine's sensor-data subscription
    heard = re.findall(r"^HEARD scan (\d+)$", llfsm_side.stdout, re.M)
    assert len(heard) >= 5, llfsm_side.stdout + llfsm_side.stderr
    # ...and never its reliable one, which says why, once, as rclpy would
    assert "STRICT HEARD" not in llfsm_side.stdout
    warning = (
        "[llfsm_sensor]: New publisher discovered on topic '/scan', offering incompatible QoS. "
        "No messages will be received from it. Last incompatible policy: RELIABILITY"
    )
    assert llfsm_side.stderr.count(warning) == 1, llfsm_side.stderr
    # the other way: rclpy hears llfsm's best-effort publisher with its sensor-data profile only
    got = dict(re.findall(r"^RCLPY (\w+) (\d+)$", rclpy_side.stdout, re.M))
    assert int(got["BEST_EFFORT"]) >= 5 and got["RELIABLE"] == "0", rclpy_side.stdout
    assert "New publisher discovered on topic '/llfsm_scan', offering incompatible QoS" in rclpy_side.stderr
    assert "New subscription discovered on topic '/llfsm_scan', requesting incompatible QoS" in llfsm_side.stderr
