"""Writing clfsm (MiEditLLFSM) machine directories for the tests of `llfsm import`: the files
MiEditLLFSM keeps for a machine, in the shape it writes them (the glue headers and `.mm`
files too, which the importer must read for targets and otherwise ignore).

This is the tests' own writer, not MiPal's: it writes what the importer reads, so that each
corner of the format has a small machine (tests/test_import.py), and the how-to's four
machines in clfsm's form, transcribed from its listings (`python tests/clfsm_writer.py DIR`
writes them into DIR: docs/import.md starts from there).
"""

from __future__ import annotations

import plistlib
import sys
from dataclasses import dataclass, field
from pathlib import Path

SECTIONS = ("OnEntry", "OnExit", "Internal", "OnSuspend", "OnResume")
HEADER = "//\n// {file}\n//\n// Automatically created through MiCASE -- do not change manually!\n//\n"


@dataclass
class ClfsmState:
    name: str
    transitions: list[tuple[str, str]] = field(default_factory=list)  # (target, guard expression)
    code: dict[str, str] = field(default_factory=dict)  # section -> C++
    variables: str = ""  # State_<S>_Variables.h lines: "type\tname;\t///< comment"


def write_clfsm(
    root: Path,
    name: str,
    states: list[ClfsmState],
    *,
    includes: str = '#include "CLMacros.h"\n',
    variables: str = "",
    initial: str | None = None,
    suspended: str | None = None,
    layout: bool = True,
    suspend_sections: bool = True,
    states_newline: bool = False,
) -> Path:
    """A clfsm machine directory `root/NAME.machine`.  `suspend_sections=False` leaves out the
    OnSuspend/OnResume files (machines older than them); `states_newline` ends `States` with a
    newline (MiEditLLFSM leaves it out)."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    index = {s.name: i for i, s in enumerate(states)}
    (d / "States").write_text("\n".join(s.name for s in states) + ("\n" if states_newline else ""))
    (d / "IncludePath").write_text("$MACHINE_DIR\n.\n")
    (d / f"{name}_Includes.h").write_text(includes)
    (d / f"{name}_Variables.h").write_text(HEADER.format(file=f"{name}_Variables.h") + variables)
    (d / f"{name}_Methods.h").write_text("\n")
    (d / f"{name}_VarRefs.mm").write_text(
        HEADER.format(file=f"{name}_VarRefs.mm") + f"{name} *_m = static_cast<{name} *>(_machine);\n"
    )
    (d / f"{name}_FuncRefs.mm").write_text(HEADER.format(file=f"{name}_FuncRefs.mm"))
    (d / f"{name}.h").write_text(_machine_header(name, len(states)))
    (d / f"{name}.mm").write_text(_machine_code(name, states, index[initial] if initial else 0,
                                                None if suspended is None else index[suspended]))  # fmt: skip
    sections = SECTIONS if suspend_sections else SECTIONS[:3]
    for s in states:
        (d / f"State_{s.name}.h").write_text(_state_header(name, s, index, suspend_sections))
        (d / f"State_{s.name}.mm").write_text(f"// State_{s.name}.mm: the glue MiEditLLFSM generates\n")
        (d / f"State_{s.name}_Includes.h").write_text("\n")
        (d / f"State_{s.name}_Methods.h").write_text("\n")
        (d / f"State_{s.name}_Variables.h").write_text(HEADER.format(file=f"State_{s.name}_Variables.h") + s.variables)
        (d / f"State_{s.name}_VarRefs.mm").write_text(HEADER.format(file=f"State_{s.name}_VarRefs.mm"))
        (d / f"State_{s.name}_FuncRefs.mm").write_text(HEADER.format(file=f"State_{s.name}_FuncRefs.mm"))
        for section in sections:
            code = s.code.get(section, "")
            (d / f"State_{s.name}_{section}.mm").write_text(code if code.endswith("\n") or not code else code + "\n")
        for i, (_target, guard) in enumerate(s.transitions):
            (d / f"State_{s.name}_Transition_{i}.expr").write_text(guard + "\n")
    if layout:
        boxes = {s.name: {"x": 100.0 + 250 * (i % 4), "y": 100.0 + 200 * (i // 4), "w": 200.0, "h": 100.0,
                          "Transitions": []} for i, s in enumerate(states)}  # fmt: skip
        (d / "Layout.plist").write_bytes(plistlib.dumps({"States": boxes}))
        (d / "WindowLayout.plist").write_bytes(plistlib.dumps({"WindowLayout.plist": {"w": 1280.0, "h": 1024.0}}))
    return d


def _machine_header(name: str, count: int) -> str:
    return HEADER.format(file=f"{name}.h") + (
        f'#include "CLMachine.h"\n\nnamespace FSM {{ namespace CLM {{\n'
        f"    class {name}: public CLMachine {{\n        CLState *_states[{count}];\n"
        f"    public:\n        virtual int numberOfStates() const {{ return {count}; }}\n"
        f'#       include "{name}_Variables.h"\n    }};\n}} }}\n'
    )


def _machine_code(name: str, states: list[ClfsmState], initial: int, suspended: int | None) -> str:
    lines = [HEADER.format(file=f"{name}.mm"), f'#include "{name}.h"\n']
    lines += [f'#include "State_{s.name}.h"\n' for s in states]
    lines.append(f"\n{name}::{name}(int mid, const char *name): CLMachine(mid, name)\n{{\n")
    lines += [f"\t_states[{i}] = new FSM{name}::State::{s.name};\n" for i, s in enumerate(states)]
    if suspended is not None:
        lines.append(f"\n\tsetSuspendState(_states[{suspended}]);            // set suspend state\n")
    lines.append(f"\tsetInitialState(_states[{initial}]);            // set initial state\n}}\n")
    return "".join(lines)


def _state_header(machine: str, s: ClfsmState, index: dict[str, int], suspend_sections: bool) -> str:
    actions = "".join(
        f"                class {a}: public CLAction {{ virtual void perform(CLMachine *, CLState *) const; }};\n"
        for a in (SECTIONS if suspend_sections else SECTIONS[:3])
    )
    transitions = "".join(
        f"                class Transition_{i}: public CLTransition\n                {{\n                public:\n"
        f"                    Transition_{i}(int toState = {index[target]}): CLTransition(toState) {{}}\n"
        f"                    virtual bool check(CLMachine *, CLState *) const;\n                }};\n"
        for i, (target, _guard) in enumerate(s.transitions)
    )
    return HEADER.format(file=f"State_{s.name}.h") + (
        f'#include "CLState.h"\n\nnamespace FSM {{ namespace CLM {{ namespace FSM{machine} {{ namespace State {{\n'
        f"            class {s.name}: public CLState\n            {{\n{actions}{transitions}"
        f"                CLTransition *_transitions[{len(s.transitions)}];\n            public:\n"
        f"                virtual int numberOfTransitions() const {{ return {len(s.transitions)}; }}\n"
        f'#               include "State_{s.name}_Variables.h"\n            }};\n}} }} }} }}\n'
    )


# -- the how-to's four machines, in clfsm's form (transcribed from its listings) ------------------

NOT_OK = "!rclcpp::ok()"
ROS_INIT = """int argc = 1; static char *argv[1];
std::string node_name="{node}";
char * cstr = new char [node_name.length()+1];
std::strcpy (cstr, node_name.c_str());
argv[0]= cstr;
rclcpp::init(argc, argv);
node = rclcpp::Node::make_shared(node_name);
"""
MOVE = "msg.linear.x = {x};\nmsg.angular.z = {z};\npublisher_->publish(msg);\n"


def state(name: str, *transitions: tuple[str, str], entry: str = "") -> ClfsmState:
    """A state whose transitions to END test `!rclcpp::ok()` first, as the how-to's all do."""
    return ClfsmState(name, [("END", NOT_OK), *transitions], {"OnEntry": entry} if entry else {})


