"""`llfsm launch`: reading launch files (XML and YAML front ends, the model, substitutions,
`$(eval)`), and every refusal: one line with the file and line, exit status 2, nothing started."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, write_machine

from llfsm.cli import run_args
from llfsm.launch import LaunchError, plan
from llfsm.launch.evaluate import ExpressionError, evaluate
from llfsm.launch.substitutions import Context, SubstitutionError, parse, perform


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def refused(path: Path, *args: str) -> str:
    """The one line `llfsm launch` prints for a launch file it refuses (status 2)."""
    r = llfsm("launch", path, *args)
    assert r.status == 2, r
    assert r.stdout == ""
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    return lines[0]


# -- substitutions ----------------------------------------------------------------------------------
def perform_text(text: str, configurations: dict[str, str] | None = None, env: dict[str, str] | None = None) -> str:
    return perform(parse(text), Context(configurations or {}, env or {}, "/where/a.launch.xml"))


def test_substitutions_are_performed_in_text() -> None:
    assert perform_text("x=$(var a), y=$(env B), z=$(env C zed)", {"a": "1"}, {"B": "bee"}) == "x=1, y=bee, z=zed"
    assert perform_text("$(var missing fallback)") == "fallback"
    assert perform_text("$(dirname)/m.machine") == "/where/m.machine"
    assert perform_text("$(var $(var which))", {"which": "a", "a": "nested"}) == "nested"
    assert perform_text(r"costs \$(var a) and \\ one") == "costs $(var a) and \\ one"


def test_eval_quoted_with_nested_substitutions() -> None:
    assert perform_text("$(eval \"'$(var mode)' == 'sim'\")", {"mode": "sim"}) == "True"
    assert perform_text("$(eval '$(var n) * 2 + 1')", {"n": "20"}) == "41"
    assert perform_text("$(eval 2*(3+4))") == "14"  # balanced parentheses need no quotes


def test_find_pkg_share_reads_the_ament_index(tmp_path: Path) -> None:
    (tmp_path / "share" / "ament_index" / "resource_index" / "packages").mkdir(parents=True)
    (tmp_path / "share" / "ament_index" / "resource_index" / "packages" / "bots").write_text("")
    env = {"AMENT_PREFIX_PATH": f"/nowhere:{tmp_path}"}
    assert perform_text("$(find-pkg-share bots)/launch", env=env) == f"{tmp_path}/share/bots/launch"
    with pytest.raises(SubstitutionError, match="package 'other' not found"):
        perform_text("$(find-pkg-share other)", env=env)
    with pytest.raises(SubstitutionError, match="AMENT_PREFIX_PATH is not set"):
        perform_text("$(find-pkg-share bots)")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("$(var a", "never closed"),
        ("$(command ls)", r"does not perform \$\(command\)"),
        ("$(var)", r"\$\(var\) takes 1 or 2 arguments, not 0"),
        ("$(dirname x)", r"\$\(dirname\) takes 0 arguments"),
        ("$(eval '1' math)", "cannot import modules"),
        ("$(eval '$(var a)' == 'x')", "quote the whole expression"),
        ("$(env 'a)", "never closed"),
    ],
)
def test_bad_substitutions_are_refused_when_read(text: str, message: str) -> None:
    with pytest.raises(SubstitutionError, match=message):
        parse(text)


def test_unset_names_are_refused_when_performed() -> None:
    with pytest.raises(SubstitutionError, match="no launch argument or `let` named 'a'"):
        perform_text("$(var a)")
    with pytest.raises(SubstitutionError, match="environment variable NOPE is not set"):
        perform_text("$(env NOPE)")


def test_a_value_cannot_grow_without_bound() -> None:
    configurations = {"x": "y" * 40_000}
    with pytest.raises(SubstitutionError, match="longer than 64 KiB"):
        perform_text("$(var x)$(var x)", configurations)


# -- $(eval) ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("expression", "value"),
    [
        ("1 + 2 * 3", "7"),
        ("7 // 2 + 7 % 2 - 2 ** 3", "-4"),
        ("10 / 4", "2.5"),
        ("'a' + 'b' * 2", "abb"),
        ("1 < 2 <= 2 != 3", "True"),
        ("'x' in 'xyz' and not 'q' in 'xyz'", "True"),
        ("0 or 'fallback'", "fallback"),
        ("'yes' if 3 > 2 else 'no'", "yes"),
        ("-(+3)", "-3"),
    ],
)
def test_eval_does_arithmetic_comparisons_and_logic(expression: str, value: str) -> None:
    assert evaluate(expression) == value


@pytest.mark.parametrize(
    ("expression", "message"),
    [
        ("__import__('os').system('touch /tmp/pwned')", "a call is not allowed"),
        ("open('/etc/passwd')", "a call is not allowed"),
        ("(1).__class__", "an attribute is not allowed"),
        ("'abc'.upper()", "a call is not allowed"),
        ("x + 1", "a name is not allowed"),
        ("'abc'[0]", "a subscript is not allowed"),
        ("[c for c in 'ab']", "a comprehension is not allowed"),
        ("lambda: 1", "a lambda is not allowed"),
        ("f'{1}'", "an f-string is not allowed"),
        ("[1, 2]", "a container is not allowed"),
        ("1 << 3", "the operator `<<` is not allowed"),
        ("'%s' % 1", "formatting of strings is not allowed"),
        ("9 ** 9 ** 9", "larger than 4096 bits"),
        ("'x' * 10 ** 9", "longer than 64 KiB"),
        ("1 / 0", "division by zero"),
        ("import os", "not an expression"),
        ("(" * 300 + "1" + ")" * 300, "nested too deeply|not an expression"),
    ],
)
def test_eval_refuses_everything_else(expression: str, message: str) -> None:
    with pytest.raises(ExpressionError, match=message):
        evaluate(expression)


def test_eval_refusal_names_the_file_and_line(tmp_path: Path) -> None:
    f = write(
        tmp_path / "e.launch.xml",
        '<launch>\n  <let name="a" value="1"/>\n  <let name="b" value="$(eval \'__import__(&quot;os&quot;)\')"/>\n'
        "</launch>\n",
    )
    line = refused(f)
    assert line.startswith(f"llfsm: {f}:3: $(eval '__import__(\"os\")'): a call is not allowed")


# -- the front ends and the model ------------------------------------------------------------------------
def test_xml_and_yaml_read_to_the_same_model_of_every_tag(tmp_path: Path) -> None:
    xml = write(
        tmp_path / "all.launch.xml",
        """<launch>
  <arg name="robot" default="r1" description="which robot">
    <choice value="r1"/>
    <choice value="r2"/>
  </arg>
  <let name="speed" value="2.0"/>
  <set_env name="ROS_DOMAIN_ID" value="7"/>
  <unset_env name="ROS_LOCALHOST_ONLY"/>
  <group scoped="true">
    <push_ros_namespace namespace="$(var robot)"/>
    <node pkg="turtlesim" exec="turtlesim_node" name="sim" output="screen" respawn="true" respawn_delay="1.5">
      <param name="background_r" value="255"/>
      <param name="pen"><param name="width" value="3"/></param>
      <remap from="turtle1/cmd_vel" to="cmd"/>
      <env name="EXTRA" value="x"/>
    </node>
  </group>
  <executable cmd="true" name="once" on_exit="shutdown" if="$(eval '$(var speed) > 1')"/>
