"""`llfsm edit`'s server without a browser (SPEC 13): what it has open, conflicts, another
program's changes, undo, and hostile requests, which must write nothing anywhere."""

from __future__ import annotations

import hashlib
import http.client
import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import MACHINES, llfsm_process

pytest.importorskip("aiohttp")

from llfsm.web.edit_server import EditServer
from llfsm.web.workspace import Workspace, WorkspaceError, WriteConflict, digest


def _tree(root: Path) -> dict[str, str]:
    """Every file below root (links as their target's name), hashed: what a hostile request
    must leave as it was."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in filenames + [d for d in dirnames if os.path.islink(os.path.join(dirpath, d))]:
            p = Path(dirpath, name)
            rel = str(p.relative_to(root))
            out[rel] = f"-> {os.readlink(p)}" if p.is_symlink() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A folder holding a copy of the ping pong machine, inside a parent that holds a file the
    requests below aim at."""
    (tmp_path / "outside.txt").write_text("keep me\n")
    f = tmp_path / "work"
    f.mkdir()
    shutil.copytree(MACHINES / "ros2_ping_pong.machine", f / "ros2_ping_pong.machine")
    return f


@pytest.fixture
def server(folder: Path) -> Iterator[EditServer]:
    srv = EditServer(Workspace([folder]), "127.0.0.1", 0)
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


def _post(srv: EditServer, path: str, body: Any, headers: dict[str, str] | None = None) -> tuple[int, dict[str, Any]]:
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=20)
    data = body if isinstance(body, bytes) else json.dumps(body).encode()
    h = {"Content-Type": "application/json", "Origin": f"http://127.0.0.1:{srv.port}", **(headers or {})}
    conn.request("POST", path, body=data, headers=h)
    resp = conn.getresponse()
    raw = resp.read()
    conn.close()
    try:
        answer = json.loads(raw)
    except ValueError:
        answer = {"raw": raw[:200].decode("utf-8", "replace")}
    return resp.status, answer


# -- what is open --------------------------------------------------------------------------------------


def test_the_machine_is_read_checked_and_drawn_without_running_its_code(folder: Path, monkeypatch: Any) -> None:
    ws = Workspace([folder])
    [key] = ws.machines
    full = ws.full(key)
    assert full["structure"]["initial"] == "INITIAL"
    assert [t["target"] for t in full["structure"]["states"][0]["transitions"]] == ["END", "PUBLISH"]
    assert full["diagnostics"] == []
    assert 'data-state="WAIT_AND_COUNT"' in full["svg"]
    assert full["versions"]["Variables.py"] == digest(full["files"]["Variables.py"])


def test_a_bad_path_is_one_line() -> None:
    with pytest.raises(WorkspaceError, match="no such machine directory or folder"):
        Workspace([Path("/nonexistent/x.machine")])
    result = llfsm_process("edit", "/nonexistent/x.machine", "--web", "127.0.0.1:0", timeout=60)
    assert result.status == 2
    assert result.stderr.strip().count("\n") == 0 and "no such machine directory" in result.stderr


def test_a_stale_write_is_a_conflict_and_writes_nothing(folder: Path) -> None:
    ws = Workspace([folder])
    [key] = ws.machines
    path = folder / "ros2_ping_pong.machine" / "Variables.py"
    base = digest(path.read_text())
    path.write_text("count: int = 5\n")  # another program
    with pytest.raises(WriteConflict) as e:
        ws.write(key, "Variables.py", "count: int = 9\n", base)
    assert e.value.disk == "count: int = 5\n"
    assert path.read_text() == "count: int = 5\n"


def test_another_programs_change_is_seen_and_checked(folder: Path) -> None:
    ws = Workspace([folder])
    [key] = ws.machines
    ws.full(key)
    assert ws.poll() == {}
    entry = folder / "ros2_ping_pong.machine" / "State_WAIT_AND_COUNT_OnEntry.py"
    entry.write_text("count +=\n")
    assert ws.poll() == {key: ["State_WAIT_AND_COUNT_OnEntry.py"]}
    assert any(d["file"] == "State_WAIT_AND_COUNT_OnEntry.py" for d in ws.full(key)["diagnostics"])


def test_a_new_machine_appears_when_another_program_makes_one(folder: Path) -> None:
    ws = Workspace([folder])
    assert not ws.rescan()
    shutil.copytree(MACHINES / "ros2_ping_pong.machine", folder / "second.machine")
    assert ws.rescan()
    assert "second" in ws.machines


# -- hostile requests ---------------------------------------------------------------------------------

BAD_NAMES = ["../outside.txt", "../../outside.txt", "/etc/passwd", "State_A\x00.py", "sub/State_A_OnEntry.py", ".."]


@pytest.mark.parametrize("name", BAD_NAMES)
def test_a_write_outside_the_machine_or_of_no_machine_file_writes_nothing(
    server: EditServer, folder: Path, name: str
) -> None:
    before = _tree(folder.parent)
    status, answer = _post(server, "/api/write", {"machine": "ros2_ping_pong", "file": name, "text": "x = 1\n"})
    assert status == 400 and answer["success"] is False and answer["message"]
    assert _tree(folder.parent) == before


