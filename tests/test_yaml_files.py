"""Every reader of YAML files that anyone may have written (launch files, verification files, ROS 2
params files, machine.yaml) refuses the same things the same way (llfsm.yamlfile): an alias bomb,
nesting past its bound, a file past its size, a FIFO where a file should be; each in one line
naming the file and the line, in the reader's own words."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from pathlib import Path

import pytest
from helpers import write_machine

from llfsm.lang.check import check_machine
from llfsm.launch.frontend import FrontEndError
from llfsm.launch.frontend import read as read_launch
from llfsm.props.file import FileError, read_verify_file
from llfsm.ros.parameter_files import ParameterTextError, read_params_file

#: (file name, reader, its error, the kind of file its messages name)
READERS: dict[str, tuple[str, Callable[[Path], object], type[Exception], str]] = {
    "launch": ("x.launch.yaml", lambda p: read_launch(str(p)), FrontEndError, "a launch file"),
    "verify": ("x.verify.yaml", read_verify_file, FileError, "a verification file"),
    "params": ("params.yaml", read_params_file, ParameterTextError, "a params file"),
}

BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi", strict=True)
)


def refusal(which: str, folder: Path, text: str | bytes | None) -> str:
    """What the reader says of a file holding `text` (None: a FIFO, which opening for reading
    would wait on for a writer), with the file's path as `FILE`; it must answer within 30 s."""
    name, read, error, _ = READERS[which]
    folder.mkdir()
    path = folder / name
    if text is None:
        os.mkfifo(path)
    elif isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    out: list[str] = []

    def attempt() -> None:
        with pytest.raises(error) as e:
            read(path)
        out.append(str(e.value).replace(str(path), "FILE"))

    reader = threading.Thread(target=attempt, daemon=True)
    reader.start()
    reader.join(timeout=30)
    assert out, f"the {which} reader hung or did not refuse"
    return out[0]


@pytest.mark.parametrize("which", READERS)
def test_every_yaml_reader_refuses_what_cannot_be_read_safely_at_its_line(which: str, tmp_path: Path) -> None:
    what = READERS[which][3]
    assert refusal(which, tmp_path / "a", "ok: 1\n" + BOMB) == f"FILE:2: anchors and aliases are not allowed in {what}"
    deep = "ok: 1\nx: " + "[" * 100 + "]" * 100 + "\n"
    assert refusal(which, tmp_path / "b", deep) == "FILE:2: nested deeper than 64 levels"
    assert refusal(which, tmp_path / "c", b"ok: 1\nx: \xff\n").endswith("FILE:2: not UTF-8 text")
    assert refusal(which, tmp_path / "d", "x" * (17 << 20)) == {
        "launch": "FILE: larger than 1 MiB: not a launch file",
        "verify": "FILE: larger than 1 MiB",
        "params": "FILE: larger than 16 MB: not a params file",
    }[which]
    assert refusal(which, tmp_path / "e", None) == "FILE: not a regular file"


def test_machine_yaml_gives_the_same_refusals_as_rules(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"A": None})
    (m / "machine.yaml").write_text("states:\n  - name: A\n" + BOMB)
    [d] = check_machine(m).diagnostics
    assert (d.code, d.line, d.message) == ("LF005", 3, "anchors and aliases are not allowed in machine.yaml")
