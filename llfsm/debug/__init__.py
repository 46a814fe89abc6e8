"""The debugger (SPEC 14, docs/debug.md): pause a run between ringlets, step it, stop it at
breakpoints, read and set its machines' variables, keep its history, and replay a recorded run.

- `debugger.py`: the `Debugger` of a run (pause, step, continue, the watcher, the pause loop);
- `breakpoints.py`: break expressions (the property language's atoms, and `fired`);
- `history.py`: the last N ringlets, and the arrangement as it was at any of them;
- `variables.py`: a machine read as plain values, and a typed set;
- `prompt.py`: the terminal's `(llfsm)` prompt;
- `services.py`: the same control as services over the graph;
- `replay.py`: a `--trace` file or a counterexample read back as a history.
"""