def end_states() -> list[ClfsmState]:
    return [ClfsmState("END"), ClfsmState("SUSPENDED")]


def ping_pong(root: Path) -> Path:
    publish = (
        "auto message = std_msgs::msg::String();\nstd::stringstream ss;\n"
        'ss << "The count is " << count;\nmessage.data = ss.str();\n'
        "RCLCPP_INFO(node->get_logger(), \"Publishing: '%s'\", message.data.c_str());\n"
        "publisher_->publish(message);\n"
    )
    setup = 'publisher_ = node->create_publisher<std_msgs::msg::String>("pingpong", 10);\ncount=0;\n'
    return write_clfsm(
        root,
        "ros2_ping_pong",
        [
            state("INITIAL", ("PUBLISH", "after_ms(1000)"), entry=ROS_INIT.format(node="ros_ping_pong") + setup),
            state("PUBLISH", ("WAIT_AND_COUNT", "after_ms(500)"), entry=publish),
            state("WAIT_AND_COUNT", ("PUBLISH", "after_ms(500)"), entry="count++;\n"),
            *end_states(),
        ],
        includes='#include "rclcpp/rclcpp.hpp"\n#include "std_msgs/msg/string.hpp"\n#include "CLMacros.h"\n',
        variables=(
            "int\tcount;\t///<\n"
            "rclcpp::Publisher<std_msgs::msg::String>::SharedPtr\tpublisher_;\t///<\n"
            "std::shared_ptr<rclcpp::Node>\tnode;\t///<\n"
        ),
        suspended="SUSPENDED",
    )


TURTLE_INCLUDES = '#include "rclcpp/rclcpp.hpp"\n#include "geometry_msgs/msg/twist.hpp"\n#include "CLMacros.h"\n'
TURTLE_VARIABLES = (
    "std::shared_ptr<rclcpp::Node>\tnode;\t///<\n"
    "rclcpp::Publisher<geometry_msgs::msg::Twist>::SharedPtr\tpublisher_;\t///<\n"
    "geometry_msgs::msg::Twist\tmsg;\t///<\n"
)
HALT = "msg = geometry_msgs::msg::Twist();\n" + "".join(
    f"msg.{part}.{axis} = 0.0;\n" for part in ("linear", "angular") for axis in "xyz"
)
CMD_VEL = 'publisher_ = node->create_publisher<geometry_msgs::msg::Twist>("/turtle1/cmd_vel", 10);\n'
POSE = "turtle_sensor_interface::srv::TurtlePosition"


