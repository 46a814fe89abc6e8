"""llfsm: logic-labelled finite-state machines in Python, with clfsm's semantics."""

__version__ = "0.1.0"
