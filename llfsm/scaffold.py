"""Skeletons: `llfsm new machine` and `llfsm new package`, rendered from templates/.

Both write into a hidden folder beside the target and rename it into place at the end, so a
failure (a bad name, a full disk, an interrupt) leaves nothing behind, never half a package.
"""

from __future__ import annotations

import getpass
import json
import os
import re
import secrets
import shutil
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import jinja2

from .lang.files import MAX_STATE_NAME
from .lang.model import MAX_MACHINE_NAME, is_valid_name
from .templating import environment

TEMPLATES = Path(__file__).resolve().parent / "templates"

#: The licence identifiers `ros2 pkg create` knows (ament_copyright's); others get its warning.
AMENT_LICENSES = (
    "Apache-2.0",
    "BSL-1.0",
    "BSD-2.0",
    "BSD-2-Clause",
    "BSD-3-Clause",
    "GPL-3.0-only",
    "LGPL-3.0-only",
    "MIT",
    "MIT-0",
)
DEFAULT_LICENSE = "TODO: License declaration"  # what ros2 pkg create writes when given none
PACKAGE_VERSION = "0.0.0"
# REP 144 and ros2 pkg create: lower case, digits and single underscores, a letter first.
# No trailing underscore either: llfsm.msgs.<pkg> refuses such names for the package's interfaces.
_PACKAGE_NAME = re.compile(r"^[a-z](?:[a-z0-9]|_(?=[a-z0-9]))+\Z")  # \Z: `$` would pass "name\n"
# A dependency is a ROS package or a rosdep key (python3-pytest, libboost-dev): no spaces, no markup.
_DEPENDENCY = re.compile(r"^[a-z0-9][a-z0-9_.+-]*\Z")
_EMAIL_LOCAL = re.compile(r"[^A-Za-z0-9_%+-]+")


class ScaffoldError(Exception):
    pass


def _env(folder: str) -> jinja2.Environment:
    return environment(
        TEMPLATES / folder,
        trim=folder == "package",
        # package.xml gets its text escaped; Python and YAML templates use explicit filters
        autoescape=jinja2.select_autoescape(enabled_extensions=("xml.j2",), default_for_string=False, default=False),
        # a Python string literal that reads back as the value (a JSON string is one)
        py=lambda v: json.dumps(v, ensure_ascii=False),
    )


def _yaml_text(text: str) -> str:
    """A one-line YAML scalar that reads back as `text` whatever it holds."""
    return json.dumps(" ".join(text.split()))  # JSON strings are YAML strings


