"""ROS 2's command-line arguments (`--ros-args -r a:=b -p x:=1 --log-level debug --`) as `llfsm
run` takes them: one table for `llfsm run`, which reads them (llfsm.cli.run_args), and `llfsm
launch`, which passes a node's `ros_args` (and the ROS arguments in its `args`) straight to the
`llfsm run` it starts, after checking them, so that a mistake is one line with the launch file's
line before anything starts (llfsm.launch.plan).

llfsm takes ROS's spellings as its own options (-r/--remap, -p/--param, --params-file,
--log-level), so within a `--ros-args` block the markers only need to go; rcl's logging flags
have a spelling of llfsm's (`--enable-external-lib-logs` is `--log-file`); the rest of rcl's
arguments (an enclave, a logging configuration file, rosout and stdout switches) are refused
by name.

Standard library only, and light: `llfsm run` reads this on its start-up fast path.
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Sequence

#: What starts ROS arguments on a command line (`ros2 run PKG EXE --ros-args -r a:=b`); `--`
#: ends them.
ROS_ARGS = "--ros-args"
#: The ROS arguments that take a value: each is the `llfsm run` option of the same spelling.
WITH_VALUE = frozenset({"-r", "--remap", "-p", "--param", "--params-file", "--log-level"})
#: ROS arguments with a spelling of llfsm's own (None: nothing to do).
SPELLINGS = {"--enable-external-lib-logs": "--log-file", "--disable-external-lib-logs": None}
#: ROS arguments llfsm does not take (rcl's), named in the message that refuses them.
ROS_ONLY = frozenset(
    {"-e", "--enclave", "--log-config-file", "--enable-rosout-logs", "--disable-rosout-logs"}
    | {"--enable-stdout-logs", "--disable-stdout-logs"}
)
#: What the refusals say llfsm run takes.
TAKEN = "-r/--remap, -p/--param, --params-file, --log-level and --enable-external-lib-logs"


class RosArgsError(ValueError):
    """A ROS argument `llfsm run` does not take: `word`, and `why` (which says what it takes)."""

    def __init__(self, word: str, why: str) -> None:
        super().__init__(f"{ROS_ARGS} {word}: {why}")
        self.word, self.why = word, why


def without_ros_args(args: Sequence[str]) -> list[str]:
    """`args` with the `--ros-args` markers (and the `--` that closes their block) taken out
    and rcl's spellings of llfsm's options put in: what click and `llfsm run`'s parser then
    read.  RosArgsError for an argument of rcl's that llfsm does not take."""
    if ROS_ARGS not in args:
        return list(args)
    out: list[str] = []
    inside = False
    for arg in args:
        if arg == ROS_ARGS:
            inside = True
        elif inside and arg == "--":
            inside = False
        elif inside and arg in SPELLINGS:
            spelling = SPELLINGS[arg]
            if spelling is not None:
                out.append(spelling)
        elif inside and arg.partition("=")[0] in ROS_ONLY:
            raise RosArgsError(arg, f"llfsm run takes {TAKEN}")
        else:
            out.append(arg)
    return out


def blocks(args: Sequence[str]) -> list[list[str]]:
    """The words of each `--ros-args` block of a command line (up to `--` or the end)."""
    out: list[list[str]] = []
    block: list[str] | None = None
    for arg in args:
        if arg == ROS_ARGS:
            block = []
            out.append(block)
        elif block is not None and arg == "--":
            block = None
        elif block is not None:
            block.append(arg)
    return out


def options(words: Sequence[str]) -> list[tuple[str, str | None]]:
    """A block of ROS arguments as (option, value) pairs (value None for a flag): only what
    `llfsm run` takes, each option that takes a value with it (`--remap a:=b` or `--remap=a:=b`);
    RosArgsError for anything else."""
    out: list[tuple[str, str | None]] = []
    i = 0
    while i < len(words):
        word = words[i]
        i += 1
        name, eq, value = word.partition("=") if word.startswith("--") else (word, "", "")
        if name in WITH_VALUE:
            if not eq:
                if i == len(words) or words[i] == ROS_ARGS:
                    raise RosArgsError(word, f"takes a value ({TAKEN}, each with its value)")
                value = words[i]
                i += 1
            out.append((name, value))
        elif word in SPELLINGS:
            out.append((word, None))
        else:
            raise RosArgsError(word, f"llfsm run takes {TAKEN}")
    return out
