"""The machine language's front end: what a `NAME.machine/` folder says, read and checked from
its text alone (never imported or run).

- `discover`: where machines are below a folder (what one is on disk: llfsm.machinedir);
- `model`, `reader`: machine.yaml and the code files, read into a `Machine`;
- `positions`: lines and columns of source text as `ast` counts them;
- `scopes`: which names a piece of code reads that nothing binds (Python's scopes, from `ast`);
- `bindings`: which bare names are the machine's, where code uses them and binds them;
- `diagnostics`: the rule catalogue and the report formats;
- `check`: the rules themselves (`llfsm check`), a module per concern.

The compiler (llfsm.compiler) generates code from what this package hands it; nothing here
imports the compiler, the bus or the messages.
"""
