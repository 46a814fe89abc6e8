"""Nodes: Python participants on the bus beside the machines, started with `llfsm run --node NAME`.

Beside machines they never keep a run alive: the run ends when its machines do.  A run of
nodes alone (no machine) runs until Ctrl-C, SIGTERM or --duration, as `ros2 run` does (docs/turtlesim.md).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from ..runtime.context import RunContext

#: name -> module whose `start(ctx, options)` creates the node
REGISTRY = {
    "turtlesim": "llfsm.nodes.turtlesim",
    "turtle_sensor_poster": "llfsm.nodes.turtle_sensor_poster",
    "teleop": "llfsm.nodes.teleop",
    "wall_sensor": "llfsm.nodes.wall_sensor",
}


@dataclass
class NodeOptions:
    """What the command line passes on to nodes."""

    image: Path | None = None
    view: bool = False


class NodeError(Exception):
    """A node that cannot start (unknown name, missing optional dependency): exit status 2."""


def start(name: str, ctx: RunContext, options: NodeOptions) -> object:
    """Start the node `name` in the run of `ctx`; the node, for whoever serves it beside the run
    (the web view draws turtlesim's world)."""
    if name not in REGISTRY:
        raise NodeError(f"--node {name}: no such node (available: {', '.join(sorted(REGISTRY))})")
    module = importlib.import_module(REGISTRY[name])
    return module.start(ctx, options)
