"""`RunOptions`: the options of `llfsm run` as one frozen value (llfsm.session's first part).

Both parsers build it (the click command, llfsm.cli.run, and the start-up fast path,
llfsm.cli.run_args, from the same table of options: its fields are that table's keywords).  A
plain class rather than a dataclass: `dataclasses` imports `inspect`, a fifth of a warm run's
start-up.
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any, NoReturn


# -- the options ---------------------------------------------------------------------------------
#: The targets, then the options in the order `llfsm run --help` lists them.
FIELDS = (
    "targets",
    "verbose",
    "trace_file",
    "clock",
    "period",
    "idle",
    "duration",
    "grace",
    "suspended",
    "keep_accepting",
    "nodes",
    "remaps",
    "params",
    "params_files",
    "log_levels",
    "log_file",
    "echoes",
    "image",
    "view",
    "introspect",
    "web",
    "transport",
    "record",
    "record_topics",
    "storage",
    "play",
    "play_topics",
    "play_rate",
    "native",
    "monitor",
    "monitor_properties",
    "on_violation",
    "paused",
    "breaks",
    "history",
    "debug_prompt",
)


class RunOptions:
    """What `llfsm run` was asked to do: the machines, the clock, and what opens beside them
    (transport, nodes, bags, web view).  Immutable: the session reads it, never changes it."""

    __slots__ = FIELDS

    targets: tuple[str, ...]
    verbose: bool
    trace_file: str | None
    clock: str  # wall | sim
    period: int | None  # ns
    idle: int  # ns
    duration: int | None  # ns
    grace: int  # ns
    suspended: tuple[str, ...]
    keep_accepting: bool
    nodes: tuple[str, ...]
    remaps: tuple[str, ...]
    params: tuple[str, ...]
    params_files: tuple[str, ...]
    log_levels: tuple[str, ...]
    log_file: bool
    echoes: tuple[str, ...]
    image: str | None
    view: bool
    introspect: bool
    web: str | None
    transport: str  # inproc | dds
    record: str | None
    record_topics: tuple[str, ...]
    storage: str  # mcap | sqlite3
    play: str | None
    play_topics: tuple[str, ...]
    play_rate: float
    native: bool
    monitor: str | None
    monitor_properties: tuple[str, ...]
    on_violation: str  # log | pause | stop
    paused: bool
    breaks: tuple[str, ...]
    history: int | None  # ringlets kept
    debug_prompt: bool

    def __init__(
        self,
        targets: tuple[str, ...] = (),
        *,
        verbose: bool = False,
        trace_file: str | None = None,
        clock: str = "wall",
        period: int | None = None,
        idle: int = 10_000_000,
        duration: int | None = None,
        grace: int = 1_000_000_000,
        suspended: tuple[str, ...] = (),
        keep_accepting: bool = False,
        nodes: tuple[str, ...] = (),
        remaps: tuple[str, ...] = (),
        params: tuple[str, ...] = (),
        params_files: tuple[str, ...] = (),
        log_levels: tuple[str, ...] = (),
        log_file: bool = False,
        echoes: tuple[str, ...] = (),
        image: str | None = None,
        view: bool = False,
        introspect: bool = False,
        web: str | None = None,
        transport: str = "inproc",
        record: str | None = None,
        record_topics: tuple[str, ...] = (),
        storage: str = "mcap",
        play: str | None = None,
        play_topics: tuple[str, ...] = (),
        play_rate: float = 1.0,
        native: bool = False,
        monitor: str | None = None,
        monitor_properties: tuple[str, ...] = (),
        on_violation: str = "log",
        paused: bool = False,
        breaks: tuple[str, ...] = (),
        history: int | None = None,
        debug_prompt: bool = False,
    ) -> None:
        given = locals()  # every parameter by name: one loop instead of 34 assignments
        for name in FIELDS:
            object.__setattr__(self, name, given[name])

    def replace(self, **changes: Any) -> RunOptions:
        """A copy with some options changed (as dataclasses.replace)."""
        return RunOptions(**{**self.as_dict(), **changes})

    def as_dict(self) -> dict[str, Any]:
        """The options as the keywords they were given with."""
        return {name: getattr(self, name) for name in FIELDS}

    def __setattr__(self, name: str, value: object) -> NoReturn:
        raise AttributeError(f"RunOptions is frozen: cannot set {name}")

    def __delattr__(self, name: str) -> NoReturn:
        raise AttributeError(f"RunOptions is frozen: cannot delete {name}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RunOptions):
            return NotImplemented
        return self.as_dict() == other.as_dict()

    def __hash__(self) -> int:
        return hash(tuple(self.as_dict().values()))

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={value!r}" for name, value in self.as_dict().items())
        return f"RunOptions({fields})"
