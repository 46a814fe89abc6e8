"""The options of `llfsm run`, in one table, and a small parser for the common cases.

The click command (llfsm.cli.run) is built from RUN_OPTIONS, and so is `parse`, the parser of
the start-up fast path: `llfsm run` without importing click saves a third of its start-up time.
Both hand the run its options as one llfsm.session.RunOptions, whose fields are the table's
keywords.
`parse` accepts only what it fully understands and what click would accept the same way;
anything else (--help, an unknown option, a value that does not convert, shell completion)
returns None, and the caller hands the whole command line to click, which gives its usual
message and status.  So the two can differ only in speed; tests/test_run_fast_path.py compares
`parse` with click's own parse of the same arguments.
"""

from __future__ import annotations

import os
import stat

from ..rosargs import RosArgsError, without_ros_args
from ._exits import duration_ns

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence
    from typing import Any

    from ..session import RunOptions

#: Kinds of option: how the value is converted (click: is_flag, str, click.Path(dir_okay=False),
#: click.Choice, Duration, float, click.IntRange(min=1)).
FLAG, TEXT, FILE, CHOICE, DURATION, FLOAT, COUNT = "flag", "text", "file", "choice", "duration", "float", "count"


class RunOption:
    """One option of `llfsm run`: its spellings, the keyword it fills, and how it converts."""

    __slots__ = ("choices", "default", "dest", "envvar", "flags", "help", "kind", "metavar", "multiple", "show_default")

    def __init__(
        self,
        flags: tuple[str, ...],
        dest: str,
        kind: str,
        help: str,
        *,
        default: Any = None,
        multiple: bool = False,
        choices: tuple[str, ...] = (),
        metavar: str | None = None,
        show_default: bool = False,
        envvar: str | None = None,
    ) -> None:
        self.flags = flags
        self.dest = dest
        self.kind = kind
        self.help = help
        self.default = default
        self.multiple = multiple
        self.choices = choices
        self.metavar = metavar
        self.show_default = show_default
        self.envvar = envvar


