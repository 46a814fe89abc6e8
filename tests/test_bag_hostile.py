"""Bags are files from anywhere: a hostile bag is one clear line and a failed status, never a
traceback, and it writes nothing outside llfsm's own scratch folder (issue 18, items 6 and 7).

Each bag here is a real one (rosbags' writer, as `ros2 bag record` lays it out) that is then
tampered with: its embedded message definitions name packages such as `..`, or its
metadata.yaml holds what rosbag2 never writes.  The three readers of a bag are tried on each:
`llfsm bag info` (status 1), `llfsm bag play` and `llfsm run --play` (status 2, as every bad
bag to play is).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from helpers import llfsm_process, write_machine

from llfsm.bag.errors import BagError

EVIL_DEFINITIONS = {
    # what each embedded definition names; `..` would write beside the scratch folder
    "parent package": "Evil inner\n" + "=" * 80 + "\nMSG: ../Evil\nint32 x\n",
    "parent package, long form": "Evil inner\n" + "=" * 80 + "\nMSG: ../msg/Evil\nint32 x\n",
    "absolute": "Evil inner\n" + "=" * 80 + "\nMSG: /Evil\nint32 x\n",
    "dotted name": "Evil inner\n" + "=" * 80 + "\nMSG: evil_msgs/..\nint32 x\n",
    "module path": "Evil inner\n" + "=" * 80 + "\nMSG: os.path/Evil\nint32 x\n",
}


def _bag(path: Path, storage: str = "mcap", msgtype: str = "evil_msgs/msg/Root", definition: str | None = None) -> None:
    """A bag as ROS 2 tools write it: a Twist topic, and a topic of a type llfsm has no class
    for, with `definition` as the definition it embeds (a harmless one by default)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    Twist = store.types["geometry_msgs/msg/Twist"]
    Vector3 = store.types["geometry_msgs/msg/Vector3"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        tw = w.add_connection("/turtle1/cmd_vel", "geometry_msgs/msg/Twist", typestore=store)
        t0 = 1_700_000_000_000_000_000
        twist = Twist(linear=Vector3(x=1.0, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.5))
        w.write(tw, t0, store.serialize_cdr(twist, "geometry_msgs/msg/Twist"))
        if definition is not None:
            ev = w.add_connection("/evil", msgtype, msgdef=definition, rihs01="RIHS01_" + "0" * 64)
            w.write(ev, t0 + 1, bytes([0, 1, 0, 0, 7, 0, 0, 0]))


def _files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*")}


def _one_clear_line(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, stderr
    assert lines[0].startswith("llfsm: ") and "Traceback" not in stderr and "internal error" not in stderr, stderr
    return lines[0]


def _idle(root: Path) -> Path:
    return write_machine(root, "idle", {"A": [("A", "False")]})


def _play_verbs(root: Path, bag: Path) -> list[tuple[str, list[str | os.PathLike[str]]]]:
    return [
        ("bag play", ["bag", "play", bag]),
        ("run --play", ["run", "--clock", "sim", _idle(root), "--duration", "10ms", "--play", bag]),
    ]


# -- item 6: names in embedded definitions never become paths outside the scratch folder ------------


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
@pytest.mark.parametrize("case", sorted(EVIL_DEFINITIONS))
def test_a_definition_naming_a_bad_package_is_refused_and_writes_nothing(
    tmp_path: Path, storage: str, case: str
) -> None:
    bag = tmp_path / "bag"
    _bag(bag, storage, definition=EVIL_DEFINITIONS[case])
    scratch = tmp_path / "scratch" / "tmp"  # TMPDIR: `..` of a scratch folder is tmp_path/scratch
    scratch.mkdir(parents=True)
    machines = tmp_path / "m"
    machines.mkdir()
    before = _files(tmp_path)
    for verb, args in _play_verbs(machines, bag):
        before = _files(tmp_path)
        r = llfsm_process(*args, env=dict(os.environ, TMPDIR=str(scratch)))
        line = _one_clear_line(r.stderr)
        assert r.status == 2, (verb, r.stderr)
        assert "not a valid message type name" in line, (verb, line)
        assert _files(tmp_path) == before, (verb, _files(tmp_path) - before)
        assert not (tmp_path / "scratch" / "msg").exists() and not (tmp_path / "msg").exists()


def test_the_type_of_a_topic_is_checked_before_it_becomes_a_path(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    _bag(bag, "mcap", msgtype="../msg/Evil", definition="int32 x\n")
    scratch = tmp_path / "scratch" / "tmp"
    scratch.mkdir(parents=True)
    before = _files(tmp_path)
    r = llfsm_process("bag", "play", bag, env=dict(os.environ, TMPDIR=str(scratch)))
    assert r.status == 2 and "not a valid message type name" in _one_clear_line(r.stderr)
    assert _files(tmp_path) == before


def test_generated_definitions_never_follow_a_symlink(tmp_path: Path) -> None:
    """The scratch folder is private and fresh; even so, a link found in it is never written
    through: not a linked package folder, not a dangling link where a file would go."""
    from llfsm.bag.typesupport import class_from_definition

    outside = tmp_path / "outside"
    outside.mkdir()
    folder = tmp_path / "scratch"
    (folder / "link_msgs").mkdir(parents=True)
    (folder / "link_msgs" / "msg").symlink_to(outside)
    with pytest.raises(BagError, match="link_msgs"):
        class_from_definition("link_msgs/msg/Root", "ros2msg", "int32 x\n", folder)
    assert list(outside.iterdir()) == []

    (folder / "dangling_msgs" / "msg").mkdir(parents=True)
    (folder / "dangling_msgs" / "msg" / "Root.msg").symlink_to(outside / "Root.msg")
    with pytest.raises(BagError, match=r"Root\.msg"):
        class_from_definition("dangling_msgs/msg/Root", "ros2msg", "int32 x\n", folder)
    assert list(outside.iterdir()) == []


def test_a_good_definition_still_builds_its_class(tmp_path: Path) -> None:
    from llfsm.bag.typesupport import class_from_definition

    definition = "Inner inner\nint8 k\n" + "=" * 80 + "\nMSG: good_msgs/Inner\nfloat64 v\n"
    folder = tmp_path / "scratch"
    folder.mkdir()
    cls = class_from_definition("good_msgs/msg/Outer", "ros2msg", definition, folder)
    assert cls._TYPE == "good_msgs/msg/Outer"
    assert _files(folder) == {
        "good_msgs",
        "good_msgs/msg",
        "good_msgs/msg/Outer.msg",
        "good_msgs/msg/Inner.msg",
    }


# -- item 7: metadata.yaml is validated, one line naming the field --------------------------------------


def _meta(bag: Path) -> dict:
    return yaml.safe_load((bag / "metadata.yaml").read_text())


def _write_meta(bag: Path, doc: dict) -> None:
    (bag / "metadata.yaml").write_text(yaml.safe_dump(doc, sort_keys=False))


def _set(doc: dict, dotted: str, value: object) -> dict:
    node = doc["rosbag2_bagfile_information"]
    *path, last = dotted.split(".")
    for key in path:
        node = node[int(key)] if isinstance(node, list) else node[key]
    node[last] = value
    return doc


BAD_FIELDS = [
    # (field as the error names it, where to put what)
    ("starting_time.nanoseconds_since_epoch", "starting_time.nanoseconds_since_epoch", 10**30),
    ("starting_time.nanoseconds_since_epoch", "starting_time.nanoseconds_since_epoch", "soon"),
    ("duration.nanoseconds", "duration.nanoseconds", -1),
    ("duration", "duration", 5),
    ("topics_with_message_count[0]", "topics_with_message_count", [1, 2]),
    ("topics_with_message_count[0].message_count", "topics_with_message_count.0.message_count", "abc"),
    ("topics_with_message_count[0].topic_metadata.name", "topics_with_message_count.0.topic_metadata.name", ["x"]),
    ("message_count", "message_count", "abc"),
    ("message_count", "message_count", float("inf")),
    ("message_count", "message_count", True),
    ("relative_file_paths", "relative_file_paths", "bag_0.mcap"),
    ("custom_data", "custom_data", [1, 2]),
    ("version", "version", "nine"),
    ("storage_identifier", "storage_identifier", "mcap\x1b[2J"),
]


@pytest.mark.parametrize(("field", "where", "value"), BAD_FIELDS, ids=[f"{w}={v!r}" for _f, w, v in BAD_FIELDS])
def test_a_bad_field_is_one_line_naming_metadata_yaml_and_the_field(
    tmp_path: Path, field: str, where: str, value: object
) -> None:
    bag = tmp_path / "bag"
    _bag(bag)
    _write_meta(bag, _set(_meta(bag), where, value))
    r = llfsm_process("bag", "info", bag)
    line = _one_clear_line(r.stderr)
    assert r.status == 1, r.stderr
    assert "metadata.yaml" in line and f"{field}:" in line, line
    assert "line " in line, line
    for verb, args in _play_verbs(tmp_path, bag):
        r = llfsm_process(*args)
        line = _one_clear_line(r.stderr)
        assert r.status == 2 and "metadata.yaml" in line and f"{field}:" in line, (verb, r.stderr)


def test_the_line_of_the_bad_field_is_named(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    _bag(bag)
    text = (bag / "metadata.yaml").read_text()
    lines = text.splitlines()
    number = next(i for i, ln in enumerate(lines, 1) if ln.strip().startswith("message_count:"))
    lines[number - 1] = lines[number - 1].split(":")[0] + ": .inf"
    (bag / "metadata.yaml").write_text("\n".join(lines) + "\n")
    r = llfsm_process("bag", "info", bag)
    assert r.status == 1
    assert f"metadata.yaml: line {number}: " in _one_clear_line(r.stderr), r.stderr


@pytest.mark.parametrize("how", ["parent", "absolute", "symlink", "fifo"])
def test_files_outside_the_bag_are_refused(tmp_path: Path, how: str) -> None:
    bag = tmp_path / "bag"
    _bag(bag)
    secret = tmp_path / "secret.mcap"
    secret.write_bytes(b"s" * 12345)
    doc = _meta(bag)
    if how == "parent":
        _set(doc, "relative_file_paths", ["../secret.mcap"])
    elif how == "absolute":
        _set(doc, "relative_file_paths", [str(secret)])
    elif how == "symlink":
        (bag / "bag.mcap").unlink()
        (bag / "bag.mcap").symlink_to(secret)
    else:  # inside the bag, but opening it would wait for a writer for ever
        (bag / "bag.mcap").unlink()
        os.mkfifo(bag / "bag.mcap")
    _write_meta(bag, doc)
    why = "not a regular file" if how == "fifo" else "outside the bag"
    r = llfsm_process("bag", "info", bag, timeout=30)
    line = _one_clear_line(r.stderr)
    assert r.status == 1 and "relative_file_paths[0]" in line and why in line, line
    assert "12.1 KiB" not in r.stdout
    for verb, args in _play_verbs(tmp_path, bag):
        r = llfsm_process(*args, timeout=30)
        line = _one_clear_line(r.stderr)
        assert r.status == 2 and why in line, (verb, r.stderr)


def _alias_bomb(levels: int = 6) -> str:
    lines = ["  custom_data:", '    l0: &l0 ["x", "x", "x", "x", "x", "x", "x", "x", "x", "x"]']
    for i in range(1, levels):
        refs = ", ".join([f"*l{i - 1}"] * 10)
        lines.append(f"    l{i}: &l{i} [{refs}]")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("case", ["alias bomb", "nested 500", "nested 5000", "self alias", "not utf-8", "fifo"])
def test_hostile_yaml_is_one_clear_line(tmp_path: Path, case: str) -> None:
    bag = tmp_path / "bag"
    _bag(bag)
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    if case == "alias bomb":
        text = text.replace("  custom_data: null\n", _alias_bomb())
    elif case.startswith("nested"):
        depth = int(case.split()[1])
        text = text.replace("  custom_data: null\n", "  custom_data: " + "[" * depth + "]" * depth + "\n")
    elif case == "self alias":
        text = text.replace("  custom_data: null\n", "  custom_data: &a {x: *a}\n")
    if case == "not utf-8":
        meta.write_bytes(text.encode() + b"  ros_distro: \xff\xfe\n")
    elif case == "fifo":
        meta.unlink()
        os.mkfifo(meta)
    else:
        meta.write_text(text)
    r = llfsm_process("bag", "info", bag, timeout=30)
    line = _one_clear_line(r.stderr)
    assert r.status == 1 and "metadata.yaml" in line, r.stderr
    for verb, args in _play_verbs(tmp_path, bag):
        r = llfsm_process(*args, timeout=30)
        line = _one_clear_line(r.stderr)
        assert r.status == 2 and "metadata.yaml" in line, (verb, r.stderr)


def test_the_bags_llfsm_and_ros_tools_write_still_pass(tmp_path: Path) -> None:
    """The model is no stricter than rosbag2: bags from rosbags' writer, and the fields it
    leaves out where older rosbag2 versions did (files, custom_data, ros_distro)."""
    from llfsm.bag.info import format_info, read_metadata

    for storage in ("mcap", "sqlite3"):
        bag = tmp_path / storage
        _bag(bag, storage)
        assert read_metadata(bag).message_count == 1
        assert "Messages:          1\n" in format_info(bag)
    doc = _meta(tmp_path / "mcap")
    for key in ("files", "custom_data", "ros_distro", "compression_format", "compression_mode"):
        del doc["rosbag2_bagfile_information"][key]
    _write_meta(tmp_path / "mcap", doc)
    assert "ROS Distro:        unknown\n" in format_info(tmp_path / "mcap")


def test_the_interface_search_never_joins_a_name_that_is_not_a_package(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The import hook's lookup (find_package) is the other place a type's package becomes a
    path: `..`, `a/b`, `x\\n` are never looked for, whatever folders the search path holds."""
    from llfsm.msgs import find_package

    root = tmp_path / "root" / "inner"
    (tmp_path / "root" / "msg").mkdir(parents=True)  # `root/inner/..` looks like a package
    (tmp_path / "pkg" / "msg").mkdir(parents=True)
    root.mkdir()
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(root))
    for name in ("..", "../pkg", "../../pkg", "/tmp", "", "pkg\n", "Pkg"):
        assert find_package(name) is None, name


@pytest.mark.parametrize("depth", [30, 5000])
def test_deep_nesting_is_refused_by_the_pure_python_parser_too(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, depth: int
) -> None:
    """Where PyYAML has no libyaml, its parser recurses: a deep nesting is its RecursionError or
    our depth limit, one MetadataError either way."""
    from llfsm.bag.info import MetadataError, read_metadata

    monkeypatch.delattr(yaml, "CSafeLoader", raising=False)
    bag = tmp_path / "bag"
    _bag(bag)
    meta = bag / "metadata.yaml"
    nested = "[" * depth + "]" * depth
    meta.write_text(meta.read_text().replace("  custom_data: null\n", f"  custom_data: {nested}\n"))
    with pytest.raises(MetadataError, match=r"metadata\.yaml") as e:
        read_metadata(bag)
    assert "\n" not in str(e.value)
