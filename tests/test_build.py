"""`llfsm build`, generated modules, and the smaller commands (graph, schema, new machine)."""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from helpers import MACHINES, REPO, llfsm, run_sim, write_machine
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from llfsm.compiler import build as build_mod
from llfsm.compiler.build import build_machine


def test_build_writes_one_module_per_machine_and_it_runs(tmp_path: Path) -> None:
    out = tmp_path / "out"
    r = llfsm("build", MACHINES / "counter.machine", "-o", out)
    assert r.status == 0
    assert r.stderr.strip() == f"[1/1] counter: compiled -> {out}/counter.py"
    r = run_sim(out / "counter.py")
    assert r.status == 0 and r.lines[-1] == "done"


def test_generated_module_reads_like_hand_written_code_and_is_ruff_clean(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "ping",
        {
            "INITIAL": [("PING", "after_ms(10)")],
            "PING": [("END", "count >= 3 or not ok"), ("PING", "after(0.5)")],
            "END": None,
        },
        {"PING_OnEntry": "# say it\ncount += 1\nprint(f'ping {count}')\n", "PING_OnExit": "print('bye')"},
        variables="count: int = 0\nok: bool = True\n",
        includes="import math\n",
    )
    outcome = build_machine(m, tmp_path / "out")
    text = outcome.module.read_text()  # type: ignore[union-attr]
    assert "class PingMachine(Machine):" in text
    assert 'def _llfsm_enter_PING(self: "PingMachine") -> "int | None":' in text
    assert 'def _llfsm_steady_PING(self: "PingMachine") -> "int | None":' in text
    assert "    # State_PING_OnEntry.py:1\n    # say it\n    self.count += 1\n" in text
    assert "    # State_PING_Transition_0.expr:1\n    if self.count >= 3 or not self.ok:\n" in text
    assert "        self.on_exit_PING()\n" in text
    assert "        # Variables.py:1\n        self.count: int = 0\n        self.ok: bool = True\n" in text
    ruff = shutil.which("ruff", path=str(Path(sys.executable).parent)) or "ruff"
    proc = subprocess.run(
        [ruff, "check", "--isolated", "--select", "E,F,W", "--line-length", "120", str(outcome.module)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout


def test_generated_module_imports_only_the_runtime(tmp_path: Path) -> None:
    out = tmp_path / "out"
    llfsm("build", MACHINES / "counter.machine", "-o", out)
    code = (
        "import sys, importlib.util\n"
        f"spec = importlib.util.spec_from_file_location('counter', {str(out / 'counter.py')!r})\n"
        "mod = importlib.util.module_from_spec(spec); spec.loader.exec_module(mod)\n"
        "names = ('yaml', 'jinja2', 'pydantic', 'llfsm.compiler', 'llfsm.lang', 'click')\n"
        "heavy = [m for m in names if m in sys.modules]\n"
        "print(heavy)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert proc.stdout.strip() == "[]", proc.stderr


def test_warm_run_of_a_machine_directory_does_not_load_the_compiler(tmp_path: Path) -> None:
    m = shutil.copytree(MACHINES / "counter.machine", tmp_path / "counter.machine")
    env = dict(os.environ, LLFSM_CACHE_DIR=str(tmp_path / "cache"))
    probe = (
        "import atexit, sys\n"
        "atexit.register(lambda: sys.stderr.write('HEAVY %s\\n' % sorted(m for m in ('yaml', 'jinja2', 'pydantic',"
        " 'llfsm.compiler.generate', 'llfsm.lang') if m in sys.modules)))\n"
        "from llfsm.cli import main\n"
        f"sys.argv = ['llfsm', 'run', '--clock', 'sim', {str(m)!r}]\n"
        "main()\n"
    )
    cold = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env)
    warm = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env)
    assert "HEAVY ['jinja2', 'llfsm.compiler.generate', 'llfsm.lang', 'pydantic', 'yaml']" in cold.stderr
    assert "HEAVY []" in warm.stderr
    assert warm.stdout == cold.stdout and "done" in warm.stdout


def test_build_is_incremental(tmp_path: Path) -> None:
    m = shutil.copytree(MACHINES / "counter.machine", tmp_path / "counter.machine")
    out = tmp_path / "out"
    assert build_machine(m, out).status == "compiled"
    module = out / "counter.py"
    before = module.stat().st_mtime_ns
    assert build_machine(m, out).status == "unchanged"
    assert module.stat().st_mtime_ns == before
    (m / "State_END_OnEntry.py").write_text('print("finished")\n')
    assert build_machine(m, out).status == "compiled"
    assert 'print("finished")' in module.read_text()
    assert build_machine(m, out, force=True).status == "compiled"


def test_an_interrupted_build_leaves_no_half_written_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    m = shutil.copytree(MACHINES / "counter.machine", tmp_path / "counter.machine")
    out = tmp_path / "out"
    build_machine(m, out)
    good = (out / "counter.py").read_text()
    (m / "State_END_OnEntry.py").write_text('print("changed")\n')

    def interrupted(src: str, dst: str) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(build_mod.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        build_machine(m, out)
    assert (out / "counter.py").read_text() == good
    assert sorted(p.name for p in out.iterdir()) == ["counter.py"]


def test_failed_build_exits_1_and_writes_nothing(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "bad", {"A": [("B", "True")]})
    out = tmp_path / "out"
    r = llfsm("build", m, "-o", out)
    assert r.status == 1 and "LF020" in r.stderr and "bad: failed" in r.stderr
    assert not out.exists() or list(out.iterdir()) == []


def test_build_without_paths_builds_every_machine_below_the_current_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_machine(tmp_path / "machine", "one", {"A": None})
    write_machine(tmp_path / "machine", "two", {"A": None})
    monkeypatch.chdir(tmp_path)
    r = llfsm("build")
    assert r.status == 0
    assert sorted(p.name for p in (tmp_path / "build" / "llfsm").iterdir()) == ["one.py", "two.py"]


def test_hostile_text_cannot_inject_code(tmp_path: Path) -> None:
    marker = tmp_path / "injected"
    desc = f'x"""\nimport os; os.system("touch {marker}")\n"""'
    m = write_machine(tmp_path / "we\"ird'dir", "m", {"A": None}, yaml_extra="description: " + json.dumps(desc))
    r = run_sim(m)
    assert r.status == 0, r.stderr
    assert not marker.exists()
    text = next((Path(os.environ["LLFSM_CACHE_DIR"])).rglob("m.py")).read_text()
    assert '"""m: x\\"\\"\\" import os; os.system(\\"touch' in text


def test_unicode_and_multiline_strings_survive_compilation(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "text",
        {"A": None},
        {"A_OnEntry": 'msg = """first\n  second"""\nprint(msg)\nprint("ünïcödé", f"{len(msg)}")\n'},
    )
    r = run_sim(m)
    assert r.lines == ["first", "  second", "ünïcödé 14"]


def test_machine_variables_inside_callbacks_lambdas_and_comprehensions(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "scopes",
        {"A": None},
        {
            "A_OnEntry": (
                "def bump(by):\n    total += by\n"
                "bump(2)\n"
                "add = lambda total: total + 100\n"  # a parameter named like the variable shadows it
                "squares = [total * total for total in range(3)]\n"
                "print(total, add(1), squares, [total for _ in range(2)])\n"
            )
        },
        variables="total: int = 1\n",
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    assert r.lines == ["3 101 [0, 1, 4] [3, 3]"]


def test_state_variables_keep_their_values_across_entries_and_are_private(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "sv",
        {"A": [("END", "visits == 3"), ("A", "True")], "END": None},
        {"A_Variables": "visits: int = 0\n", "A_OnEntry": "visits += 1\nprint('visit', visits)"},
    )
    r = run_sim(m)
    assert r.lines == ["visit 1", "visit 2", "visit 3"]


# -- graph, schema, new ------------------------------------------------------------------------


def test_graph_mermaid_and_dot_show_guards(tmp_path: Path) -> None:
    m = MACHINES / "counter.machine"
    r = llfsm("graph", m)
    assert r.status == 0
    assert r.stdout.splitlines()[:3] == [
        "stateDiagram-v2",
        "    %% Counts to five, one count every 200 ms, then stops.",
        "    [*] --> INITIAL",
    ]
    assert "    COUNT --> END : 0. count >= limit" in r.stdout
    assert "    END --> [*]" in r.stdout
    r = llfsm("graph", m, "--format", "dot")
    assert '"COUNT" -> "COUNT" [label="1. after_ms(200)"];' in r.stdout


def test_graph_draws_svg_and_png_itself(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no Graphviz, whatever the machine has
    m = MACHINES / "counter.machine"
    assert llfsm("graph", m, "--format", "svg", "-o", tmp_path / "g.svg").status == 0
    root = ET.parse(tmp_path / "g.svg").getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    states = {g.get("data-state") for g in root.iterfind(".//s:g[@data-state]", ns)}
    assert states == {"INITIAL", "COUNT", "END", "SUSPENDED"}
    arrows = {(p.get("data-source"), p.get("data-index"), p.get("data-target")) for p in root.iterfind(".//s:path", ns)}
    assert {("INITIAL", "0", "COUNT"), ("COUNT", "0", "END"), ("COUNT", "1", "COUNT")} <= arrows
    labels = ["".join(t.itertext()) for t in root.iterfind(".//s:g[@class='guard']/s:text", ns)]
    assert "0: count >= limit" in labels and "1: after_ms(200)" in labels
    assert root.find("s:style", ns) is not None  # it carries its look: it is a file of its own
    assert llfsm("graph", m, "--format", "png", "-o", tmp_path / "g.png").status == 0
    with Image.open(tmp_path / "g.png") as img:
        assert img.format == "PNG"
        assert img.size == (round(float(root.get("width")) * 2), round(float(root.get("height")) * 2))
        pixels = img.convert("RGB")
        colours = {c for _, c in pixels.getcolors(maxcolors=1 << 24) or []}
    assert (255, 255, 255) in colours and (227, 242, 253) in colours  # the page, the states' fill
    assert any(r < 100 and g < 120 and b < 130 for r, g, b in colours)  # edges and names in ink


def test_graph_places_states_where_layout_yaml_says(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "p", {"A": [("B", "True")], "B": [("A", "after(1)")]})
    layout = "states:\n  A: {x: 100, y: 100}\n  B: {x: 400, y: 100}\n"
    (m / "layout.yaml").write_text(layout)

    def centres() -> dict[str, tuple[float, float]]:
        root = ET.fromstring(llfsm("graph", m, "--format", "svg").stdout.split("\n", 1)[1])
        out = {}
        for g in root.iter("{http://www.w3.org/2000/svg}g"):
            if g.get("data-state"):
                r = g.find("{http://www.w3.org/2000/svg}rect")
                assert r is not None
                out[g.get("data-state")] = (
                    float(r.get("x")) + float(r.get("width")) / 2,
                    float(r.get("y")) + float(r.get("height")) / 2,
                )
        return out

    c = centres()
    assert c["B"][0] - c["A"][0] == 300 and c["B"][1] == c["A"][1]  # side by side, 300 apart
    assert llfsm("graph", m, "--format", "png", "-o", m.parent / "p.png").status == 0
    (m / "layout.yaml").write_text(layout.replace("x: 400, y: 100", "x: 100, y: 400"))
    c = centres()
    assert c["B"][1] - c["A"][1] == 300 and c["B"][0] == c["A"][0]  # one under the other


def test_a_labels_box_in_the_png_is_as_wide_as_its_text(tmp_path: Path) -> None:
    """The PNG draws labels in the font Pillow ships, narrower than the page's monospace font
    the SVG sizes their boxes for: a box sized for the page ran past the text and hid what lay
    beside it (here the edge A -> B, under the end of the box of a label placed beside it)."""
    m = write_machine(
        tmp_path, "w", {"A": [("B", "after(1)"), ("B", "ill")], "B": None}, variables="ill: bool = False\n"
    )
    (m / "layout.yaml").write_text(
        "states:\n  A: {x: 100, y: 60}\n  B: {x: 100, y: 260}\nlabels:\n  A:\n    0: {x: 140, y: 100}\n"
        "    1: {x: 60, y: 150}\n"  # "1: ill": 48.2 wide for the page, so over x = 100
    )
    root = ET.fromstring(llfsm("graph", m, "--format", "svg").stdout.split("\n", 1)[1])
    ns = "{http://www.w3.org/2000/svg}"
    edge = next(p for p in root.iter(f"{ns}path") if p.get("data-index") == "0")
    assert edge.get("d") == "M100.0 77.0 L100.0 243.0"  # straight down at x = 100
    [box] = [
        g.find(f"{ns}rect") for g in root.iter(f"{ns}g") if g.get("data-index") == "1" and g.get("class") == "guard"
    ]
    assert box is not None and float(box.get("x")) < 100 < float(box.get("x")) + float(box.get("width"))
    left, top = (float(v) for v in root.get("viewBox", "").split()[:2])
    inner = next(g for g in root.iter(f"{ns}g") if g.get("transform"))  # the drawing, below the initial dot
    dx, dy = (float(v) for v in re.findall(r"-?[\d.]+", inner.get("transform", ""))[:2])

    def pixel(x: float, y: float) -> tuple[int, int]:
        return round((x + dx - left) * 2), round((y + dy - top) * 2)

    assert llfsm("graph", m, "--format", "png", "-o", tmp_path / "w.png").status == 0
    with Image.open(tmp_path / "w.png") as img:
        pixels = img.convert("L")
        column = [
            min(pixels.getpixel((pixel(100, y)[0] + d, pixel(100, y)[1])) for d in (-1, 0, 1)) for y in range(152, 165)
        ]
        assert max(column) < 160, column  # the edge is drawn beside the label, not hidden by its box
        text = [pixels.getpixel(pixel(x / 2, 158)) for x in range(128, 160)]
        assert min(text) < 100  # and the label's text is there


def test_schema_is_json_schema_of_machine_yaml() -> None:
    r = llfsm("schema")
    doc = json.loads(r.stdout)
    assert doc["title"] == "machine.yaml"
    assert doc["required"] == ["states"]
    assert set(doc["properties"]) == {"description", "initial", "suspended", "states", "inputs", "parameters"}
    assert "/llfsm/<machine>" in doc["properties"]["parameters"]["description"]
    assert doc["additionalProperties"] is False
    name = doc["$defs"]["YamlState"]["properties"]["name"]["pattern"]
    assert name.startswith("^") and name.endswith("$")  # JSON Schema patterns search: anchor them


def test_new_machine_is_valid_and_runs(tmp_path: Path) -> None:
    r = llfsm("new", "machine", "greeter", "--dir", tmp_path, "--description", 'Says "hi": twice.')
    assert r.status == 0
    m = tmp_path / "greeter.machine"
    assert llfsm("check", "--strict", m).status == 0
    run = run_sim(m)
    assert run.status == 0 and run.lines == ["greeter: hello from INITIAL"]
    assert llfsm("new", "machine", "greeter", "--dir", tmp_path).status == 2
    assert llfsm("new", "machine", "no-dashes", "--dir", tmp_path).status == 2
    assert llfsm("new", "machine", "for", "--dir", tmp_path).status == 2


def test_readme_starts_with_the_two_setup_commands() -> None:
    text = (REPO / "README.md").read_text()
    head = text[: text.index("\n## ")]
    assert "make demo" in head and "make test" in head


def _ring(root: Path, name: str, entry: str = "count += 1\n", guard: str = "count > -1") -> Path:
    return write_machine(
        root,
        name,
        {"A": [("B", guard)], "B": [("END", "True")], "END": None},
        {"A_OnEntry": entry, "END_OnEntry": "print(machine_name(), count)\n"},
        variables="count: int = 0\n",
    )


def test_a_parallel_build_writes_what_a_serial_one_does_and_its_rebuild_reads_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Workers build (and sign, for the next build's stat check) what a single process does:
    the same modules byte for byte, the same outcomes and diagnostics, in the machines' order."""
    monkeypatch.setattr(build_mod, "RACY_NS", 0)  # trust the stats of files written just now
    src = tmp_path / "src"
    machines = [_ring(src, f"m{i}", entry=f"count += {i}\nscratch = [x for x in range(3)]\n") for i in range(5)]
    machines.insert(2, write_machine(src, "broken", {"A": [("NOPE", "True")]}))
    serial = list(build_mod.build_all(machines, tmp_path / "one", jobs=1))
    parallel = list(build_mod.build_all(machines, tmp_path / "two", jobs=2))
    assert [(o.name, o.status, o.diagnostics) for o in serial] == [(o.name, o.status, o.diagnostics) for o in parallel]  # type: ignore[union-attr]
    assert [o.status for o in parallel] == ["compiled", "compiled", "failed", "compiled", "compiled", "compiled"]  # type: ignore[union-attr]
    for m in machines:
        name = m.name.removesuffix(".machine")
        if name != "broken":
            assert (tmp_path / "one" / f"{name}.py").read_bytes() == (tmp_path / "two" / f"{name}.py").read_bytes()

    def no_reading(*_args: object) -> str:
        raise AssertionError("an unchanged machine was read again")

    monkeypatch.setattr(build_mod, "machine_fingerprint", no_reading)
    again = list(build_mod.build_all([m for m in machines if m.name != "broken.machine"], tmp_path / "two", jobs=2))
    assert [o.status for o in again] == ["unchanged"] * 5  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("entry", "guard", "verified"),
    [
        ("count += 1\nscratch = [x * 2 for x in range(3)]\n", "count > -1", False),
        ("if count:\n\tcount = 0\n", "count > -1", True),  # a tab: indenting must keep the blocks
        ("print(f'{count=}')\n", "count > -1", True),  # rewritten inside an f-string
        ("text = '''a\n  b'''\n", "count > -1", True),  # a string over two lines keeps its text
        ("count = 1 + \\\n    2\n", "count > -1", True),  # a backslash continuation
        ("count += 1\n", "(count >\n -1)", True),  # a guard on two lines
        ("count += 1\n", "count > -1  # enough", True),  # a guard with a comment
    ],
)
def test_the_module_is_compiled_at_build_time_when_its_assembly_could_go_wrong(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, entry: str, guard: str, verified: bool
) -> None:
    """check proves every piece compiles where the module puts it; the build compiles the whole
    module only when indenting or joining the pieces could still break it.  Either way the
    module compiles and runs."""
    from llfsm.compiler import generate

    calls: list[str] = []
    real = generate._verify
    monkeypatch.setattr(generate, "_verify", lambda source, m: calls.append(m.name) or real(source, m))
    m = _ring(tmp_path, "ring", entry, guard)
    outcome = build_machine(m, tmp_path / "out")
    assert outcome.status == "compiled", outcome.diagnostics
    assert calls == (["ring"] if verified else [])
    assert outcome.module is not None
    compile(outcome.module.read_text(encoding="utf-8"), str(outcome.module), "exec", dont_inherit=True)
    assert run_sim(outcome.module).status == 0


def test_a_rebuild_sees_an_edit_that_keeps_the_size_and_the_modification_time(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The warm build's stat record includes change times (as `llfsm run`'s does): an edit that
    puts the old modification time back is still seen, and the machine is compiled again."""
    monkeypatch.setattr(build_mod, "RACY_NS", 0)
    m = _ring(tmp_path / "src", "m", entry="count += 1\n")
    assert [o.status for o in build_mod.build_all([m], tmp_path / "out")] == ["compiled"]  # type: ignore[union-attr]
    assert [o.status for o in build_mod.build_all([m], tmp_path / "out")] == ["unchanged"]  # type: ignore[union-attr]
    f = m / "State_A_OnEntry.py"
    st = f.stat()
    f.write_text("count += 2\n")  # same size
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert [o.status for o in build_mod.build_all([m], tmp_path / "out")] == ["compiled"]  # type: ignore[union-attr]
    assert "count += 2" in (tmp_path / "out" / "m.py").read_text()


def test_the_same_machine_gives_the_same_module_in_any_folder(tmp_path: Path) -> None:
    """Builds are reproducible: a machine and its build folder copied as a whole to another
    absolute folder build to the same bytes, and the module holds no absolute path (it names
    the machine folder relative to its own)."""
    one = tmp_path / "one" / "project"
    shutil.copytree(MACHINES / "ros2_wall_turtle_bot.machine", one / "machines" / "ros2_wall_turtle_bot.machine")
    assert build_machine(one / "machines" / "ros2_wall_turtle_bot.machine", one / "build").status == "compiled"
    two = tmp_path / "second place" / "deeper" / "project"
    shutil.copytree(one, two)
    (two / "build" / "ros2_wall_turtle_bot.py").unlink()
    assert build_machine(two / "machines" / "ros2_wall_turtle_bot.machine", two / "build").status == "compiled"
    first = (one / "build" / "ros2_wall_turtle_bot.py").read_bytes()
    assert (two / "build" / "ros2_wall_turtle_bot.py").read_bytes() == first
    text = first.decode()
    assert str(tmp_path) not in text and str(REPO) not in text
    assert "# Source: ../machines/ros2_wall_turtle_bot.machine\n" in text
    # the copy's module is up to date where it is: the fingerprint does not depend on the folder
    assert build_machine(two / "machines" / "ros2_wall_turtle_bot.machine", two / "build").status == "unchanged"


def test_the_module_names_states_and_has_no_dead_branches_nor_long_lines(tmp_path: Path) -> None:
    """What the template writes: state numbers named, no `if True:` / `if False:`, no line over
    120 characters (a long description, many transitions, long names), the public finish."""
    description = " ".join(f"word{i}" for i in range(80)) + " " + "x" * 150
    states: dict[str, list[tuple[str, str]] | None] = {
        "A_STATE_WITH_A_RATHER_LONG_NAME": [(f"S{i}", f"count > {i} and not done") for i in range(12)]
        + [("END", "True")],
        **{f"S{i}": [("END", "False"), ("A_STATE_WITH_A_RATHER_LONG_NAME", "True")] for i in range(12)},
        "END": None,
    }
    m = write_machine(
        tmp_path,
        "long_machine",
        states,
        variables="count: int = 0\ndone: bool = False\n",
        yaml_extra=f"description: {description}",
    )
    outcome = build_machine(m, tmp_path / "out")
    assert outcome.status == "compiled", outcome.diagnostics
    text = outcome.module.read_text()  # type: ignore[union-attr]
    assert [line for line in text.splitlines() if len(line) > 120] == []
    assert "if True" not in text and "if False" not in text
    assert "        self._state = 1  # S0\n" in text
    assert "is always true: the transition fires at once\n    self._state = 13  # END\n" in text
    assert "self._arr.finish(self)" in text and "._finish(" not in text
    assert run_sim(outcome.module).status == 0  # type: ignore[arg-type]


TEXTS = st.lists(
    st.sampled_from(['"', "'", "\\", "\n", "\t", "\x00", " ", "é", "\u2028", "word ", "z" * 130, '"""'])
).map("".join)
LITERALS = st.recursive(
    st.one_of(TEXTS, st.integers(-1000, 10**6)), lambda inner: st.tuples(inner, inner) | st.tuples(inner)
)


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(LITERALS, st.sampled_from([0, 4, 18]))
def test_literals_and_docstrings_keep_their_values_within_120_columns(value: object, start: int) -> None:
    """What the template writes of its own (literals, docstrings from descriptions) reads back as
    the same value and never passes column 120."""
    from llfsm.compiler.literals import WIDTH, doc_lines, py, py_block

    block = py_block(value, 4, start)
    assert ast.literal_eval(block) == value
    assert all(len(line) <= WIDTH for line in (" " * start + block).split("\n"))
    if start + len(py(value)) <= WIDTH:
        assert block == py(value)  # what fits stays on one line
    text = str(value)
    for indent in (0, 4):
        doc = doc_lines(text, indent)
        tree = ast.parse(f"class C:\n{doc}\n" if indent else f"{doc}\n")
        want = " ".join(text.split()) or "A machine."
        assert ast.get_docstring(tree.body[0] if indent else tree, clean=False) == want
        assert all(len(line) <= WIDTH for line in doc.split("\n"))


def test_a_300_state_machine_is_laid_out_within_the_dummy_budget() -> None:
    # every state also goes to END, as the how-to writes `not ros.ok()`: 90,000 dummies unbounded
    from llfsm.diagram import layout as layout_mod
    from llfsm.diagram.svg import layout

    names = [f"S{i}" for i in range(299)] + ["END"]
    states = [
        {
            "name": s,
            "transitions": [{"index": 0, "target": "END", "guard": "not ros.ok()"}]
            + ([{"index": 1, "target": names[i + 1], "guard": "True"}] if i < 298 else []),
            "accepting": False,
        }
        for i, s in enumerate(names[:-1])
    ] + [{"name": "END", "transitions": [], "accepting": True}]
    placed = layout({"name": "big", "states": states, "initial": "S0", "suspend": None})
    assert set(placed.centres) == set(names)
    assert len(placed.routes) == 597 and all(len(r.points) >= 2 and r.label is not None for r in placed.routes)
    straight = [r for r in placed.routes if len(r.points) == 2]  # beyond the budget: one curve each
    long = sum((len(r.points) - 2) // 2 for r in placed.routes if len(r.points) > 2)  # two points per dummy
    assert straight and long <= layout_mod.MAX_DUMMIES
