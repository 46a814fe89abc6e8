"""TYPE strings to classes for every verb group: `pkg/msg/Name` (or `pkg/Name`, as `ros2`
accepts) to llfsm's message, service and action classes, a mistake being the verbs' one-line
usage error; and the working directory on the interface search path, where a user's packages
sit.  The lookup itself is llfsm/msgs/_lookup.py, which the web view reads TYPEs through too (a
layer below both).  Shared by the verb groups (topic, service, action, interface), so none of
them imports another.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from ..msgs import Message, Service, _lookup, add_search_path
from ..msgs._lookup import TypeNameError
from ..msgs._message import Action
from . import CliError

_T = TypeVar("_T")


def use_working_directory(cwd: str | os.PathLike[str] | None = None) -> None:
    """Search the working directory and its three parents for interface packages, as `llfsm
    run` searches the folders above its machines."""
    here = Path(os.path.realpath(cwd or os.getcwd()))
    for folder in [here, *list(here.parents)[:3]]:
        add_search_path(folder)


def _as_usage_error(lookup: Callable[..., _T], *args: str) -> _T:
    """The lookup's answer, or its one-line TypeNameError as the verbs' usage error (status 2)."""
    try:
        return lookup(*args)
    except TypeNameError as e:
        raise CliError(str(e)) from None


def split_type(text: str, kind: str) -> tuple[str, str, str]:
    """("turtlesim", "srv", "Spawn") from "turtlesim/srv/Spawn" or "turtlesim/Spawn"; `kind`
    is what a two-part name means.  Anything else is a usage error."""
    return _as_usage_error(_lookup.split_type, text, kind)


def message_class(text: str) -> type[Message]:
    """The message class that TYPE names (`std_msgs/msg/String`, `std_msgs/String`)."""
    return _as_usage_error(_lookup.message_class, text)


def service_class(text: str) -> type[Service]:
    """The service class that TYPE names (`turtlesim/srv/Spawn`, `turtlesim/Spawn`)."""
    return _as_usage_error(_lookup.service_class, text)


def action_class(text: str) -> type[Action]:
    """The action class that TYPE names (`turtlesim/action/RotateAbsolute`)."""
    return _as_usage_error(_lookup.action_class, text)