</launch>
""",
    )
    yaml = write(
        tmp_path / "all.launch.yaml",
        """launch:
  - arg:
      name: robot
      default: r1
      description: which robot
      choice: [{value: r1}, {value: r2}]
  - let: {name: speed, value: "2.0"}
  - set_env: {name: ROS_DOMAIN_ID, value: "7"}
  - unset_env: {name: ROS_LOCALHOST_ONLY}
  - group:
      scoped: "true"
      children:
        - push_ros_namespace: {namespace: $(var robot)}
        - node:
            pkg: turtlesim
            exec: turtlesim_node
            name: sim
            output: screen
            respawn: "true"
            respawn_delay: "1.5"
            param:
              - {name: background_r, value: 255}
              - name: pen
                param: [{name: width, value: 3}]
            remap: [{from: turtle1/cmd_vel, to: cmd}]
            env: [{name: EXTRA, value: x}]
  - executable: {cmd: "true", name: once, on_exit: shutdown, if: "$(eval '$(var speed) > 1')"}
""",
    )
    env = {"PATH": "/usr/bin:/bin", "ROS_LOCALHOST_ONLY": "1"}
    from_xml, from_yaml = plan(str(xml), {}, env), plan(str(yaml), {}, env)
    assert [(p.label, p.argv, p.env, p.output, p.respawn, p.respawn_delay, p.shutdown_on_exit) for p in from_xml] == [
        (p.label, p.argv, p.env, p.output, p.respawn, p.respawn_delay, p.shutdown_on_exit) for p in from_yaml
    ]
    sim, once = from_xml
    assert sim.label == "turtlesim_node-1" and once.label == "once-2"
    assert sim.argv[3:] == [
        "run",
        "--transport",
        "dds",
        "--node",
        "turtlesim",
        "--remap",
        "__node:=sim",
        "--remap",
        "__ns:=/r1",
        "-p",
        "background_r:=255",
        "-p",
        "pen.width:=3",
        "--remap",
        "turtle1/cmd_vel:=cmd",
    ]
    assert sim.env["ROS_DOMAIN_ID"] == "7" and sim.env["EXTRA"] == "x" and "ROS_LOCALHOST_ONLY" not in sim.env
    assert (sim.output, sim.respawn, sim.respawn_delay) == ("screen", True, 1.5)
    assert once.argv == ["true"] and once.shutdown_on_exit


@pytest.mark.parametrize("name", ["turtle_follower", "ros2_wall_turtle_bot"])
def test_the_shipped_launch_files_start_the_same_processes_in_xml_and_yaml(name: str) -> None:
    env = {"PATH": os.environ["PATH"]}
    xml, yaml = (plan(str(MACHINES / f"{name}.launch.{ext}"), {}, env) for ext in ("xml", "yaml"))
    assert [(p.label, p.argv, p.output, p.respawn, p.respawn_delay) for p in xml] == [
        (p.label, p.argv, p.output, p.respawn, p.respawn_delay) for p in yaml
    ]
    assert xml[-1].argv[3:] == ["run", "--transport", "dds", str(MACHINES / f"{name}.machine")]


def test_the_wall_bot_launch_file_opens_turtlesims_window_when_asked() -> None:
    for ext in ("xml", "yaml"):
        sim = plan(str(MACHINES / f"ros2_wall_turtle_bot.launch.{ext}"), {"view": "true"}, {})[0]
        assert sim.argv[3:] == ["run", "--transport", "dds", "--node", "turtlesim", "--view"]


def test_yaml_quoted_parameter_values_stay_strings(tmp_path: Path) -> None:
    f = write(
        tmp_path / "p.launch.yaml",
        "launch:\n  - node:\n      pkg: turtlesim\n      exec: turtlesim_node\n      param:\n"
        "        - {name: a, value: '255'}\n        - {name: b, value: 255}\n        - {name: c, value: [1, '2']}\n",
    )
    (p,) = plan(str(f), {}, {})
    assert p.argv[-6:] == ["-p", "a:='255'", "-p", "b:=255", "-p", "c:=[1, '2']"]


@pytest.mark.parametrize(
    ("name", "text", "line", "message"),
    [
        (
            "tag.launch.xml",
            "<launch>\n\n  <nodes pkg='x' exec='y'/>\n</launch>",
            3,
            "unknown tag <nodes> (llfsm launch knows",
        ),
        ("tag.launch.yaml", "launch:\n  - let: {name: a, value: b}\n  - nodes: {pkg: x}\n", 3, "unknown tag <nodes>"),
        (
            "attr.launch.xml",
            "<launch>\n  <node pkg='turtlesim' exec='turtlesim_node' nmae='x'/>\n</launch>",
            2,
            "<node> has no attribute 'nmae' (it takes",
        ),
        (
            "attr.launch.yaml",
            "launch:\n  - node:\n      pkg: turtlesim\n      exec: turtlesim_node\n      nmae: x\n",
            5,
            "<node> has no attribute 'nmae'",
        ),
        (
            "missing.launch.xml",
            "<launch>\n  <node pkg='turtlesim'/>\n</launch>",
            2,
            "<node> needs the attribute 'exec'",
        ),
        (
            "child.launch.xml",
            "<launch>\n  <node pkg='turtlesim' exec='turtlesim_node'>\n    <arg name='a' value='b'/>\n"
            "  </node>\n</launch>",
            3,
            "<node> cannot hold <arg> (it holds env, param, remap)",
        ),
        ("root.launch.xml", "<launches/>", 1, "the root is <launches>, not <launch>"),
        ("xml.launch.xml", "<launch>\n  <node pkg='a'\n</launch>", 3, "not XML"),
        ("doctype.launch.xml", '<!DOCTYPE launch [<!ENTITY x "y">]>\n<launch/>', 1, "a DOCTYPE is not allowed"),
        ("yaml.launch.yaml", "launch:\n  - node: {pkg: [\n", 3, "not YAML"),
        ("anchor.launch.yaml", "launch:\n  - let: &a {name: a, value: b}\n  - let: *a\n", 2, "anchors and aliases"),
        (
            "cond.launch.xml",
            "<launch>\n  <let name='a' value='b' if='true' unless='false'/>\n</launch>",
            2,
            "`if` and `unless` cannot be used together",
        ),
        (
            "on_exit.launch.xml",
            "<launch>\n  <executable cmd='true' on_exit='restart'/>\n</launch>",
            2,
            'on_exit: takes only "shutdown"',
        ),
        (
            "delay.launch.xml",
            "<launch>\n  <executable cmd='true' respawn_delay='-1'/>\n</launch>",
            2,
            "`respawn_delay` takes a number of seconds (0 or more)",
        ),
        ("subst.launch.xml", "<launch>\n  <let name='a' value='$(var b'/>\n</launch>", 2, "never closed"),
        (
            "param.launch.xml",
            "<launch><node pkg='turtlesim' exec='turtlesim_node'>\n<param value='1'/>\n</node></launch>",
            2,
            "needs `name`",
        ),
    ],
)
def test_what_the_model_refuses_is_one_line_with_file_and_line(
    tmp_path: Path, name: str, text: str, line: int, message: str
) -> None:
    f = write(tmp_path / name, text)
    out = refused(f)
    assert out.startswith(f"llfsm: {f}:{line}: "), out
    assert message in out


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        (
            "<arg name='robot' description='its name'/>",
            2,
            "the launch argument 'robot' (its name) is required: give it as robot:=VALUE",
        ),
        ("<arg name='mode' default='x'><choice value='a'/></arg>", 2, "'mode' is 'x': expected one of 'a'"),
        ("<let name='a' value='b' if='maybe'/>", 2, "`if` is 'maybe': expected true, false, 1 or 0"),
        ("<let name='a' value='$(var nope)'/>", 2, "no launch argument or `let` named 'nope'"),
        ("<include file='nowhere.launch.xml'/>", 2, "no launch file 'nowhere.launch.xml'"),
        (
            "<node pkg='turtle_coop' exec='turtle_coop'/>",
            2,
            "pkg='turtle_coop' exec='turtle_coop': not one of llfsm's nodes",
        ),
        ("<node pkg='llfsm' exec='run' args='gone.machine'/>", 2, "no machine directory 'gone.machine'"),
        ("<executable cmd='no-such-program-xyz --flag'/>", 2, "no executable 'no-such-program-xyz' on PATH"),
        (
            "<executable cmd='true' output='loud'/>",
            2,
            "output='loud': expected one of screen, log, both, own_log, full",
        ),
        ("<node pkg='turtlesim' exec='turtlesim_node' name='bad name'/>", 2, "name: invalid node name 'bad name'"),
        ("<node pkg='turtlesim' exec='turtlesim_node'><remap from='a b' to='c'/></node>", 2, "invalid remapped name"),
        ("<push_ros_namespace namespace='9bad'/>", 2, "invalid namespace"),
    ],
)
def test_what_the_walk_refuses_is_one_line_with_file_and_line(
    tmp_path: Path, text: str, line: int, message: str
) -> None:
    f = write(tmp_path / "w.launch.xml", f"<launch>\n  {text}\n</launch>\n")
    out = refused(f)
    assert out.startswith(f"llfsm: {f}:{line}: "), out
    assert message in out


def test_an_include_cycle_names_the_include_and_the_chain(tmp_path: Path) -> None:
    a = write(tmp_path / "a.launch.xml", "<launch>\n  <include file='$(dirname)/b.launch.yaml'/>\n</launch>\n")
    b = write(
        tmp_path / "b.launch.yaml",
        "launch:\n  - let: {name: x, value: y}\n  - include: {file: $(dirname)/a.launch.xml}\n",
    )
    out = refused(a)
    assert out == f"llfsm: {b}:3: include cycle: {a} includes {b} includes {a}"


def test_a_refused_file_starts_nothing(tmp_path: Path) -> None:
    marker = tmp_path / "started"
    f = write(
        tmp_path / "half.launch.xml",
        f"<launch>\n  <executable cmd='touch {marker}'/>\n  <executable cmd='true' output='loud'/>\n</launch>\n",
    )
    assert "output='loud'" in refused(f)
    assert not marker.exists()


def test_command_line_arguments(tmp_path: Path) -> None:
    f = write(
        tmp_path / "a.launch.xml", "<launch>\n  <arg name='n'/>\n  <executable cmd='echo $(var n)'/>\n</launch>\n"
    )
    r = llfsm("launch", f, "n:=5", "--print")
    assert r.status == 0 and r.stdout == "[echo-1] echo 5\n"
    assert refused(f, "n=5") == "llfsm: malformed launch argument 'n=5', expected format '<name>:=<value>'"
    assert refused(tmp_path / "none.launch.xml") == f"llfsm: {tmp_path / 'none.launch.xml'}: no such launch file"


def test_show_args_lists_the_arguments_of_the_file_and_its_includes(tmp_path: Path) -> None:
    write(tmp_path / "inner.launch.yaml", "launch:\n  - arg: {name: depth}\n")
    f = write(
        tmp_path / "outer.launch.xml",
        "<launch>\n  <arg name='speed' default='2.0' description='how fast'/>\n"
        "  <group if='false'><arg name='hidden' default='$(var speed)'/></group>\n"
        "  <arg name='mode' default='a'><choice value='a'/><choice value='b'/></arg>\n"
        "  <include file='$(dirname)/inner.launch.yaml'/>\n</launch>\n",
    )
    r = llfsm("launch", f, "--show-args")
    assert r.status == 0, r
    assert r.stdout == (
        "Arguments (pass arguments as '<name>:=<value>'):\n\n"
        "    'speed':\n        how fast\n        (default: '2.0')\n\n"
        "    'hidden':\n        no description given\n        (default: '$(var speed)')\n\n"
        "    'mode':\n        One of: ['a', 'b']\n        (default: 'a')\n\n"
        "    'depth':\n        no description given\n"
    )


def test_plan_errors_are_launch_errors(tmp_path: Path) -> None:
    f = write(tmp_path / "a.launch.yaml", "launch:\n  - arg: {name: must}\n")
    with pytest.raises(LaunchError, match=r"a.launch.yaml:2: the launch argument 'must'"):
        plan(str(f), {}, {})


def echoes(path: Path, arguments: dict[str, str] | None = None, env: dict[str, str] | None = None) -> list[str]:
    """The words after `echo` of each process the file starts."""
    return [" ".join(p.argv[1:]) for p in plan(str(path), arguments or {}, {"PATH": os.environ["PATH"], **(env or {})})]


def test_groups_scope_configurations_and_environment_and_includes_do_not(tmp_path: Path) -> None:
    write(
        tmp_path / "inner.launch.yaml",
        "launch:\n  - arg: {name: given}\n  - let: {name: leaked, value: from-inner}\n"
        "  - executable: {cmd: echo $(var given) $(dirname)}\n",
    )
    f = write(
        tmp_path / "scopes.launch.xml",
        """<launch>
  <let name="a" value="outer"/>
  <set_env name="E" value="outer-env"/>
  <group>
    <let name="a" value="inner"/>
    <set_env name="E" value="inner-env"/>
    <executable cmd="echo $(var a) $(env E)"/>
  </group>
  <executable cmd="echo $(var a) $(env E)"/>
  <group scoped="false">
    <let name="a" value="unscoped"/>
  </group>
  <executable cmd="echo $(var a)"/>
  <group forwarding="false">
    <keep name="k" value="kept"/>
    <executable cmd="echo $(var a fresh) $(var k) $(env E first)"/>
  </group>
  <include file="$(dirname)/inner.launch.yaml">
    <arg name="given" value="$(var a)-arg"/>
  </include>
  <executable cmd="echo $(var leaked) $(var given)"/>
  <unset_env name="E"/>
  <executable cmd="echo $(env E gone)"/>
