"""A launch file, read, checked and performed into the list of processes it starts.

launch runs a description's actions in order, performing each one's substitutions when it runs;
llfsm does the same walk before starting anything, so every mistake (a required argument not
given, an include that is missing or includes itself, a condition that is neither true nor
false, a package not found) is one line with its file and line, exit status 2, and nothing
started.  The walk follows launch's scoping:
- launch configurations (`arg`, `let`, an include's `arg`s, `push_ros_namespace`, which sets
  `ros_namespace`) and the environment (`set_env`, `unset_env`) are scoped by `group` (unless
  `scoped="false"`; `forwarding="false"` starts the group from its `keep`s and the launch's
  first environment);
- an `include` is not a scope: its arguments are set where it stands, and what the included
  file sets stays set after it, as IncludeLaunchDescription does;
- `arg` sets its default only when the argument was not given; a required one not given fails.
"""

from __future__ import annotations

import os
import shlex
import shutil
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import ModuleType

from .. import rosargs
from . import executables, frontend, model
from .model import Where
from .substitutions import Context, SubstitutionError, Text, literal, perform, show

#: Includes nested deeper than this are refused (a cycle is refused by name before that), and
#: so are more includes in all, or more processes, than this: a file that includes another ten
#: times, which includes a third ten times... would otherwise cost time exponential in its size.
MAX_INCLUDE_DEPTH = 32
MAX_INCLUDES = 256
MAX_PROCESSES = 256
#: `output` values, as launch.logging's aliases.
OUTPUTS = ("screen", "log", "both", "own_log", "full")
#: launch's defaults: ExecuteProcess's output, and the `sigterm_timeout` / `sigkill_timeout`
#: launch configurations.
DEFAULT_OUTPUT = "log"
DEFAULT_TIMEOUT = 5.0


class LaunchError(ValueError):
    """A launch file that cannot be launched as written: the message starts with FILE:LINE."""


@dataclass
class ProcessSpec:
    """One process to start, everything performed."""

    label: str  # `turtlesim_node-1`: the prefix of its output lines and the name of its log files
    argv: list[str]
    env: dict[str, str]
    where: Where
    cwd: str | None = None
    shell: bool = False
    output: str = DEFAULT_OUTPUT
    respawn: bool = False
    respawn_delay: float = 0.0
    respawn_max_retries: int = -1
    shutdown_on_exit: bool = False
    sigterm_timeout: float = DEFAULT_TIMEOUT
    sigkill_timeout: float = DEFAULT_TIMEOUT
    #: The llfsm node it is (teleop is told it has no terminal), if any.
    node: str | None = None
    #: Started through a launch-prefix (which may give it a terminal of its own).
    prefixed: bool = False

    @property
    def shown(self) -> str:
        return executables.shown(self.argv)


@dataclass
class ArgumentInfo:
    """A declared `arg`, for `--show-args`."""

    name: str
    description: str | None
    default: str | None
    choices: list[str] = field(default_factory=list)

    @property
    def described(self) -> str:
        """Its description as DeclareLaunchArgument words it (with its choices)."""
        if not self.choices:
            return self.description or "no description given"
        if self.description is None:
            return f"One of: {self.choices}"
        return f"{self.description.removesuffix('.')}. Valid choices are: {self.choices}"


@dataclass
class _Scope:
    configurations: dict[str, str]
    environment: dict[str, str]

    def copy(self) -> _Scope:
        return _Scope(dict(self.configurations), dict(self.environment))


@dataclass
class _Walk:
    first_environment: dict[str, str]
    processes: list[ProcessSpec] = field(default_factory=list)
    including: list[str] = field(default_factory=list)  # real paths of the files being walked
    read: dict[str, model.Launch] = field(default_factory=dict)  # each file is read once
    includes: int = 0


def load(path: str) -> model.Launch:
    """A launch file read and checked against the model; LaunchError with FILE:LINE."""
    try:
        return model.build(frontend.read(path))
    except (frontend.FrontEndError, model.ModelError) as e:
        raise LaunchError(str(e)) from None


