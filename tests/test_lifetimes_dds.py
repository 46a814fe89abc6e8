"""Issue 22, item 1 over DDS: a restart through /llfsm/M/restart re-runs INITIAL, which makes
the machine's node again; the old one leaves the graph other processes see (`node list`,
`topic info`), as it does in process (test_lifetimes.py)."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish
from helpers import REPO, Run, write_machine

pytestmark = pytest.mark.dds


def llfsm(ns: NetNamespace, *args: str | os.PathLike[str], timeout: float = 60) -> Run:
    status, out, err = finish(ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], cwd=REPO), timeout)
    return Run(status, out, err)


def bot(root: Path) -> Path:
    return write_machine(
        root,
        "bot",
        {"INITIAL": [("DRIVE", "True")], "DRIVE": [("DRIVE", "after_ms(100)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('wall_bot')\npub = node.create_publisher(Twist, '/turtle1/cmd_vel', 10)\n"
            ),
            "DRIVE_OnEntry": "pub.publish(Twist())\n",
        },
        variables="node: ros.Node\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n",
    )


def until(ns: NetNamespace, *args: str, needle: str, timeout: float = 30) -> Run:
    deadline = time.monotonic() + timeout
    while True:
        r = llfsm(ns, *args)
        if needle in r.stdout or time.monotonic() > deadline:
            return r
        time.sleep(0.2)


def test_a_restart_over_dds_leaves_one_node_and_one_publisher(netns: NetNamespace, tmp_path: Path) -> None:
    run = netns.popen([sys.executable, "-m", "llfsm", "run", "--transport", "dds", bot(tmp_path), "--duration", "60"],
                      cwd=REPO)  # fmt: skip
    assert "/wall_bot" in until(netns, "node", "list", needle="/wall_bot").stdout
    for _ in range(2):
        r = llfsm(netns, "service", "call", "/llfsm/bot/restart", "std_srvs/srv/Trigger", "--timeout", "20")
        assert r.status == 0 and "success=True" in r.stdout, r.stderr
    # the restarted INITIAL runs and the old node's goodbye crosses in their own time (a second
    # was too short under load): until one node and one publisher, or a minute
    deadline = time.monotonic() + 60
    while True:
        nodes = llfsm(netns, "node", "list")
        info = llfsm(netns, "topic", "info", "/turtle1/cmd_vel")
        one = nodes.stdout.splitlines().count("/wall_bot") == 1 and "Publisher count: 1\n" in info.stdout
        if one or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    assert nodes.stdout.splitlines().count("/wall_bot") == 1, nodes.stdout
    assert "Publisher count: 1\n" in info.stdout, info.stdout
    run.terminate()
    _, _, err = finish(run, 20)
    assert "duplicate" not in err.lower() and "Traceback" not in err, err
