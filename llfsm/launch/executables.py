"""What a `node`'s `pkg` and `exec` start: llfsm's nodes and machines on the DDS transport.

ROS 2's launch finds `lib/<pkg>/<exec>` under the prefixes of AMENT_PREFIX_PATH; llfsm has no
C++ nodes to find, so the pairs a ROS 2 user writes for turtlesim, its teleop and the how-to's
pose service are llfsm's own nodes, and machines run with `llfsm run` (docs/launch.md):

| pkg / exec | runs |
|---|---|
| turtlesim / turtlesim_node | `llfsm run --transport dds --node turtlesim` |
| turtlesim / turtle_teleop_key | `llfsm run --transport dds --node teleop` (a launched process has no terminal) |
| turtle_sensor_poster / turtle_sensor_poster_node | `llfsm run --transport dds --node turtle_sensor_poster` |
| llfsm / NODE (turtlesim, teleop, turtle_sensor_poster, wall_sensor) | `llfsm run --transport dds --node NODE` |
| llfsm / run, clfsm / clfsm | `llfsm run --transport dds ARGS` (the how-to's `ros2 run clfsm clfsm -v M.machine`) |
| P / MACHINE, installed by colcon | `llfsm run --transport dds P/MACHINE`, as llfsm.targets finds it |
"""

from __future__ import annotations

import os
import shlex
import sys
from dataclasses import dataclass

from ..nodes import REGISTRY

#: ROS 2's names for the nodes llfsm ships.
_ROS_NODES = {
    ("turtlesim", "turtlesim_node"): "turtlesim",
    ("turtlesim", "turtle_teleop_key"): "teleop",
    ("turtle_sensor_poster", "turtle_sensor_poster_node"): "turtle_sensor_poster",
}
#: Every pair that starts a node: ROS 2's names, and llfsm's own (`pkg="llfsm" exec="turtlesim"`).
NODES: dict[tuple[str, str], str] = {**_ROS_NODES, **{("llfsm", name): name for name in REGISTRY}}
#: Pairs whose `args` are `llfsm run`'s (targets and options).
RUNNERS = frozenset({("llfsm", "run"), ("clfsm", "clfsm")})
#: How a launched llfsm process is started, and how it is shown.
LLFSM = [sys.executable, "-m", "llfsm"]
RUN_PREFIX = ["run", "--transport", "dds"]


class UnknownExecutable(ValueError):
    """A pkg/exec pair llfsm cannot start (the message says what it can)."""


@dataclass(frozen=True)
class Started:
    """What a node starts: `llfsm run` arguments (after `llfsm`), or a command of its own."""

    args: tuple[str, ...]
    llfsm: bool = True
    #: The llfsm node it is (`--node NAME`), if it is one.
    node: str | None = None
    #: A run of machines (several nodes: the machines' own and their /llfsm/M nodes).
    machines: bool = False
    #: Its machines are given by `args` (`llfsm run`'s targets): their paths are checked first.
    targets_in_args: bool = False


def started(pkg: str | None, exe: str) -> Started:
    """What `node pkg=... exec=...` starts; UnknownExecutable when llfsm has nothing by that name."""
    if pkg is None:  # launch_ros: `exec` alone is a command on PATH
        return Started((exe,), llfsm=False)
    node = NODES.get((pkg, exe))
    if node is not None:
        return Started((*RUN_PREFIX, "--node", node), node=node)
    if (pkg, exe) in RUNNERS:
        return Started(tuple(RUN_PREFIX), machines=True, targets_in_args=True)
    # deferred: start-up (only a node from an installed package reads the colcon prefixes)
    from ..targets import TargetError, find_installed

    try:
        find_installed(f"{pkg}/{exe}")  # as the launched `llfsm run P/MACHINE` will find it
    except TargetError as e:
        why = str(e).removeprefix(f"{pkg}/{exe}: ")
        if _has_machines(pkg):
            raise UnknownExecutable(f"pkg={pkg!r} exec={exe!r}: {why}") from None
        known = ", ".join(f"{p}/{x}" for p, x in _ROS_NODES)
        raise UnknownExecutable(
            f"pkg={pkg!r} exec={exe!r}: not one of llfsm's nodes ({known}, llfsm/run), "
            f"nor an installed llfsm machine ({why})"
        ) from None
    return Started((*RUN_PREFIX, f"{pkg}/{exe}"), machines=True)


def _has_machines(pkg: str) -> bool:
    """An installed package of llfsm machines by that name is on AMENT_PREFIX_PATH."""
    for prefix in filter(None, os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)):
        share = os.path.join(prefix, "share", pkg)
        if os.path.isdir(os.path.join(share, "llfsm")) or os.path.isdir(os.path.join(share, "machine")):
            return True
    return False


def shown(argv: list[str]) -> str:
    """A command line as the user would type it (`llfsm run ...`, not the interpreter's path)."""
    if argv[: len(LLFSM)] == LLFSM:
        argv = ["llfsm", *argv[len(LLFSM) :]]
    return shlex.join(argv)
