"""The gate in front of a machine's ringlet: how whatever changes a machine between its ringlets
(a control command, new values for its variables, a new input value) waits for the machine's
next turn and is applied there, never in the middle of a ringlet (docs/semantics.md); and
`finish`, which unloads a machine that reached an accepting state.

A held machine's `_run` points at the gate (`_hold`); its next turn goes through `_release`:
the inputs' snapshot, the variables, the pending command, then the real ringlet if the machine
is still to run.  A machine nothing holds runs its ringlet directly, so the round loops
(scheduler.py) pay nothing for the gate.  `Gated` is the arrangement's part that does this; the
scheduler's `Arrangement` is built on it and sets what it declares.
"""

from __future__ import annotations

from .machine import RESTART, RESUME, SUSPEND, Machine, UnknownMachineError

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable

    from .context import RunContext
    from .trace import Tracer


class Gated:
    """The machines of an arrangement, what is waiting for their next turn, and the gate that
    applies it.  What the gate reads of the arrangement is set by Arrangement.__init__
    (scheduler.py), which says what each is."""

    ctx: RunContext
    tracer: Tracer | None
    machines: list[Machine]
    by_name: dict[str, Machine]
    _attn: bool
    _variables: dict[int, dict[str, object]]
    _stopped: int | None
    on_release: Callable[[Machine], None] | None
    around_release: Callable[[Machine, Callable[[Machine], bool]], bool] | None

    @property
    def _attention(self) -> bool:
        """Something to look at before the next round: a command, an unload, an interrupt."""
        return self._attn

    @_attention.setter
    def _attention(self, value: bool) -> None:
        self._attn = value
        if value:
            self.ctx.wake = 0  # the round loops watch only the context's wake time

    # -- what machines call --------------------------------------------------------------
    def machine(self, name: str) -> Machine:
        try:
            return self.by_name[name]
        except (KeyError, TypeError):
            loaded = ", ".join(self.by_name) or "none"
            raise UnknownMachineError(f"no machine named {name!r} is loaded (loaded: {loaded})") from None

    def command(self, name: str, cmd: str) -> None:
        """Schedule a control command; it is applied at the start of the target's next ringlet."""
        m = self.machine(name)
        if m._finished and cmd != RESTART:
            return  # a finished machine can only be restarted; it stays finished until then
        m._pending = cmd  # a later command replaces an earlier pending one
        _hold(m)  # a machine commanding itself may still fire a transition: _rehold fixes that
        self._attention = True

    def hold_for_inputs(self, m: Machine) -> None:
        """A new input value came for `m` (llfsm.runtime.inputs): its next ringlet starts at the
        gate, which takes the snapshot first.  (Called during m's own ringlet, the ringlet may
        still point `_run` past the gate: `_rehold` puts it back after the round.)"""
        _hold(m)
        self._attention = True

    def set_variables(self, name: str, values: dict[str, object]) -> None:
        """Give machine variables new values (a machine's parameters set from outside,
        llfsm.ros.control): they take effect at the start of the machine's next ringlet, before
        a pending command, never in the middle of a ringlet.  Later values replace earlier ones."""
        m = self.machine(name)
        self._variables.setdefault(m._id, {}).update(values)
        _hold(m)  # the gate sets them; a machine setting its own may still fire: _rehold fixes that
        self._attention = True

    def suspend_now(self, m: Machine, remember: int | None) -> None:
        """Move `m` to its suspend state and run that state's OnEntry (no OnExit anywhere)."""
        m._resume_to = remember
        m._state = m.SUSPENDED
        m._suspended = True
        if self.tracer is not None:
            self.tracer.command("suspend", m, m.SUSPENDED)
            self.tracer.entry(m, m.SUSPENDED)
        enter = m.ENTER[m.SUSPENDED]
        m._run = enter
        enter(m)  # the suspend state's ringlet is its OnEntry only
        _hold(m)
        self._attention = True

    # -- control commands -------------------------------------------------------------------
    def _apply(self, m: Machine) -> bool:
        """Apply m's pending command; True if the ringlet goes on (step 2), False if it ends."""
        cmd, m._pending = m._pending, None
        self._attention = True
        tr = self.tracer
        if cmd == SUSPEND:
            if not m._suspended:
                hook = m.ON_SUSPEND[m._state]
                if hook is not None:
                    hook(m)
                self.suspend_now(m, remember=m._state)
            return False
        if cmd == RESUME:
            if not m._suspended:
                return True  # nothing to resume: an ordinary ringlet
            hook = m.ON_RESUME[m.SUSPENDED]
            if hook is not None:
                hook(m)
            target = m.INITIAL if m._resume_to is None else m._resume_to
            m._state, m._suspended, m._resume_to = target, False, None
            _regate(m, self._variables)
            hook = m.ON_RESUME[target]
            if hook is not None:
                hook(m)
            m._entered = True
            if tr is not None:
                tr.command("resume", m, target)
            return True
        # RESTART (which also brings a finished machine back)
        m._state, m._suspended, m._resume_to, m._entered = m.INITIAL, False, None, True
        m._finished = False
        _regate(m, self._variables)
        if tr is not None:
            tr.command("restart", m, m.INITIAL)
        return True

    def _release(self, m: Machine) -> bool:
        """The turn of a held machine: `_let_go`, through `around_release` when one is set."""
        around = self.around_release
        return self._let_go(m) if around is None else around(m, self._let_go)

    def _let_go(self, m: Machine) -> bool:
        """The turn of a held machine (a new input value to take, new variable values, a command
        pending, or suspended): take the inputs' snapshot, set the variables, apply the command;
        True if the ringlet goes on."""
        if self._stopped is not None:
            return False  # the run ends at this boundary (stop_at_boundary)
        if self.on_release is not None:
            self.on_release(m)
        inputs = m._inputs
        if inputs is not None and inputs.fresh:
            inputs.snapshot()
        if self._variables:
            values = self._variables.pop(m._id, None)
            if values is not None:
                for name, value in values.items():
                    setattr(m, name, value)
        if m._pending is not None:
            if not self._apply(m):
                return False  # the command (suspend) ended the ringlet
        elif m._suspended:
            return False  # suspended: no ringlet
        _regate(m, self._variables)
        return True

    def _gate(self, m: Machine) -> int | None:
        """Stands in for the ringlet of a held machine: release it, then run the real ringlet
        if that lets it go on."""
        return m._run(m) if self._release(m) else None

    def finish(self, m: Machine) -> None:
        """The machine has finished: unload it.  The hook generated code calls, from the ringlet
        of an accepting state, unless the run keeps accepting machines (`keep_accepting`)."""
        if self.tracer is not None:
            self.tracer.finish(m)
        m._finished = True
        m._suspended = False
        _regate(m, self._variables)
        self._attention = True
        self.ctx.references_dropped = True  # what it held is released between rounds
        self.ctx.wake = 0

    def _rehold(self) -> None:
        """Between rounds: a machine that commanded itself and then fired a transition in the
        same ringlet pointed `_run` past its gate; put the gate back in front."""
        for m in self.machines:
            inputs = m._inputs
            fresh = inputs is not None and inputs.fresh  # a new input value for its snapshot
            if m._pending is not None or m._suspended or m._id in self._variables or fresh:
                _hold(m)

    def hold(self, m: Machine) -> None:
        """Send m's next turn through the gate (and `on_release`): the debugger's pause before
        a turn.  The gate lets it go on as before once passed."""
        _hold(m)

    def hold_all(self) -> None:
        """Put the gate in front of every machine's next ringlet, so that whoever wraps the gate
        (`_gate_fn`: a monitor) is called at the next boundary, even inside a plain loop.  The
        gate lets a machine held for nothing else through at once."""
        for m in self.machines:
            _hold(m)


def _hold(m: Machine) -> None:
    """Put the gate in front of the machine's next ringlet (kept in `_next`)."""
    if m._run is not m._held:
        m._next, m._run = m._run, m._held


def _regate(m: Machine, variables: dict[int, dict[str, object]]) -> None:
    """Point the machine's `_run` at the gate while it is held (a command, suspended, new values
    for its variables waiting: `variables`, the arrangement's), at its next ringlet otherwise."""
    if m._pending is not None or m._suspended or m._id in variables:
        _hold(m)
    elif m._run is m._held:
        m._run = m._next
