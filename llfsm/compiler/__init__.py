"""The compiler: machine directories in, plain importable Python modules out.

It generates code from what the front end (llfsm.lang) hands it: a checked machine, its
parsed code, and which names are the machine's; it never reads a machine any other way.

- rewrite.py   applies the front end's name edits to user code (`count` -> `self.count`)
- literals.py  the literals and docstrings the module writes of its own, within 120 columns
- generate.py  the module source for one checked machine (templates/machine.py.j2), in named steps
- views.py     what the template renders: user code ready to go in, guards, states
- build.py     incremental, atomic builds into an output folder
- native.py    `--native`: modules and the runtime compiled with mypyc (docs/native.md)

docs/machine-format.md shows a generated module and how to read it.
"""
