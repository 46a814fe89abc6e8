"""The property language (SPEC 11, 16): one package that `llfsm verify`, a run's monitor, `llfsm
bag check` and the debugger's `--break` all use (docs/architecture.md, "The property language").

- `kinds`: the one table of property kinds (always, never, reachable, eventually, leads_to, ctl,
  ltl): how each is written, the formula it stands for, how verify and the monitor judge it,
  whether it takes `within:`; parsing, checking, exporting and help text read it.
- `atoms`: conditions (Python boolean expressions over states, variables, inputs, `published`),
  checked with `ast` and compiled, never `eval`ed as written; bounded (text, depth, repetition).
- `formula`: `ltl:`/`ctl:` text into formulas over atoms, bounded in depth and chain length.
- `parse`: a property from its kind and text: `parse_property(kind, text, infos)`.
- `automaton`: LTL to Büchi automata on the fly, bounded; `Verdict3`, LTL on a finite run.
- `graph`: strongly connected components and cycles (iterative), for the automata and verify.
- `file`: verification files (`NAME.verify.yaml`): machines, properties, options, bounds,
  the environment.

Evaluating atoms, live or on a snapshot.  `infos = infos_of(classes)` (a live run's machine
classes) or verify's `machine_infos(loaded)` say what atoms may name; `atom =
compile_atom(text, infos)` checks and compiles one (PropertyError, one line, otherwise);
`atom.fn(machines, published)` evaluates it on machine objects as they are now: a running
arrangement's `arr.machines` between two ringlets (the monitor, `--break`), or the objects
verify has put a configuration into.  `published` is the set of topics published since the
last ringlet boundary (the caller keeps it: a tap on the bus).  An evaluation is one call of a
compiled lambda over attribute reads; `atom.machines` (the load indices read) and
`atom.reads_published` let a caller skip ringlets that cannot change it.  An atom may raise
(a variable of another type than it expects, RepeatError past a bound): callers report it with
`atom.text` and `atom.where`.

Nothing here imports the bus, verify, or user code; the layers contract puts this package beside
`lang/`, below `verify/` and the monitor.
"""