</launch>
""",
    )
    assert echoes(f) == [
        "inner inner-env",
        "outer outer-env",
        "unscoped",
        "fresh kept first",
        f"unscoped-arg {tmp_path}",
        "from-inner unscoped-arg",
        "gone",
    ]


def test_arguments_take_their_default_only_when_not_given(tmp_path: Path) -> None:
    f = write(
        tmp_path / "args.launch.xml",
        "<launch>\n  <arg name='n' default=\"$(eval '6 * 7')\"/>\n  <arg name='n' default='ignored'/>\n"
        "  <executable cmd='echo $(var n)'/>\n</launch>\n",
    )
    assert echoes(f) == ["42"]
    assert echoes(f, {"n": "1"}) == ["1"]


def test_conditions(tmp_path: Path) -> None:
    f = write(
        tmp_path / "if.launch.yaml",
        """launch:
  - arg: {name: on, default: "true"}
  - executable: {cmd: echo if-on, if: $(var on)}
  - executable: {cmd: echo unless-on, unless: $(var on)}
  - executable: {cmd: echo one, if: "1"}
  - executable: {cmd: echo TRUE, if: " TRUE "}
  - group:
      if: $(eval "'$(var on)' == 'false'")
      children:
        - executable: {cmd: echo in-group}
""",
    )
    assert echoes(f) == ["if-on", "one", "TRUE"]
    assert echoes(f, {"on": "false"}) == ["unless-on", "one", "TRUE", "in-group"]
    assert echoes(f, {"on": "FALSE"}) == ["unless-on", "one", "TRUE"]  # conditions ignore case, == does not


def test_namespaces_are_pushed_and_joined(tmp_path: Path) -> None:
    f = write(
        tmp_path / "ns.launch.xml",
        """<launch>
  <push_ros_namespace namespace="fleet"/>
  <group>
    <push-ros-namespace namespace="robot1"/>
    <node pkg="turtlesim" exec="turtlesim_node"/>
    <node pkg="turtlesim" exec="turtlesim_node" namespace="sim"/>
    <node pkg="turtlesim" exec="turtlesim_node" namespace="/absolute"/>
  </group>
  <node pkg="llfsm" exec="run" name="bot" args="$(dirname)/bot.machine --period 10ms"/>
