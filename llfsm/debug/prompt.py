"""The debugger's prompt on the terminal, in pdb's manner (docs/debug.md, "In the terminal").

At each pause it prints where the run stands and reads commands after `(llfsm) `:

    c            continue                 s          step one ringlet
    n            step to the end of the round
    p [EXPR]     every machine, machine M, or an expression (`p ping.count + 1`)
    set M.V = VALUE                       set a variable or an input (VALUE in YAML)
    w            where: every machine's state
    b [EXPR]     add a breakpoint, or list them       cl [N]   clear one, or all
    hist [N]     the last N ringlets (10)             q        end the run, as Ctrl-C does
    h            this help                            (empty)  the last command again

Commands come from standard input, so a script or a test drives it through a pipe
(`--debug-prompt`); on a terminal, readline gives history and completion.  Everything it prints
goes to standard error: the run's standard output stays the machines' own.  It reads on a
thread of its own and hands each command to the scheduler's thread (`Debugger.submit`), which
carries it out between ringlets.  At the end of its input the prompt lets the run go on: with
nothing else to continue the run (no page), it clears the breakpoints and continues.
"""

from __future__ import annotations

import signal
import sys
import threading
from functools import partial
from typing import IO, Any

from ..props.atoms import PropertyError, compile_atom, infos_of
from ..runtime.generated import inputs_of
from ..runtime.readout import plain, variable_names
from .debugger import CONTINUE, ROUND, STEP, DebugError, Debugger
from .variables import as_yaml

PROMPT = "(llfsm) "
HELP = __doc__.split("\n\n")[2].rstrip() if __doc__ else ""
#: Records `hist` shows when not told how many.
HIST = 10
_NAMES = {
    "c": "continue",
    "cont": "continue",
    "continue": "continue",
    "s": "step",
    "step": "step",
    "n": "next",
    "next": "next",
    "p": "print",
    "print": "print",
    "set": "set",
    "w": "where",
    "where": "where",
    "b": "break",
    "break": "break",
    "cl": "clear",
    "clear": "clear",
    "hist": "hist",
    "history": "hist",
    "q": "quit",
    "quit": "quit",
    "h": "help",
    "help": "help",
    "?": "help",
}


