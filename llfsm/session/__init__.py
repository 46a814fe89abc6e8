"""The run session: everything `llfsm run` opens beside its machines, in one place (SPEC §2-§10).

- `options`: RunOptions, the options of `llfsm run` as one value (both parsers build it);
- `session`: Session, which loads the machines, opens the watchdog, transport, bus, nodes, bags,
  tracer, arrangement and web view in order, runs, and closes them whatever happened;
- `errors`: what a session raises instead of ending the process (usage error, machine error,
  lost output), with the exit status each means.

This package imports nothing itself: the click command needs only `options` (every `llfsm`
command loads it), and a run imports `session` when it starts.
"""