_O = RunOption
#: In the order `llfsm run --help` lists them.
RUN_OPTIONS: tuple[RunOption, ...] = (
    _O(
        ("-v", "--verbose"), "verbose", FLAG, "clfsm's trace on stderr: a line before each ringlet that enters a state."
    ),
    _O(("--trace",), "trace_file", FILE, "Write every event to FILE.jsonl."),
    _O(
        ("--clock",),
        "clock",
        CHOICE,
        "wall: real time; sim: virtual time, reproducible byte for byte.",
        choices=("wall", "sim"),
        default="wall",
        show_default=True,
    ),
    _O(("--period",), "period", DURATION, "Round period (time-triggered); sim default 1ms."),
    _O(
        ("--idle",),
        "idle",
        DURATION,
        "Wall clock: sleep after a round in which no transition fired.",
        default="10ms",
        show_default=True,
    ),
    _O(("--duration",), "duration", DURATION, "End the run after this much run time."),
    _O(
        ("--grace",),
        "grace",
        DURATION,
        "After Ctrl-C/SIGTERM, keep running rounds this long so machines can reach END.",
        default="1s",
        show_default=True,
    ),
    _O(("--suspended",), "suspended", TEXT, "Load MACHINE suspended.", multiple=True, metavar="MACHINE"),
    _O(("--keep-accepting",), "keep_accepting", FLAG, "Keep machines loaded in accepting states."),
    _O(
        ("--node",),
        "nodes",
        TEXT,
        "Start a node beside the machines: turtlesim, turtle_sensor_poster, teleop.",
        multiple=True,
        metavar="NAME",
    ),
    _O(
        ("-r", "--remap"),
        "remaps",
        TEXT,
        "Remap a topic or service name, as ros2's -r.",
        multiple=True,
        metavar="[NODE:]FROM:=TO",
    ),
    _O(
        ("-p", "--param"),
        "params",
        TEXT,
        "Set a parameter of every node (NAME:=VALUE) or of one (NODE:NAME:=VALUE), as ros2's -p.",
        multiple=True,
        metavar="[NODE:]NAME:=VALUE",
    ),
    _O(
        ("--params-file",),
        "params_files",
        TEXT,
        "Set parameters from a ROS 2 params file (node: {ros__parameters: {...}}, /** wildcards).",
        multiple=True,
        metavar="FILE",
    ),
    _O(
        ("--log-level",),
        "log_levels",
        TEXT,
        "Log level of every logger, or of logger NAME: debug, info, warn, error, fatal (as ros2's --log-level).",
        multiple=True,
        metavar="[NAME:=]LEVEL",
    ),
    _O(
        ("--log-file",),
        "log_file",
        FLAG,
        "Also write the log lines to a file in ~/.ros/log (ROS_LOG_DIR, ROS_HOME), as ROS 2 nodes do.",
    ),
    _O(("--echo",), "echoes", TEXT, "Print the topic's messages as YAML.", multiple=True, metavar="TOPIC"),
    _O(("--image",), "image", FILE, "turtlesim: write the picture (.png or .svg) at the end."),
    _O(("--view",), "view", FLAG, "turtlesim: open a live window (needs pygame)."),
    _O(("--introspect",), "introspect", FLAG, "At the end, print the nodes, topics and services on stderr."),
    _O(
        ("--web",),
        "web",
        TEXT,
        "Serve a live web view of the run (127.0.0.1 unless HOST is given; 0: a free port). Needs llfsm[web].",
        metavar="[HOST:]PORT",
    ),
    _O(
        ("--transport",),
        "transport",
        CHOICE,
        "inproc: the in-process bus; dds: ROS 2's wire (Cyclone DDS), seen by other processes and ROS 2 nodes. "
        "Also LLFSM_TRANSPORT.",
        choices=("inproc", "dds"),
        default="inproc",
        envvar="LLFSM_TRANSPORT",
        show_default=True,
    ),
    # -- bags (llfsm.bag) --
    _O(("--record",), "record", TEXT, "Record every message on the bus into the rosbag2 bag DIR.", metavar="DIR"),
    _O(("--record-topic",), "record_topics", TEXT, "Record only TOPIC (repeatable).", multiple=True, metavar="TOPIC"),
    _O(
        ("--storage",),
        "storage",
        CHOICE,
        "--record: the bag's storage.",
        choices=("mcap", "sqlite3"),
        default="mcap",
        show_default=True,
    ),
    _O(("--play",), "play", TEXT, "Publish the messages of the bag DIR at their recorded times.", metavar="DIR"),
    _O(("--play-topic",), "play_topics", TEXT, "Play only TOPIC (repeatable).", multiple=True, metavar="TOPIC"),
    _O(("--play-rate",), "play_rate", FLOAT, "--play: time scale (2 = twice as fast).", default=1.0, show_default=True),
    _O(("--native",), "native", FLAG, "Run machines compiled with mypyc (see docs/native.md)."),
    # -- the monitor (llfsm.monitor, docs/monitor.md) --
    _O(
        ("--monitor",),
        "monitor",
        TEXT,
        "Judge the properties of FILE.verify.yaml while the run goes on.",
        metavar="FILE",
    ),
    _O(
        ("--monitor-property",),
        "monitor_properties",
        TEXT,
        "Judge a property while the run goes on (repeatable).",
        multiple=True,
        metavar="KIND:TEXT",
    ),
    _O(
        ("--on-violation",),
        "on_violation",
        CHOICE,
        "What a violated property does: log it, pause the run (the debugger), or stop it (exit status 4).",
        choices=("log", "pause", "stop"),
        default="log",
        show_default=True,
    ),
    # -- the debugger (llfsm.debug, docs/debug.md) --
    _O(("--paused",), "paused", FLAG, "Start paused (the debugger: a prompt on the terminal, or the page)."),
    _O(
        ("--break",),
        "breaks",
        TEXT,
        'Pause where EXPR becomes true: state(m) == "S", m.count > 3, fired(m, "S", 0)... (repeatable).',
        multiple=True,
        metavar="EXPR",
    ),
    _O(
        ("--history",),
        "history",
        COUNT,
        "Keep the last N ringlets for the debugger (the page keeps 1000).",
        metavar="N",
    ),
    _O(
        ("--debug-prompt",),
        "debug_prompt",
        FLAG,
        "The debugger's (llfsm) prompt on standard input, with --web too (scripts drive it through a pipe).",
    ),
)
del _O

