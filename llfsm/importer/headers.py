"""The headers of a clfsm machine: includes (`<M>_Includes.h`, `State_<S>_Includes.h`),
variables (`<M>_Variables.h`, `State_<S>_Variables.h`) and functions (`*_Methods.h`).

An include becomes the import its code needs (`rclcpp/rclcpp.hpp` -> `from llfsm import ros`,
`geometry_msgs/msg/twist.hpp` -> `from llfsm.msgs.geometry_msgs.msg import Twist`); a C or
C++ standard header needs nothing in Python (what its functions need, `math` or `sys`, is
imported where the code uses them).  A header llfsm has no counterpart for (the whiteboard's,
a robot's SDK) is kept as a marked line.  A variable becomes `name: annotation = value`
(llfsm.importer.kinds), with its `///<` comment.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .cxx import (
    MAX_DEPTH,
    Node,
    code_lines,
    end_line_of,
    line_of,
    parse_expression,
    parse_members,
    parse_unit,
    too_deep,
)
from .expressions import Expressions
from .kinds import Imports, annotation
from .statements import Statements, Translation, comment_lines, marked, python_name
from .terms import Scope, Untranslatable

#: Headers of the C and C++ standard libraries and of clfsm itself: Python needs none of them.
_NOTHING_NEEDED = re.compile(
    r"(?:iostream|string|sstream|cmath|math\.h|cstdlib|stdlib\.h|cstdio|stdio\.h|cstring|string\.h|unistd\.h|"
    r"fcntl\.h|memory|chrono|functional|vector|cstdint|stdint\.h|stdbool\.h|climits|limits\.h|ctime|time\.h|"
    r"iomanip|algorithm|utility|cassert|assert\.h|errno\.h|cerrno|sys/types\.h|sys/stat\.h|CLMacros\.h|"
    r"CLMachine\.h|CLState\.h|CLAction\.h|CLTransition\.h)\Z"
)
_MESSAGE_HEADER = re.compile(r"(?P<pkg>[a-z][a-z0-9_]*)/(?P<sub>msg|srv)/(?P<snake>[a-z][a-z0-9_]*)\.hpp?\Z")
_BLOCK_WORKAROUND = re.compile(r"#\s*(?:undef\s+__block|define\s+__block\b.*)\Z")
_INTERFACES = Path(__file__).resolve().parent.parent / "msgs" / "_interfaces"


def message_type_name(pkg: str, sub: str, snake: str) -> str:
    """The type a message header declares: `turtle_position.hpp` declares TurtlePosition.
    Looked up among llfsm's interface definitions where the package ships (so `tf_message`
    is TFMessage), else spelt in CamelCase."""
    folder = _INTERFACES / pkg / sub
    wanted = snake.replace("_", "").lower()
    try:
        for f in folder.iterdir():
            if f.stem.lower() == wanted:
                return f.stem
    except OSError:
        pass
    return "".join(part.capitalize() for part in snake.split("_"))


@dataclass
class Define:
    """`#define NAME value` of a constant: a machine variable of llfsm, declared first."""

    name: str
    python: str
    kind: str
    value: str
    source: str


@dataclass
class Included:
    """A translated includes header: its lines for Includes.py, and the constants it defines."""

    translation: Translation
    defines: list[Define] = field(default_factory=list)


def translate_includes(text: str, source: str, scope: Scope) -> Included:
    parsed = parse_unit(text)
    out = Included(Translation([], len(code_lines(parsed.root, 1, len(parsed.lines)))))
    for node in parsed.root.named_children:
        first, last = line_of(node), end_line_of(node)
        if node.type == "comment":
            if not _generated_comment(parsed.text(node)):
                out.translation.lines.extend(f"# {ln}".rstrip() for ln in comment_lines(parsed.text(node)))
            continue
        if node.type == "preproc_def":
            why = _define(node, source, scope, out)
        else:
            why = _include(node, parsed.text(node).strip(), scope.imports)
        if why is None:
            continue
        out.translation.lines.extend(marked("", why, parsed.text(node).strip()))
        rows = sorted(code_lines(node, first, last))
        out.translation.left.extend((r, why if i == 0 else "") for i, r in enumerate(rows))
    return out


def _define(node: Node, source: str, scope: Scope, out: Included) -> str | None:
    """`#define NAME 0.5` becomes the machine variable `NAME: float = 0.5`; `#define FLAG`
    needs nothing in Python (an `#ifdef FLAG` that reads it is left for a person)."""
    name = node.child_by_field_name("name").text.decode("utf-8", "replace")
    value = node.child_by_field_name("value")
    if _BLOCK_WORKAROUND.match(f"#define {name}"):
        return None
    if value is None:
        out.translation.lines.append(f"# clfsm: #define {name}")
        return None
    text = value.text.decode("utf-8", "replace").strip()
    parsed = parse_expression(text)
    try:
        if not parsed.ok:
            raise Untranslatable("a macro that is not a constant")
        e = Expressions(scope).value(parsed.root)
    except Untranslatable:
        return "a macro that is not a constant of a number or a string"
    if e.kind not in ("int", "float", "str", "bool"):
        return "a macro that is not a constant of a number or a string"
    py = python_name(name, scope.taken)
    scope.taken.add(py)
    out.defines.append(Define(name, py, e.kind, e.text, source))
    return None


def _include(node: Node, text: str, imports: Imports) -> str | None:
    """Why an include line cannot be carried over, or None once its import is recorded."""
    if node.type == "preproc_include":
        path_node = node.child_by_field_name("path")
        header = path_node.text.decode("utf-8", "replace").strip('<>"') if path_node is not None else ""
        if _NOTHING_NEEDED.match(header):
            return None
        if header in ("rclcpp/rclcpp.hpp", "rclcpp/rclcpp.h"):
            imports.ros = True
            return None
        m = _MESSAGE_HEADER.match(header)
        if m:
            imports.message(m["pkg"], m["sub"], message_type_name(m["pkg"], m["sub"], m["snake"]))
            return None
        return f"the header {header}: llfsm has no counterpart"
    if node.type == "using_declaration" or text.startswith("using namespace"):
        return None  # Python names need no namespace
    if node.type == "preproc_call" and text.startswith("#pragma"):
        return None  # a compiler's settings: Python has none
    if _BLOCK_WORKAROUND.match(re.sub(r"\s+", " ", text)):
        return None  # clfsm's workaround for Apple's blocks: nothing in Python
    return "C++ that Includes.py cannot hold"


def _generated_comment(text: str) -> bool:
    """The comment MiEditLLFSM writes at the top of a header (its name, "Automatically created")."""
    body = " ".join(comment_lines(text))
    return not body.strip() or "Automatically created" in body or bool(re.fullmatch(r"\s*[\w.]+\.(?:h|mm)\s*", body))


_PLACEHOLDER = "# a placeholder for the line above"


@dataclass
class Declared:
    """The variables of one variables header: Python lines, and C name -> (Python name, kind)."""

    translation: Translation
    names: dict[str, tuple[str, str | None]] = field(default_factory=dict)


def translate_variables(text: str, scope: Scope) -> Declared:
    """`<M>_Variables.h` or `State_<S>_Variables.h` as a variables file.  A variable whose type
    llfsm does not know is declared `name: object` after its marked line, so that code using
    it is marked for that reason rather than for an unknown name."""
    parsed = parse_members(text)
    s = Statements(scope)
    if not parsed.ok:
        return Declared(translate_methods(text, "C++ the parser cannot read as variables"))
    out: list[str] = []
    left: list[tuple[int, str]] = []
    names: dict[str, tuple[str, str | None]] = {}
    last_row = -1
    for node in parsed.root.named_children:
        if node.type == "comment":
            if _generated_comment(parsed.text(node)):
                continue
            lines = comment_lines(parsed.text(node))
            if line_of(node) == last_row and len(lines) == 1 and out and not out[-1].startswith("#"):
                if lines[0]:  # `///< what it is`, after the declaration (or its placeholder)
                    out[-1] = out[-1].replace(_PLACEHOLDER, f"# {lines[0]} ({_PLACEHOLDER[2:]})", 1)
                    out[-1] += "" if lines[0] in out[-1] else f"  # {lines[0]}"
            else:
                out.extend(f"# {ln}".rstrip() for ln in lines)
            continue
        last_row = end_line_of(node)
        try:
            if node.type != "field_declaration" or node.has_error:
                raise Untranslatable("not a variable declaration")
            if too_deep(node):
                raise Untranslatable(f"nested deeper than {MAX_DEPTH} levels")
            out.extend(_variables(s, node, names, scope))
        except Untranslatable as e:
            out.extend(marked("", str(e), parsed.text(node)))
            rows = sorted(code_lines(node, line_of(node), end_line_of(node)))
            left.extend((r, str(e) if i == 0 else "") for i, r in enumerate(rows))
            for name in _declared_names(node):
                if name not in names:
                    py = python_name(name, scope.taken)
                    scope.taken.add(py)
                    names[name] = (py, None)
                    out.append(f"{py}: object  {_PLACEHOLDER}")
    code = len(code_lines(parsed.whole, 1, len(parsed.lines)))
    return Declared(Translation(out, code, left), names)


def _variables(s: Statements, node: Node, names: dict[str, tuple[str, str | None]], scope: Scope) -> list[str]:
    type_node = node.child_by_field_name("type")
    if type_node is None:
        raise Untranslatable("a declaration without a type")
    type_text = s.text(type_node)
    lines = []
    for d in node.children_by_field_name("declarator"):
        value = node.child_by_field_name("default_value")
        pointer, size = False, None
        while d.type in ("pointer_declarator", "array_declarator", "reference_declarator", "init_declarator"):
            if d.type == "reference_declarator":
                raise Untranslatable("a reference")
            if d.type == "init_declarator":
                value = d.child_by_field_name("value")
            elif d.type == "pointer_declarator":
                pointer = True
            else:
                size = d.child_by_field_name("size")
                if size is None:
                    raise Untranslatable("an array without a size")
            d = d.child_by_field_name("declarator") or d.named_children[-1]
        if d.type not in ("field_identifier", "identifier"):
            raise Untranslatable(f"the declaration of {s.text(d)}")
        name = s.text(d)
        text, kind = s.typed_value(type_text, pointer, size, value)
        py = python_name(name, scope.taken)
        scope.taken.add(py)
        names[name] = (py, kind)
        lines.append(f"{py}: {annotation(kind)}" + (f" = {text}" if text is not None else ""))
    return lines


def _declared_names(node: Node) -> list[str]:
    """The names a declaration declares, found however its declarators are written."""
    out = []
    stack = list(node.children_by_field_name("declarator"))
    while stack:
        d = stack.pop(0)
        if d.type in ("field_identifier", "identifier"):
            out.append(d.text.decode("utf-8", "replace"))
        else:
            inner = d.child_by_field_name("declarator")
            if inner is not None:
                stack.append(inner)
    return out


def translate_methods(
    text: str, why: str = "a function of the clfsm machine: write it in a helper module beside the machine"
) -> Translation:
    """A `*_Methods.h`: C++ functions, each line kept for a person (llfsm machines keep their
    functions in helper modules beside the machine, imported by Includes.py)."""
    parsed = parse_unit(text)
    code = sorted(code_lines(parsed.root, 1, len(parsed.lines)))
    if not code:
        return Translation([], 0)
    lines = marked("", why, "\n".join(parsed.lines[code[0] - 1 : code[-1]]))
    return Translation(lines, len(code), [(r, why if i == 0 else "") for i, r in enumerate(code)])
