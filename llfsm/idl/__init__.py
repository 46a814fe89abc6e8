"""The interface toolchain: ROS `.msg` / `.srv` definitions into llfsm's message modules
(docs/bus.md, "Messages" and "Your own interfaces").

One way through, each stage a module:
- `spec`: what a definition says (packages, messages, services, fields, constants, name rules);
- `parser`: definition text into specs, with the file and line of a mistake;
- `package`: a folder in ROS layout read, checked and compiled into the cache (the builder the
  import hook of llfsm.msgs calls);
- `generate`: both generators over one package: `pygen` (the classes, templates/msgs.py.j2)
  and `ddsgen` (their DDS forms, templates/msgs_dds.py.j2: IdlStructs, the CDR code of
  `cdrgen`, the type hashes of `typehash`), laid out by `layout` as ruff formats;
- `shipped`: the shipped packages regenerated from llfsm/msgs/_interfaces/ (`python -m
  llfsm.idl`, `make msgs`).

The toolchain imports the run-time message base (llfsm.msgs._message); run time reaches the
toolchain through one door only, the import hook compiling a user's package.  Nothing at run
time imports this for a shipped message: the generated modules carry everything.
"""