def plan(path: str, arguments: Mapping[str, str], environ: Mapping[str, str]) -> list[ProcessSpec]:
    """The processes `llfsm launch PATH NAME:=VALUE...` starts, in order, with the environment
    `environ` (the launcher's); LaunchError with FILE:LINE for the first problem."""
    walk = _Walk(dict(environ))
    scope = _Scope(dict(arguments), dict(environ))
    _file(path, scope, walk, None)
    return walk.processes


def _file(path: str, scope: _Scope, walk: _Walk, included_at: Where | None) -> None:
    real = os.path.realpath(path)
    if real in walk.including:
        chain = [frontend.shown(p) for p in walk.including[walk.including.index(real) :]]
        raise LaunchError(f"{included_at}: include cycle: {' includes '.join([*chain, frontend.shown(path)])}")
    if len(walk.including) >= MAX_INCLUDE_DEPTH:
        raise LaunchError(f"{included_at}: includes nested deeper than {MAX_INCLUDE_DEPTH}")
    if included_at is not None:
        walk.includes += 1
        if walk.includes > MAX_INCLUDES:
            raise LaunchError(f"{included_at}: more than {MAX_INCLUDES} includes in one launch")
    root = walk.read.get(real)
    if root is None:
        root = walk.read[real] = load(path)
    walk.including.append(real)
    _entities(root.children, scope, walk)
    walk.including.pop()


def _entities(entities: Iterable[model.AnyEntity], scope: _Scope, walk: _Walk) -> None:
    for e in entities:
        ctx = Context(scope.configurations, scope.environment, e.where.file)
        if not _condition(e, ctx):
            continue
        if isinstance(e, model.Arg):
            _arg(e, scope, ctx)
        elif isinstance(e, model.Let):
            scope.configurations[_perform(e.name, ctx, e.where)] = _perform(e.value, ctx, e.where)
        elif isinstance(e, model.SetEnv):
            scope.environment[_perform(e.name, ctx, e.where)] = _perform(e.value, ctx, e.where)
        elif isinstance(e, model.UnsetEnv):
            scope.environment.pop(_perform(e.name, ctx, e.where), None)
        elif isinstance(e, model.PushRosNamespace):
            pushed = _perform(e.namespace, ctx, e.where)
            scope.configurations["ros_namespace"] = _namespace(
                scope.configurations.get("ros_namespace"), pushed, e.where
            )
        elif isinstance(e, model.Group):
            _group(e, scope, walk, ctx)
        elif isinstance(e, model.Include):
            for a in e.args:
                scope.configurations[_perform(a.name, ctx, a.where)] = _perform(a.value, ctx, a.where)
            _file(_existing(_perform(e.file, ctx, e.where), e.where, "launch file"), scope, walk, e.where)
        else:
            if len(walk.processes) >= MAX_PROCESSES:
                raise LaunchError(f"{e.where}: more than {MAX_PROCESSES} processes in one launch")
            walk.processes.append(_process(e, scope, ctx, len(walk.processes) + 1))


def _condition(e: model.Entity, ctx: Context) -> bool:
    """launch's IfCondition / UnlessCondition: `true`/`1` or `false`/`0`, any case, else an error."""
    text, negate, which = (e.if_, False, "if") if e.if_ is not None else (e.unless, True, "unless")
    if text is None:
        return True
    value = _truth(_perform(text, ctx, e.where), f"`{which}`", e.where)
    return value != negate


def _truth(value: str, what: str, where: Where) -> bool:
    v = value.strip().lower()
    if v in ("true", "1"):
        return True
    if v in ("false", "0"):
        return False
    raise LaunchError(f"{where}: {what} is {value!r}: expected true, false, 1 or 0")


def _arg(e: model.Arg, scope: _Scope, ctx: Context) -> None:
    if e.name not in scope.configurations:
        if e.default is None:
            about = f" ({e.description})" if e.description else ""
            raise LaunchError(
                f"{e.where}: the launch argument {e.name!r}{about} is required: give it as {e.name}:=VALUE"
            )
        scope.configurations[e.name] = _perform(e.default, ctx, e.where)
    choices = [c.value for c in e.choices]
    if choices and scope.configurations[e.name] not in choices:
        raise LaunchError(
            f"{e.where}: the launch argument {e.name!r} is {scope.configurations[e.name]!r}: "
            f"expected one of {', '.join(map(repr, choices))}"
        )


