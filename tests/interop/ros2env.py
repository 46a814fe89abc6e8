"""Run real ROS 2 (rclpy from PyPI wheels) beside llfsm, each test in a private network.

`make .venv-ros/.installed` creates `.venv-ros/`, a second virtualenv holding rclpy, the message
packages and rmw_fastrtps_cpp as wheels (`ros-rclpy`, `ros-std-msgs`, ...; no ROS install, no
rmw_cyclonedds wheel exists).  The wheels need no setup: no `source setup.bash`, no
AMENT_PREFIX_PATH or LD_LIBRARY_PATH (each wheel finds its libraries beside itself); we only pin
RMW_IMPLEMENTATION=rmw_fastrtps_cpp (the one rmw installed) and clear variables of the calling
environment that would change discovery (CYCLONEDDS_URI, FASTDDS_DEFAULT_PROFILES_FILE, ...).

(tests/ is on sys.path as pytest's rootdir-based import puts it, and tests/interop is a
package, so the import above works from any test file.)

Isolation: every process of a test runs inside ONE fresh network namespace (`unshare -n`, as
root), where only `lo` exists, is up, and carries multicast (route 224.0.0.0/4), so DDS
discovery works as on a LAN and nothing leaves the machine.  Use:

    from interop.ros2env import requires_ros, run_ros, run_together, ros_command, llfsm_command

    @requires_ros                      # skips with the reason when .venv-ros or unshare is missing
    def test_x():
        out = run_ros("import rclpy; print(rclpy.__version__)", timeout=30)   # one rclpy snippet
        assert out.returncode == 0, out.stderr

        # several processes at once in one namespace, e.g. an rclpy subscriber and an llfsm run:
        sub, pub = run_together(
            [ros_command(SUBSCRIBER_CODE), llfsm_command(["run", "machines/x.machine", "--transport", "dds"])],
            timeout=30,
        )
        assert "data: ping" in sub.stdout

Each result is a `subprocess.CompletedProcess` (stdout/stderr as text).  Every process is
killed at `timeout` (returncode then -9, `timed_out` in the result's attributes); the whole
namespace disappears with its last process.  `run_together(..., stop_after_first=N)` ends the
others once the N-th command (an index) has exited, for servers that run until killed.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from functools import cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: `make test` names the venv it made (`make test-latest` makes .venv-ros-latest); .venv-ros by default.
VENV_ROS = Path(os.environ.get("LLFSM_ROS_VENV") or REPO / ".venv-ros")
ROS_PYTHON = VENV_ROS / "bin" / "python"

# Set up loopback with multicast inside the new namespace, then run the command.
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"

# Variables of the caller that would steer DDS somewhere else: dropped for every process.
_DROPPED = (
    "CYCLONEDDS_URI",
    "FASTDDS_DEFAULT_PROFILES_FILE",
    "FASTRTPS_DEFAULT_PROFILES_FILE",
    "RMW_FASTRTPS_USE_QOS_FROM_XML",
    "ROS_LOCALHOST_ONLY",
    "ROS_AUTOMATIC_DISCOVERY_RANGE",
    "ROS_STATIC_PEERS",
    "ROS_DISCOVERY_SERVER",
    "PYTHONPATH",
    "VIRTUAL_ENV",
)


def ros_installed() -> bool:
    return ROS_PYTHON.exists() and (VENV_ROS / ".installed").exists()


@cache
def netns_works() -> bool:
    """Whether this machine lets us make a network namespace (needs root or user namespaces)."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return False
    try:
        r = subprocess.run(["unshare", "-n", "sh", "-c", NETNS_SETUP], capture_output=True, timeout=10, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def skip_reason() -> str | None:
    if not ros_installed():
        return "real ROS 2 not installed: run `make .venv-ros/.installed` (rclpy wheels from PyPI)"
    if not netns_works():
        return "cannot create a private network namespace (unshare -n) for DDS tests here"
    return None


requires_ros = pytest.mark.skipif(skip_reason() is not None, reason=skip_reason() or "")
requires_netns = pytest.mark.skipif(
    not netns_works(), reason="cannot create a private network namespace (unshare -n) for DDS tests here"
)


def clean_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in _DROPPED}
    env.setdefault("ROS_DOMAIN_ID", "0")
    env["PYTHONUNBUFFERED"] = "1"
    env.update(extra or {})
    return env


