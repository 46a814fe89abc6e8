"""The machine language's front end: what a `NAME.machine/` folder says, read and checked from
its text alone (never imported or run).

- `discover`: which files make a machine directory, and where machines are;
- `model`, `reader`: machine.yaml and the code files, read into a `Machine`;
- `scopes`: which names a piece of code reads and binds (Python's scopes, from `ast`);
- `diagnostics`: the rule catalogue and the report formats;
- `check`: the rules themselves (`llfsm check`).

The compiler (llfsm.compiler) generates code from what this package hands it.
"""
