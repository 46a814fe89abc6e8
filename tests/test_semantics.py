"""SPEC section 2, rule by rule: machines print from their sections, run under the sim clock."""

from __future__ import annotations

import json
from pathlib import Path

from helpers import llfsm, run_sim, write_machine


def test_ringlet_runs_onentry_then_guards_then_onexit_and_target_entry_waits_for_next_ringlet(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "order",
        {"A": [("B", 'print("guard A0") or False'), ("B", 'print("guard A1") or True')], "B": None},
        {
            "A_OnEntry": 'print("A entry")',
            "A_OnExit": 'print("A exit")',
            "A_Internal": 'print("A internal")',
            "B_OnEntry": 'print("B entry")',
        },
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    assert r.lines == ["A entry", "guard A0", "guard A1", "A exit", "B entry"]


def test_internal_runs_only_when_no_transition_fires_and_onentry_only_once(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "internal",
        {"A": [("END", "n >= 3")], "END": None},
        {"A_OnEntry": 'print("entry")', "A_Internal": 'n += 1\nprint("internal", n)', "A_OnExit": 'print("exit")'},
        variables="n: int = 0\n",
    )
    r = run_sim(m)
    assert r.lines == ["entry", "internal 1", "internal 2", "internal 3", "exit"]


def test_round_robin_gives_each_machine_one_ringlet_per_round_in_load_order(tmp_path: Path) -> None:
    a = write_machine(
        tmp_path, "first", {"S": [("S", "True")]}, {"S_OnEntry": 'print("first", n)\nn += 1'}, variables="n: int = 0\n"
    )
    b = write_machine(
        tmp_path,
        "second",
        {"S": [("S", "True")]},
        {"S_OnEntry": 'print("second", n)\nn += 1'},
        variables="n: int = 0\n",
    )
    r = run_sim(a, b, "--duration", "3ms")
    assert r.lines == ["first 0", "second 0", "first 1", "second 1", "first 2", "second 2"]
    r = run_sim(b, a, "--duration", "2ms")
    assert r.lines == ["second 0", "first 0", "second 1", "first 1"]


def test_self_transition_exits_and_reenters_and_restarts_the_timer(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "selfloop",
        {"A": [("END", "k == 3"), ("A", "after_ms(5)")], "END": None},
        {"A_OnEntry": "k += 1\nprint('entry', k, 'at', t())", "A_OnExit": "print('exit')"},
        variables="k: int = 0\n",
        includes="from llfsm.runtime import current\n",
    )
    # t() reads the run clock in ms through the documented run context
    (m / "Includes.py").write_text(
        "from llfsm.runtime import current\n\n\ndef t():\n    return current().clock.now // 1_000_000\n"
    )
    r = run_sim(m)
    # not allowed: Includes.py may only import; the check refuses it
    assert r.status == 2 and "LF031" in r.stderr
    (m / "Includes.py").write_text("from llfsm.runtime import current\n")
    (m / "State_A_OnEntry.py").write_text("k += 1\nprint('entry', k, 'at', current().clock.now // 1_000_000)\n")
    r = run_sim(m)
    assert r.status == 0, r.stderr
    # entered at 0; after_ms(5) is first true at 6 ms; re-entered at the next ringlet (7 ms)
    assert r.lines == ["entry 1 at 0", "exit", "entry 2 at 7", "exit", "entry 3 at 14", "exit"]


def test_after_ms_is_strictly_more_than_the_time_since_entry(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "timer",
        {"A": [("END", "after_ms(10)")], "END": None},
        {"A_Internal": "print(after_ms(9), after_ms(10), after_us(10_000), after(0.01))"},
    )
    r = run_sim(m, "--trace", tmp_path / "t.jsonl")
    events = [json.loads(x) for x in (tmp_path / "t.jsonl").read_text().splitlines()]
    fired = [e for e in events if e["event"] == "transition"]
    assert fired[0]["t"] == 0.011 and fired[0]["round"] == 11
    # Internal ran at 0..10 ms: after_ms(9) turns true at 10 ms, after_ms(10) never while in A
    assert r.lines[9] == "False False False False"
    assert r.lines[10] == "True False False False"
    assert len(r.lines) == 11


def test_after_with_a_coarser_period(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "coarse", {"A": [("END", "after(1)")], "END": None})
    tr = tmp_path / "t.jsonl"
    run_sim(m, "--period", "100ms", "--trace", tr)
    fired = [json.loads(x) for x in tr.read_text().splitlines() if '"transition"' in x]
    assert fired[0]["t"] == 1.1


SUSPENDER = {
    "WAIT": [("STOP", "after_ms(3)")],
    "STOP": [("GO", "after_ms(5)")],
    "GO": [("END", "after_ms(5)")],
    "END": None,
}


def _worker(tmp_path: Path) -> Path:
    return write_machine(
        tmp_path,
        "worker",
        {"A": [("END", "False")], "END": None},
        {
            "A_OnEntry": "print('A entry', current().clock.now // 10**6)",
            "A_Internal": "print('A internal', current().clock.now // 10**6)",
            "A_OnExit": "print('A exit')",
            "A_OnSuspend": "print('A suspend')",
            "A_OnResume": "print('A resume')",
            "SUSPENDED_OnEntry": "print('SUSPENDED entry')",
            "SUSPENDED_OnResume": "print('SUSPENDED resume')",
            "SUSPENDED_OnExit": "print('SUSPENDED exit')",
        },
        includes="from llfsm.runtime import current\n",
        yaml_extra="",
    )


def _boss(tmp_path: Path, stop: str = 'suspend("worker")', go: str = 'resume("worker")') -> Path:
    return write_machine(
        tmp_path,
        "boss",
        SUSPENDER,
        {"STOP_OnEntry": f"{stop}\nprint('boss: {stop}')", "GO_OnEntry": f"{go}\nprint('boss: {go}')"},
    )


def _with_suspended_state(worker: Path) -> None:
    y = (worker / "machine.yaml").read_text().replace("  - name: END\n", "  - name: END\n  - name: SUSPENDED\n")
    (worker / "machine.yaml").write_text(y)


def test_suspend_runs_onsuspend_not_onexit_and_the_machine_gets_no_ringlets(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    _with_suspended_state(w)
    b = _boss(tmp_path)
    r = run_sim(b, w, "--duration", "20ms")
    out = r.lines
    # the boss fires WAIT -> STOP at 4 ms; STOP's OnEntry suspends the worker at 5 ms
    assert out[:6] == ["A entry 0"] + [f"A internal {t}" for t in range(5)]
    i = out.index('boss: suspend("worker")')
    assert out[i + 1 : i + 3] == ["A suspend", "SUSPENDED entry"]
    assert "A exit" not in out
    # while suspended (5 ms to the resume at 12 ms) the worker prints nothing
    j = out.index('boss: resume("worker")')
    assert out[i + 3 : j] == []


def test_resume_runs_onresume_twice_then_onentry_again_and_restarts_the_timer(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    _with_suspended_state(w)
    b = _boss(tmp_path)
    r = run_sim(b, w, "--duration", "20ms")
    out = r.lines
    j = out.index('boss: resume("worker")')
    assert out[j + 1 : j + 4] == ["SUSPENDED resume", "A resume", "A entry 12"]
    assert out[j + 4] == "A internal 12"
    assert "SUSPENDED exit" not in out and "A exit" not in out


def test_resume_restarts_the_state_timer(tmp_path: Path) -> None:
    w = write_machine(
        tmp_path,
        "worker",
        {"A": [("END", "after_ms(6)")], "END": None},
        {"END_OnEntry": "print('worker done at', current().clock.now // 10**6)"},
        includes="from llfsm.runtime import current\n",
    )
    b = _boss(tmp_path)
    r = run_sim(b, w)
    # entered A at 0, suspended at 5 ms, resumed at 12 ms: the timer counts from 12 ms again
    assert "worker done at 20" in r.lines


def test_implicit_suspend_state_when_none_is_declared(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = _boss(tmp_path)
    r = run_sim(b, w, "--duration", "20ms", "-v")
    assert "m  1 s  2 - worker               - SUSPENDED" in r.stderr
    assert "A suspend" in r.lines and "A resume" in r.lines


def test_restart_enters_the_initial_state_without_onexit_and_keeps_variables(tmp_path: Path) -> None:
    w = write_machine(
        tmp_path,
        "worker",
        {"A": [("B", "True")], "B": [("END", "False")], "END": None},
        {"A_OnEntry": "n += 1\nprint('A entry', n)", "B_OnExit": "print('B exit')", "B_OnEntry": "print('B entry')"},
        variables="n: int = 0\n",
    )
    b = _boss(tmp_path, stop='restart("worker")', go='print("noop")')
    r = run_sim(b, w, "--duration", "8ms")
    out = r.lines
    i = out.index('boss: restart("worker")')
    assert out[i + 1] == "A entry 2"
    assert "B exit" not in out


def test_restart_ends_a_suspension(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = _boss(tmp_path, go='restart("worker")')
    r = run_sim(b, w, "--duration", "20ms")
    out = r.lines
    j = out.index('boss: restart("worker")')
    assert out[j + 1] == "A entry 12"  # no OnResume, straight into the initial state
    assert "A resume" not in out


def test_a_later_command_replaces_an_earlier_pending_one(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = _boss(tmp_path, stop='suspend("worker"); resume("worker")')
    r = run_sim(b, w, "--duration", "8ms")
    assert "A suspend" not in r.lines  # the resume replaced the suspend: nothing to resume either
    assert r.lines.count("A entry 0") == 1 and "A internal 7" in r.lines


def test_suspend_self_and_no_turns_until_resumed_by_another_machine(tmp_path: Path) -> None:
    w = write_machine(
        tmp_path,
        "worker",
        {"A": [("END", "False")], "END": None},
        {"A_OnEntry": "n += 1\nif n == 1:\n    suspend_self()\nprint('entry', n)", "A_Internal": "print('internal')"},
        variables="n: int = 0\n",
    )
    b = write_machine(
        tmp_path,
        "boss",
        {"W": [("R", "after_ms(5)")], "R": [("END", "True")], "END": None},
        {"R_OnEntry": "print('boss sees', is_suspended('worker'), is_running('worker'))\nresume('worker')"},
    )
    r = run_sim(b, w, "--duration", "8ms")
    # the command applies at the worker's next ringlet; the boss resumes it at 7 ms
    assert r.lines == ["entry 1", "internal", "boss sees True False", "entry 2", "internal"]


def test_accepting_machine_is_unloaded_but_stays_known(tmp_path: Path) -> None:
    quick = write_machine(
        tmp_path, "quick", {"A": [("DONE", "True")], "DONE": None}, {"DONE_OnEntry": "print('quick done')"}
    )
    watcher = write_machine(
        tmp_path,
        "watcher",
        {"W": [("END", "after_ms(3)")], "END": None},
        {"W_Internal": "print(is_running('quick'), is_suspended('quick'), state_name_of('quick'))"},
    )
    r = run_sim(quick, watcher, "-v")
    assert r.status == 0
    # round 0: quick fires A -> DONE before the watcher looks; round 1: quick runs DONE and finishes
    assert r.lines[0] == "True False DONE"
    assert r.lines[1] == "quick done"
    assert r.lines[2:] == ["False False DONE"] * 3
    # trace lines keep the load index of the watcher (1) after quick is gone
    assert "m  1 s  1 - watcher              - END" in r.stderr


def test_keep_accepting_keeps_the_machine_loaded(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path, "keep", {"A": [("DONE", "True")], "DONE": None}, {"DONE_Internal": "print('still here')"}
    )
    r = run_sim(m, "--keep-accepting", "--duration", "5ms")
    assert r.lines == ["still here"] * 4


def test_run_ends_when_every_machine_left_is_suspended(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "lonely", {"A": [("END", "False")], "END": None}, {"A_OnEntry": "suspend_self()"})
    tr = tmp_path / "t.jsonl"
    r = run_sim(m, "--trace", tr)
    assert r.status == 0
    events = [json.loads(x)["event"] for x in tr.read_text().splitlines()]
    assert events == ["machine", "entry", "suspend", "entry"]


def test_suspended_option_loads_a_machine_suspended(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = write_machine(
        tmp_path,
        "boss",
        {"W": [("R", "after_ms(2)")], "R": [("END", "True")], "END": None},
        {"R_OnEntry": "resume('worker')"},
    )
    r = run_sim(b, w, "--suspended", "worker", "--duration", "5ms")
    assert r.lines[:3] == ["SUSPENDED resume", "A resume", "A entry 4"]
    r = run_sim(b, w, "--suspended", "nobody")
    assert r.status == 2 and "nobody" in r.stderr


def test_duration_ends_before_the_first_round_at_or_after_it(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "tick", {"A": [("A", "True")]}, {"A_OnEntry": "print('round')"})
    assert len(run_sim(m, "--duration", "10ms").lines) == 10
    assert len(run_sim(m, "--duration", "10ms", "--period", "3ms").lines) == 4  # 0, 3, 6, 9
    assert len(run_sim(m, "--duration", "0").lines) == 0


def test_two_sim_runs_are_identical_byte_for_byte(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = _boss(tmp_path)
    runs = []
    for i in range(2):
        tr = tmp_path / f"t{i}.jsonl"
        r = run_sim(b, w, "--duration", "30ms", "-v", "--trace", tr)
        runs.append((r.stdout, r.stderr, tr.read_bytes()))
    assert runs[0] == runs[1]
    assert runs[0][0] and runs[0][1] and runs[0][2]


def test_verbose_trace_is_clfsms_format_before_each_entering_ringlet(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "a_machine_with_a_long_name",
        {"INITIAL": [("SECOND", "True")], "SECOND": [("END", "True")], "END": None},
    )
    r = run_sim(m, "-v")
    assert r.stderr.splitlines() == [
        "m  0 s  0 - a_machine_with_a_lon - INITIAL",
        "m  0 s  1 - a_machine_with_a_lon - SECOND",
        "m  0 s  2 - a_machine_with_a_lon - END",
    ]


def test_trace_file_records_every_kind_of_event_with_time_and_round(tmp_path: Path) -> None:
    w = _worker(tmp_path)
    b = _boss(tmp_path, go='resume("worker")')
    b2 = write_machine(
        tmp_path / "x",
        "restarter",
        {"W": [("R", "after_ms(15)")], "R": [("END", "True")], "END": None},
        {"R_OnEntry": "restart('worker')"},
    )
    tr = tmp_path / "t.jsonl"
    run_sim(b, w, b2, "--duration", "20ms", "--trace", tr)
    events = [json.loads(x) for x in tr.read_text().splitlines()]
    kinds = {e["event"] for e in events}
    assert kinds == {"machine", "entry", "transition", "suspend", "resume", "restart", "finish"}
    for e in events:
        assert {"t", "round", "event", "machine", "id"} <= e.keys()
    sus = next(e for e in events if e["event"] == "suspend")
    assert sus["machine"] == "worker" and sus["round"] == 5 and sus["t"] == 0.005


def test_locals_belong_to_one_section(tmp_path: Path) -> None:
    # Internal binds `math` as a local; the guard's `math` is still the module (C++: separate functions)
    m = write_machine(
        tmp_path,
        "scoped",
        {"A": [("END", "n > 2 and math.pi > 3")], "END": None},
        {"A_Internal": "math = 'a local of Internal'\nn += 1\nprint(math)", "A_OnEntry": "x = 1\nprint('entry', x)"},
        variables="n: int = 0\n",
        includes="import math\n",
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    assert r.lines == ["entry 1"] + ["a local of Internal"] * 3


def test_a_restart_of_a_finished_machine_is_not_undone_by_a_later_resume(tmp_path: Path) -> None:
    once = write_machine(
        tmp_path,
        "once",
        {"A": [("DONE", "True")], "DONE": None},
        {"A_OnEntry": "print('once runs')", "DONE_Internal": "print('done')"},
    )
    boss = write_machine(
        tmp_path,
        "boss",
        {"W": [("R", "after_ms(3)")], "R": [("END", "True")], "END": None},
        {"R_OnEntry": "restart('once'); resume('once')\nprint('boss', is_running('once'))"},
    )
    tr = tmp_path / "t.jsonl"
    r = run_sim(once, boss, "--trace", tr)
    assert r.lines == ["once runs", "done", "boss False", "once runs", "done"]
    events = [json.loads(x)["event"] for x in tr.read_text().splitlines() if '"once"' in x]
    assert events.count("finish") == 2 and events.count("restart") == 1


def test_wall_clock_sleeps_when_no_transition_fires_even_with_a_suspended_machine(tmp_path: Path) -> None:
    from llfsm.runtime import Arrangement, WallClock
    from llfsm.targets import load

    idle = write_machine(tmp_path, "idle", {"A": [("END", "False")], "END": None})
    sleeper = write_machine(tmp_path, "sleeper", {"A": [("END", "False")], "END": None})
    arr = Arrangement([load(str(idle)), load(str(sleeper))], clock=WallClock(20_000_000), suspended=["sleeper"])
    rounds = arr.run(duration_ns=200_000_000).rounds
    assert 5 <= rounds <= 12, rounds  # ~200 ms / 20 ms; without the idle sleep: hundreds of thousands


def test_wall_clock_run_time_begins_with_the_rounds_not_the_start_up(tmp_path: Path) -> None:
    """A run's start-up (the transport, the nodes, the page; 20 s on a loaded machine was seen)
    is not run time: counted from the clock's making, the first round saw 0, the next one the
    whole start-up, so a `--duration` ended a run after one round and a wait in INITIAL
    (`wait_for_service(timeout_sec=8.0)`) gave up at once."""
    from llfsm.runtime import Arrangement, WallClock
    from llfsm.targets import load

    m = write_machine(tmp_path, "m", {"INITIAL": [("END", "True")], "END": None})
    clock = WallClock(1_000_000)
    clock._start -= 30_000_000_000  # as if the start-up after the clock's making had taken 30 s
    result = Arrangement([load(str(m))], clock=clock).run(duration_ns=10_000_000_000)
    assert result.reason == "finished", result  # INITIAL, then END: two rounds, not ended by --duration
    assert result.time_ns < 10_000_000_000, result


def test_wall_clock_period_is_time_triggered(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "tick", {"A": [("A", "True")]}, {"A_OnEntry": "print('tick')"})
    r = llfsm("run", m, "--period", "25ms", "--duration", "200ms")
    assert 7 <= len(r.lines) <= 9, len(r.lines)  # rounds at 0, 25, ..., 175 ms
