"""What `llfsm run` does once its arguments are parsed: open the run's session
(llfsm.session.Session) with them, and turn how it ended into messages and the exit
status (docs/cli.md: `llfsm run`, exit statuses).

Free of click, so that the start-up fast path (llfsm.cli.main with llfsm.cli.run_args) can run a
machine without importing it; the click command (llfsm.cli.run) calls `run` too.
"""

from __future__ import annotations

import os
import sys

from ..session import RunOutcome, Session, SessionError
from ._exits import echo, fail

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any, NoReturn

    from ..session import RunOptions, WebPage


def run(options: RunOptions) -> NoReturn:
    """Run with these options; ends the process with the run's exit status."""
    web: WebPage | None = None
    if options.web is not None:
        from ._web import RunPage  # deferred: start-up (a run without --web never imports the page)

        web = RunPage(options.web)
    try:
        session = Session(options, web=web, say=echo)
        if options.native and not os.environ.get("LLFSM_NATIVE"):
            _run_native(options.targets)  # compiles (or finds) the native build, then runs in a fresh process
        outcome = session.run()
    except SessionError as e:
        exit_with(e)
    finish(outcome)


def exit_with(error: SessionError) -> NoReturn:
    """What the session could not do, as the user is told it, and its status."""
    if error.details:
        echo(error.details, nl=False)
    if error.message:
        echo(f"llfsm: {error.message}")
    sys.exit(error.status)


def finish(outcome: RunOutcome) -> NoReturn:
    """The run's report (an error in machine code, `--introspect`'s graph, lost outputs) and its
    exit status."""
    sys.stdout.flush()
    if outcome.result.error is not None:
        echo(outcome.result.error.format(), nl=False)
    if outcome.graph is not None:
        echo(_graph_text(outcome.graph), nl=False)
    for message in outcome.failed_outputs:
        echo(f"llfsm: {message}")
    sys.exit(outcome.status)


def _run_native(targets: tuple[str, ...]) -> None:
    """`--native`: build the targets' modules natively (one compile, cached), then start the
    same command again with LLFSM_NATIVE set, so that the compiled runtime is the one imported.
    Returns only when nothing could be compiled (the run then goes on as plain Python)."""
    # deferred: start-up (only --native loads the compiler)
    from pathlib import Path

    from ..cachedir import cache_root
    from ..compiler.native import ENV, NativeUnavailable, native_build
    from ..targets import InvalidMachine, MachineLoadError, TargetError, resolve

    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if getattr(spec, "name", None) != "llfsm.__main__" and Path(getattr(main, "__file__", "") or "").name != "llfsm":
        fail("--native starts the run in a fresh process: use it from the llfsm command")
    modules = []
    for t in targets:
        try:
            modules.append(resolve(t).resolve())
        except (TargetError, InvalidMachine, MachineLoadError):
            return  # the ordinary path reports it
    from ..progress import Status  # deferred: start-up (--native only)

    try:
        with Status().doing("native") as say:
            build = native_build(modules, cache_root(), say)
    except NativeUnavailable as e:
        fail(f"--native: {e}")
    for w in build.warnings:
        echo(w)
    if not any(build.modules.values()):
        return
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, [sys.executable, *sys.orig_argv[1:]], {**os.environ, ENV: str(build.folder)})


def _graph_text(graph: dict[str, Any]) -> str:
    out = ["nodes:"] + [f"  {n}" for n in graph["nodes"]] + ["topics:"]
    for name, t in graph["topics"].items():
        out.append(
            f"  {name} [{t['type']}] publishers: {t['publishers']}, subscriptions: {t['subscriptions']}, "
            f"messages: {t['messages']}"
        )
    out.append("services:")
    out += [f"  {name} [{typ}]" for name, typ in graph["services"].items()]
    return "\n".join(out) + "\n"