#: The positional argument (click: nargs=-1, not required).
TARGETS = "targets"
#: The environment variable with which click would complete the command line instead of running it.
COMPLETE_VAR = "_LLFSM_COMPLETE"

_BY_FLAG = {flag: opt for opt in RUN_OPTIONS for flag in opt.flags}


class _Delegate(Exception):
    """Something `parse` leaves to click (which then reports it, or does it)."""


def _convert(opt: RunOption, text: str) -> Any:
    """The value click would give `opt` for `text`, or _Delegate where click would complain."""
    if opt.kind == TEXT:
        return text
    if opt.kind == CHOICE:
        if text not in opt.choices:
            raise _Delegate
        return text
    if opt.kind == FLOAT:
        try:
            return float(text)
        except ValueError:
            raise _Delegate from None
    if opt.kind == DURATION:
        try:
            return duration_ns(text)
        except ValueError:
            raise _Delegate from None
    if opt.kind == COUNT:  # click.IntRange(min=1)
        if not text.strip().lstrip("+").isdigit() or int(text) < 1:
            raise _Delegate
        return int(text)
    if opt.kind == FILE:  # click.Path(dir_okay=False): an existing path must be a readable non-directory
        try:
            st = os.stat(text)
        except OSError:
            return text  # not there yet: fine for an output file
        except ValueError:  # a NUL byte: click would not cope either
            raise _Delegate from None
        if stat.S_ISDIR(st.st_mode) or not os.access(text, os.R_OK):
            raise _Delegate
        return text
    raise AssertionError(opt.kind)


def run_options(args: Sequence[str], environ: Mapping[str, str] | None = None) -> RunOptions | None:
    """The options of `llfsm run ARGS`, or None when click should handle ARGS (see `parse`)."""
    keywords = parse(args, environ)
    if keywords is None:
        return None
    from ..session import RunOptions  # deferred: start-up (the click command reads this table for every verb)

    return RunOptions(**keywords)


def parse(args: Sequence[str], environ: Mapping[str, str] | None = None) -> dict[str, Any] | None:
    """The keyword arguments of the run for `llfsm run ARGS`, exactly as click would make them,
    or None when click should handle ARGS (help, errors, forms this parser does not take)."""
    environ = os.environ if environ is None else environ
    if COMPLETE_VAR in environ or os.name == "nt":  # completion; Windows, where click expands globs
        return None
    try:
        return _parse(args, environ)
    except _Delegate:
        return None


def _parse(args: Sequence[str], environ: Mapping[str, str]) -> dict[str, Any]:
    try:
        args = without_ros_args(args)
    except RosArgsError:
        raise _Delegate from None  # click says it
    given: dict[str, Any] = {}
    targets: list[str] = []
    i = 0
    while i < len(args):
        arg = args[i]
        i += 1
        if not arg.startswith("-"):
            targets.append(arg)
            continue
        name, eq, value = arg.partition("=") if arg.startswith("--") else (arg, "", "")
        opt = _BY_FLAG.get(name)
        if opt is None:  # --help, --, -, -vv, an unknown or misspelled option: click's to handle
            raise _Delegate
        if opt.kind == FLAG:
            if eq:
                raise _Delegate
            given[opt.dest] = True
            continue
        if not eq:
            if i >= len(args):
                raise _Delegate
            value = args[i]
            i += 1
            if value.startswith("-"):  # click would take it as the value; rare enough to leave to it
                raise _Delegate
        converted = _convert(opt, value)
        if opt.multiple:
            given.setdefault(opt.dest, []).append(converted)
        else:
            given[opt.dest] = converted
    out: dict[str, Any] = {TARGETS: tuple(targets)}
    for opt in RUN_OPTIONS:
        if opt.dest in given:
            value = given[opt.dest]
            out[opt.dest] = tuple(value) if opt.multiple else value
        elif opt.multiple:
            out[opt.dest] = ()
        elif opt.kind == FLAG:
            out[opt.dest] = False
        elif opt.envvar and environ.get(opt.envvar):
            out[opt.dest] = _convert(opt, environ[opt.envvar])
        elif opt.default is not None:
            out[opt.dest] = _convert(opt, opt.default) if isinstance(opt.default, str) else opt.default
        else:
            out[opt.dest] = None
    return out