@pytest.mark.parametrize(
    ("op", "args"),
    [
        ("state_add", {"name": "../x"}),
        ("state_add", {"name": "a/b"}),
        ("state_add", {"name": "a\x00b"}),
        ("state_rename", {"old": "PUBLISH", "new": "../../outside"}),
        ("transition_add", {"source": "PUBLISH", "target": "../END"}),
        ("set_guard", {"source": "../PUBLISH", "index": 0, "guard": "True"}),
        ("state_add", {"name": 7}),
        ("transition_move", {"source": "PUBLISH", "index": "0", "to": 1}),
        ("no_such_op", {}),
    ],
)
def test_a_structure_operation_with_a_bad_name_writes_nothing(
    server: EditServer, folder: Path, op: str, args: dict[str, Any]
) -> None:
    before = _tree(folder.parent)
    status, answer = _post(server, "/api/op", {"machine": "ros2_ping_pong", "op": op, "args": args})
    assert status == 400 and answer["success"] is False
    assert _tree(folder.parent) == before


@pytest.mark.parametrize("machine", ["../work/ros2_ping_pong", "/tmp", "ros2_ping_pong/..", None, 3])
def test_a_machine_that_was_not_opened_is_refused(server: EditServer, folder: Path, machine: Any) -> None:
    before = _tree(folder.parent)
    status, answer = _post(server, "/api/write", {"machine": machine, "file": "Variables.py", "text": "x: int = 1\n"})
    assert status == 400 and "is open" in answer["message"]
    assert _tree(folder.parent) == before


@pytest.mark.parametrize("name", ["../evil", "a/b", "x\x00", "class", ""])
def test_a_new_machine_with_a_bad_name_is_refused(server: EditServer, folder: Path, name: str) -> None:
    before = _tree(folder.parent)
    status, answer = _post(server, "/api/new", {"name": name})
    assert status == 400 and answer["success"] is False
    assert _tree(folder.parent) == before


def test_a_huge_body_and_a_foreign_origin_write_nothing(server: EditServer, folder: Path) -> None:
    before = _tree(folder.parent)
    huge = json.dumps({"machine": "ros2_ping_pong", "file": "Variables.py", "text": "x = 1\n" * 800_000}).encode()
    status, _ = _post(server, "/api/write", huge)
    assert status == 413
    status, _ = _post(
        server,
        "/api/write",
        {"machine": "ros2_ping_pong", "file": "Variables.py", "text": "x: int = 1\n"},
        {"Origin": "http://evil.example"},
    )
    assert status == 403
    status, _ = _post(server, "/api/new", {"name": "evil"}, {"Origin": "http://evil.example"})
    assert status == 403
    assert _tree(folder.parent) == before


def test_a_file_linked_out_of_the_machine_is_neither_read_nor_written(tmp_path: Path, folder: Path) -> None:
    machine = folder / "ros2_ping_pong.machine"
    (machine / "State_END_OnEntry.py").symlink_to(tmp_path / "outside.txt")
    srv = EditServer(Workspace([folder]), "127.0.0.1", 0)
    srv.start()
    try:
        status, answer = _post(srv, "/api/machine", {"machine": "ros2_ping_pong"})
        assert status == 200 and "State_END_OnEntry.py" not in answer["machine"]["files"]
        before = _tree(folder.parent)
        status, _ = _post(
            srv, "/api/write", {"machine": "ros2_ping_pong", "file": "State_END_OnEntry.py", "text": "x = 1\n"}
        )
        assert status == 400
        assert _tree(folder.parent) == before
        assert (tmp_path / "outside.txt").read_text() == "keep me\n"
    finally:
        srv.stop()


def test_a_good_write_changes_only_its_file_and_undo_restores_it(server: EditServer, folder: Path) -> None:
    before = _tree(folder.parent)
    status, answer = _post(server, "/api/machine", {"machine": "ros2_ping_pong"})
    version = answer["machine"]["versions"]["Includes.py"]
    status, answer = _post(
        server,
        "/api/write",
        {"machine": "ros2_ping_pong", "file": "Includes.py", "text": "import math\n", "base": version},
    )
    assert status == 200 and answer["files"] == ["Includes.py"], answer
    after = _tree(folder.parent)
    assert {k for k in after if after[k] != before.get(k)} == {"work/ros2_ping_pong.machine/Includes.py"}
    status, answer = _post(server, "/api/undo", {})
    assert status == 200
    assert _tree(folder.parent) == before


