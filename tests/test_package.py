"""`llfsm new package`, colcon builds of it, LF106 (undeclared dependencies) and the pre-commit hook."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from catkin_pkg.package import parse_package
from helpers import REPO, llfsm, llfsm_process, write_machine

from llfsm import scaffold
from llfsm.lang.check import check_machine
from llfsm.lang.check.packages import undeclared_dependencies

VENV_BIN = Path(sys.executable).parent


def new_package(src: Path, name: str, *args: str) -> Path:
    src.mkdir(parents=True, exist_ok=True)
    r = llfsm("new", "package", name, "--dir", src, *args)
    assert r.status == 0, r.stderr
    return src / name


def listing(folder: Path) -> list[str]:
    """Everything below `folder`, hidden entries included (a leftover temp folder would show)."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def lf106(machine: Path) -> list[tuple[str, int, str]]:
    return [(Path(d.file).name, d.line, d.message) for d in check_machine(machine).diagnostics if d.code == "LF106"]


# -- llfsm new package -----------------------------------------------------------------------------


def test_new_package_writes_an_ament_python_package_that_catkin_pkg_accepts(tmp_path: Path) -> None:
    r = llfsm(
        "new", "package", "turtle_bots", "--dir", tmp_path, "--dependencies", "geometry_msgs", "std_msgs",
        "--license", "Apache-2.0", "--machine", "blind", "wall",
    )  # fmt: skip
    assert r.status == 0, r.stderr
    assert r.stderr == ""  # a known licence: no warning
    pkg_dir = tmp_path / "turtle_bots"
    assert listing(pkg_dir) == [
        "machine",
        *[f"machine/{m}.machine{f}" for m in ("blind", "wall") for f in (
            "", "/Includes.py", "/State_INITIAL_OnEntry.py", "/State_INITIAL_Transition_0.expr", "/Variables.py",
            "/machine.yaml",
        )],
        "package.xml",
        "resource",
        "resource/turtle_bots",
        "setup.cfg",
        "setup.py",
        "test",
        "test/test_llfsm_check.py",
    ]  # fmt: skip
    assert (pkg_dir / "resource" / "turtle_bots").read_text() == ""
    pkg = parse_package(pkg_dir / "package.xml", warnings=[])  # validates, as colcon does
    assert pkg.package_format == 3
    assert pkg.name == "turtle_bots" and pkg.version == "0.0.0"
    assert [str(lic) for lic in pkg.licenses] == ["Apache-2.0"]
    for kind in (pkg.build_depends, pkg.exec_depends, pkg.build_export_depends):  # <depend> is all three
        assert [d.name for d in kind] == ["geometry_msgs", "std_msgs", "llfsm"]
    assert [d.name for d in pkg.test_depends] == ["python3-pytest"]
    assert pkg.get_build_type() == "ament_python"
    assert [(e.tagname, e.content) for e in pkg.exports] == [("build_type", "ament_python")]
    assert pkg.maintainers and pkg.maintainers[0].email
    assert "script_dir=$base/lib/turtle_bots" in (pkg_dir / "setup.cfg").read_text()
    compile((pkg_dir / "setup.py").read_text(), "setup.py", "exec")
    # the machines are valid skeletons, and the check the package's own test runs passes
    assert llfsm("check", "--strict", pkg_dir).status == 0
    assert r.stdout.startswith("created a new package\npackage name: turtle_bots\n")
    assert "dependencies: ['geometry_msgs', 'std_msgs', 'llfsm']\nmachines: ['blind', 'wall']\n" in r.stdout
    assert r.stdout.endswith("  llfsm run turtle_bots/blind\n")


def test_defaults_one_machine_named_after_the_package_and_ros2s_licence_warning(tmp_path: Path) -> None:
    r = llfsm("new", "package", "pinger", "--dir", tmp_path)
    assert r.status == 0
    assert (tmp_path / "pinger" / "machine" / "pinger.machine" / "machine.yaml").is_file()
    assert r.stderr.startswith("[WARNING]: Unknown license 'TODO: License declaration'.")
    assert "Apache-2.0" in r.stderr and "no LICENSE file has been created" in r.stderr
    pkg = parse_package(tmp_path / "pinger", warnings=[])
    assert [d.name for d in pkg.build_depends] == ["llfsm"]
    assert [str(lic) for lic in pkg.licenses] == ["TODO: License declaration"]


