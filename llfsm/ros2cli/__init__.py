"""The library under the ros2-style verbs (`llfsm topic|service|node|interface ...`).

The commands in llfsm/cli/ are thin: they parse arguments and print.  What they do lives here,
callable from tests without a subprocess:

- `interfaces`: TYPE strings (`pkg/msg/Name`, `pkg/Name`) to llfsm's classes, with a "did you
  mean" for near misses; `ros2 interface show`'s text of a definition.  Offline.
- `values`: VALUES (YAML as `ros2 topic pub` takes it) into a message, one clear line per mistake.
- `graph`: what the DDS graph holds (topics with types, services, nodes), formatted as `ros2 ...
  list` and `ros2 topic info` print it.  The reading itself is llfsm/ros/transports/dds_graph.py.
- `verbs`: echo, pub, hz and service call over DDS.

Errors the user causes are `CliError(message, status)`: the command prints the one line and
exits with the status (2 for bad input, 1 for nothing found).
"""

from __future__ import annotations


class CliError(Exception):
    """A mistake or an absence the user should read as one line, with the exit status to use."""

    def __init__(self, message: str, status: int = 2) -> None:
        super().__init__(message)
        self.message = message
        self.status = status


__all__ = ["CliError"]