class Prompt:
    """Reads commands at each pause of `debugger` (see the module's docstring)."""

    def __init__(
        self,
        debugger: Debugger,
        stdin: IO[str] | None = None,
        out: IO[str] | None = None,
        *,
        alone: bool = True,
    ) -> None:
        self.debugger = debugger
        self.stdin = stdin if stdin is not None else sys.stdin
        self.out = out if out is not None else sys.stderr
        #: Nothing but this prompt can continue the run (no page): at the end of input, continue for good.
        self.alone = alone
        self._cond = threading.Condition()
        self._served = 0  # the number of the last pause this prompt answered (Debugger.pauses)
        self._last = ""
        self.closed = False
        self._readline = self._use_readline()
        #: The terminal's settings before readline changed them: put back if the run ends while
        #: the prompt waits in the middle of a line (the reader thread never returns to do it).
        self._tty: Any = None
        if self._readline:
            try:
                import termios  # deferred: a terminal only

                self._tty = termios.tcgetattr(sys.stdin.fileno())
            except (ImportError, OSError, ValueError):
                self._tty = None
        debugger.listeners.append(self._changed)
        self._thread = threading.Thread(target=self._loop, name="llfsm-debug-prompt", daemon=True)
        self._thread.start()

    def _use_readline(self) -> bool:
        try:
            interactive = self.stdin is sys.stdin and sys.stdin.isatty() and sys.stdout.isatty()
        except (AttributeError, ValueError):
            return False
        if not interactive:
            return False
        try:
            import readline  # deferred: optional (not on every platform); only a terminal needs it
        except ImportError:
            return False
        readline.set_completer(self._complete)
        readline.set_completer_delims(" \t=")
        readline.parse_and_bind("tab: complete")
        return True

    def _complete(self, text: str, state: int) -> str | None:
        words = sorted(set(_NAMES))
        for m in self.debugger.arr.machines:
            words.append(m.NAME)
            names = variable_names(type(m)) + inputs_of(type(m))
            words += [f"{m.NAME}.{v}" for v in names]
        hits = [w for w in words if w.startswith(text)]
        return hits[state] if state < len(hits) else None

    # -- the scheduler's side ----------------------------------------------------------------------
    def _changed(self, debugger: Debugger) -> None:
        with self._cond:
            self._cond.notify_all()

    def _new_pause(self) -> bool:
        d = self.debugger
        return self.closed or (d.paused and d.pauses > self._served)

    def close(self) -> None:
        """The run ended: the reader stops waiting for another pause (and the terminal gets its
        settings back, should it be in the middle of reading a line)."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()
        if self._tty is not None and self._thread.is_alive():
            try:
                import termios  # deferred: a terminal only

                termios.tcsetattr(sys.stdin.fileno(), termios.TCSADRAIN, self._tty)
            except (ImportError, OSError, ValueError):
                pass

    # -- the reader's side --------------------------------------------------------------------------
    def _write(self, text: str) -> None:
        try:
            self.out.write(text if text.endswith("\n") else text + "\n")
            self.out.flush()
        except (OSError, ValueError):
            pass

    def _read(self) -> str | None:
        try:
            if self._readline:
                return input(PROMPT)
            self.out.write(PROMPT)
            self.out.flush()
            line = self.stdin.readline()
        except EOFError:
            return None
        except (OSError, ValueError):
            return None
        return line if line else None

    def _loop(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(self._new_pause)
                if self.closed:
                    return
                self._served = self.debugger.pauses
            self._write(f"> {self.debugger.where()}")
            while True:
                line = self._read()
                if line is None:
                    self._end_of_input()
                    return
                text = line.strip() or self._last
                if not text:
                    continue
                self._last = text
                try:
                    reply, resumed = self.debugger.submit(partial(self.execute, text)).result()
                except DebugError as e:
                    reply, resumed = f"*** {e}", False
                if reply:
                    self._write(reply)
                if resumed:
                    break

    def _end_of_input(self) -> None:
        self.closed = True

        def go_on() -> None:
            if self.alone:
                self.debugger.remove_break()
                self.debugger.listeners.remove(self._changed)
            if self.debugger.paused:
                self.debugger.resume(CONTINUE)

        self._write(
            "llfsm: end of the debugger's input: the run goes on" + (" without breakpoints" if self.alone else "")
        )
        try:
            self.debugger.submit(go_on).result()
        except DebugError:
            pass

    # -- the commands (scheduler's thread) ----------------------------------------------------------
    def execute(self, line: str) -> tuple[str, bool]:
        """Carry out one command line: (what to print, whether the run resumed)."""
        word, _, rest = line.strip().partition(" ")
        rest = rest.strip()
        name = _NAMES.get(word)
        if name is None:
            raise DebugError(f"unknown command {word!r} (h for help)")
        d = self.debugger
        if name == "continue":
            d.resume(CONTINUE)
            return "", True
        if name == "step":
            d.resume(STEP)
            return "", True
        if name == "next":
            d.resume(ROUND)
            return "", True
        if name == "print":
            return self._print(rest), False
        if name == "set":
            return self._set(rest), False
        if name == "where":
            return "\n".join([d.where(), *d.states()]), False
        if name == "break":
            if not rest:
                return "\n".join(f"{b.number}: {b.text}" for b in d.breaks.items) or "no breakpoints", False
            bp = d.add_break(rest)
            return f"breakpoint {bp.number}: {bp.text}", False
        if name == "clear":
            if rest and not rest.isdigit():
                raise DebugError("cl takes a breakpoint's number (b lists them), or nothing to clear them all")
            gone = d.remove_break(int(rest) if rest else None)
            return f"cleared {', '.join(str(b.number) for b in gone) or 'nothing'}", False
        if name == "hist":
            return self._hist(rest), False
        if name == "quit":
            d.arr.interrupt(signal.SIGINT)
            return "", True
        return HELP, False

    def _print(self, rest: str) -> str:
        d = self.debugger
        if not rest:
            return as_yaml(d.read()).rstrip()
        if rest in d.arr.by_name:
            return as_yaml(d.read(rest)).rstrip()
        try:
            atom = compile_atom(rest, infos_of([type(m) for m in d.arr.machines]), "p")
            value = atom.fn(d.arr.machines, ())
        except PropertyError as e:
            raise DebugError(str(e)) from None
        except Exception as e:  # evaluated on the live run: show what went wrong
            raise DebugError(f"{rest}: {type(e).__name__}: {e}") from None
        return _show(value)

    def _set(self, rest: str) -> str:
        target, eq, value = rest.partition("=")
        machine, dot, variable = target.strip().partition(".")
        if not eq or not dot or not variable.strip() or not value.strip():
            raise DebugError("write set M.VARIABLE = VALUE (VALUE in YAML: 3, 2.5, true, hello, [1, 2])")
        return self.debugger.set_value(machine.strip(), variable.strip(), value.strip())

    def _hist(self, rest: str) -> str:
        h = self.debugger.history
        if h is None:
            raise DebugError("no history is kept: run with --history N")
        if rest and not rest.isdigit():
            raise DebugError("hist takes how many ringlets to show")
        lines = []
        for r in h.last(int(rest) if rest else HIST):
            if r["kind"] == "set":
                what = "set by the debugger"
            elif r["state"] is None:
                what = f"{r['after']} (no ringlet: suspended)" if r["before"] == r["after"] else f"-> {r['after']}"
            elif r["transition"] is not None:
                what = f"{r['state']} -> {r['after']} (transition {r['transition']})"
            else:
                what = r["after"]
            changed = ", ".join(f"{k}: {_short(o)} -> {_short(n)}" for k, (o, n) in r["changed"].items())
            published = f"; published {', '.join(r['published'])}" if r["published"] else ""
            lines.append(
                f"{r['ringlet']:>6} r{r['round']} {r['t']:.3f}s {r['machine']}: {what}"
                + (f"; {changed}" if changed else "")
                + published
            )
        return "\n".join(lines) or "nothing yet"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:39] + "…"


def _show(value: Any) -> str:
    shown = plain(value)
    return as_yaml(shown).rstrip().removesuffix("\n...") if isinstance(shown, dict | list) else repr(shown)
