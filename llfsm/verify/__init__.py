"""`llfsm verify`: prove properties of an arrangement before it runs (docs/verify.md).

The compiled ringlets themselves are explored, breadth first, on snapshots taken from and put
back into the machine objects, so what is verified is what runs:

- `load`: the machines as `llfsm run` loads them (checked, read, cached), or a NAME.verify.yaml;
- `refuse`: what cannot be explored faithfully, one diagnostic per place (LF200-LF203), and each
  state's `after*` thresholds;
- `values`, `snapshot`: a machine's part of a configuration, by value, taken and put back;
- `explorer`: the configurations and steps (abstract or exact time, inputs, interrupts);
- `props`: the property language (atoms from `ast`, LTL and CTL formulas);
- `check`: one verification, safety on the fly, liveness by `ltl` (Büchi automata, fairness),
  `ctl` by fixpoints, over `graph`'s components;
- `report`, `export`, `replay`: what is printed, the SPIN/NuSMV/DOT exports, counterexample bags.

Nothing below this layer imports it; the click command (llfsm.cli.verify) is its only caller.
"""