def blind_turtle_bot(root: Path) -> Path:
    setup = ROS_INIT.format(node="ros2_blind_turtle_bot") + CMD_VEL + HALT + "publisher_->publish(msg);\n"
    return write_clfsm(
        root,
        "ros2_blind_turtle_bot",
        [
            state("INITIAL", ("STRAIGHT", "after_ms(1000)"), entry=setup),
            state("STRAIGHT", ("TURN_RIGHT", "after_ms(1000)"), entry=MOVE.format(x="2.0", z="0.0")),
            state("TURN_RIGHT", ("STRAIGHT", "after_ms(1000)"), entry=MOVE.format(x="0.0", z="-2.0")),
            *end_states(),
        ],
        includes=TURTLE_INCLUDES,
        variables=TURTLE_VARIABLES,
        suspended="SUSPENDED",
    )


def wall_turtle_bot(root: Path) -> Path:
    setup = ROS_INIT.format(node="ros2_wall_turtle_bot") + CMD_VEL
    setup += f'client_ = node->create_client<{POSE}>("turtle_pose_service");\n' + HALT
    stop = MOVE.format(x="0.0", z="0.0") + (
        f"auto request = std::make_shared<{POSE}::Request>();\n"
        "result = client_->async_send_request(request);\n"
        "I_wait = rclcpp::spin_until_future_complete(node, result) ;\n"
    )
    inside = "position_x > 2.0 && position_y > 2.0 && position_x < 9.0 && position_y < 9.0"
    failed = (
        'RCLCPP_ERROR(node->get_logger(), "/turtle_pose_service did not answer: is turtle_sensor_poster running?");\n'
    )
    return write_clfsm(
        root,
        "ros2_wall_turtle_bot",
        [
            state("INITIAL", ("STRAIGHT", "after_ms(1000)"), entry=setup),
            state("STRAIGHT", ("STOP", "after_ms(1000)"), entry=MOVE.format(x="2.0", z="0.0")),
            state(
                "STOP",
                ("TEST", "(I_wait == rclcpp::FutureReturnCode::SUCCESS)"),
                ("SERVICE_FAILS", "I_wait != rclcpp::FutureReturnCode::SUCCESS"),
                entry=stop,
            ),
            state(
                "TEST",
                ("STRAIGHT", inside),
                ("BACK", "after_ms(500)"),
                entry="position_x = result.get()->x;\nposition_y = result.get()->y;\n",
            ),
            state("BACK", ("TURN_RIGHT", "after_ms(1000)"), entry=MOVE.format(x="-2.0", z="0.0")),
            state("TURN_RIGHT", ("STRAIGHT", "after_ms(1000)"), entry=MOVE.format(x="0.0", z="-2.0")),
            ClfsmState("SERVICE_FAILS", [("END", "true")], {"OnEntry": failed}),
            *end_states(),
        ],
        includes=TURTLE_INCLUDES + '#include "turtle_sensor_interface/srv/turtle_position.hpp"\n',
        variables=TURTLE_VARIABLES
        + (
            f"rclcpp::Client<{POSE}>::SharedPtr\tclient_;\t///<\n"
            "rclcpp::FutureReturnCode\tI_wait;\t///<\n"
            f"rclcpp::Client<{POSE}>::SharedFuture\tresult;\t///<\n"
            "float\tposition_x;\t///<\nfloat\tposition_y;\t///<\n"
        ),
        suspended="SUSPENDED",
    )


def turtle_suspend_resume(root: Path) -> Path:
    bot = '"ros2_blind_turtle_bot"'
    setup = (
        "// rclcpp is up before the bot has run its own INITIAL\n"
        f"int argc = 0;\nrclcpp::init(argc, nullptr);\nsuspend({bot});\n"
    )
    return write_clfsm(
        root,
        "ros2_turtle_suspend_resume",
        [
            state("INITIAL", ("RESUME", f"is_suspended({bot})"), entry=setup),
            state("RESUME", ("SUSPEND_BOT", f"is_running({bot}) && after_ms(1500)"), entry=f"resume({bot});\n"),
            state("SUSPEND_BOT", ("RESUME", f"is_suspended({bot}) && after_ms(500)"), entry=f"suspend({bot});\n"),
            *end_states(),
        ],
        includes='#include "rclcpp/rclcpp.hpp"\n#include "CLMacros.h"\n',
        suspended="SUSPENDED",
    )


HOW_TO = (ping_pong, blind_turtle_bot, wall_turtle_bot, turtle_suspend_resume)

if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("clfsm")
    for make in HOW_TO:
        print(make(out))