def test_several_values_as_ros2_pkg_create_takes_them_or_repeated_or_with_commas(tmp_path: Path) -> None:
    a = new_package(tmp_path / "a", "pk", "--dependencies", "std_msgs", "turtlesim", "--license", "MIT")
    b = new_package(tmp_path / "b", "pk", "--dependencies", "std_msgs,turtlesim", "--license", "MIT")
    c = new_package(tmp_path / "c", "pk", "--dependencies", "std_msgs", "--dependencies", "turtlesim", "--license=MIT")
    for p in (a, b, c):
        assert [d.name for d in parse_package(p, warnings=[]).exec_depends] == ["std_msgs", "turtlesim", "llfsm"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["My_pkg"], "not a valid ROS package name"),
        (["1pkg"], "not a valid ROS package name"),
        (["my-pkg"], "not a valid ROS package name"),
        (["my__pkg"], "not a valid ROS package name"),
        (["pkg_"], "not a valid ROS package name"),
        (["p"], "not a valid ROS package name"),
        (["ok_pkg", "--dependencies", "Geometry_msgs"], "'Geometry_msgs' is not a valid dependency name"),
        (["ok_pkg", "--dependencies", "std_msgs/msg"], "'std_msgs/msg' is not a valid dependency name"),
        (["ok_pkg", "--dependencies", "<x>"], "'<x>' is not a valid dependency name"),
        (["ok_pkg", "--dependencies", "ok_pkg"], "cannot depend on itself"),
        (["ok_pkg", "--machine", "2fast"], "'2fast' is not a valid machine name"),
        (["ok_pkg", "--machine", "class"], "'class' is not a valid machine name"),
        (["import"], "'import' is not a valid machine name"),  # a fine package name, but the default machine
        (["ok_pkg", "--maintainer-email", "not an e-mail"], "package.xml would be invalid"),
        (["ok_pkg", "--license", " "], "--license must not be empty"),
        (["existing"], "already exists; nothing was written"),
    ],
)
def test_bad_input_is_one_message_exit_2_and_nothing_written(tmp_path: Path, args: list[str], message: str) -> None:
    src = tmp_path / "src"
    (src / "existing").mkdir(parents=True)
    before = listing(src)
    r = llfsm("new", "package", *args, "--dir", src)
    assert r.status == 2
    assert r.stdout == ""
    assert r.stderr.startswith("llfsm: ") and r.stderr.count("\n") == 1 and message in r.stderr, r.stderr
    assert listing(src) == before


def test_name_after_an_option_with_several_values_is_explained(tmp_path: Path) -> None:
    r = llfsm("new", "package", "--dependencies", "std_msgs", "walker", "--dir", tmp_path)
    assert r.status == 2 and "missing NAME: put it before --dependencies" in r.stderr
    assert listing(tmp_path) == []


def test_bad_input_in_a_real_process_has_no_traceback(tmp_path: Path) -> None:
    r = llfsm_process("new", "package", "Bad-Name", "--dir", tmp_path)
    assert r.status == 2 and r.stderr.startswith("llfsm: 'Bad-Name' is not a valid ROS package name")
    assert "Traceback" not in r.stderr
    r = llfsm_process("new", "package", "fine", "--dir", tmp_path / "missing")
    assert r.status == 2 and "no such directory" in r.stderr and not (tmp_path / "missing").exists()


