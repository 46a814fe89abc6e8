"""The compiler: machine directories in, plain importable Python modules out.

- rewrite.py  bare names in user code -> machine attributes (`count` -> `self.count`)
- generate.py the module source for one checked machine (templates/machine.py.j2)
- build.py    incremental, atomic builds into an output folder
"""
