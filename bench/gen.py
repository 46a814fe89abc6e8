"""Generate machine directories of a given size, for benchmarks and soak runs."""

from __future__ import annotations

from pathlib import Path


def write_toggle(root: Path, name: str = "toggle") -> Path:
    """Two states, guards `True`, OnEntry increments a variable: one fired transition per ringlet."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [B]\n  - name: B\n    transitions: [A]\n")
    for s in "AB":
        (d / f"State_{s}_Transition_0.expr").write_text("True\n")
        (d / f"State_{s}_OnEntry.py").write_text("count += 1\n")
    (d / "Variables.py").write_text("count: int = 0\n")
    return d


def write_bus_toggle(root: Path, name: str = "bus_toggle") -> Path:
    """The toggle, from a machine that uses the bus: its INITIAL makes a node with a 10 ms timer,
    a publisher and a callback subscriber, as every ROS run has, and keeps them in its variables
    (so the bus's lifetimes walk looks at them), then it toggles as `write_toggle` does."""
    d = write_toggle(root, name)
    (d / "machine.yaml").write_text(
        "states:\n  - name: INITIAL\n    transitions: [A]\n"
        "  - name: A\n    transitions: [B]\n  - name: B\n    transitions: [A]\n"
    )
    (d / "State_INITIAL_Transition_0.expr").write_text("True\n")
    (d / "State_INITIAL_OnEntry.py").write_text(
        "ros.init()\nnode = ros.Node('bench')\ntimer = node.create_timer(0.01, lambda: None)\n"
        "pub = node.create_publisher(String, '/chatter', 10)\n"
        "sub = node.create_subscription(String, '/chatter', lambda m: None, 10)\n"
    )
    (d / "Includes.py").write_text("from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n")
    (d / "Variables.py").write_text(
        "count: int = 0\nnode: ros.Node = None\ntimer: ros.Timer = None\npub: ros.Publisher = None\n"
        "sub: ros.Subscription = None\n"
    )
    return d


def write_idle(root: Path, name: str = "idle") -> Path:
    """One state whose only guard is false: every ringlet is idle (guard evaluated, nothing fires)."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text("states:\n  - name: WAIT\n    transitions: [END]\n  - name: END\n")
    (d / "State_WAIT_Transition_0.expr").write_text("stop\n")
    (d / "Variables.py").write_text("stop: bool = False\n")
    return d


def write_big(root: Path, name: str, states: int = 10) -> Path:
    """A machine of `states` states in a ring, with variables, code in every section and two
    guards per state: the kind of machine a real behaviour has, for check/build timings."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    names = [f"S{i}" for i in range(states - 1)] + ["END"]
    lines = [f"description: Generated machine {name} with {states} states.", "states:"]
    for i, s in enumerate(names[:-1]):
        nxt = names[i + 1]
        lines += [f"  - name: {s}", f"    transitions: [END, {nxt}]"]
        (d / f"State_{s}_OnEntry.py").write_text(f"visits += 1\nlast = {s!r}\nscratch = [x * 2 for x in range(3)]\n")
        (d / f"State_{s}_Internal.py").write_text("ticks += 1\n")
        (d / f"State_{s}_OnExit.py").write_text("if ticks > limit:\n    ticks = 0\n")
        (d / f"State_{s}_Transition_0.expr").write_text("visits > limit * 100 and not running\n")
        (d / f"State_{s}_Transition_1.expr").write_text(f"after_ms({(i % 5) + 1})\n")
    lines += ["  - name: END"]
    (d / "machine.yaml").write_text("\n".join(lines) + "\n")
    (d / "State_END_OnEntry.py").write_text("print(machine_name(), 'visited', visits, 'states')\n")
    (d / "Variables.py").write_text(
        "visits: int = 0\nticks: int = 0\nlimit: int = 10\nlast: str = ''\nrunning: bool = True\n"
    )
    (d / "Includes.py").write_text("import math\n")
    return d
