"""The lean round loop keeps the semantics where it skips work: the bus executor runs only when
something is due, the sim clock lives in a local between rounds, the wall clock is read in
batches, and a machine that commands itself and fires in the same ringlet stays held."""

from __future__ import annotations

from pathlib import Path

from helpers import run_sim, write_machine

ROS = "from llfsm import ros\nfrom llfsm.runtime import current\nfrom llfsm.msgs.std_msgs.msg import String\n"


def test_a_spin_that_moves_the_sim_clock_is_kept_and_the_next_round_follows_it(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "sleeper",
        {"INIT": [("A", "True")], "A": [("B", "True")], "B": [("END", "True")], "END": None},
        {
            "INIT_OnEntry": "ros.init()\nnode = ros.Node('sleeper')",
            "A_OnEntry": "print('A at', current().clock.now)\nros.spin_once(node, timeout_sec=0.5)\n"
            "print('after spin', current().clock.now)",
            "B_OnEntry": "print('B at', current().clock.now)",
        },
        variables="node: object = None\n",
        includes=ROS,
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    # INIT at 0 ms, A at 1 ms, the spin jumps to 501 ms, B one period later
    assert r.lines == ["A at 1000000", "after spin 501000000", "B at 502000000"]


def test_timers_fire_when_due_and_callbacks_run_before_the_next_round(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "talker",
        {"INIT": [("WAIT", "True")], "WAIT": [("END", "len(heard) >= 3")], "END": None},
        {
            "INIT_OnEntry": "ros.init()\nnode = ros.Node('talker')\n"
            "pub = node.create_publisher(String, '/t', 10)\n"
            "node.create_subscription(String, '/t', lambda msg: heard.append((msg.data, current().clock.now)), 10)\n"
            "node.create_timer(0.005, lambda: pub.publish(String(data='tick')))",
            "WAIT_OnEntry": "pub.publish(String(data='hello'))",
            "END_OnEntry": "print(heard)",
        },
        variables="node: object = None\npub: object = None\nheard: list = []\n",
        includes=ROS,
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    # hello: published in round 1 (1 ms), delivered between rounds 1 and 2 (at 2 ms);
    # the timer (5 ms period, made at 0 ms) publishes at 5 and 10 ms: delivered right after
    assert r.lines == ["[('hello', 2000000), ('tick', 5000000), ('tick', 10000000)]"]


def test_a_machine_that_suspends_itself_and_fires_in_the_same_ringlet_stays_suspended(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "quitter",
        {"A": [("B", "True")], "B": [("A", "True")]},
        {"A_OnEntry": "print('A', n)\nn += 1\nif n == 2:\n    suspend_self()", "B_OnEntry": "print('B')"},
        variables="n: int = 0\n",
    )
    boss = write_machine(
        tmp_path,
        "boss",
        {"S": [("T", "after_ms(5)")], "T": [("END", "True")], "END": None},
        {"T_OnEntry": "print('resume at', state_name_of('quitter'))\nresume('quitter')"},
    )
    r = run_sim(m, boss, "--duration", "11ms")
    assert r.status == 0, r.stderr
    # A's guard still fires after suspend_self() (round 2): B is current and entered; the
    # suspension takes effect at quitter's next ringlet (round 3), so B's OnEntry waits; the
    # boss resumes it in round 7, B's OnEntry runs in round 8, and the toggling goes on
    assert r.lines == ["A 0", "B", "A 1", "resume at SUSPENDED", "B", "A 2", "B"]


def test_the_wall_clock_moves_on_during_back_to_back_rounds(tmp_path: Path) -> None:
    from helpers import llfsm

    m = write_machine(
        tmp_path,
        "busy",
        {"A": [("END", "after_ms(30)"), ("A", "False")], "END": None},
        {"A_Internal": "n += 1", "END_OnEntry": "print('busy rounds', n > 100)"},
        variables="n: int = 0\n",
    )
    r = llfsm("run", m, "--idle", "0")
    assert r.status == 0, r.stderr
    assert r.lines == ["busy rounds True"]