def test_an_interrupted_write_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    written: list[Path] = []
    real = Path.write_text

    def flaky(self: Path, text: str, *a: object, **kw: object) -> int:
        if len(written) == 3:
            raise KeyboardInterrupt
        written.append(self)
        return real(self, text, *a, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(Path, "write_text", flaky)
    with pytest.raises(KeyboardInterrupt):
        scaffold.create_package(tmp_path, "half", license="MIT")
    assert len(written) == 3
    assert listing(tmp_path) == []


def test_new_machine_still_works_and_is_written_whole(tmp_path: Path) -> None:
    r = llfsm("new", "machine", "greeter", "--dir", tmp_path / "deeper")
    assert r.status == 0
    assert llfsm("check", "--strict", tmp_path / "deeper" / "greeter.machine").status == 0
    assert listing(tmp_path / "deeper") == [
        "greeter.machine",
        "greeter.machine/Includes.py",
        "greeter.machine/State_INITIAL_OnEntry.py",
        "greeter.machine/State_INITIAL_Transition_0.expr",
        "greeter.machine/Variables.py",
        "greeter.machine/machine.yaml",
    ]


def test_build_from_the_package_root_builds_every_machine(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pkg = new_package(tmp_path, "two_bots", "--machine", "one", "two", "--license", "MIT")
    monkeypatch.chdir(pkg)
    r = llfsm("build")
    assert r.status == 0, r.stderr
    assert sorted(p.name for p in (pkg / "build" / "llfsm").iterdir()) == ["one.py", "two.py"]
    assert llfsm("build").stderr.count("unchanged") == 2


def test_the_packages_own_test_passes(tmp_path: Path) -> None:
    """What `colcon test` runs in the package: llfsm check --strict on its machines."""
    pkg = new_package(tmp_path, "tested", "--license", "MIT")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(pkg / "test")]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=pkg)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (pkg / "machine" / "tested.machine" / "Includes.py").write_text("from llfsm.msgs.std_msgs.msg import String\n")
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=pkg)
    assert proc.returncode == 1 and "LF106" in proc.stdout


# -- the colcon round trip -------------------------------------------------------------------------


