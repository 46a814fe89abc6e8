"""`llfsm verify` (SPEC 11): the explorer against structures computed by hand, every kind of
property holding and failing, shortest counterexamples, lassos, refusals, the state limit, and
hostile property texts."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, write_machine

from llfsm.verify.explorer import Options
from llfsm.verify.judge import verify
from llfsm.verify.load import PropertySource, VerifyError, load_arrangement


def explore(*machines: Path, props: list[tuple[str, str]] = (), **options: object):  # type: ignore[assignment]
    loaded = load_arrangement([str(m) for m in machines])
    return verify(loaded, [PropertySource(k, t) for k, t in props], Options(**options), keep_graph=True)  # type: ignore[arg-type]


def shape(result) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    return result.configurations, result.steps


def verdicts(result) -> list[str]:  # type: ignore[no-untyped-def]
    return [o.verdict for o in result.outcomes]


# -- the structure, by hand ---------------------------------------------------------------------------


def test_one_transition_then_the_end(tmp_path: Path) -> None:
    # INITIAL (entry pending) -> END (entry pending) -> finished: the run has ended, and stays so
    m = write_machine(tmp_path, "a", {"INITIAL": [("END", "True")], "END": None})
    r = explore(m)
    assert shape(r) == (3, 3)
    e = r.explorer
    assert list(e.edges) == [1, 2, 2]


def test_suspend_self_then_the_run_ends_suspended(tmp_path: Path) -> None:
    # round 0: OnEntry asks for the suspend, the guard still fires (END, entry pending, the gate
    # put back in front between rounds); round 1: the gate applies the suspend; then every
    # machine left is suspended: the end
    m = write_machine(tmp_path, "w", {"INITIAL": [("END", "True")], "END": None}, {"INITIAL_OnEntry": "suspend_self()"})
    r = explore(m)
    assert shape(r) == (3, 3)
    last = r.explorer.configs[2]
    assert last[0] == -1  # ended
    part = r.explorer.part(last, 0)
    assert part[2] == 2 and part[4] is True and part[5] == 1  # SUSPENDED, suspended, resumes to END


def test_a_bool_input_branches_every_ringlet(tmp_path: Path) -> None:
    # c0 --x=F--> c1 (INITIAL, x=F) --x=F--> c1, --x=T--> c2 (END pending, x=T); c0 --x=T--> c2;
    # c2 --x=F--> c3 (finished, x=F), --x=T--> c4 (finished, x=T); c3, c4 stay
    m = write_machine(
        tmp_path, "i", {"INITIAL": [("END", "x")], "END": None}, yaml_extra="inputs:\n  x:\n    type: bool\n"
    )
    r = explore(m)
    assert shape(r) == (5, 8)


def test_abstract_time_moves_forward_in_intervals(tmp_path: Path) -> None:
    # c0 A pending -> c1 A, at most 100 ms; c1 stays (still at most 100 ms) or goes past: END
    # pending (c2) -> finished (c3), which stays
    m = write_machine(tmp_path, "t", {"A": [("END", "after_ms(100)")], "END": None})
    r = explore(m)
    assert shape(r) == (4, 5)


def test_exact_time_counts_each_period_and_caps_past_the_largest_threshold(tmp_path: Path) -> None:
    # --period 50ms: A entered at 0, then 50, 100, 150 (capped: 150 > 100 already) ms in A;
    # after_ms(100) fires at 150: END pending, finished, the end
    m = write_machine(tmp_path, "t", {"A": [("END", "after_ms(100)")], "END": None})
    r = explore(m, period=50_000_000)
    assert shape(r) == (6, 6)


def test_suspend_by_another_machine_and_fairness(tmp_path: Path) -> None:
    # boss waits (abstract time may stay at most 10 ms for ever: unfair), STOP suspends w, then
    # END; w is suspended, boss finishes: the run ends.  Nine configurations (docs/verify.md)
    boss = write_machine(
        tmp_path,
        "boss",
        {"WAIT": [("STOP", "after_ms(10)")], "STOP": [("END", "True")], "END": None},
        {"STOP_OnEntry": 'suspend("w")'},
    )
    w = write_machine(tmp_path, "w", {"MOVE": [("END", "False")], "END": None})
    r = explore(
        boss,
        w,
        props=[
            ("eventually", "finished(boss)"),  # holds only because time passes (fairness)
            ("always", "not finished(w)"),
            ("reachable", "suspended(w) and finished(boss)"),
        ],
    )
    assert shape(r) == (9, 10)
    assert verdicts(r) == ["holds", "holds", "holds"]


# -- properties -----------------------------------------------------------------------------------------


@pytest.fixture
def counter(tmp_path: Path) -> Path:
    return write_machine(
        tmp_path,
        "c",
        {"COUNT": [("END", "n >= 3"), ("COUNT", "True")], "END": None},
        {"COUNT_OnEntry": "n += 1"},
        variables="n: int = 0\n",
    )


def test_every_kind_of_property_holding(counter: Path) -> None:
    r = explore(
        counter,
        props=[
            ("always", "c.n <= 3"),
            ("never", "c.n > 3"),
            ("reachable", 'state(c) == "END" and c.n == 3'),
            ("eventually", "finished(c)"),
            ("leads_to", 'c.n == 1, state(c) == "END"'),
            ("ltl", 'G (c.n == 3 -> F state(c) == "END")'),
            ("ctl", "AG (c.n < 3 -> EF finished(c))"),
            ("ctl", "AF finished(c)"),
        ],
    )
    assert verdicts(r) == ["holds"] * 8
    assert r.status == 0


def test_every_kind_of_property_failing(counter: Path) -> None:
    r = explore(
        counter,
        props=[
            ("always", "c.n < 2"),
            ("never", "c.n == 2"),
            ("reachable", "c.n == 4"),
            ("eventually", "c.n == 7"),
            ("leads_to", "c.n == 1, c.n == 0"),
            ("ltl", "G F c.n == 1"),
            ("ctl", "AG c.n < 3"),
            ("ctl", "EG c.n == 0"),
        ],
    )
    assert verdicts(r) == ["fails"] * 8
    assert r.status == 1


def test_a_safety_counterexample_is_a_shortest_one(counter: Path) -> None:
    r = explore(counter, props=[("always", "c.n < 2")])
    trace = r.outcomes[0].trace
    # COUNT's OnEntry (n=1) and its guard True re-enters it; OnEntry again (n=2): two ringlets
    assert len(trace.steps) - 1 == 2
    last = r.explorer.part(trace.steps[-1][0], 0)
    assert last[-1] == 2


def test_a_liveness_counterexample_is_a_lasso_with_its_loop_marked(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "p",
        {"A": [("B", "True")], "B": [("A", "True")]},
        {"A_OnEntry": "k = 1", "B_OnEntry": "k = 2"},
        variables="k: int = 0\n",
    )
    r = explore(m, props=[("eventually", "p.k == 3")])
    o = r.outcomes[0]
    assert o.verdict == "fails" and o.trace.loop is not None
    out = llfsm("verify", m, "--property", "eventually: p.k == 3").stdout
    assert "a lasso" in out and "-- the loop starts here --" in out and "-- and back to where the loop starts --" in out


def test_the_counterexample_shows_inputs_time_and_changed_variables(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "s",
        {"IDLE": [("ALARM", "hot and after_ms(200)")], "ALARM": None},
        {"IDLE_Internal": "seen += 1"},
        variables="seen: int = 0\n",
        yaml_extra="inputs:\n  hot:\n    type: bool\n",
    )
    r = llfsm("verify", m, "--property", 'never: state(s) == "ALARM"')
    assert r.status == 1
    out = r.stdout
    assert "fails" in out
    assert "inputs hot=True" in out and "time more than 200 ms in IDLE" in out
    assert "s.seen: 0 -> 1" in out
    assert "m  0 s  1 - s                    - ALARM" not in out  # ALARM is reached, not yet entered


def test_an_exception_in_machine_code_is_reported_with_the_path_to_it(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "d",
        {"A": [("A", "True")]},
        {"A_OnEntry": "n -= 1\nx = 10 / n"},
        variables="n: int = 3\n",
    )
    r = llfsm("verify", m)
    assert r.status == 1
    assert "State_A_OnEntry.py:2: error: ZeroDivisionError" in r.stdout
    assert "the path to it" in r.stdout and "Traceback" not in r.stdout + r.stderr


# -- what is refused ----------------------------------------------------------------------------------------


def test_code_that_reads_the_world_is_refused_one_line_per_place(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "r",
        {"A": [("END", "after_ms(delay)"), ("END", "random.random() > 0.5")], "END": None},
        {
            "A_OnEntry": 'ros.init()\nnode = ros.Node("r")\nsub = node.create_subscription(Bool, "/b", None, 10)\n'
            "t = time.time()\n",
            "A_OnResume": "x = after_ms(5)",
        },
        variables="delay: int = 100\nnode: ros.Node\nsub: object\n",
        includes="import random\nimport time\nfrom llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Bool\n",
        yaml_extra="inputs:\n  level:\n    type: int\n",
    )
    r = llfsm("verify", m, "--property", "always: True")
    assert r.status == 2
    lines = r.stdout.splitlines()
    got = sorted((ln.split(":")[0].rsplit("/", 1)[1], ln.split(":")[1], ln.split()[1]) for ln in lines)
    assert got == [
        ("Includes.py", "1", "LF200"),
        ("Includes.py", "2", "LF200"),
        ("State_A_OnEntry.py", "3", "LF200"),
        ("State_A_OnEntry.py", "4", "LF200"),  # time.time(): where `time` is used, as well as its import
        ("State_A_OnResume.py", "1", "LF201"),
        ("State_A_Transition_0.expr", "1", "LF201"),
        ("State_A_Transition_1.expr", "1", "LF200"),  # random.random() in the guard (SPEC 16)
        ("machine.yaml", "2", "LF202"),
    ]
    assert "make what it reads an input" in r.stdout
    assert "State_A_Transition_1.expr:1:1: LF200 error: `random` (randomness" in r.stdout
    assert "nothing was explored" in r.stderr


def test_an_action_client_is_refused_where_it_is_made_and_used_not_where_it_is_annotated() -> None:
    # turtle_rotator (docs/actions.md) waits on what an action server answers: verify cannot
    # explore that; its `client: ros.ActionClient` annotation in Variables.py is no use of one
    r = llfsm("verify", MACHINES / "turtle_rotator.machine", "--property", "always: True")
    assert r.status == 2, r.stderr
    got = sorted(
        (ln.split(":")[0].rsplit("/", 1)[1], int(ln.split(":")[1]), ln.split("`")[1]) for ln in r.stdout.splitlines()
    )
    assert got == [
        ("State_INITIAL_OnEntry.py", 3, "ActionClient()"),
        ("State_INITIAL_Transition_1.expr", 1, ".server_is_ready"),
        ("State_ROTATE_OnEntry.py", 2, ".get_result_async"),
        ("State_ROTATE_OnSuspend.py", 4, ".cancel_goal_async"),
        ("State_ROTATE_Transition_3.expr", 1, ".server_is_ready"),
        ("State_SEND_OnEntry.py", 1, ".send_goal_async"),
        ("State_SEND_OnSuspend.py", 2, ".cancel_goal_async"),
        ("State_SEND_Transition_2.expr", 1, ".server_is_ready"),
    ], r.stdout
    assert all("LF200" in ln and "make what it reads an input" in ln for ln in r.stdout.splitlines())


def test_the_state_limit_names_the_growing_variable(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "g",
        {"A": [("A", "True")]},
        {"A_OnEntry": "n += 1\nflag = not flag"},
        variables="n: int = 0\nflag: bool = False\n",
    )
    r = llfsm("verify", m, "--max-states", "500", "--property", "always: g.n >= 0")
    assert r.status == 3
    assert "state limit" in r.stdout and "g.n (" in r.stdout and "from 0 to" in r.stdout
    assert "g.flag" not in r.stdout
    assert "unknown (state limit)" in r.stdout


def test_a_bad_property_is_one_clear_line(counter: Path) -> None:
    cases = {
        'always: state(c) == "CONT"': "c has no state CONT (did you mean COUNT?)",
        "always: c.nn > 1": "c has no variable or input nn (did you mean c.n?)",
        "always: q.n > 1": "no machine named q",
        "always: c.n >": "not a Python expression",
        "sometimes: c.n > 1": "write KIND:TEXT",
        "ltl: G c.n > 1 U": "ends where a condition was expected",
        "ctl: G c.n > 1": "needs a path quantifier",
    }
    for text, message in cases.items():
        r = llfsm("verify", counter, "--property", text)
        assert r.status == 2, text
        assert message in r.stderr, (text, r.stderr)
        assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize(
    "text",
    [
        '__import__("os").system("touch {marker}")',
        "c.__class__.__init__.__globals__",
        "[x for x in ().__class__.__bases__[0].__subclasses__()]",
        "(lambda: open('{marker}', 'w'))()",
        "getattr(c, 'n')",
        'eval("1")',
        "c.n.__class__",
        "(y := 3)",
        '"a" ** 2',
        "((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((("
        "((((((((1))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))"
        "))))))))",
    ],
)
def test_hostile_property_texts_run_nothing(counter: Path, tmp_path: Path, text: str) -> None:
    marker = tmp_path / "ran"
    r = llfsm("verify", counter, "--property", "always: " + text.format(marker=marker))
    assert r.status == 2
    assert not marker.exists()
    assert "Traceback" not in r.stderr


def test_a_verification_file_names_machines_relative_to_it_and_its_properties(tmp_path: Path) -> None:
    write_machine(tmp_path / "m", "c", {"A": [("END", "True")], "END": None})
    vf = tmp_path / "c.verify.yaml"
    vf.write_text(
        "machines:\n  - m/c.machine\nproperties:\n  - name: it ends\n    eventually: finished(c)\n"
        '  - always: state(c) != "A"\n'
    )
    r = llfsm("verify", vf, "--format", "json")
    doc = json.loads(r.stdout)
    assert r.status == 1
    assert [(p["name"], p["verdict"]) for p in doc["properties"]] == [
        ("it ends", "holds"),
        ('always: state(c) != "A"', "fails"),
    ]
    assert doc["properties"][1]["where"] == f"{vf}:6"
    bad = tmp_path / "bad.verify.yaml"
    bad.write_text("machines: [m/c.machine]\nproperties:\n  - sometimes: x\n")
    r = llfsm("verify", bad)
    assert r.status == 2 and f"{bad}:3: unknown key 'sometimes'" in r.stderr


def test_github_and_sarif_report_failed_properties(counter: Path) -> None:
    gh = llfsm("verify", counter, "--property", "always: c.n < 2", "--format", "github")
    assert gh.status == 1 and gh.stdout.startswith("::error file=") and "c.machine/machine.yaml" in gh.stdout
    sarif = json.loads(llfsm("verify", counter, "--property", "always: c.n < 2", "--format", "sarif").stdout)
    results = sarif["runs"][0]["results"]
    assert [r["ruleId"] for r in results] == ["property-fails"]
    assert "counterexample" in results[0]["message"]["text"]


def test_seed_verification_file_holds_as_documented() -> None:
    r = llfsm("verify", MACHINES / "suspend_resume.verify.yaml")
    assert r.status == 0, r.stdout + r.stderr
    assert "fails" not in r.stdout


def test_a_machine_with_errors_is_not_explored(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "e", {"A": [("NOWHERE", "True")]})
    with pytest.raises(VerifyError) as info:
        load_arrangement([str(m)])
    assert info.value.status == 2 and info.value.diagnostics[0].code == "LF020"


@pytest.mark.parametrize("period", [None, 10_000_000])
def test_the_specialised_loop_hash_compaction_and_the_generic_step_explore_alike(
    period: int | None, tmp_path: Path
) -> None:
    if period is None:  # abstract time: suspension by another machine, an input, timers, nodes
        boss = write_machine(
            tmp_path,
            "boss",
            {"WAIT": [("STOP", "after_ms(10)")], "STOP": [("GO", "True")], "GO": [("WAIT", "after_ms(5)")]},
            {"STOP_OnEntry": 'suspend("w")', "GO_OnEntry": 'resume("w")'},
        )
        w = write_machine(
            tmp_path,
            "w",
            {"MOVE": [("MOVE", "after_ms(3)")]},
            {"MOVE_OnEntry": "n = (n + 1) % 3"},
            variables="n: int = 0\n",
        )
        targets = [str(boss), str(w), str(MACHINES / "wall_follower.machine")]
        props = [PropertySource("eventually", "finished(wall_follower)")]
    else:
        targets = [
            str(MACHINES / "ros2_turtle_suspend_resume.machine"),
            str(MACHINES / "ros2_blind_turtle_bot.machine"),
        ]
        props = [PropertySource("eventually", "finished(ros2_blind_turtle_bot)")]
    loaded = load_arrangement(targets)
    shapes = []
    for hash_compact, generic in ((False, False), (False, True), (True, False), (True, True)):
        options = Options(period=period, interrupt=True, hash_compact=hash_compact, generic=generic)
        r = verify(loaded, props, options)
        e = r.explorer
        assert r.error is None and r.partial is None
        shapes.append((r.configurations, r.steps, list(e.edges), list(e.labels), list(e.fair), verdicts(r)))
    assert shapes[0] == shapes[1] == shapes[2] == shapes[3]
    assert shapes[0][0] > 500


def test_a_long_exploration_shows_progress_and_ctrl_c_gives_a_partial_result(tmp_path: Path) -> None:
    import signal
    import subprocess
    import sys
    import time

    m = write_machine(
        tmp_path, "big", {"A": [("A", "True")]}, {"A_OnEntry": "n = (n + 1) % 100000000"}, variables="n: int = 0\n"
    )
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "llfsm",
            "verify",
            str(m),
            "--max-states",
            "200000000",
            "--property",
            "always: big.n >= 0",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    # the progress line comes once the exploration has run for 2 s; then Ctrl-C
    assert proc.stderr is not None
    deadline = time.monotonic() + 120
    first = ""
    while time.monotonic() < deadline and "llfsm verify:" not in first:
        first = proc.stderr.readline()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    err = first + err
    assert proc.returncode == 130, err
    assert "configurations (" in first and "/s), queue" in first
    assert "always: big.n >= 0: unknown (interrupted)" in out
    assert "interrupted: a partial result" in out
    assert "Traceback" not in err


def test_a_path_that_does_not_replay_alike_is_said(tmp_path: Path) -> None:
    # a helper module's global is state verify does not keep: the path, run again, differs
    (tmp_path / "ticker_helper.py").write_text("calls = [0]\n\ndef tick():\n    calls[0] += 1\n    return calls[0]\n")
    m = write_machine(
        tmp_path,
        "h",
        {"A": [("A", "True")]},
        {"A_OnEntry": "x = ticker_helper.tick() % 4"},
        variables="x: int = 0\n",
        includes="import ticker_helper\n",
    )
    r = llfsm("verify", m, "--property", "never: h.x == 3")
    assert r.status == 1
    assert "warning: never: h.x == 3: its path, run again, did not give the configurations explored" in r.stdout


def test_a_wait_while_inputs_stay_the_same_is_folded_too() -> None:
    """Issue 27, item 10: a machine with inputs reads them in every ringlet, so its waits were
    never folded (a 154-step path printed 174 lines)."""
    r = llfsm(
        "verify", MACHINES / "wall_follower.machine", "--period", "10ms", "-v",
        "--property", 'reachable: state(wall_follower) == "FORWARD" and wall_follower.msg.angular.z == 1.5',
    )  # fmt: skip
    lines = r.stdout.splitlines()
    assert "  witness, 34 steps:" in lines and len(lines) < 25, r.stdout
    assert (
        "    ... 26 more ringlets in which nothing fired, changed or was published, the inputs as before "
        "(rounds 5-30; --format json lists each) ..." in lines
    )
    # a ringlet that reads other inputs is shown: the sensor turning clear in round 2
    assert "    [round 2] wall_follower: no transition (inputs wall_close=False)" in lines


def test_a_long_wait_in_a_counterexample_is_folded_in_text_and_whole_in_json() -> None:
    """In exact time the seed's bot waits a thousand 1 ms rounds for each `after_ms(1000)`: the
    text shows the ringlets in which something happened and folds the quiet ones between them
    (saying how many, and which rounds); the JSON report keeps every step."""
    args = [
        "verify", MACHINES / "ros2_turtle_suspend_resume.machine", MACHINES / "ros2_blind_turtle_bot.machine",
        "--period", "1ms", "--property", 'never: state(ros2_blind_turtle_bot) == "TURN_RIGHT"',
    ]  # fmt: skip
    r = llfsm(*args)
    assert r.status == 1, r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) < 100, r.stdout
    assert (
        "    ... 1,997 more ringlets in which nothing fired, changed or was published (rounds 4-1002; "
        "--format json lists each) ..." in lines
    )
    # what happened is all there: the entries, the commands, the changes, the transition it is about
    assert "    ros2_blind_turtle_bot: suspend applied -> SUSPENDED" in lines
    assert "        ros2_blind_turtle_bot.msg.linear.x: 0.0 -> 2.0" in lines
    fired = "ros2_blind_turtle_bot: transition 1 of STRAIGHT fired -> TURN_RIGHT (time 1.001 s in STRAIGHT or more)"
    assert lines[-2:] == [
        f"    [round 3007] {fired}",
        "    then: ros2_turtle_suspend_resume RESUME, ros2_blind_turtle_bot TURN_RIGHT",
    ]
    full = llfsm(*args, "--format", "json")
    steps = json.loads(full.stdout)
    text = json.dumps(steps)
    assert text.count('"round": 500,') == 2  # a folded round, once per machine


def test_the_counterexample_writes_values_as_python_prints_them(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "s",
        {"A": [("B", "True")], "B": None},
        {"A_OnExit": "hits.add(3)\nnone = frozenset(none)"},
        variables="hits: set = set()\nnone: frozenset = frozenset()\nitems: dict = {}\n",
    )
    out = llfsm("verify", m, "--property", 'never: state(s) == "B"').stdout
    assert "s.hits: set() -> {3}" in out  # `{}` would read as the empty dict
    assert "s.none:" not in out  # frozenset() is what it was


def test_what_grew_in_size_counts_bytes_characters_and_items(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "g",
        {"A": [("A", "True")]},
        {"A_OnEntry": "blob = blob + b'x' * 1000\ntext = text + 'yz'\nitems.append('a long string of text')"},
        variables="blob: bytes = b''\ntext: str = ''\nitems: list = []\n",
    )
    r = llfsm("verify", m, "--max-states", "40")
    assert r.status == 3, r.stdout + r.stderr
    assert "the variables that kept growing: " in r.stdout
    grew = r.stdout.split("the variables that kept growing: ")[1].splitlines()[0].split("; ")
    assert sorted(grew) == [
        "g.blob (41 values, in size from 0 to 40,000 bytes)",  # not 2,500 "items" (bytes ÷ 16)
        "g.items (41 values, in size from 0 to 40 items)",  # a string is an item of a list
        "g.text (41 values, in size from 0 to 80 characters)",
    ]
