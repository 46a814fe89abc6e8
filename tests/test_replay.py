"""Replay (SPEC 14, docs/debug.md): a `--trace` file and a counterexample of `llfsm verify` read
back as records and frames, the page's history of a recorded run; and files that are neither,
refused in one line."""

from __future__ import annotations

import http.client
import json
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, turning_machine, write_machine

from llfsm.web.replay import CHECKPOINT, ReplayError, read


def test_a_trace_replays_ringlet_by_ringlet(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", MACHINES / "counter.machine", "--trace", trace).status == 0
    r = read(trace)
    assert r.kind == "trace" and r.names == ["counter"]
    moves = [(x["before"], x["after"], x["transition"]) for x in r.records]
    assert moves[0] == ("INITIAL", "COUNT", 0)
    assert moves.count(("COUNT", "COUNT", 1)) == 4 and moves[-2:] == [("COUNT", "END", 0), ("END", "END", None)]
    counts = [r.frame(k)["machines"][0]["values"]["count"] for k in range(len(r.records) + 1)]
    assert counts == sorted(counts) and set(counts) == {0, 1, 2, 3, 4, 5}  # each ringlet that entered COUNT
    assert r.frame(0)["machines"][0] == {"machine": "counter", "state": "INITIAL", "values": {"count": 0, "limit": 5}}
    assert r.frame(len(r.records))["machines"][0]["state"] == "END"
    assert r.frame(2)["record"]["ringlet"] == 2


def test_frames_far_from_a_checkpoint_are_the_same_as_stepping_there(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path, "ticker", {"A": [("A", "True")]}, {"A_OnEntry": "n += 1\nxs.append(n)"}, "n: int = 0\nxs: list = []\n"
    )
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", m, "--trace", trace, "--duration", "700ms").status == 0
    r = read(trace)
    assert len(r.records) == 700
    k = 2 * CHECKPOINT + 17
    frame = r.frame(k)["machines"][0]
    assert frame["values"]["n"] == k
    assert frame["values"]["xs"][-1].endswith("truncated)")  # bounded as the trace wrote it


def test_a_counterexample_replays_its_steps_with_their_inputs(tmp_path: Path) -> None:
    m = turning_machine(tmp_path)
    cx = tmp_path / "cx"
    v = llfsm(
        "verify", m, "--period", "100ms", "--property", 'never: w.turns == 2 and state(w) == "TURN"',
        "--counterexample", cx, "--format", "json",
    )  # fmt: skip
    assert v.status == 1
    steps = json.loads(v.stdout)["properties"][0]["counterexample"]["steps"]
    r = read(cx)
    assert r.kind == "counterexample" and len(r.records) == len(steps)
    assert [x["after"] for x in r.records] == [s["state"] for s in steps]
    assert [x["inputs"]["wall_close"] for x in r.records] == [s["inputs"]["wall_close"] for s in steps]
    last = r.frame(len(r.records))["machines"][0]
    assert last["state"] == "TURN" and last["values"]["turns"] == 2
    # the bag beside it still replays with `llfsm run --play`: the two files live side by side
    assert (cx / "metadata.yaml").is_file() and (cx / "steps.jsonl").is_file()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("hello\n", ":1: not JSON (Expecting value)"),
        ("[1, 2]\n", ":1: not an event of a --trace file"),
        ('{"event": "entry", "machine": "m", "id": 0, "state": "A"}\n', ":1: no `machine` event before it"),
        ('{"event": "entry", "round": "three"}\n', ":1: round: Input should be a valid integer"),
        ("", "no machine in it: not a --trace file of llfsm run"),
    ],
)
def test_what_is_not_a_replay_is_one_line(tmp_path: Path, content: str, message: str) -> None:
    f = tmp_path / "bad.jsonl"
    f.write_text(content)
    with pytest.raises(ReplayError) as e:
        read(f)
    assert message in str(e.value) and str(e.value).startswith(str(f)) and "\n" not in str(e.value)


def test_a_trace_naming_a_state_its_machine_lacks_is_refused(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", MACHINES / "counter.machine", "--trace", trace).status == 0
    lines = trace.read_text().splitlines()
    lines[3] = lines[3].replace('"COUNT"', '"NOWHERE"', 1)
    trace.write_text("\n".join(lines) + "\n")
    with pytest.raises(ReplayError, match=r"t.jsonl:4: counter has no state 'NOWHERE'"):
        read(trace)
    with pytest.raises(ReplayError, match="a folder, but not a counterexample"):
        read(tmp_path)
    with pytest.raises(ReplayError, match="no such file or folder"):
        read(tmp_path / "nope.jsonl")


def test_llfsm_replay_serves_the_page_of_a_trace_and_refuses_what_is_not_one(tmp_path: Path) -> None:
    pytest.importorskip("aiohttp")
    bad = tmp_path / "bad.jsonl"
    bad.write_text("not json\n")
    r = llfsm("replay", bad, "--web", "127.0.0.1:0")
    assert (
        r.status == 2
        and r.stderr == f"llfsm: {bad}:1: not JSON (Expecting value): a --trace file has one JSON object a line\n"
    )
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", MACHINES / "counter.machine", "--trace", trace).status == 0
    proc = subprocess.Popen(
        [sys.executable, "-m", "llfsm", "replay", str(trace), "--web", "127.0.0.1:0", "--duration", "20s"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert proc.stderr is not None
        url = next(line.split("web view at ", 1)[1].strip() for line in proc.stderr if "web view at " in line)
        port = int(url.rstrip("/").rsplit(":", 1)[1])
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("GET", "/")
        assert conn.getresponse().status == 200
        conn.close()
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("POST", "/api/debug/frame", body='{"at": 2}', headers={"Content-Type": "application/json"})
        frame = json.loads(conn.getresponse().read())
        conn.close()
        assert frame["record"]["ringlet"] == 2 and frame["machines"][0]["state"] == "COUNT"
        assert frame["machines"][0]["values"] == {"count": 1, "limit": 5}
    finally:
        proc.terminate()
        proc.wait(10)