def _group(e: model.Group, scope: _Scope, walk: _Walk, ctx: Context) -> None:
    keeps = {_perform(k.name, ctx, k.where): _perform(k.value, ctx, k.where) for k in e.keeps}
    if not e.scoped:
        scope.configurations.update(keeps)
        _entities(e.children, scope, walk)
        return
    if e.forwarding:
        inner = scope.copy()
        inner.configurations.update(keeps)
    else:
        inner = _Scope(keeps, dict(walk.first_environment))
    _entities(e.children, inner, walk)


def _namespace(previous: str | None, pushed: str, where: Where) -> str:
    """launch_ros's prefix_namespace and make_namespace_absolute: a relative namespace goes under
    the previous one, an absolute one replaces it."""
    if previous and not pushed.startswith("/"):
        pushed = previous.rstrip("/") + "/" + pushed
    names = _ros_names()
    try:
        return names.normalise_namespace(pushed or "/")
    except names.InvalidNameError as e:
        raise LaunchError(f"{where}: {e}") from None


def _ros_names() -> ModuleType:
    """ROS 2's name rules, as `llfsm run` will apply them."""
    # deferred: start-up (llfsm.ros loads the whole rclpy look-alike; most launch files name no
    # node, namespace or remap, and every tenth of a second here delays every process)
    from ..ros import names

    return names


def _perform(text: Text, ctx: Context, where: Where) -> str:
    try:
        return perform(text, ctx)
    except SubstitutionError as e:
        raise LaunchError(f"{where}: {e}") from None


def _existing(path: str, where: Where, what: str) -> str:
    """A file named in a launch file: as given (relative to the current folder, as launch takes
    it), else relative to the launch file's folder; LaunchError when neither exists."""
    candidates = [path] if os.path.isabs(path) else [path, os.path.join(os.path.dirname(where.file), path)]
    for p in candidates:
        if os.path.isfile(p):
            return p
    if os.path.isdir(path):
        raise LaunchError(f"{where}: {what} {path!r} is a folder")
    raise LaunchError(f"{where}: no {what} {path!r}")


# -- processes ------------------------------------------------------------------------------------------
def split_command(text: Text, ctx: Context, where: Where) -> list[str]:
    """Words of a command line as launch's ExecuteProcess._parse_cmdline makes them: written
    text is split as a shell would (quotes group), a substitution's value is never split, and
    joins the word it touches."""
    words: list[str] = []
    word: list[str] | None = None
    for part in text:
        if not isinstance(part, str):
            word = (word or []) + [_perform((part,), ctx, where)]
            continue
        try:
            tokens = shlex.split(part)
        except ValueError as e:
            raise LaunchError(f"{where}: cannot split {show(text)!r}: {e}") from None
        if not tokens:
            if word is not None and part:
                words.append("".join(word))
                word = None
            continue
        if part[0].isspace() and word is not None:
            words.append("".join(word))
            word = None
        first, *rest = tokens
        word = (word or []) + [first]
        if rest:
            words.append("".join(word))
            words.extend(rest[:-1])
            word = [rest[-1]]
        if part[-1].isspace():
            words.append("".join(word))
            word = None
    if word is not None:
        words.append("".join(word))
    return words