def test_scaffold_check_colcon_build_source_run(tmp_path: Path) -> None:
    """The three commands of docs/packages.md, as a user types them, in a fresh workspace."""
    colcon = VENV_BIN / "colcon"
    assert colcon.exists(), "colcon is a dev dependency: pip install -e '.[dev]'"
    ws = tmp_path / "ros2_ws"
    (ws / "src").mkdir(parents=True)
    # a second machine uses an interface of the package itself, installed to share/demo_bot/msg
    script = """
        set -eo pipefail
        cd src
        llfsm new package demo_bot --dependencies std_msgs --machine demo_bot talker --license Apache-2.0
        mkdir demo_bot/msg
        printf 'string text\\nint32 count\\n' > demo_bot/msg/Note.msg
        echo 'from llfsm.msgs.demo_bot.msg import Note' > demo_bot/machine/talker.machine/Includes.py
        echo 'print(Note(text="hi", count=3))' > demo_bot/machine/talker.machine/State_INITIAL_OnEntry.py
        llfsm check --strict .
        cd ..
        colcon build
        source install/setup.bash
        llfsm run demo_bot/demo_bot --clock sim -v
        llfsm run demo_bot/talker --clock sim
    """
    env = {k: v for k, v in os.environ.items() if not k.startswith(("AMENT_", "COLCON_", "PYTHONPATH"))}
    env |= {"PATH": f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}", "COLCON_HOME": str(tmp_path / "colcon_home")}
    proc = subprocess.run(
        ["bash", "--noprofile", "--norc", "-c", script], cwd=ws, env=env, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Summary: 1 package finished" in proc.stdout
    lines = proc.stdout.splitlines()
    assert "demo_bot: hello from INITIAL" in lines
    assert "demo_bot.msg.Note(text='hi', count=3)" in lines
    assert "m  0 s  0 - demo_bot             - INITIAL" in proc.stderr
    share = ws / "install" / "demo_bot" / "share"
    installed = {str(p.relative_to(share)) for p in share.rglob("*") if p.is_file()}
    assert {
        "ament_index/resource_index/packages/demo_bot",
        "demo_bot/package.xml",
        "demo_bot/llfsm/demo_bot.py",
        "demo_bot/llfsm/talker.py",
        "demo_bot/machine/demo_bot.machine/machine.yaml",
        "demo_bot/machine/talker.machine/Includes.py",
        "demo_bot/msg/Note.msg",
        "demo_bot/hook/ament_prefix_path.dsv",
    } <= installed
    assert "class DemoBotMachine" in (share / "demo_bot" / "llfsm" / "demo_bot.py").read_text()


def test_a_machine_with_errors_fails_the_colcon_build(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    pkg = new_package(ws / "src", "broken_bot", "--license", "MIT")
    (pkg / "machine" / "broken_bot.machine" / "State_INITIAL_Transition_0.expr").write_text("after_ms(\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("AMENT_", "COLCON_"))}
    env |= {"PATH": f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}", "COLCON_HOME": str(tmp_path / "colcon_home")}
    proc = subprocess.run(
        [str(VENV_BIN / "colcon"), "build"], cwd=ws, env=env, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode != 0
    out = proc.stdout + proc.stderr
    assert "LF030" in out and "broken_bot: the machine has errors; broken_bot was not built" in out
    assert not (ws / "install" / "broken_bot" / "share" / "broken_bot" / "llfsm").exists()


# -- LF106 undeclared-dependency -------------------------------------------------------------------

PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>0.1.0</version>
  <description>d</description>
  <maintainer email="a@b.org">a</maintainer>
  <license>MIT</license>
{deps}
</package>
"""


def package(root: Path, name: str = "bots", deps: str = "") -> Path:
    root.mkdir(parents=True, exist_ok=True)
    (root / "package.xml").write_text(PACKAGE_XML.format(name=name, deps=deps))
    return root


def test_lf106_an_import_of_an_undeclared_message_package(tmp_path: Path) -> None:
    pkg = package(tmp_path / "bots", deps="  <depend>std_msgs</depend>")
    m = write_machine(
        pkg / "machine",
        "bot",
        {"INITIAL": [("END", "True")], "END": None},
        {"INITIAL_OnEntry": "if True:\n    import llfsm.msgs.turtlesim.srv as tsrv\nprint(tsrv)\n"},
        includes=(
            "from llfsm import ros\n"
            "from llfsm.msgs.std_msgs.msg import String\n"
            "from llfsm.msgs.geometry_msgs.msg import Twist\n"
            "from llfsm.msgs import geometry_msgs, turtle_sensor_interface\n"
            "from llfsm.msgs.bots.msg import Own\n"  # the package's own interfaces
            "from llfsm.msgs._message import Message\n"  # llfsm's own module, not a package
        ),
    )
    found = lf106(m)
    assert [(f, line) for f, line, _ in found] == [
        ("Includes.py", 3),
        ("Includes.py", 4),
        ("Includes.py", 4),
        ("State_INITIAL_OnEntry.py", 2),
    ]
    assert "'geometry_msgs'" in found[0][2] and "add <depend>geometry_msgs</depend>" in found[0][2]
    assert str(pkg / "package.xml") in found[0][2]
    assert "'turtle_sensor_interface'" in found[2][2] and "'turtlesim'" in found[3][2]
    d = next(d for d in check_machine(m).diagnostics if d.code == "LF106")
    assert d.severity == "warning" and (d.line, d.column) == (3, 1)
    r = llfsm("check", m)
    assert r.status == 0 and "LF106 warning" in r.stdout
    assert llfsm("check", "--strict", m).status == 1


def test_lf106_declared_by_depend_exec_depend_or_build_depend_is_fine(tmp_path: Path) -> None:
    includes = "from llfsm.msgs.std_msgs.msg import String\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n"
    for n, deps in enumerate(
        [
            "<depend>std_msgs</depend><depend>geometry_msgs</depend>",
            "<exec_depend>std_msgs</exec_depend><build_depend>geometry_msgs</build_depend>",
        ]
    ):
        pkg = package(tmp_path / f"p{n}", deps=deps)
        m = write_machine(pkg / "machine", "bot", {"A": None}, includes=includes)
        assert lf106(m) == []
    pkg = package(tmp_path / "tests_only", deps="<test_depend>std_msgs</test_depend><depend>geometry_msgs</depend>")
    m = write_machine(pkg / "machine", "bot", {"A": None}, includes=includes)
    assert [line for _, line, _ in lf106(m)] == [1]  # a test dependency is not there at run time


def test_lf106_outside_a_package_nothing_is_checked(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "loose", {"A": None}, includes="from llfsm.msgs.geometry_msgs.msg import Twist\n")
    assert lf106(m) == []


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        ('<?xml version="1.0"?>\n<package format="3">\n  <name>x</name>\n<oops>\n', 5, "invalid XML"),
        ('<package format="3">\n  <name>bots</name>\n</package>\n', 1, 'exactly one "version" tag'),
        ('<package format="4"><name>bots</name></package>\n', 1, "AssertionError"),
        ('<package format="x"><name>bots</name></package>\n', 1, "ValueError"),
        ("\n\n<package format='3'><name>bots</name><version>1.0</version></package>\n", 3, '"description" tag'),
    ],
)
def test_lf106_a_broken_package_xml_is_a_diagnostic(tmp_path: Path, text: str, line: int, words: str) -> None:
    pkg = tmp_path / "bots"
    pkg.mkdir()
    (pkg / "package.xml").write_text(text)
    m = write_machine(pkg / "machine", "bot", {"A": None}, includes="from llfsm.msgs.std_msgs.msg import String\n")
    diags = undeclared_dependencies(m, check_machine(m).read.trees)
    assert len(diags) == 1
    d = diags[0]
    assert (d.code, d.file, d.line) == ("LF106", str(pkg / "package.xml"), line)
    assert d.message.startswith("package.xml cannot be read") and words in d.message, d.message
    assert "\n" not in d.message
    r = llfsm_process("check", m)
    assert r.status == 0 and "Traceback" not in r.stderr and f"package.xml:{line}:" in r.stdout


def test_lf106_the_scaffold_and_a_missing_depend(tmp_path: Path) -> None:
    pkg = new_package(tmp_path, "walker", "--dependencies", "std_msgs", "--license", "MIT")
    m = pkg / "machine" / "walker.machine"
    (m / "Includes.py").write_text("from llfsm.msgs.std_msgs.msg import String\n")
    assert llfsm("check", "--strict", pkg).status == 0
    (m / "Includes.py").write_text(
        "from llfsm.msgs.std_msgs.msg import String\nfrom llfsm.msgs.turtlesim.msg import Pose\n"
    )
    r = llfsm("check", "--strict", "--format", "github", pkg)
    assert r.status == 1
    assert r.stdout.startswith(f"::warning file={m}/Includes.py,line=2,col=1,title=LF106::imports messages")


def test_lf106_names_package_xml_as_the_machine_was_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Relative in, relative out: GitHub annotations and SARIF need paths inside the repository."""
    pkg = new_package(tmp_path, "walker", "--license", "MIT")
    (pkg / "machine" / "walker.machine" / "Includes.py").write_text("from llfsm.msgs.std_msgs.msg import String\n")
    (pkg / "package.xml").write_text((pkg / "package.xml").read_text().replace("<name>", "<nom>", 1))
    monkeypatch.chdir(tmp_path)
    r = llfsm("check", "--format", "sarif", "walker")
    assert '"uri": "walker/package.xml"' in r.stdout
    (pkg / "package.xml").write_text((pkg / "package.xml").read_text().replace("<nom>", "<name>", 1))
    r = llfsm("check", "walker")
    assert "which walker/package.xml does not declare" in r.stdout


# -- pre-commit --------------------------------------------------------------------------------------


def the_hook() -> dict[str, object]:
    hooks = yaml.safe_load((REPO / ".pre-commit-hooks.yaml").read_text())
    (hook,) = [h for h in hooks if h["id"] == "llfsm-check"]
    return hook


def consumer_repo(root: Path) -> Path:
    """A project with one good machine, one broken machine and a file that is no machine's."""
    root.mkdir()
    write_machine(root / "machines", "good", {"A": [("END", "after_ms(5)")], "END": None})
    write_machine(root / "machines", "broken", {"A": [("B", "True")]})
    (root / "README.md").write_text("# robots\n")
    return root


def test_the_hook_is_llfsm_check_on_machine_files() -> None:
    hook = the_hook()
    assert hook["language"] == "python" and hook["entry"] == "llfsm check" and hook["require_serial"] is True
    files = re.compile(str(hook["files"]))
    assert files.search("machines/good.machine/machine.yaml")
    assert files.search("src/pkg/machine/walker.machine/State_A_OnEntry.py")
    assert not files.search("README.md") and not files.search("machines/notes.txt")


def test_the_hook_entry_with_file_names_as_pre_commit_passes_them(tmp_path: Path) -> None:
    """What pre-commit runs: the entry, then the changed files that match `files`."""
    repo = consumer_repo(tmp_path / "repo")
    files = re.compile(str(the_hook()["files"]))
    changed = sorted(str(p.relative_to(repo)) for p in repo.rglob("*") if p.is_file())
    passed = [f for f in changed if files.search(f)]
    assert "README.md" not in passed
    entry = [sys.executable, "-m", "llfsm", *shlex.split(str(the_hook()["entry"]))[1:]]
    proc = subprocess.run([*entry, *passed], cwd=repo, capture_output=True, text=True)
    assert proc.returncode == 1
    assert "machines/broken.machine/machine.yaml:3:19: LF020 error" in proc.stdout
    assert "checked 2 machine(s): 1 error(s)" in proc.stderr  # each machine once, however many files
    good = [f for f in passed if "good.machine" in f]
    proc = subprocess.run([*entry, *good], cwd=repo, capture_output=True, text=True)
    assert proc.returncode == 0 and "checked 1 machine(s)" in proc.stderr
    proc = subprocess.run([*entry, "README.md"], cwd=repo, capture_output=True, text=True)
    assert proc.returncode == 2  # a file that is no machine's is still a usage error


def test_pre_commit_runs_the_hook(tmp_path: Path) -> None:
    """pre-commit itself, offline: the hook from .pre-commit-hooks.yaml as a local hook.

    Only `language` differs: `python` would make pre-commit pip-install llfsm from this
    repository into its own environment (network); `system` runs the llfsm already installed."""
    pre_commit = VENV_BIN / "pre-commit"
    assert pre_commit.exists(), "pre-commit is a dev dependency: pip install -e '.[dev]'"
    git = shutil.which("git")
    if git is None:
        pytest.skip("pre-commit needs git")
    repo = consumer_repo(tmp_path / "repo")
    hook = the_hook() | {"language": "system"}
    hook["entry"] = " ".join([shlex.quote(sys.executable), "-m", "llfsm", *shlex.split(str(hook["entry"]))[1:]])
    (repo / ".pre-commit-config.yaml").write_text(yaml.safe_dump({"repos": [{"repo": "local", "hooks": [hook]}]}))
    env = {k: v for k, v in os.environ.items() if not k.startswith("GIT_")}
    env |= {"PRE_COMMIT_HOME": str(tmp_path / "pre-commit-home"), "HOME": str(tmp_path)}

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(args, cwd=repo, env=env, capture_output=True, text=True, timeout=120)

    assert run(git, "init", "-q").returncode == 0
    assert run(git, "add", "-A").returncode == 0
    proc = run(str(pre_commit), "run", "--all-files")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "llfsm check" in proc.stdout and "Failed" in proc.stdout
    assert "machines/broken.machine/machine.yaml:3:19: LF020 error" in proc.stdout
    # require_serial: one process for all files, so each problem is reported once
    assert proc.stdout.count("LF020") == 1 and "checked 2 machine(s)" in proc.stdout
    proc = run(str(pre_commit), "run", "--files", "machines/good.machine/machine.yaml", "README.md")
    assert proc.returncode == 0 and "Passed" in proc.stdout, proc.stdout + proc.stderr
    proc = run(str(pre_commit), "run", "--files", "README.md")
    assert proc.returncode == 0 and "no files to check" in proc.stdout and "Skipped" in proc.stdout