def ros_command(code: str, env: dict[str, str] | None = None) -> tuple[list[str], dict[str, str]]:
    """(argv, env) running `code` with rclpy's Python (Fast DDS)."""
    e = clean_env({"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "RCUTILS_LOGGING_BUFFERED_STREAM": "0"})
    e.update(env or {})
    return [str(ROS_PYTHON), "-c", code], e


def python_command(code: str, env: dict[str, str] | None = None) -> tuple[list[str], dict[str, str]]:
    """(argv, env) running `code` with llfsm's Python (the test's own interpreter)."""
    e = clean_env()
    e.update(env or {})
    return [sys.executable, "-c", code], e


def llfsm_command(args: Sequence[str], env: dict[str, str] | None = None) -> tuple[list[str], dict[str, str]]:
    """(argv, env) running `llfsm ARGS...` with the test's interpreter."""
    e = clean_env()
    e.update(env or {})
    return [sys.executable, "-m", "llfsm", *args], e


# The launcher runs inside the namespace: starts every command, waits for them (killing all at
# the deadline, or the rest once `stop_after` has exited) and prints the results as JSON.
_LAUNCHER = r"""
import json, subprocess, sys, time
spec = json.load(sys.stdin)
deadline = time.monotonic() + spec["timeout"]
procs = [subprocess.Popen(c["argv"], env=c["env"], cwd=c["cwd"], stdin=subprocess.DEVNULL,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace")
         for c in spec["commands"]]
import threading
outs = [None] * len(procs)
def collect(i, p):
    outs[i] = p.communicate()
threads = [threading.Thread(target=collect, args=(i, p), daemon=True) for i, p in enumerate(procs)]
for t in threads:
    t.start()
timed_out = [False] * len(procs)
stop_after = spec["stop_after"]
stopped_at = None
while any(p.poll() is None for p in procs):
    now = time.monotonic()
    if stop_after is not None and procs[stop_after].poll() is not None and stopped_at is None:
        stopped_at = now
        for p in procs:
            if p.poll() is None:
                p.terminate()
    if stopped_at is not None and now > stopped_at + 3:
        for p in procs:
            if p.poll() is None:
                p.kill()
    if now > deadline:
        for i, p in enumerate(procs):
            if p.poll() is None:
                timed_out[i] = True
                p.kill()
    time.sleep(0.02)
for t in threads:
    t.join(5)
print(json.dumps([{"returncode": p.returncode, "stdout": (o or ("", ""))[0], "stderr": (o or ("", ""))[1],
                   "timed_out": to} for p, o, to in zip(procs, outs, timed_out)]))
"""


def run_together(
    commands: Sequence[tuple[list[str], dict[str, str]]],
    *,
    timeout: float = 60,
    stop_after_first: int | None = None,
    cwd: str | os.PathLike[str] = REPO,
) -> list[subprocess.CompletedProcess[str]]:
    """Run `commands` ((argv, env) pairs from ros_command/llfsm_command/python_command)
    concurrently in one private network namespace; results in the same order."""
    spec = {
        "timeout": timeout,
        "stop_after": stop_after_first,
        "commands": [{"argv": list(a), "env": e, "cwd": os.fspath(cwd)} for a, e in commands],
    }
    argv = ["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", sys.executable, "-c", _LAUNCHER]
    r = subprocess.run(argv, input=json.dumps(spec), capture_output=True, text=True, timeout=timeout + 30, check=False)
    if r.returncode != 0:
        raise RuntimeError(f"network namespace launcher failed ({r.returncode}): {r.stderr.strip()}")
    results = []
    for (a, _), res in zip(commands, json.loads(r.stdout), strict=True):
        cp = subprocess.CompletedProcess(a, res["returncode"], res["stdout"], res["stderr"])
        cp.timed_out = res["timed_out"]  # type: ignore[attr-defined]
        results.append(cp)
    return results


def run_ros(code: str, *, timeout: float = 60, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """Run one rclpy snippet in its own network namespace."""
    return run_together([ros_command(code, env)], timeout=timeout)[0]


def run_ros_plain(code: str, *, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """Run an rclpy snippet that touches no network (serialization, type support) directly."""
    argv, env = ros_command(code)
    return subprocess.run(argv, env=env, capture_output=True, text=True, timeout=timeout, check=False)