def _process(e: model.Node | model.Executable, scope: _Scope, ctx: Context, number: int) -> ProcessSpec:
    where = e.where
    env = dict(scope.environment)
    for v in e.env:
        env[_perform(v.name, ctx, v.where)] = _perform(v.value, ctx, v.where)
    cwd = _perform(e.cwd, ctx, where) if e.cwd is not None else None
    if cwd is not None and not os.path.isdir(cwd):
        raise LaunchError(f"{where}: cwd {cwd!r} is not a folder")
    args = split_command(e.args, ctx, where) if e.args is not None else []
    node: str | None = None
    if isinstance(e, model.Node):
        argv, node, label = _node_argv(e, scope, ctx, args, cwd)
        if e.exec_name is not None:
            label = _perform(e.exec_name, ctx, where)
    else:
        if e.shell:  # the command as written, to the shell (launch joins its words with spaces)
            command = _perform(e.cmd, ctx, where)
            argv = ["/bin/sh", "-c", " ".join([command, *map(shlex.quote, args)])]
            first = command.split()[:1]
        else:
            words = split_command(e.cmd, ctx, where)
            argv = [_on_path(words[0], env, cwd, where), *words[1:], *args] if words else []
            first = words[:1]
        if not first:
            raise LaunchError(f"{where}: <executable> cmd is empty")
        label = _perform(e.name, ctx, where) if e.name is not None else os.path.basename(first[0])
    prefix = split_command(e.launch_prefix, ctx, where) if e.launch_prefix is not None else []
    if prefix:
        argv = [_on_path(prefix[0], env, cwd, where), *prefix[1:], *argv]
    if node is not None or argv[: len(executables.LLFSM)] == executables.LLFSM:
        env.setdefault("PYTHONUNBUFFERED", "1")  # its lines reach the launch as they are printed
    env.setdefault("LLFSM_TRANSPORT", "dds")  # an `executable` running llfsm is on the launch's wire too
    output = _perform(e.output, ctx, where) if e.output is not None else DEFAULT_OUTPUT
    if output not in OUTPUTS:
        raise LaunchError(f"{where}: output={output!r}: expected one of {', '.join(OUTPUTS)}")
    return ProcessSpec(
        label=f"{label}-{number}",
        argv=argv,
        env=env,
        where=where,
        cwd=cwd,
        shell=isinstance(e, model.Executable) and e.shell,
        output=output,
        respawn=_truth(_perform(e.respawn, ctx, where), "respawn", where) if e.respawn is not None else False,
        respawn_delay=_seconds(e.respawn_delay, "respawn_delay", 0.0, ctx, where),
        respawn_max_retries=_integer(e.respawn_max_retries, ctx, where),
        shutdown_on_exit=e.on_exit == "shutdown",
        sigterm_timeout=_timeout(e.sigterm_timeout, "sigterm_timeout", scope, ctx, where),
        sigkill_timeout=_timeout(e.sigkill_timeout, "sigkill_timeout", scope, ctx, where),
        node=node,
        prefixed=bool(prefix),
    )


def _node_argv(
    e: model.Node, scope: _Scope, ctx: Context, args: list[str], cwd: str | None
) -> tuple[list[str], str | None, str]:
    """A node's command line, the llfsm node it is, and its label when none is given."""
    where = e.where
    pkg = _perform(e.pkg, ctx, where) if e.pkg is not None else None
    exe = _perform(e.exec_, ctx, where)
    try:
        what = executables.started(pkg, exe)
    except executables.UnknownExecutable as err:
        raise LaunchError(f"{where}: {err}") from None
    if what.targets_in_args:
        _machines_exist(args, cwd, where)
    if what.llfsm:  # `llfsm run` reads the ROS arguments in `args` itself: checked here first
        for block in rosargs.blocks(args):
            _ros_args(block, where, "args")
    ros_args = _ros_args(split_command(e.ros_args, ctx, where), where, "ros_args") if e.ros_args is not None else []
    ros: list[str] = []
    if e.name is not None and not what.machines:
        # a node's name, as launch_ros passes it; a machine run holds several nodes (the
        # machine's own and /llfsm/M), which one name would make clash: there, `name` only
        # names the process (docs/launch.md)
        node_name = _perform(e.name, ctx, where)
        names = _ros_names()
        try:
            names.validate_node_name(node_name)
        except names.InvalidNameError as err:
            raise LaunchError(f"{where}: name: {err}") from None
        ros += ["--remap", f"__node:={node_name}"]
    ns = _perform(e.namespace, ctx, where) if e.namespace is not None else None
    base = scope.configurations.get("ros_namespace")
    if ns is not None or base is not None:
        ros += ["--remap", f"__ns:={_namespace(base, ns or '', where)}"]
    for p in e.params:
        ros += _param_args(p, "", ctx)
    for r in e.remaps:
        rule = f"{_perform(r.from_, ctx, r.where)}:={_perform(r.to, ctx, r.where)}"
        names = _ros_names()
        try:
            names.Remap.parse(rule)
        except names.InvalidNameError as err:
            raise LaunchError(f"{r.where}: {err}") from None
        ros += ["--remap", rule]
    # `ros_args` as launch_ros passes them: straight after `args`, before the node's own name,
    # namespace, parameters and remaps (which therefore win, as they do under ros2 launch)
    own = [rosargs.ROS_ARGS, *ros_args] if ros_args else []
    if not what.llfsm:  # a command on PATH: ROS 2 arguments as launch_ros passes them
        ros = ["-r" if a == "--remap" else a for a in ros]
        argv = [_on_path(exe, scope.environment, cwd, where), *args, *own, *([rosargs.ROS_ARGS, *ros] if ros else [])]
        return argv, None, os.path.basename(exe)
    label = exe
    if what.machines and e.name is not None:
        label = _perform(e.name, ctx, where)
    elif what.targets_in_args:
        label = _first_machine(args) or exe
    return [*executables.LLFSM, *what.args, *args, *([*own, "--"] if own else []), *ros], what.node, label


