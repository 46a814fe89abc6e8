"""The library under the ros2-style verbs (`llfsm topic|node|service|action|interface ...`), a
module per verb group as ros2cli has a package per verb group; the commands in llfsm/cli/ are
thin click layers over it, and tests call it without a subprocess.  No click here.

Verb groups (each verb a function named after it, `list_` and `type_` where Python has the
name):

- `topic/`: `list`, `info`, `type`, `find`, `echo`, `pub`, `hz`, a module each (the group is big).
- `node`: `list`, `info`.
- `service`: `list`, `type`, `find`, `call`.
- `action`: `list`, `info`, `send_goal` (docs/actions.md).
- `interface`: `show`, `list`, `package`.  Offline.

What the groups share:

- `discovery`: opening the DDS view of the ROS graph (llfsm/ros/transports/dds_graph.py),
  waiting for discovery, the domain named in "nothing found".
- `endpoints`: the verbs' own endpoints: a DataReader with ros2's QoS for the verbs that listen,
  a hidden node of llfsm's bus for the verbs that talk.  cyclonedds is optional and heavy:
  only here and in the verbs it is imported, inside functions (`llfsm --help` never loads it).
- `arguments`: topic and service names, VALUES (YAML as `ros2 topic pub` takes it).
- `lookup`: TYPE strings (`pkg/msg/Name`, `pkg/Name`) to llfsm's classes, as the verbs' usage
  errors, and the working directory on the interface search path.

The groups never import each other (the `verb-groups` contract of pyproject.toml): what two of
them need is one of these.

The close names the graph has, for the lines that say something was not found, are
llfsm.suggest's.

Adding a verb (as `service type` was): write `def type_(service: str, *, timeout: float = TIMEOUT)
-> str` in `service.py` (for `topic`, a new module such as `topic/find.py`), taking typed arguments
and returning the text `ros2` prints (or, for a verb that streams, writing to `out`); check
the user's input (names, TYPE, VALUES) before the domain is joined.  Then add its click
command to llfsm/cli/service.py (a new group: a new llfsm/cli/ module, registered in
llfsm/cli/_commands.py), calling the function and echoing its text; docs/cli.md lists the verbs.

Errors the user causes are `CliError(message, status)`: the command prints the one line and
exits with the status (2 for bad input, NOT_FOUND (1) for nothing found).
"""

from __future__ import annotations

#: The exit status of a verb that finds nothing (a topic, a message, a server) in time.
NOT_FOUND = 1
#: How long a list waits for discovery (`ros2 ... --no-daemon` spins 0.5 s; a loaded machine
#: needs a little more for the endpoints of every participant to arrive).
SPIN_TIME = 1.0
#: How long a verb waits for the topic, service or message it needs before it gives up.
TIMEOUT = 5.0


class CliError(Exception):
    """A mistake or an absence the user should read as one line, with the exit status to use."""

    def __init__(self, message: str, status: int = 2) -> None:
        super().__init__(message)
        self.message = message
        self.status = status


__all__ = ["NOT_FOUND", "SPIN_TIME", "TIMEOUT", "CliError"]