def _write_tree(target: Path, files: dict[str, str]) -> None:
    """Create the folder `target` holding `files` (relative path -> text), all at once: they
    are written into a hidden sibling first, which is renamed to `target` at the end."""
    tmp = target.parent / f".{target.name}.{secrets.token_hex(4)}.llfsm-new"
    tmp.mkdir()  # mkdir, not mkdtemp: the folder gets the user's usual permissions
    try:
        for rel, text in files.items():
            path = tmp / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        if target.exists():  # created meanwhile: never replace someone's folder
            raise ScaffoldError(f"{target} already exists; nothing was written")
        os.rename(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


#: The states of a new machine when none are named: INITIAL -> END.
DEFAULT_STATES = ("INITIAL", "END")
#: Most states `--states` takes (a skeleton, not a generator).
MAX_STATES = 1000


def machine_files(name: str, description: str | None, states: Sequence[str] | None = None) -> dict[str, str]:
    """The files of a new machine NAME (relative name -> text): `states` in a chain, each to the
    next after 100 ms (the first says hello in its OnEntry), the last accepting; every guard file
    starts with `# -> TARGET` (docs/machine-format.md).  ScaffoldError for a bad name."""
    if not is_valid_name(name) or len(name) > MAX_MACHINE_NAME:
        raise ScaffoldError(
            f"{_shown(name)} is not a valid machine name: use letters, digits and _, not starting "
            f"with a digit, not a Python keyword, at most {MAX_MACHINE_NAME} characters"
        )
    chain = list(DEFAULT_STATES if states is None else states)
    if not chain or len(chain) > MAX_STATES:
        raise ScaffoldError(f"a machine needs 1 to {MAX_STATES} states, not {len(chain)}")
    for s in chain:
        if not isinstance(s, str) or not is_valid_name(s) or len(s) > MAX_STATE_NAME:
            raise ScaffoldError(
                f"{_shown(s)} is not a valid state name: use letters, digits and _, not starting with a digit, "
                f"not a Python keyword, at most {MAX_STATE_NAME} characters"
            )
    twice = sorted({s for s in chain if chain.count(s) > 1})
    if twice:
        raise ScaffoldError(f"state {twice[0]} is named twice")
    env = _env("skeleton")
    links = list(zip(chain, [*chain[1:], None], strict=True))
    files = {
        "machine.yaml": env.get_template("machine.yaml.j2").render(
            description=_yaml_text(description or f"The machine {name}."), chain=links
        ),
        "Includes.py": env.get_template("Includes.py.j2").render(),
        "Variables.py": env.get_template("Variables.py.j2").render(),
        f"State_{chain[0]}_OnEntry.py": env.get_template("OnEntry.py.j2").render(state=chain[0]),
    }
    for s, t in links:
        if t is not None:
            files[f"State_{s}_Transition_0.expr"] = env.get_template("guard.expr.j2").render(target=t)
    return files


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"


def create_machine(
    directory: Path, name: str, description: str | None = None, states: Sequence[str] | None = None
) -> Path:
    """Write NAME.machine (`machine_files`); never overwrites anything."""
    files = machine_files(name, description, states)
    target = directory / f"{name}.machine"
    if target.exists() or target.is_symlink():
        raise ScaffoldError(f"{target} already exists; nothing was written")
    directory.mkdir(parents=True, exist_ok=True)
    _write_tree(target, files)
    return target


# -- packages ------------------------------------------------------------------------------------


@dataclass
class CreatedPackage:
    """What `create_package` wrote, for the command to report as ros2 pkg create does."""

    path: Path
    name: str
    description: str
    maintainer: str
    license: str
    dependencies: list[str]
    machines: list[str]
    files: list[str] = field(default_factory=list)  # relative to path, in creation order
    warnings: list[str] = field(default_factory=list)


def split_names(values: Iterable[str]) -> list[str]:
    """`--dependencies a b`, `--dependencies a,b` and repeated options all mean [a, b]."""
    out: list[str] = []
    for v in values:
        for part in re.split(r"[,\s]+", v):
            if part and part not in out:
                out.append(part)
    return out


def check_package_name(name: str) -> None:
    if not _PACKAGE_NAME.match(name):
        raise ScaffoldError(
            f"{name!r} is not a valid ROS package name: use lower-case letters, digits and single "
            "underscores, start with a letter, do not end with an underscore, at least two characters "
            "(REP 144)"
        )


def create_package(
    directory: Path,
    name: str,
    dependencies: Iterable[str] = (),
    machines: Iterable[str] = (),
    license: str = DEFAULT_LICENSE,
    description: str | None = None,
    maintainer_name: str | None = None,
    maintainer_email: str | None = None,
) -> CreatedPackage:
    """Write DIRECTORY/NAME, a ROS 2 ament_python package of llfsm machines that colcon builds.

    Everything is validated before anything is written; package.xml is rendered from its
    template and parsed back with catkin_pkg (as colcon will), so a package that this returns
    is one colcon accepts.  Raises ScaffoldError with one message for any bad input.
    """
    check_package_name(name)
    if not directory.is_dir():
        raise ScaffoldError(f"{directory}: no such directory; nothing was written")
    target = directory / name
    if target.exists() or target.is_symlink():
        raise ScaffoldError(f"{target} already exists; nothing was written")
    deps = split_names(dependencies)
    for d in deps:
        if not _DEPENDENCY.match(d):
            raise ScaffoldError(
                f"{d!r} is not a valid dependency name: a ROS package or rosdep key, in lower case "
                "(letters, digits, _ . + -), such as std_msgs or python3-numpy"
            )
        if d == name:
            raise ScaffoldError(f"the package {name} cannot depend on itself")
    if "llfsm" not in deps:
        deps.append("llfsm")  # setup.py compiles with it, and `llfsm run` runs the machines
    names = split_names(machines) or [name]
    in_machines: dict[str, str] = {}
    for m in names:
        for fname, text in machine_files(m, None).items():
            in_machines[f"machine/{m}.machine/{fname}"] = text
    license = " ".join(license.split())
    if not license:
        raise ScaffoldError("--license must not be empty")
    maintainer_name = " ".join((maintainer_name or _user()).split())
    if not maintainer_name:
        raise ScaffoldError("--maintainer-name must not be empty")
    maintainer_email = (
        maintainer_email or f"{_EMAIL_LOCAL.sub('_', maintainer_name).strip('_') or 'maintainer'}@todo.todo"
    )
    description = " ".join((description or f"llfsm machines: {', '.join(names)}.").split())

    values = {
        "name": name,
        "version": PACKAGE_VERSION,
        "description": description,
        "maintainer_name": maintainer_name,
        "maintainer_email": maintainer_email,
        "license": license,
        "depends": deps,
    }
    env = _env("package")
    files = {
        "package.xml": env.get_template("package.xml.j2").render(values),
        "setup.py": env.get_template("setup.py.j2").render(values),
        "setup.cfg": env.get_template("setup.cfg.j2").render(values),
        f"resource/{name}": "",  # the ament index marker: colcon-ros installs it as the package's entry
        "test/test_llfsm_check.py": env.get_template("test/test_llfsm_check.py.j2").render(values),
        **in_machines,
    }
    warnings = _validate_manifest(files["package.xml"], name, deps, license)
    if license not in AMENT_LICENSES:
        warnings.append(
            f"Unknown license '{license}'. This has been set in the package.xml, but no LICENSE file "
            "has been created. It is recommended to use one of the ament license identifiers: "
            + ", ".join(AMENT_LICENSES)
        )
    _write_tree(target, files)
    return CreatedPackage(
        path=target,
        name=name,
        description=description,
        maintainer=f"{maintainer_name} <{maintainer_email}>",
        license=license,
        dependencies=deps,
        machines=names,
        files=list(files),
        warnings=warnings,
    )


def _validate_manifest(text: str, name: str, deps: list[str], license: str) -> list[str]:
    """Parse the rendered package.xml back with catkin_pkg, the parser colcon and rosdep use.

    catkin_pkg can write a package.xml (package_templates.create_package_xml), but only in
    format 2 with catkin's ROS 1 template and no XML escaping, so the file comes from our
    template and catkin_pkg is the judge: anything it refuses (a malformed e-mail, say) is the
    user's input, reported as such.
    """
    from catkin_pkg.package import InvalidPackage, parse_package_string  # deferred: start-up (packages only)

    warnings: list[str] = []
    try:
        pkg = parse_package_string(text, warnings=warnings)
    except InvalidPackage as e:
        problems = [s.strip().removeprefix("- ") for s in str(e.msg).splitlines() if s.strip() not in ("", "Error(s):")]
        raise ScaffoldError(f"package.xml would be invalid: {'; '.join(problems)}; nothing was written") from None
    declared = [d.name for d in pkg.build_depends]
    if (
        pkg.package_format != 3
        or pkg.name != name
        or declared != deps
        or [str(x) for x in pkg.licenses] != [license]
        or pkg.get_build_type() != "ament_python"
    ):
        raise ScaffoldError(f"package.xml for {name} did not read back as written (an llfsm bug); nothing was written")
    return warnings


def _user() -> str:
    try:
        return getpass.getuser()
    except (KeyError, OSError):  # no passwd entry (some containers)
        return "maintainer"