def _param_args(p: model.Param, prefix: str, ctx: Context) -> list[str]:
    """`-p NAME:=VALUE` for a parameter (nested names joined by dots), `--params-file F` for `from`."""
    if p.from_ is not None:
        return ["--params-file", _existing(_perform(p.from_, ctx, p.where), p.where, "params file")]
    assert p.name is not None
    name = prefix + _perform(p.name, ctx, p.where)
    if p.params:
        return [a for q in p.params for a in _param_args(q, name + ".", ctx)]
    assert p.value is not None
    return ["-p", f"{name}:={_param_text(p.value, p, ctx)}"]


def _param_text(v: model.ParamValue, p: model.Param, ctx: Context) -> str:
    """The value as `-p` reads it (YAML): a quoted YAML string, or one of `type="str"`, stays a
    string; `value-sep` makes a list."""
    kind = (p.type or "yaml").removeprefix("list_of_")
    if v.items is not None:
        return "[" + ", ".join(_param_text(x, p, ctx) for x in v.items) + "]"
    text = _perform(v.text, ctx, p.where)
    if p.value_sep is not None and v is p.value:
        return "[" + ", ".join(_typed(x.strip(), kind, p) for x in text.split(p.value_sep)) + "]"
    return _typed(text, "str" if v.quoted else kind, p)


def _typed(text: str, kind: str, p: model.Param) -> str:
    """One value for `-p`, checked against its `type`."""
    if kind == "str":
        return "'" + text.replace("'", "''") + "'"
    try:
        if kind == "int":
            int(text)
        elif kind == "float":
            float(text)
        elif kind == "bool" and text.lower() not in ("true", "false"):
            raise ValueError(text)
    except ValueError:
        raise LaunchError(f"{p.where}: {text!r} is not of type {p.type}") from None
    return text


def _ros_args(words: list[str], where: Where, attr: str) -> list[str]:
    """ROS arguments for `llfsm run` (a node's `ros_args`, or a `--ros-args` block of its `args`),
    checked as `llfsm run` will read them: what it takes (llfsm.rosargs), each remap a remap,
    each parameter NAME:=VALUE, each log level a level, each params file there (its path as
    found: beside the launch file, as `param from=`).  The words, or LaunchError at `where`."""
    try:
        pairs = rosargs.options(words)
    except rosargs.RosArgsError as e:
        raise LaunchError(f"{where}: {attr}: {e.word}: {e.why}") from None
    out: list[str] = []
    for option, value in pairs:
        if value is None:
            out.append(option)
            continue
        if option == "--params-file":
            value = _existing(value, where, "params file")
        else:
            try:
                _check_ros_value(option, value)
            except ValueError as err:  # its words name the option and the value
                raise LaunchError(f"{where}: {attr}: {err}") from None
        out += [option, value]
    return out


