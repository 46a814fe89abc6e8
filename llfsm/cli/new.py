"""`llfsm new machine|package`: skeletons that pass `check` as they are."""

from __future__ import annotations

from pathlib import Path

import click

from ._group import EXIT_ERRORS, cli, fail

# -- new ---------------------------------------------------------------------------------------


@cli.group()
def new() -> None:
    """Create a machine or a colcon package from a skeleton."""


@new.command("machine")
@click.argument("name")
@click.option(
    "-d",
    "--dir",
    "directory",
    type=click.Path(file_okay=False),
    default=".",
    show_default=True,
    help="Folder to create NAME.machine in.",
)
@click.option("--description", default=None, help="One line saying what the machine does.")
@click.option(
    "--states",
    default=None,
    metavar="A,B,C",
    help="The states, in a chain: each goes to the next after 100 ms, the first is initial, the last "
    "accepting (default: INITIAL,END).",
)
def new_machine(name: str, directory: str, description: str | None, states: str | None) -> None:
    """A valid machine skeleton: INITIAL -> END, or the chain of --states."""
    from ..scaffold import ScaffoldError, create_machine  # deferred: start-up (jinja2)

    try:
        chain = [s for s in states.replace(",", " ").split()] if states is not None else None
        path = create_machine(Path(directory), name, description, chain)
    except ScaffoldError as e:
        fail(str(e))
    except OSError as e:  # a full disk, a read-only folder: nothing was written (_write_tree)
        fail(f"{directory}: cannot write: {e.strerror or e}", EXIT_ERRORS)
    click.echo(f"created {path}")


class _SeveralValues(click.Command):
    """`ros2 pkg create` takes `--dependencies a b c`; a click option takes one value, so the
    words after such an option (up to the next option) are spread into repeated options."""

    several = ("--dependencies", "--machine")

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        out: list[str] = []
        i = 0
        while i < len(args):
            arg = args[i]
            out.append(arg)
            i += 1
            if arg == "--":
                out += args[i:]
                break
            if arg in self.several:
                first = True
                while i < len(args) and (first or not args[i].startswith("-")):
                    if not first:
                        out.append(arg)
                    out.append(args[i])
                    first = False
                    i += 1
        try:
            return super().parse_args(ctx, out)
        except click.MissingParameter as e:
            if e.param is not None and e.param.name == "name" and any(a in self.several for a in args):
                raise click.UsageError(
                    "missing NAME: put it before --dependencies and --machine, which take every word after them",
                    ctx,
                ) from None
            raise


@new.command("package", cls=_SeveralValues)
@click.argument("name")
@click.option(
    "--dependencies",
    multiple=True,
    metavar="D...",
    help="Packages the machines use (std_msgs geometry_msgs ...): <depend> tags in package.xml.",
)
@click.option(
    "--machine",
    "machines",
    multiple=True,
    metavar="M...",
    help="Machines to create in machine/ (default: one named NAME).",
)
@click.option(
    "--license",
    "license_",
    default="TODO: License declaration",
    help="License in package.xml (default, as ros2 pkg create: 'TODO: License declaration'); "
    "a warning unless an ament identifier such as Apache-2.0 or MIT.",
)
@click.option("--description", default=None, help="Description in package.xml.")
@click.option("--maintainer-name", default=None, help="Maintainer (default: your user name).")
@click.option("--maintainer-email", default=None, help="Maintainer's e-mail (default: NAME@todo.todo).")
@click.option(
    "--dir",
    "--destination-directory",
    "directory",
    type=click.Path(file_okay=False),
    default=".",
    show_default=True,
    help="Folder to create the package in: a workspace's src/.",
)
def new_package(
    name: str,
    dependencies: tuple[str, ...],
    machines: tuple[str, ...],
    license_: str,
    description: str | None,
    maintainer_name: str | None,
    maintainer_email: str | None,
    directory: str,
) -> None:
    """A ROS 2 ament_python package of machines that `colcon build` builds.

    Run in a workspace's src/.  It writes NAME/package.xml (format 3), setup.py, setup.cfg,
    resource/NAME, machine/M.machine for each machine and test/.  Then, from the workspace:
    `colcon build`, `source install/setup.bash`, `llfsm run NAME/M`.  NAME comes before the
    options that take several values.
    """
    from ..scaffold import ScaffoldError, create_package  # deferred: start-up (jinja2)

    try:
        pkg = create_package(
            Path(directory),
            name,
            dependencies,
            machines,
            license_,
            description,
            maintainer_name,
            maintainer_email,
        )
    except ScaffoldError as e:
        fail(str(e))
    except OSError as e:  # a full disk, a read-only folder: nothing was written (_write_tree)
        fail(f"{directory}: cannot write: {e.strerror or e}", EXIT_ERRORS)
    # the summary ros2 pkg create prints, so the two read alike (printed once all is written)
    click.echo("created a new package")
    click.echo(f"package name: {name}")
    click.echo(f"destination directory: {Path(directory).resolve()}")
    click.echo("package format: 3")
    click.echo("version: 0.0.0")
    click.echo(f"description: {pkg.description}")
    click.echo(f"maintainer: {[pkg.maintainer]}")
    click.echo(f"licenses: {[pkg.license]}")
    click.echo("build type: ament_python")
    click.echo(f"dependencies: {pkg.dependencies}")
    click.echo(f"machines: {pkg.machines}")
    rel = Path(directory) / name
    for f in pkg.files:
        if not f.startswith("machine/"):
            click.echo(f"created {rel / f}")
    for m in pkg.machines:
        click.echo(f"created {rel / 'machine' / (m + '.machine')}/")
    for w in pkg.warnings:
        click.echo(f"[WARNING]: {w}", err=True)
    click.echo("next, from the workspace (the folder that holds src/):")
    click.echo(f"  colcon build --packages-select {name}")
    click.echo("  source install/setup.bash")
    click.echo(f"  llfsm run {name}/{pkg.machines[0]}")