</launch>
""",
    )
    (tmp_path / "bot.machine").mkdir()
    specs = plan(str(f), {}, {})
    assert [p.argv[p.argv.index("--remap") + 1] for p in specs] == [
        "__ns:=/fleet/robot1",
        "__ns:=/fleet/robot1/sim",
        "__ns:=/absolute",
        "__ns:=/fleet",
    ]
    bot = specs[-1]  # a run of machines: `name` names the process, not its nodes
    assert bot.label == "bot-4" and "__node:=bot" not in bot.argv
    assert bot.argv[3:] == [
        "run",
        "--transport",
        "dds",
        f"{tmp_path}/bot.machine",
        "--period",
        "10ms",
        "--remap",
        "__ns:=/fleet",
    ]


def test_process_attributes(tmp_path: Path) -> None:
    (tmp_path / "params.yaml").write_text("/**:\n  ros__parameters:\n    a: 1\n")
    f = write(
        tmp_path / "proc.launch.xml",
        f"""<launch>
  <let name="sigterm_timeout" value="2"/>
  <executable cmd="echo 'two words' $(var missing 'a b')x" cwd="{tmp_path}" name="say" output="both"
              launch-prefix="env A=1" respawn="True" respawn_max_retries="3" sigkill_timeout="0.5">
    <env name="ONLY_HERE" value="1"/>
  </executable>
  <executable cmd="echo $HOME | tr a-z A-Z" shell="true" args="one 'two words'"/>
  <node pkg="turtlesim" exec="turtlesim_node" exec_name="sim" args="--view">
    <param from="$(dirname)/params.yaml"/>
    <param name="colours" value="1,2,3" value-sep=","/>
  </node>
  <node exec="echo" name="talker" args="hello">
    <remap from="chatter" to="talk"/>
  </node>
