"""`llfsm launch`: several processes from one file in ROS 2's launch front ends (docs/launch.md).

- `frontend`: XML and YAML files as one tree of elements with their lines;
- `model`: the pydantic model of every tag and attribute, built from that tree;
- `substitutions`, `evaluate`: `$(var)`, `$(env)`, `$(find-pkg-share)`, `$(dirname)`, and
  `$(eval)` on arithmetic, comparisons and boolean logic only;
- `plan`: the walk (conditions, scopes, includes) into the processes to start, all checked
  before anything starts;
- `executables`: what a node's `pkg`/`exec` start (llfsm's nodes, `llfsm run`, installed
  machines), each on the DDS transport;
- `logs`, `supervisor`: the screen and the per-launch log folder; the processes started,
  prefixed, respawned and stopped.

The click command (llfsm.cli.launch) is its only caller.
"""

from __future__ import annotations

from collections.abc import Mapping

from .plan import OUTPUTS, ArgumentInfo, LaunchError, ProcessSpec, declared_arguments, plan

__all__ = [
    "OUTPUTS",
    "ArgumentInfo",
    "LaunchError",
    "ProcessSpec",
    "declared_arguments",
    "plan",
    "supervise",
]


def supervise(specs: list[ProcessSpec], environ: Mapping[str, str]) -> int:
    """Start the processes and supervise them until the launch ends; its exit status."""
    from .logs import LaunchLog  # deferred: start-up (`--show-args` and `--print` start nothing)
    from .supervisor import Supervisor

    log = LaunchLog(environ)
    try:
        return Supervisor(specs, log).run()
    finally:
        log.close()
