"""The monitor judges a property only where its value can change (docs/monitor.md, "Cost"): the
verdicts must be exactly those of judging every ringlet boundary, run for run (ringlet numbers,
states, variables), over machines that change their variables through other names, command each
other, publish, take parameters from outside, and finish."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from helpers import write_machine

from llfsm.monitor import Monitor
from llfsm.props.file import PropertySource
from llfsm.runtime import SimClock
from llfsm.runtime.context import RunContext
from llfsm.runtime.reads import class_reads
from llfsm.runtime.scheduler import Arrangement
from llfsm.targets import load


def _machines(root: Path) -> list[Path]:
    a = write_machine(
        root,
        "a",
        {
            "INIT": [("GROW", "True")],
            "GROW": [("WAIT", "after_ms(2)")],
            "WAIT": [("GROW", "after_ms(3) and len(items) < 9")],
        },
        code={
            "INIT_OnEntry": "alias = items\nkeep(box)\n",
            "GROW_OnEntry": "n += 1\n",
            "GROW_Internal": "if n % 2 == 0:\n    alias.append(n)\n",
            "WAIT_OnEntry": "seen = f'{n} {len(items)}'\n",
            "WAIT_Internal": "poke()\n",
        },
        variables="n: int = 0\nitems: list = []\nalias: list = []\nseen: str = ''\nquiet: int = 7\nbox: list = []\n",
        # box is handed to a function of a helper module, which keeps it; another changes it
        includes="from monitor_keeper import keep, poke\n",
    )
    (root / "monitor_keeper.py").write_text(
        "KEPT = []\ndef keep(x):\n    KEPT.append(x)\ndef poke():\n    KEPT[-1].append(1)\n"
    )
    b = write_machine(
        root,
        "b",
        {"S1": [("S2", "after_ms(7)")], "S2": [("S1", "after_ms(5)")]},
        code={"S2_OnEntry": 'suspend("a")\nk += 1\n', "S1_OnEntry": 'if k:\n    resume("a")\n'},
        variables="k: int = 0\n",
    )
    c = write_machine(
        root,
        "c",
        {
            "START": [("PUB", "True")],
            "PUB": [("IDLE", "True")],
            "IDLE": [("PUB", "after_ms(4)"), ("END", "k > 5")],
            "END": None,
        },
        code={
            "START_OnEntry": 'ros.init()\nnode = ros.Node("c")\npub = node.create_publisher(Int32, "/tick", 10)\n',
            "PUB_OnEntry": "k += 1\npub.publish(Int32(data=k))\n",
        },
        variables="k: int = 0\nnode: object = None\npub: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Int32\n",
    )
    return [a, b, c]


PROPERTIES = [
    ("always", "a.n < 4"),
    ("never", "len(a.items) >= 2"),
    ("never", 'suspended(a) and state(b) == "S1"'),
    ("always", 'state(a) != "WAIT" or a.seen != ""'),
    ("never", "a.quiet != 7"),
    ("never", "len(a.box) >= 3"),
    ("always", 'not published("/tick") or state(c) == "PUB"'),
    ("never", 'published("/tick") and c.k == 3'),
    ("reachable", "finished(c)"),
    ("eventually", 'state(b) == "S2" and suspended(a)'),
    ("leads_to", '[state(b) == "S2", state(a) == "GROW"]'),
    ("ltl", 'G (published("/tick") -> F state(c) == "IDLE")'),
    ("ltl", 'F G state(c) == "END"'),
    ("ltl", 'G (state(a) == "WAIT" -> state(a) == "WAIT" U state(a) == "GROW")'),
]


def _run(classes: list[Any], sources: list[PropertySource], targeted: bool, period: int = 1_000_000) -> list[str]:
    lines: list[str] = []
    ctx = RunContext(SimClock(period))
    arr = Arrangement(classes, context=ctx)
    monitor = Monitor(sources, classes, "log", lines.append, targeted=targeted)
    monitor.attach(arr)
    told = []

    def parameters() -> None:  # a parameter set from outside once, between rounds
        if ctx.clock.now >= 23_000_000 and not told:
            told.append(1)
            arr.set_variables("a", {"quiet": 8})
        ctx.wake_at(23_000_000)

    ctx.between_rounds.append(parameters)
    ctx.wake_at(0)
    arr.run(90_000_000)
    return lines


@pytest.fixture(scope="module")
def classes(tmp_path_factory: pytest.TempPathFactory) -> list[Any]:
    return [load(str(p)) for p in _machines(tmp_path_factory.mktemp("m"))]


@pytest.mark.parametrize("kind, text", PROPERTIES, ids=[f"{k}-{n}" for n, (k, _) in enumerate(PROPERTIES)])
def test_each_property_gets_the_verdicts_of_judging_every_boundary(classes: list[Any], kind: str, text: str) -> None:
    src = [PropertySource(kind, text)]
    every = _run(classes, src, targeted=False)
    assert every, "each property here gets a verdict"
    assert _run(classes, src, targeted=True) == every


def test_all_properties_together_and_at_another_period(classes: list[Any]) -> None:
    src = [PropertySource(k, t) for k, t in PROPERTIES]
    assert _run(classes, src, targeted=True, period=700_000) == _run(classes, src, targeted=False, period=700_000)


def test_what_a_ringlet_can_change_is_read_from_its_code(classes: list[Any]) -> None:
    a = class_reads(classes[0])
    assert a is not None
    # alias = items makes the two one object: a ringlet changing either changes both
    assert a.group["alias"] == a.group["items"]
    # n handed to alias.append joins their group too (a value put into a list can be reached there)
    grown = {"_llfsm_enter_INIT", "_llfsm_enter_GROW", "_llfsm_steady_GROW"}
    assert a.changers("items") == a.changers("n") == grown
    # WAIT's OnEntry reads n and items only as values (an f-string, len) and assigns seen alone
    assert a.changers("seen") == {"_llfsm_enter_WAIT"}
    assert a.changers("quiet") == set()  # nothing of a's own changes it: a parameter from outside does
    assert a.is_escaped("box") and not a.is_escaped("quiet")