</launch>
""",
    )
    say, shell, sim, talker = plan(str(f), {}, {"PATH": os.environ["PATH"]})
    assert say.argv == ["env", "A=1", "echo", "two words", "a bx"]
    assert (say.cwd, say.label, say.output, say.env["ONLY_HERE"]) == (str(tmp_path), "say-1", "both", "1")
    assert say.env["LLFSM_TRANSPORT"] == "dds"
    assert (say.respawn, say.respawn_max_retries, say.sigterm_timeout, say.sigkill_timeout) == (True, 3, 2.0, 0.5)
    assert shell.argv == ["/bin/sh", "-c", "echo $HOME | tr a-z A-Z one 'two words'"] and shell.label == "echo-2"
    assert sim.label == "sim-3"
    assert sim.argv[3:] == [
        "run", "--transport", "dds", "--node", "turtlesim", "--view",
        "--params-file", f"{tmp_path}/params.yaml", "-p", "colours:=[1, 2, 3]",
    ]  # fmt: skip
    assert "ONLY_HERE" not in sim.env and sim.env["PYTHONUNBUFFERED"] == "1"
    assert talker.argv == ["echo", "hello", "--ros-args", "-r", "__node:=talker", "-r", "chatter:=talk"]
    assert talker.label == "echo-4"


def test_a_machine_of_an_installed_package_runs_by_its_package_and_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "install" / "share" / "bots" / "llfsm").mkdir(parents=True)
    (tmp_path / "install" / "share" / "bots" / "llfsm" / "wall_bot.py").write_text("")
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path / "install"))
    f = write(
        tmp_path / "pkg.launch.xml",
        "<launch>\n  <node pkg='bots' exec='wall_bot' name='first'/>\n  <node pkg='bots' exec='wal_bot'/>\n</launch>\n",
    )
    message = (
        r"pkg.launch.xml:3: pkg='bots' exec='wal_bot': no installed machine 'wal_bot' in package 'bots' "
        r"\(package bots has: wall_bot; did you mean wall_bot\?\)"
    )
    with pytest.raises(LaunchError, match=message):
        plan(str(f), {}, {})
    f.write_text("<launch>\n  <node pkg='bots' exec='wall_bot' name='first'/>\n</launch>\n")
    (bot,) = plan(str(f), {}, {})
    assert bot.argv[3:] == ["run", "--transport", "dds", "bots/wall_bot"] and bot.label == "first-1"


def test_includes_that_fan_out_are_bounded(tmp_path: Path) -> None:
    """Each file includes the next ten times: 10**4 includes if nothing stopped it."""
    for n in range(4):
        body = "".join(f"  <include file='$(dirname)/f{n + 1}.launch.xml'/>\n" for _ in range(10))
        write(tmp_path / f"f{n}.launch.xml", f"<launch>\n{body}</launch>\n")
    write(tmp_path / "f4.launch.xml", "<launch>\n  <let name='x' value='y'/>\n</launch>\n")
    out = refused(tmp_path / "f0.launch.xml")
    assert out.endswith(": more than 256 includes in one launch"), out


def test_parameter_types_and_ros_args(tmp_path: Path) -> None:
    f = write(
        tmp_path / "types.launch.xml",
        """<launch>
  <node pkg="turtlesim" exec="turtlesim_node" ros_args="-r a:=b --param x:=1 --remap c:=d">
    <param name="s" value="100" type="str"/>
    <param name="l" value="2, 5, 8" value-sep=", " type="list_of_str"/>
    <param name="n" value="2.5, 3" value-sep=", " type="list_of_float"/>
    <param name="t" value="True" type="bool"/>
  </node>
