"""Interface types by name (issue 22, items 11 and 12): the packages a course robot needs ship
(sensor_msgs, nav_msgs), an unknown type gets a suggestion only when one is close and says
where llfsm looks, and the offline `interface list|package` verbs print what `ros2` prints.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import llfsm

from llfsm.msgs import _dds
from llfsm.ros2cli import CliError
from llfsm.ros2cli.lookup import message_class, service_class


@pytest.mark.parametrize(
    ("type_name", "field"),
    [
        ("sensor_msgs/msg/LaserScan", "ranges"),
        ("sensor_msgs/msg/Imu", "angular_velocity"),
        ("sensor_msgs/msg/Range", "variance"),  # Jazzy's definition (the current LTS)
        ("nav_msgs/msg/Odometry", "child_frame_id"),
        ("nav_msgs/msg/OccupancyGrid", "data"),
    ],
)
def test_course_robot_messages_ship(type_name: str, field: str) -> None:
    cls = message_class(type_name)
    msg = cls()
    assert field in dict(cls._FIELDS)
    assert _dds.from_cdr(_dds.cdr(msg), cls) == msg


def test_their_services_ship_too() -> None:
    assert service_class("nav_msgs/srv/GetMap")._TYPE == "nav_msgs/srv/GetMap"
    assert service_class("sensor_msgs/srv/SetCameraInfo").Request().camera_info.width == 0


def test_interface_show_prints_the_ros_definition() -> None:
    r = llfsm("interface", "show", "nav_msgs/msg/Odometry")
    assert r.status == 0, r.stderr
    assert "string child_frame_id" in r.stdout and "geometry_msgs/PoseWithCovariance pose" in r.stdout
    assert "\tPose pose" in r.stdout  # nested definitions one tab deeper, as ros2 prints them


class TestUnknownTypes:
    def _message(self, text: str, kind: str = "msg") -> str:
        with pytest.raises(CliError) as e:
            message_class(text) if kind == "msg" else service_class(text)
        return e.value.message

    @pytest.mark.parametrize(
        "text", ["robot_test_msgs/msg/BasicTypes", "example_interfaces/msg/Int64", "my_robot/msg/Status"]
    )
    def test_no_suggestion_that_is_not_close(self, text: str) -> None:
        msg = self._message(text)
        assert "did you mean" not in msg, msg

    @pytest.mark.parametrize(
        ("text", "meant"),
        [
            ("geometry_msgs/msg/Twits", "geometry_msgs/msg/Twist"),
            ("std_msgs/msg/string", "std_msgs/msg/String"),
            ("sensor_msg/msg/LaserScan", "sensor_msgs/msg/LaserScan"),
            ("nav_msgs/msg/Odom", "nav_msgs/msg/Odometry"),
            ("geometry_msgs/Twistt", "geometry_msgs/msg/Twist"),
            ("geometry/msg/Twist", "geometry_msgs/msg/Twist"),
        ],
    )
    def test_a_close_one_is_suggested(self, text: str, meant: str) -> None:
        assert f"did you mean '{meant}'?" in self._message(text)

    def test_an_unknown_package_says_where_llfsm_looks(self, monkeypatch: pytest.MonkeyPatch) -> None:
        monkeypatch.delenv("LLFSM_INTERFACE_PATH", raising=False)
        monkeypatch.setenv("AMENT_PREFIX_PATH", "/opt/ros/humble")
        msg = self._message("robot_test_msgs/msg/BasicTypes")  # (test_msgs may be in this process's path)
        assert "no interface package 'robot_test_msgs'" in msg
        assert "LLFSM_INTERFACE_PATH (not set)" in msg and "share/ of AMENT_PREFIX_PATH (/opt/ros/humble)" in msg

    def test_a_known_package_without_the_type(self) -> None:
        msg = self._message("sensor_msgs/msg/Lidar")
        assert "sensor_msgs has no message 'Lidar'" in msg and "did you mean" not in msg

    def test_the_command_line_says_it_in_one_line(self) -> None:
        r = llfsm("interface", "show", "robot_test_msgs/msg/BasicTypes")
        assert r.status == 2
        assert r.stderr.count("\n") == 1 and "std_msgs/msg/Byte" not in r.stderr, r.stderr


class TestInterfaceList:
    """`ros2 interface list` and `ros2 interface package`, offline, as ros2interface prints them."""

    def test_list_has_every_kind_under_its_heading(self) -> None:
        r = llfsm("interface", "list")
        assert r.status == 0, r.stderr
        lines = r.stdout.splitlines()
        assert lines[0] == "Messages:"
        assert "    sensor_msgs/msg/LaserScan" in lines and "    geometry_msgs/msg/Twist" in lines
        assert "Services:" in lines and "    std_srvs/srv/Trigger" in lines
        assert lines.index("Services:") > lines.index("    sensor_msgs/msg/LaserScan")
        assert "    turtlesim/srv/Spawn" in lines[lines.index("Services:") :]

    def test_list_only_messages(self) -> None:
        r = llfsm("interface", "list", "-m")
        assert r.status == 0
        assert r.stdout.startswith("Messages:\n") and "Services:" not in r.stdout

    def test_a_users_package_in_the_search_path(self, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
        (tmp_path / "my_msgs" / "msg").mkdir(parents=True)
        (tmp_path / "my_msgs" / "msg" / "Note.msg").write_text("string text\n")
        monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(tmp_path))
        assert "    my_msgs/msg/Note" in llfsm("interface", "list").stdout.splitlines()
        r = llfsm("interface", "package", "my_msgs")
        assert (r.status, r.stdout) == (0, "my_msgs/msg/Note\n")

    def test_package_lists_its_types(self) -> None:
        r = llfsm("interface", "package", "turtlesim")
        assert r.status == 0
        lines = r.stdout.splitlines()
        assert lines == sorted(lines) and all(line.startswith("turtlesim/") for line in lines)
        assert {
            "turtlesim/msg/Color",
            "turtlesim/msg/Pose",
            "turtlesim/srv/Kill",
            "turtlesim/srv/SetPen",
            "turtlesim/srv/Spawn",
            "turtlesim/srv/TeleportAbsolute",
            "turtlesim/srv/TeleportRelative",
        } <= set(lines)
        only = llfsm("interface", "package", "-s", "turtlesim").stdout.splitlines()
        assert only and all(line.startswith("turtlesim/srv/") for line in only)

    def test_an_unknown_package(self) -> None:
        r = llfsm("interface", "package", "sensor_msg")
        assert r.status == 1
        assert "Unknown package 'sensor_msg'" in r.stderr and "sensor_msgs" in r.stderr


def test_a_machine_importing_an_unknown_package_says_where_llfsm_looks(tmp_path: Path) -> None:
    from helpers import run_sim, write_machine

    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "True")], "END": None},
        includes="from llfsm.msgs.robot_test_msgs.msg import BasicTypes\n",
    )
    r = run_sim(m)
    assert r.status == 1
    assert "no interface package 'robot_test_msgs'" in r.stderr and "LLFSM_INTERFACE_PATH" in r.stderr, r.stderr
