"""Parameters across processes over DDS (SPEC §12): `llfsm param` against llfsm's turtlesim (whose
picture changes with background_r/g/b), against a machine tuned while it runs, and against an
rclpy node (Fast DDS, from .venv-ros); an rclpy parameter client against an llfsm node.

Each test has a private network namespace (tests/dds_netns.py); every process has a timeout.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from dds_netns import NetNamespace, Watched, finish
from helpers import REPO, Run, write_machine
from interop.ros2env import ROS_PYTHON, ros_installed

pytestmark = pytest.mark.dds  # every test talks DDS across processes


def llfsm(ns: NetNamespace, *args: str | os.PathLike[str], timeout: float = 60) -> Run:
    status, out, err = finish(ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], cwd=REPO), timeout)
    return Run(status, out, err)


def wait_for_node(ns: NetNamespace, node: str, timeout: float = 40) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if node in llfsm(ns, "node", "list").stdout.split():
            return
        time.sleep(0.2)
    raise AssertionError(f"{node} never showed up")


def test_param_verbs_against_llfsm_turtlesim_and_the_picture_changes(netns: NetNamespace, tmp_path: Path) -> None:
    png = tmp_path / "bg.png"
    run = netns.popen(
        [sys.executable, "-m", "llfsm", "run", "--transport", "dds", "--node", "turtlesim", "--duration", "120s",
         "--image", png],
        cwd=REPO,
    )  # fmt: skip
    wait_for_node(netns, "/turtlesim")
    r = llfsm(netns, "param", "list", "/turtlesim")
    assert r.stdout == "  background_b\n  background_g\n  background_r\n", r.stderr
    assert llfsm(netns, "param", "get", "/turtlesim", "background_r").stdout == "Integer value is: 69\n"
    refused = llfsm(netns, "param", "set", "/turtlesim", "background_r", "300")
    assert refused.status == 1
    assert (
        refused.stderr
        == "llfsm: Setting parameter failed: Parameter background_r out of range. Min: 0, Max: 255, value: 300\n"
    )
    wrong = llfsm(netns, "param", "set", "/turtlesim", "background_r", "1.5")
    assert wrong.status == 1 and "Wrong parameter type" in wrong.stderr and "Traceback" not in wrong.stderr
    for c, v in zip("rgb", ("10", "200", "30"), strict=True):
        assert llfsm(netns, "param", "set", "turtlesim", f"background_{c}", v).stdout == "Set parameter successful\n"
    r = llfsm(netns, "param", "describe", "/turtlesim", "background_g")
    assert r.stdout == (
        "Parameter name: background_g\n  Type: integer\n  Description: Green channel of the background color\n"
        "  Constraints:\n    Min value: 0\n    Max value: 255\n    Step: 1\n"
    )
    dumped = llfsm(netns, "param", "dump", "/turtlesim").stdout
    assert yaml.safe_load(dumped) == {
        "/turtlesim": {"ros__parameters": {"background_b": 30, "background_g": 200, "background_r": 10}}
    }
    (tmp_path / "dump.yaml").write_text(dumped.replace("200", "201"))
    r = llfsm(netns, "param", "load", "/turtlesim", tmp_path / "dump.yaml")
    assert r.stdout.splitlines() == [f"Set parameter background_{c} successful" for c in "bgr"], r.stderr
    missing = llfsm(netns, "param", "get", "/nobody", "x", "--timeout", "1")
    assert missing.status == 1 and missing.stderr.startswith("llfsm: Node not found: /nobody")
    bad = llfsm(netns, "param", "load", "/turtlesim", REPO / "README.md")
    assert bad.status == 2 and "README.md" in bad.stderr and "Traceback" not in bad.stderr
    run.send_signal(signal.SIGINT)  # done with it: on a loaded machine the verbs above can take a minute
    assert finish(run, 30)[0] in (0, 130)  # an interrupted run of nodes alone: 130 (issue 27 makes it 0)
    from PIL import Image

    assert Image.open(png).convert("RGB").getpixel((2, 2)) == (10, 201, 30)  # the window's background


def test_a_machine_tuned_live_over_dds(netns: NetNamespace, tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "gainer",
        {"INITIAL": [("RUN", "True")], "RUN": [("END", "not ros.ok()"), ("RUN", "after_ms(100)")], "END": None},
        {"INITIAL_OnEntry": "ros.init()\nnode = ros.Node('gain_node')\n"
                            "pub = node.create_publisher(Float64, 'gain', 10)\n",
         "RUN_OnEntry": "pub.publish(Float64(data=gain))\n"},
        variables="gain: float = 1.0\nnode: ros.Node\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Float64\n",
        yaml_extra="parameters: [gain]\n",
    )  # fmt: skip
    out = tmp_path / "echo.txt"
    with open(out, "w") as f:
        run = netns.popen(
            [sys.executable, "-m", "llfsm", "run", "--transport", "dds", m, "--echo", "/gain"],
            cwd=REPO,
            stdout=f,
        )
        wait_for_node(netns, "/llfsm/gainer")
        assert llfsm(netns, "param", "get", "/llfsm/gainer", "gain").stdout == "Double value is: 1.0\n"
        r = llfsm(netns, "param", "set", "/llfsm/gainer", "gain", "2")
        assert (
            r.status == 1
            and r.stderr == "llfsm: Setting parameter failed: Wrong parameter type, expected '3' got '2'\n"
        )
        assert llfsm(netns, "param", "set", "/llfsm/gainer", "gain", "2.5").status == 0
        assert llfsm(netns, "param", "get", "/llfsm/gainer", "gain").stdout == "Double value is: 2.5\n"
        # Ctrl-C once the new gain is published (a --duration of 10 s ended the run before five
        # verbs of seconds each had run under load)
        deadline = time.monotonic() + 60
        while "data: 2.5" not in out.read_text() and time.monotonic() < deadline:
            time.sleep(0.1)
        run.send_signal(signal.SIGINT)
        finish(run, 120)
    gains = [d["data"] for d in yaml.safe_load_all(out.read_text()) if d]
    assert gains[0] == 1.0 and gains[-1] == 2.5 and sorted(set(gains)) == [1.0, 2.5]


def test_a_machine_with_parameters_and_no_bus_code_is_a_node_on_dds(netns: NetNamespace, tmp_path: Path) -> None:
    """Issue 27, item 1: `parameters:` puts /llfsm/M on the graph without a ros.init() in its code."""
    m = write_machine(
        tmp_path,
        "tuned",
        {"RUN": [("RUN", "after_ms(200)")]},
        {"RUN_OnEntry": "print('gain', gain, flush=True)"},
        variables="gain: float = 1.0\n",
        yaml_extra="parameters: [gain]\n",
    )
    run = Watched(netns.popen([sys.executable, "-m", "llfsm", "run", "--transport", "dds", m], cwd=REPO))
    wait_for_node(netns, "/llfsm/tuned")
    assert llfsm(netns, "param", "get", "/llfsm/tuned", "gain").stdout == "Double value is: 1.0\n"
    r = llfsm(netns, "param", "set", "/llfsm/tuned", "gain", "2.5")
    assert r.stdout == "Set parameter successful\n", r.stderr
    # Ctrl-C once it runs with the new gain (a --duration of 8 s ended the run before the verbs,
    # seconds each under load, were done); its machine has no END: Ctrl-C's status is 130
    run.wait_for(r"^gain 2\.5$", stream="out")
    status, out, err = run.finish(120, signal.SIGINT)
    assert status == 130 and "Traceback" not in err, err
    assert out.splitlines()[0] == "gain 1.0" and out.splitlines()[-1] == "gain 2.5"


_RCLPY_NODE = r"""
import rclpy
from rclpy.node import Node
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
rclpy.init()
node = Node("rclpy_tuned")
node.declare_parameter("rate", 10, ParameterDescriptor(description="loop rate"))
node.declare_parameter("label", "hi", ParameterDescriptor(read_only=True))
node.declare_parameter("gains", [1.0, 2.0])
node.add_on_set_parameters_callback(
    lambda ps: SetParametersResult(successful=all(p.value != 13 for p in ps), reason="unlucky"))
