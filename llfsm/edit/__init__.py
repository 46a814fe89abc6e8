"""Editing machine directories: the library under the structure commands (`llfsm state ...`,
`llfsm transition ...`) and the editor's server (`llfsm edit`), so that the page and the commands
can never differ (SPEC 13).

Planning is pure: a planner reads the directory and returns a `Change` (every file it touches,
before and after) or raises `EditError` with the one line the user sees.  `apply` writes a
Change to every file or to none; `invert` is its undo.  Names are checked before any path is
built from them, no symlink is followed, machine.yaml keeps its comments and formatting.

- `change`: Change, EditError, apply, invert (atomic over files);
- `plan`: what the planners share (the directory as read, machine.yaml's round trip, names);
- `structure`: states and transitions, guards, the initial and the suspend state;
- `files`: a file written whole, a new machine, a whole machine (`llfsm import`), layout.yaml;
- `yaml_doc`: YAML files edited with their comments and indentation kept.
"""

from __future__ import annotations

from .change import Change, EditError, apply, invert
from .files import MachineExists, new_machine, set_layout, write_file, write_machine
from .structure import (
    DEFAULT_GUARD,
    set_description,
    set_guard,
    set_initial,
    set_suspend,
    state_add,
    state_remove,
    state_rename,
    transition_add,
    transition_move,
    transition_remove,
    transition_retarget,
)

__all__ = [
    "DEFAULT_GUARD",
    "Change",
    "EditError",
    "MachineExists",
    "apply",
    "invert",
    "new_machine",
    "set_description",
    "set_guard",
    "set_initial",
    "set_layout",
    "set_suspend",
    "state_add",
    "state_remove",
    "state_rename",
    "transition_add",
    "transition_move",
    "transition_remove",
    "transition_retarget",
    "write_file",
    "write_machine",
]
