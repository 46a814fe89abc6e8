"""`llfsm run` takes ROS arguments as `ros2 run` does (issue 27, item 9): `--ros-args -r A:=B
--remap A:=B -p N:=V --params-file F --log-level [NAME:=]LEVEL --`, a plain `--log-level`, and
per-run log files as ROS 2 keeps them in ~/.ros/log (off unless asked: docs/bus.md, Logging)."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import run_sim, write_machine


def _talker(root: Path) -> Path:
    """Logs at each level once, from its node `talker`, and prints its parameter `gain`."""
    return write_machine(
        root,
        "talker",
        {"A": [("END", "True")], "END": None},
        {
            "A_OnEntry": (
                "ros.init()\nnode = ros.Node('talker')\nlog = node.get_logger()\n"
                "log.debug('a debug line')\nlog.info('an info line')\nlog.warning('a warning')\n"
                "print('gain', gain)\n"
            )
        },
        variables="gain: float = 1.0\nnode: ros.Node = None\n",
        includes="from llfsm import ros\n",
        yaml_extra="parameters: [gain]",
    )


def _logged(stderr: str) -> list[str]:
    return [line.split("]: ")[1] for line in stderr.splitlines() if line.startswith("[") and "[talker]" in line]


def test_log_levels_for_every_logger_and_for_one(tmp_path: Path) -> None:
    m = _talker(tmp_path)
    assert _logged(run_sim(m).stderr) == ["an info line", "a warning"]  # INFO by default, as ROS 2
    assert _logged(run_sim(m, "--log-level", "debug").stderr) == ["a debug line", "an info line", "a warning"]
    assert _logged(run_sim(m, "--ros-args", "--log-level", "WARN").stderr) == ["a warning"]
    r = run_sim(
        m, "--node", "turtlesim", "--ros-args", "--log-level", "talker:=debug", "--log-level", "turtlesim:=warn"
    )
    assert _logged(r.stderr) == ["a debug line", "an info line", "a warning"]
    assert "Starting turtlesim" not in r.stderr  # turtlesim's INFO lines are below its level


def test_ros_args_as_ros2_run_takes_them(tmp_path: Path) -> None:
    m = _talker(tmp_path)
    params = tmp_path / "p.yaml"
    params.write_text("/llfsm/talker:\n  ros__parameters:\n    gain: 3.0\n")
    r = run_sim(m, "--node", "turtlesim", "--duration", "5ms", "--introspect",
                "--ros-args", "-r", "/turtle1/pose:=/pose", "--remap", "/turtle1/cmd_vel:=/cmd",
                "-p", "talker:gain:=2.0", "--", "--verbose")  # fmt: skip
    assert r.status == 0, r.stderr
    assert r.stdout == "gain 2.0\n"
    assert "  /pose [turtlesim/msg/Pose]" in r.stderr and "  /cmd [geometry_msgs/msg/Twist]" in r.stderr
    assert "m  0 s  0 - talker" in r.stderr  # -v after the `--` that closes the ROS arguments
    assert run_sim(m, "--ros-args", "--params-file", params).stdout == "gain 3.0\n"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--ros-args", "--enclave", "/x"], "--ros-args --enclave: llfsm run takes -r/--remap, -p/--param"),
        (["--log-level", "loud"], "--log-level loud: 'loud' is not a level (debug, info, warn, error, fatal, unset)"),
        (["--log-level", ":=debug"], "--log-level :=debug: give a logger name before ':='"),
    ],
)
def test_a_bad_ros_argument_is_one_line_and_status_2(tmp_path: Path, args: list[str], message: str) -> None:
    r = run_sim(_talker(tmp_path), *args)
    assert r.status == 2 and "Traceback" not in r.stderr, r.stderr
    assert message in r.stderr.strip().splitlines()[-1]  # one line (after click's usage lines, for click's errors)


def test_log_files_are_off_unless_asked_and_kept_as_ros2_keeps_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    m = _talker(tmp_path / "m")
    logs = tmp_path / "logs"
    monkeypatch.setenv("ROS_LOG_DIR", str(logs))
    assert run_sim(m).status == 0 and not logs.exists()  # off by default
    r = run_sim(m, "--log-file", "-v", "--log-level", "debug")
    [file] = logs.glob("llfsm_*_*.log")  # <executable>_<pid>_<ms since the epoch>.log, as rcl names them
    assert f"llfsm: log file {file}" in r.stderr.splitlines()  # -v says where
    assert file.read_text().splitlines() == [
        "0.000000000 [DEBUG] [talker]: a debug line",
        "0.000000000 [INFO] [talker]: an info line",
        "0.000000000 [WARN] [talker]: a warning",
    ]
    monkeypatch.delenv("ROS_LOG_DIR")
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "home"))
    r = run_sim(m, "--ros-args", "--enable-external-lib-logs", "--")  # rcl's spelling
    assert r.status == 0 and len(list((tmp_path / "home" / "log").glob("llfsm_*.log"))) == 1
    (tmp_path / "blocked").write_text("")
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "blocked"))  # a file where the folder should be
    r = run_sim(m, "--log-file")
    assert r.status == 0 and r.stdout == "gain 1.0\n"  # the run goes on without the file
    assert f"llfsm: warning: --log-file: cannot write in {tmp_path / 'blocked'}" in r.stderr