try:
    rclpy.spin(node)
except BaseException:
    pass
"""


@pytest.mark.interop
@pytest.mark.skipif(not ros_installed(), reason="needs rclpy in .venv-ros (make .venv-ros/.installed)")
def test_param_verbs_against_an_rclpy_node(netns: NetNamespace, tmp_path: Path) -> None:
    netns.popen(
        [str(ROS_PYTHON), "-c", _RCLPY_NODE],
        env={"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wait_for_node(netns, "/rclpy_tuned")
    r = llfsm(netns, "param", "list", "/rclpy_tuned", "--param-type")
    assert "  rate (type: integer)\n" in r.stdout and "  gains (type: double array)\n" in r.stdout, r.stderr
    assert llfsm(netns, "param", "get", "/rclpy_tuned", "rate").stdout == "Integer value is: 10\n"
    assert llfsm(netns, "param", "get", "/rclpy_tuned", "gains").stdout == "Double values are: [1.0, 2.0]\n"
    assert llfsm(netns, "param", "set", "/rclpy_tuned", "rate", "20").stdout == "Set parameter successful\n"
    assert llfsm(netns, "param", "get", "/rclpy_tuned", "rate", "--hide-type").stdout == "20\n"
    # rclpy's own reasons, through its own services
    # (Cyclone may log a line of its own on stderr about a Fast DDS reply it could not read)
    unlucky = llfsm(netns, "param", "set", "/rclpy_tuned", "rate", "13")
    assert unlucky.status == 1 and unlucky.stderr.splitlines()[-1] == "llfsm: Setting parameter failed: unlucky"
    assert (
        "Trying to set a read-only parameter: label."
        in llfsm(netns, "param", "set", "/rclpy_tuned", "label", "x").stderr
    )
    assert "Wrong parameter type" in llfsm(netns, "param", "set", "/rclpy_tuned", "rate", "fast").stderr
    assert "Description: loop rate" in llfsm(netns, "param", "describe", "/rclpy_tuned", "rate").stdout
    dumped = yaml.safe_load(llfsm(netns, "param", "dump", "/rclpy_tuned").stdout)
    assert dumped["/rclpy_tuned"]["ros__parameters"]["rate"] == 20
    f = tmp_path / "p.yaml"
    f.write_text("/**:\n  ros__parameters:\n    rate: 30\n")
    assert llfsm(netns, "param", "load", "/rclpy_tuned", f).stdout == "Set parameter rate successful\n"
    assert llfsm(netns, "param", "get", "/rclpy_tuned", "rate").stdout == "Integer value is: 30\n"


_RCLPY_CLIENT = r"""
import sys, rclpy
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
rclpy.init()
node = rclpy.create_node("rclpy_setter")
client = AsyncParameterClient(node, "/turtlesim")
print("ready", client.wait_for_services(timeout_sec=20.0), flush=True)
future = client.set_parameters([Parameter("background_g", value=7)])
rclpy.spin_until_future_complete(node, future, timeout_sec=3.0)
print("answered", future.done(), flush=True)
"""


@pytest.mark.interop
@pytest.mark.skipif(not ros_installed(), reason="needs rclpy in .venv-ros (make .venv-ros/.installed)")
def test_an_rclpy_parameter_client_reaches_an_llfsm_node(netns: NetNamespace) -> None:
    """rclpy (Fast DDS) finds the llfsm node's parameter services and its set is applied; its
    reply is lost on the way back, the cross-vendor limit docs/transports.md describes."""
    run = netns.popen(
        [sys.executable, "-m", "llfsm", "run", "--transport", "dds", "--node", "turtlesim", "--duration", "30s"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wait_for_node(netns, "/turtlesim")
    client = netns.popen([str(ROS_PYTHON), "-c", _RCLPY_CLIENT], env={"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"})
    status, out, err = finish(client, 60)
    assert status == 0 and out.startswith("ready True"), err
    assert llfsm(netns, "param", "get", "/turtlesim", "background_g").stdout == "Integer value is: 7\n"
    run.send_signal(2)
    finish(run, 30)