</launch>
""",
    )
    (p,) = plan(str(f), {}, {})
    assert p.argv[8:] == [
        "--ros-args", "-r", "a:=b", "--param", "x:=1", "--remap", "c:=d", "--",  # as written, for llfsm run
        "-p", "s:='100'", "-p", "l:=['2', '5', '8']", "-p", "n:=[2.5, 3]", "-p", "t:=True",
    ]  # fmt: skip
    node = "<launch>\n  <node pkg='turtlesim' exec='turtlesim_node'>\n    {}\n  </node>\n</launch>\n"
    f.write_text(node.format("<param name='n' value='x' type='int'/>"))
    assert refused(f) == f"llfsm: {f}:3: 'x' is not of type int"
    f.write_text(node.format("<param name='n' value='1' type='long'/>"))
    assert "'long' is not a type (one of str, bool, float" in refused(f)


def test_ros_arguments_go_to_llfsm_run_as_written_and_are_checked_first(tmp_path: Path) -> None:
    """A node's `ros_args` and the `--ros-args` of its `args` reach `llfsm run` as launch_ros
    passes them (issue 27 made `llfsm run --ros-args ... --` take them all); what `llfsm run`
    would refuse is refused before anything starts, at the node's line."""
    (tmp_path / "p.yaml").write_text("/**:\n  ros__parameters:\n    a: 1\n")
    f = write(
        tmp_path / "levels.launch.xml",
        """<launch>
  <arg name="log_level" default="info"/>
  <node pkg="turtlesim" exec="turtlesim_node" name="sim" ros_args="--log-level $(var log_level) --log-level sim:=debug">
    <remap from="a" to="b"/>
  </node>
  <node pkg="llfsm" exec="run"
        args="$(dirname)/m.machine --ros-args --log-level warn --params-file $(dirname)/p.yaml --"
        ros_args="--enable-external-lib-logs -p gain:=2.0"/>
  <node exec="echo" name="talker" args="hello" ros_args="--log-level debug"/>
</launch>
""",
    )
    write_machine(tmp_path, "m", {"A": None})
    sim, run, echo = plan(str(f), {"log_level": "error"}, {"PATH": os.environ["PATH"]})
    assert sim.argv[3:] == [
        "run", "--transport", "dds", "--node", "turtlesim",
        "--ros-args", "--log-level", "error", "--log-level", "sim:=debug", "--",
        "--remap", "__node:=sim", "--remap", "a:=b",
    ]  # fmt: skip
    assert run.argv[6:] == [
        str(tmp_path / "m.machine"),
        "--ros-args", "--log-level", "warn", "--params-file", str(tmp_path / "p.yaml"), "--",
        "--ros-args", "--enable-external-lib-logs", "-p", "gain:=2.0", "--",
    ]  # fmt: skip
    assert echo.argv == ["echo", "hello", "--ros-args", "--log-level", "debug", "--ros-args", "-r", "__node:=talker"]
    # what llfsm run makes of them: its own parser (the fast path, which click agrees with)
    options = run_args.parse(sim.argv[4:])
    assert options is not None and options["log_levels"] == ("error", "sim:=debug") and options["remaps"] == (
        "__node:=sim", "a:=b")  # fmt: skip
    options = run_args.parse(run.argv[4:])
    assert options is not None and options["log_levels"] == ("warn",) and options["log_file"] is True
    assert options["params"] == ("gain:=2.0",) and options["params_files"] == (str(tmp_path / "p.yaml"),)
    node = "<launch>\n  <node pkg='turtlesim' exec='turtlesim_node' {}/>\n</launch>\n"
    for attrs, message in [
        ("ros_args='--log-level loud'", "ros_args: --log-level loud: 'loud' is not a level (debug, info, warn"),
        ("ros_args='--log-level'", "ros_args: --log-level: takes a value (-r/--remap, -p/--param, --params-file"),
        (
            "ros_args='--enclave /x'",
            "ros_args: --enclave: llfsm run takes -r/--remap, -p/--param, --params-file, --log",
        ),
        ("ros_args='--verbose'", "ros_args: --verbose: llfsm run takes -r/--remap"),
        ("ros_args='-p gain'", "ros_args: -p 'gain': expected [NODE:]NAME:=VALUE"),
        ("ros_args='-r a'", "ros_args: --remap 'a': expected FROM:=TO or NODE:FROM:=TO"),
        ("ros_args='--params-file nowhere.yaml'", "no params file 'nowhere.yaml'"),
        ("args='--ros-args --log-level loud --'", "args: --log-level loud: 'loud' is not a level"),
    ]:
        f.write_text(node.format(attrs))
        assert refused(f).startswith(f"llfsm: {f}:2: {message}"), (attrs, refused(f))