def _check_ros_value(option: str, value: str) -> None:
    """ValueError when `llfsm run` would refuse `option value`."""
    # deferred: start-up (as _ros_names: only a node with ROS arguments needs llfsm.ros)
    if option in ("-r", "--remap"):
        names = _ros_names()
        try:
            names.Remap.parse(value)
        except names.InvalidNameError as err:
            message = str(err)
            raise ValueError(message if message.startswith("--remap") else f"{option} {value}: {message}") from None
    elif option in ("-p", "--param"):
        from ..ros.parameter_files import parse_param

        parse_param(value)
    elif option == "--log-level":
        from ..ros.logging import parse_log_level

        parse_log_level(value)


def _machines_exist(args: list[str], cwd: str | None, where: Where) -> None:
    """The machine directories `llfsm run` is given exist (its other mistakes it reports itself)."""
    for a in args:
        if not a.startswith("-") and a.rstrip("/").endswith(".machine"):
            path = a if os.path.isabs(a) or cwd is None else os.path.join(cwd, a)
            if not os.path.isdir(path):
                raise LaunchError(f"{where}: no machine directory {a!r}")


def _first_machine(args: list[str]) -> str | None:
    for a in args:
        if not a.startswith("-") and a.rstrip("/").endswith(".machine"):
            return os.path.basename(a.rstrip("/")).removesuffix(".machine")
    return None


def _on_path(command: str, env: Mapping[str, str], cwd: str | None, where: Where) -> str:
    """The command's path, found as the process will find it (its PATH); LaunchError if none."""
    if os.sep in command:
        path = command if os.path.isabs(command) or cwd is None else os.path.join(cwd, command)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return command
        raise LaunchError(f"{where}: no executable {command!r}")
    found = shutil.which(command, path=env.get("PATH", os.defpath))
    if found is None:
        raise LaunchError(f"{where}: no executable {command!r} on PATH")
    return command


def _timeout(text: Text | None, what: str, scope: _Scope, ctx: Context, where: Where) -> float:
    """The process's own timeout, else the launch configuration of that name (launch's
    `sigterm_timeout:=10` on the command line), else launch's 5 s."""
    if text is None:
        text = (scope.configurations.get(what, str(DEFAULT_TIMEOUT)),)
    return _seconds(text, what, DEFAULT_TIMEOUT, ctx, where)


def _seconds(text: Text | None, what: str, default: float, ctx: Context, where: Where) -> float:
    if text is None:
        return default
    try:
        return model.seconds(_perform(text, ctx, where), what)
    except ValueError as e:
        raise LaunchError(f"{where}: {e}") from None


def _integer(text: Text | None, ctx: Context, where: Where) -> int:
    if text is None:
        return -1
    value = _perform(text, ctx, where)
    try:
        return int(value)
    except ValueError:
        raise LaunchError(f"{where}: respawn_max_retries takes a whole number, not {value!r}") from None


def declared_arguments(path: str, arguments: Mapping[str, str], environ: Mapping[str, str]) -> list[ArgumentInfo]:
    """Every `arg` of the file and of the files it includes (those whose path can be worked out
    from defaults), conditions aside, as `ros2 launch --show-args` lists them."""
    out: list[ArgumentInfo] = []
    seen: set[str] = set()

    def visit(p: str, configurations: dict[str, str]) -> None:
        real = os.path.realpath(p)
        if real in seen:
            return
        seen.add(real)
        root = load(p)
        stack: list[model.AnyEntity] = list(reversed(root.children))
        while stack:
            e = stack.pop()
            ctx = Context(configurations, dict(environ), e.where.file)
            if isinstance(e, model.Arg):
                default = None if e.default is None else (literal(e.default) or show(e.default))
                out.append(ArgumentInfo(e.name, e.description, default, [c.value for c in e.choices]))
                if e.name not in configurations and e.default is not None:
                    try:
                        configurations[e.name] = perform(e.default, ctx)
                    except SubstitutionError:
                        pass
            elif isinstance(e, model.Group):
                stack.extend(reversed(e.children))
            elif isinstance(e, model.Include):
                try:
                    included = _existing(perform(e.file, ctx), e.where, "launch file")
                except (SubstitutionError, LaunchError):
                    continue
                visit(included, configurations)

    visit(path, dict(arguments))
    return out
