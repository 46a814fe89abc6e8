"""Helper modules beside a machine, through `llfsm build` and a run of the built module
(issue 22, item 7): `llfsm build -o build` then `llfsm run build/NAME.py` must import the
`helpers.py` that sat beside the machine, and where it cannot, the message says where llfsm
looked.  In processes of their own: an in-process run would keep the first `helpers` module
it imported for every later test.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from helpers import llfsm_process, write_machine


def _project(root: Path, helper: str = "greeting") -> Path:
    """machines/talker.machine importing machines/<helper>.py, in Includes.py and in a section."""
    machines = root / "machines"
    m = write_machine(
        machines,
        "talker",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": f"print({helper}.hello())\nimport {helper}_late\nprint({helper}_late.WORD)\n"},
        includes=f"import {helper}\n",
    )
    (machines / f"{helper}.py").write_text("def hello():\n    return 'hello from a helper'\n")
    (machines / f"{helper}_late.py").write_text("WORD = 'imported by a section'\n")
    return m


def test_a_built_module_imports_the_helpers_beside_its_machine(tmp_path: Path) -> None:
    _project(tmp_path)
    build = llfsm_process("build", "machines", "-o", "out", cwd=tmp_path)
    assert build.status == 0, build.stderr
    run = llfsm_process("run", "--clock", "sim", "out/talker.py", cwd=tmp_path)
    assert run.status == 0, run.stderr
    assert run.stdout.splitlines() == ["hello from a helper", "imported by a section"]


def test_the_build_says_what_the_module_needs(tmp_path: Path) -> None:
    _project(tmp_path)
    build = llfsm_process("build", "machines", "-o", "out", cwd=tmp_path)
    assert build.status == 0, build.stderr
    assert "greeting.py" in build.stderr and "greeting_late.py" in build.stderr, build.stderr
    assert "machines" in build.stderr
    # said when the module is written, not on every build that finds it up to date
    again = llfsm_process("build", "machines", "-o", "out", cwd=tmp_path)
    assert "greeting.py" not in again.stderr, again.stderr


def test_a_build_into_the_machines_folder_needs_nothing_said(tmp_path: Path) -> None:
    _project(tmp_path)
    build = llfsm_process("build", "machines", "-o", "machines", cwd=tmp_path)
    assert build.status == 0 and "greeting.py" not in build.stderr, build.stderr


def test_a_module_moved_away_from_its_helpers_says_where_llfsm_looked(tmp_path: Path) -> None:
    _project(tmp_path)
    assert llfsm_process("build", "machines", "-o", "out", cwd=tmp_path).status == 0
    elsewhere = tmp_path / "deploy"
    elsewhere.mkdir()
    shutil.copy(tmp_path / "out" / "talker.py", elsewhere / "talker.py")
    shutil.rmtree(tmp_path / "machines")
    run = llfsm_process("run", "--clock", "sim", elsewhere / "talker.py", cwd=tmp_path)
    assert run.status == 1
    assert "Traceback" not in run.stderr
    assert "No module named 'greeting'" in run.stderr, run.stderr
    assert str(elsewhere) in run.stderr, run.stderr  # where it was looked for
    assert "copy" in run.stderr
    # copied beside the module, as the message says, the helpers are found
    shutil.copytree(tmp_path / "out", tmp_path / "unused")  # (the build folder itself is not needed)
    (elsewhere / "greeting.py").write_text("def hello():\n    return 'hello from a helper'\n")
    (elsewhere / "greeting_late.py").write_text("WORD = 'imported by a section'\n")
    run = llfsm_process("run", "--clock", "sim", elsewhere / "talker.py", cwd=tmp_path)
    assert run.status == 0, run.stderr


def test_an_installed_package_finds_the_helpers_installed_with_its_machines(tmp_path: Path) -> None:
    """A colcon install: share/PKG/llfsm/NAME.py and share/PKG/machine/ (machines and helpers)."""
    src = tmp_path / "src"
    _project(src)
    share = tmp_path / "install" / "share" / "pkg"
    shutil.copytree(src / "machines", share / "machine")
    assert llfsm_process("build", share / "machine", "-o", share / "llfsm", cwd=tmp_path).status == 0
    import os

    env = dict(os.environ, AMENT_PREFIX_PATH=str(tmp_path / "install"))
    run = llfsm_process("run", "--clock", "sim", "pkg/talker", cwd=tmp_path, env=env)
    assert run.status == 0, run.stderr
    assert run.stdout.splitlines() == ["hello from a helper", "imported by a section"]
