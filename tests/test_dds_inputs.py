"""Inputs bound to topics on `--transport dds` (SPEC 11): the wall follower in one process reads
its `wall_close` input from the wall sensor of turtlesim's process, over ROS 2's wire.  Runs in a
private network namespace (dds_netns.py)."""

from __future__ import annotations

import re
import signal

import pytest
from dds_netns import NetNamespace, Watched
from helpers import MACHINES


@pytest.mark.dds
def test_the_wall_follower_reads_its_sensor_from_another_process(netns: NetNamespace) -> None:
    sim = Watched(netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--node", "wall_sensor"))
    sim.wait_for(r"Spawning turtle \[turtle1\]")  # turtlesim's participant up first
    bot = Watched(netns.llfsm("run", "--transport", "dds", MACHINES / "wall_follower.machine", "-v"))
    # Ctrl-C once it has turned (a time counted from its start raced with a start-up that takes
    # seconds under load); the sensor's message is what makes it turn
    bot.wait_for(r"- wall_follower +- TURN\b")
    bot_status, _, bot_err = bot.finish(120, signal.SIGINT)
    sim_status, _, sim_err = sim.finish(120, signal.SIGINT)
    assert bot_status == 0 and sim_status == 0, bot_err + sim_err
    assert "Traceback" not in bot_err + sim_err
    states = re.findall(r"- wall_follower +- (\w+)", bot_err)
    assert "TURN" in states, "the sensor's messages never reached the input across processes"
    assert states[-1] == "END", bot_err
    assert "I hit the wall" not in sim_err