def test_a_state_placed_in_layout_yaml_is_drawn_there_and_the_rest_as_before(folder: Path) -> None:
    ws = Workspace([folder])
    before = ws.full("ros2_ping_pong")["svg"]
    (folder / "ros2_ping_pong.machine" / "layout.yaml").write_text("states:\n  END: {x: 500, y: -40}\n")
    assert ws.poll() == {"ros2_ping_pong": ["layout.yaml"]}
    after = ws.full("ros2_ping_pong")["svg"]

    def rect(svg: str, state: str) -> tuple[float, float, float, float]:
        m = re.search(
            rf'data-state="{state}"[^>]*><rect x="([-\d.]+)" y="([-\d.]+)" width="([\d.]+)" height="([\d.]+)"', svg
        )
        assert m, state
        return tuple(float(v) for v in m.groups())  # type: ignore[return-value]

    x, y, w, h = rect(after, "END")
    assert (x + w / 2, y + h / 2) == (500.0, -40.0)
    assert rect(after, "PUBLISH") == rect(before, "PUBLISH")
    # the drawing reaches up to the placed state: the viewBox starts above 0
    vb = [float(v) for v in re.search(r'viewBox="([^"]+)"', after).group(1).split()]  # type: ignore[union-attr]
    assert vb[1] < 0 and vb[0] + vb[2] >= 500 + w / 2
    # an edge into END ends on END's box
    d = re.search(r'data-source="WAIT_AND_COUNT" data-target="END" data-index="0" d="([^"]+)"', after)
    assert d is not None
    ex, ey = (float(v) for v in d.group(1).split()[-2:])
    assert x - 0.1 <= ex <= x + w + 0.1 and y - 0.1 <= ey <= y + h + 0.1
    assert min(abs(ex - x), abs(ex - x - w), abs(ey - y), abs(ey - y - h)) < 0.2


def test_saves_of_one_file_while_typing_are_one_undo_step(folder: Path) -> None:
    ws = Workspace([folder])
    includes = folder / "ros2_ping_pong.machine" / "Includes.py"
    original = includes.read_text()
    for text in ("import m\n", "import ma\n", "import math\n"):
        ws.write("ros2_ping_pong", "Includes.py", text)
    ws.operate("ros2_ping_pong", "state_add", {"name": "PAUSE"})
    ws.write("ros2_ping_pong", "Includes.py", "import math, os\n")
    assert len(ws.undo_stack) == 3
    ws.undo()
    ws.undo()
    assert includes.read_text() == "import math\n"
    ws.undo()
    assert includes.read_text() == original
    ws.redo()
    assert includes.read_text() == "import math\n"


def test_a_verification_file_opens_the_machines_it_names_and_no_folder() -> None:
    ws = Workspace([MACHINES / "suspend_resume.verify.yaml"])
    assert sorted(ws.machines) == ["ros2_blind_turtle_bot", "ros2_turtle_suspend_resume"]
    assert ws.folders == []
    with pytest.raises(WorkspaceError, match="open a folder"):
        ws.new_machine("extra")


def test_with_a_token_every_request_needs_it(folder: Path) -> None:
    srv = EditServer(Workspace([folder]), "127.0.0.1", 0, token="s3cret")
    srv.start()
    try:
        assert srv.url.endswith("/?token=s3cret")
        before = _tree(folder.parent)
        status, _ = _post(srv, "/api/new", {"name": "made"})
        assert status == 403
        assert _tree(folder.parent) == before
        status, answer = _post(srv, "/api/new", {"name": "made"}, {"X-LLFSM-Token": "s3cret"})
        assert status == 200 and (folder / "made.machine" / "machine.yaml").exists(), answer
    finally:
        srv.stop()


def test_the_description_is_written_into_machine_yaml_with_its_comments_kept(folder: Path) -> None:
    ws = Workspace([folder])
    yaml_file = folder / "ros2_ping_pong.machine" / "machine.yaml"
    yaml_file.write_text("# the how-to's ping pong\n" + yaml_file.read_text())
    ws.operate("ros2_ping_pong", "set_description", {"text": "Counts.\nTwice a second."})
    text = yaml_file.read_text()
    assert text.startswith("# the how-to's ping pong\n") and "description: |\n  Counts.\n  Twice a second.\n" in text
    assert ws.full("ros2_ping_pong")["structure"]["description"] == "Counts.\nTwice a second.\n"
    ws.operate("ros2_ping_pong", "set_description", {"text": ""})
    assert "description" not in yaml_file.read_text()
    ws.undo()
    assert "Twice a second." in yaml_file.read_text()


def test_a_machine_yaml_that_does_not_read_keeps_the_last_diagram_until_it_is_fixed(folder: Path) -> None:
    ws = Workspace([folder])
    good = ws.full("ros2_ping_pong")
    yaml_file = folder / "ros2_ping_pong.machine" / "machine.yaml"
    text = yaml_file.read_text()
    ws.write("ros2_ping_pong", "machine.yaml", "states: [\n")
    broken = ws.full("ros2_ping_pong")
    assert broken["stale"] and broken["svg"] == good["svg"]
    assert any(d["file"] == "machine.yaml" and d["severity"] == "error" for d in broken["diagnostics"])
    ws.write("ros2_ping_pong", "machine.yaml", text)
    fixed = ws.full("ros2_ping_pong")
    assert not fixed["stale"] and fixed["diagnostics"] == []
