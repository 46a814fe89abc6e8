"""C++ sections and guards to Python, statement by statement (llfsm.importer.expressions
does the expressions).

A statement the translator cannot carry over is kept, line by line, as a marked comment:

    # UNTRANSLATED (unlink is not a function llfsm knows): unlink(testfile);

`llfsm check` reports each such line as an error (LF080), so the machine does not build until
a person has written the Python and deleted the line.  A statement inside a block is marked
alone (its block keeps its other statements, and `pass` when nothing else is left); a block
whose own header cannot be translated is marked whole.
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Container
from dataclasses import dataclass, field

from ..runtime.machine import MACROS, RESERVED
from .cxx import MAX_DEPTH, Node, code_lines, end_line_of, line_of, parse_expression, parse_statements, too_deep
from .expressions import Expressions
from .kinds import annotation, default, kind_of, normalise
from .terms import ADD, MUL, Expr, Scope, Untranslatable, wrap

#: The marker of a line left for a person (llfsm.lang.check.untranslated reads it back).
MARKER = "# UNTRANSLATED"
INDENT = "    "

_COMPOUND_OPS = {"+=", "-=", "*=", "/=", "%=", "|=", "&=", "^=", "<<=", ">>="}
_NOT_STATEMENTS = {"{", "}", ";"}


@dataclass
class Static:
    """A `static` local of a section: kept across runs of the section, as a state variable
    of llfsm is (set once when the machine loads)."""

    name: str
    annotation: str
    initial: str | None
    line: int


@dataclass
class Translation:
    """One code file, translated: its Python lines, how many of its source lines held code,
    and the lines left (line, reason: the first line of each statement left has a reason)."""

    lines: list[str]
    code: int
    left: list[tuple[int, str]] = field(default_factory=list)
    statics: list[Static] = field(default_factory=list)

    @property
    def left_lines(self) -> int:
        return len({line for line, _ in self.left})


def python_name(name: str, *taken: Container[str]) -> str:
    """`name` as a name machine code may bind: a Python keyword, a name llfsm reserves (or
    one in `taken`) gets `_` appended until it is free."""
    out = name
    if out.startswith("_llfsm") or (out.startswith("__") and out.endswith("__")):
        out = "c_" + out.strip("_")  # no `_` appended ever makes these free
    while keyword.iskeyword(out) or out in RESERVED or out in MACROS or any(out in t for t in taken):
        out += "_"
    return out


def comment_lines(text: str) -> list[str]:
    """A C++ comment as the text of its lines (without `//`, `/*`, `*/` and leading `*`)."""
    if text.startswith("//"):
        return [text[2:].lstrip("/!<").strip()]
    body = text[2:-2] if text.endswith("*/") else text[2:]
    lines = [re.sub(r"^\s*\*?\s?", "", ln).rstrip() for ln in body.strip("*!").split("\n")]
    while lines and not lines[0]:
        lines.pop(0)
    while lines and not lines[-1]:
        lines.pop()
    return lines


def marked(indent: str, why: str, source: str) -> list[str]:
    """The marker lines of `source` (one per line), the reason on the first."""
    out = []
    for i, line in enumerate(source.split("\n")):
        if i and not line.strip():
            out.append(f"{indent}#")
            continue
        tag = f"{MARKER} ({why})" if i == 0 else MARKER
        out.append(f"{indent}{tag}: {line.strip()}".rstrip())
    return out


class Statements:
    """Translates the statements of one section."""

    def __init__(self, scope: Scope) -> None:
        self.scope = scope
        self.ex = Expressions(scope)
        self.out: list[str] = []
        self.left: list[tuple[int, str]] = []
        self.statics: list[Static] = []
        self.static_names: set[str] = set()
        self.bound: list[tuple[str, tuple[str, str | None] | None]] = []
        self.loops = 0
        self.last_row = -1

    def text(self, node: Node) -> str:
        return str(node.text.decode("utf-8", "replace"))

    # -- blocks --------------------------------------------------------------------------------

    def block(self, nodes: list[Node], depth: int) -> None:
        indent = INDENT * depth
        start = len(self.out)
        for n in nodes:
            if n.type in _NOT_STATEMENTS:
                continue
            if n.type == "comment":
                self.comment(n, indent)
                continue
            self.guarded(n, depth)
            self.last_row = end_line_of(n)
        if depth > 0 and not any(not ln.lstrip().startswith("#") for ln in self.out[start:]):
            self.out.append(indent + "pass")

    def comment(self, node: Node, indent: str) -> None:
        lines = comment_lines(self.text(node))
        same_line = line_of(node) == self.last_row and len(lines) == 1 and self.out
        if same_line and not self.out[-1].lstrip().startswith(MARKER):
            self.out[-1] += f"  # {lines[0]}" if lines[0] else ""
            return
        self.out.extend(f"{indent}# {ln}".rstrip() for ln in lines)

    def body(self, node: Node, depth: int) -> None:
        self.last_row = line_of(node)
        if node.type == "compound_statement":
            self.block(node.children, depth)
        else:
            self.block([node], depth)

    def guarded(self, node: Node, depth: int) -> None:
        """Translate one statement, or mark its lines when it cannot be translated."""
        mark, left_at, bound_at, statics_at = len(self.out), len(self.left), len(self.bound), len(self.statics)
        try:
            if node.has_error:
                raise Untranslatable("C++ the parser cannot read")
            if depth == 0 and too_deep(node):
                raise Untranslatable(f"nested deeper than {MAX_DEPTH} levels")
            self.statement(node, depth)
        except Untranslatable as e:
            del self.out[mark:]
            del self.left[left_at:]
            while len(self.bound) > bound_at:  # the statement's locals are unknown after all
                name, before = self.bound.pop()
                if before is None:
                    del self.scope.locals[name]
                else:
                    self.scope.locals[name] = before
            for st in self.statics[statics_at:]:
                self.static_names.discard(st.name)
            del self.statics[statics_at:]
            self.out.extend(marked(INDENT * depth, str(e), self.text(node)))
            first, last = line_of(node), end_line_of(node)
            lines = sorted(code_lines(node, first, last))
            self.left.extend((ln, str(e) if i == 0 else "") for i, ln in enumerate(lines))

    def bind(self, name: str, python: str, kind: str | None) -> None:
        """`name` is a local from here on (undone if its statement is left for a person)."""
        self.bound.append((name, self.scope.locals.get(name)))
        self.scope.locals[name] = (python, kind)

    def emit(self, depth: int, line: str) -> None:
        self.out.append(INDENT * depth + line)

    # -- statements ----------------------------------------------------------------------------

    def statement(self, node: Node, depth: int) -> None:
        kind = node.type
        if kind == "expression_statement":
            if node.named_child_count:
                self.expression_statement(node.named_children[0], depth)
        elif kind == "declaration":
            self.declaration(node, depth)
        elif kind == "compound_statement":
            self.block(node.children, depth)
        elif kind == "if_statement":
            self.if_statement(node, depth)
        elif kind == "while_statement":
            cond = self.condition(node)
            self.emit(depth, f"while {cond.text}:")
            self.loop_body(node.child_by_field_name("body"), depth)
        elif kind == "do_statement":
            self.do_statement(node, depth)
        elif kind == "for_statement":
            self.for_statement(node, depth)
        elif kind in ("break_statement", "continue_statement"):
            if not self.loops:
                raise Untranslatable(f"{kind[:-10]} outside a loop")
            self.emit(depth, kind[:-10])
        elif kind == "using_declaration" or kind == "alias_declaration":
            pass  # `using namespace std;`: Python needs nothing for it
        elif kind == "return_statement":
            raise Untranslatable("return: a section of an llfsm machine runs to its end")
        else:
            raise Untranslatable(kind.replace("_", " "))

    def expression_statement(self, node: Node, depth: int) -> None:
        if node.type == "assignment_expression":
            self.assignment(node, depth)
        elif node.type == "update_expression":
            target = self.ex.value(node.child_by_field_name("argument"))
            op = "+=" if self.text(node.child_by_field_name("operator")) == "++" else "-="
            self.emit(depth, f"{target.text} {op} 1")
        elif node.type == "comma_expression":
            for part in (node.child_by_field_name("left"), node.child_by_field_name("right")):
                self.expression_statement(part, depth)
        elif node.type == "binary_expression" and self.ex.stream_target(node) is not None:
            for line in self.ex.output(node) or []:
                self.emit(depth, line)
        elif node.type == "call_expression" and (
            self.strcpy(node, depth) or self.ignoring_errors(node, depth) or self.assertion(node, depth)
        ):
            pass
        else:
            self.emit(depth, self.ex.expr(node).text)

    def strcpy(self, node: Node, depth: int) -> bool:
        """`strcpy(dst, src)` copies a C string: Python's strings are values, `dst = src`."""
        name = self.text(node.child_by_field_name("function")).replace(" ", "")
        args = self.ex.arguments(node)
        if name not in ("strcpy", "std::strcpy") or len(args) != 2:
            return False
        dst, src = self.ex.value(args[0]), self.ex.value(args[1])
        if dst.kind != "str":
            raise Untranslatable("strcpy into something not a string")
        self.emit(depth, f"{dst.text} = {src.text}")
        return True

    def assertion(self, node: Node, depth: int) -> bool:
        """`assert(x);` is Python's `assert x`."""
        args = self.ex.arguments(node)
        if self.text(node.child_by_field_name("function")) != "assert" or len(args) != 1:
            return False
        self.emit(depth, f"assert {self.ex.value(args[0]).text}")
        return True

    def ignoring_errors(self, node: Node, depth: int) -> bool:
        """`unlink(path);` and `close(fd);`, whose failure C code ignores (it does not read the
        result): os.unlink and os.close raise instead, so the failure is suppressed."""
        name = self.text(node.child_by_field_name("function")).replace(" ", "")
        args = self.ex.arguments(node)
        if name not in ("unlink", "close") or len(args) != 1:
            return False
        self.scope.imports.modules.update(("os", "contextlib"))
        self.emit(depth, f"with contextlib.suppress(OSError): os.{name}({self.ex.value(args[0]).text})")
        return True

    def assignment(self, node: Node, depth: int) -> None:
        op = self.text(node.child_by_field_name("operator"))
        left_node, right_node = node.child_by_field_name("left"), node.child_by_field_name("right")
        if left_node.type not in ("identifier", "field_expression", "subscript_expression"):
            raise Untranslatable("an assignment to a pointer or a computed place")
        target = self.ex.value(left_node)
        if right_node.type == "assignment_expression":
            raise Untranslatable("an assignment inside an expression")
        if op == "=":
            value = self.initial(right_node, target.kind)
            self.emit(depth, f"{target.text} = {value}")
            return
        if op not in _COMPOUND_OPS:
            raise Untranslatable(f"the operator {op}")
        value_e = self.ex.value(right_node)
        if op == "/=" and target.kind == "int" and value_e.kind == "int":
            self.emit(depth, f"{target.text} = int({target.text} / {value_e.text})")
        elif op == "%=" and "float" in (target.kind, value_e.kind):
            self.ex.scope.imports.modules.add("math")
            self.emit(depth, f"{target.text} = math.fmod({target.text}, {value_e.text})")
        elif op == "+=" and target.kind == "str" and value_e.kind not in ("str", "any"):
            raise Untranslatable("+= of a number to a string")
        elif op in ("/=", "%=") and (target.kind, value_e.kind) == ("any", "any"):
            raise Untranslatable(f"{op} of two values whose types are unknown")
        else:
            self.emit(depth, f"{target.text} {op} {value_e.text}")

    def initial(self, node: Node, kind: str | None) -> str:
        """The Python of a value assigned to (or initialising) a variable of `kind`."""
        if node.type == "new_expression":
            if kind == "str" and self.text(node.child_by_field_name("type")).strip() == "char":
                return '""'  # a C string buffer: Python's strings need none
            raise Untranslatable("new: Python makes objects without it")
        e = self.ex.value(node)
        if e.kind is not None and e.kind.startswith("msg:") and node.type in ("identifier", "field_expression"):
            self.scope.imports.modules.add("copy")
            return f"copy.deepcopy({e.text})"  # C++ copies a message that is assigned
        return e.text

    def declaration(self, node: Node, depth: int) -> None:
        type_text = self.text(node.child_by_field_name("type"))
        static = any(c.type == "storage_class_specifier" and self.text(c) == "static" for c in node.children)
        for d in node.children_by_field_name("declarator"):
            self.declarator(type_text, d, static, depth, line_of(node))

    def declarator(self, type_text: str, d: Node, static: bool, depth: int, line: int) -> None:
        value = None
        if d.type == "init_declarator":
            value = d.child_by_field_name("value")
            d = d.child_by_field_name("declarator")
        pointer, size = False, None
        while d.type in ("pointer_declarator", "array_declarator", "reference_declarator"):
            if d.type == "reference_declarator":
                raise Untranslatable("a reference")
            if d.type == "pointer_declarator":
                pointer = True
            else:
                if size is not None:
                    raise Untranslatable("an array of arrays")
                size = d.child_by_field_name("size")
                if size is None:
                    raise Untranslatable("an array without a size")
            d = d.child_by_field_name("declarator") or d.named_children[-1]
        if d.type != "identifier":
            raise Untranslatable(f"the declaration of {self.text(d)}")
        name = self.text(d)
        text, kind = self.typed_value(type_text, pointer, size, value)
        py = python_name(name, self.scope.taken, self.scope.variables, self.static_names)
        self.bind(name, py, kind)
        if static:
            self.statics.append(Static(py, annotation(kind), text, line))
            self.static_names.add(py)
            return
        self.emit(depth, f"{py} = {text if text is not None else 'None'}")

    def typed_value(
        self, type_text: str, pointer: bool, size: Node | None, value: Node | None
    ) -> tuple[str | None, str]:
        """The initial value and kind of a declared variable (a `char` array is a C string)."""
        if size is not None and not pointer and normalise(type_text) == "char":
            if value is None:
                return '""', "str"
            if value.type in ("string_literal", "concatenated_string"):
                return self.ex.value(value).text, "str"
            raise Untranslatable("a char array initialised from a value")
        kind = kind_of(type_text, pointer, self.scope.imports)
        if kind is None:
            raise Untranslatable(f"the type {type_text.strip()}{' *' if pointer else ''}")
        return self.declared_value(kind, pointer, size, value)

    def declared_value(self, kind: str, pointer: bool, size: Node | None, value: Node | None) -> tuple[str | None, str]:
        if size is not None:
            n = self.ex.value(size)
            if value is not None:
                if value.type != "initializer_list":
                    raise Untranslatable("an array initialised from a value")
                items = [self.ex.value(v).text for v in value.named_children]
                return f"[{', '.join(items)}]", f"list:{kind}"
            start = "None" if pointer else (default(kind) or "None")
            return f"[{start}] * {wrap(n, MUL, True)}", f"list:{kind}"
        if value is None or (value.type == "initializer_list" and not value.named_children):
            return (None if pointer else default(kind)), kind
        if value.type in ("argument_list", "initializer_list"):
            args = [a for a in value.named_children if a.type != "comment"]
            if kind in ("int", "float", "bool", "str") and len(args) == 1:
                return self.ex.value(args[0]).text, kind
            raise Untranslatable("a constructor with arguments")
        text = self.initial(value, kind)
        if kind == "any":
            kind = self.ex.value(value).kind or "any"
        return text, kind

    def condition(self, node: Node) -> Expr:
        clause = node.child_by_field_name("condition")
        if clause is None:
            raise Untranslatable("a loop without a condition")
        if clause.type == "condition_clause":
            if clause.child_by_field_name("initializer") is not None:
                raise Untranslatable("a declaration in a condition")
            value = clause.child_by_field_name("value")
        else:
            value = clause
        if value is None or value.type == "declaration":
            raise Untranslatable("a declaration in a condition")
        return self.ex.value(value)

    def if_statement(self, node: Node, depth: int, keyword_: str = "if") -> None:
        if any(c.type == "constexpr" for c in node.children):
            raise Untranslatable("if constexpr")
        cond = self.condition(node)
        self.emit(depth, f"{keyword_} {cond.text}:")
        self.body(node.child_by_field_name("consequence"), depth + 1)
        alt = node.child_by_field_name("alternative")
        if alt is None:
            return
        inner = [c for c in alt.named_children if c.type != "comment"]
        if len(inner) == 1 and inner[0].type == "if_statement":
            self.if_statement(inner[0], depth, "elif")
        else:
            self.emit(depth, "else:")
            self.block(alt.children[1:], depth + 1)

    def loop_body(self, node: Node, depth: int, tail: list[str] | None = None) -> None:
        self.loops += 1
        try:
            self.body(node, depth + 1)
        finally:
            self.loops -= 1
        for line in tail or []:
            self.emit(depth + 1, line)

    def do_statement(self, node: Node, depth: int) -> None:
        body = node.child_by_field_name("body")
        if self.continues(body):
            raise Untranslatable("continue in a do-while loop")
        cond = self.condition(node)
        self.emit(depth, "while True:")
        self.loop_body(body, depth, [f"if not {wrap(cond, 4)}:", INDENT + "break"])

    def continues(self, node: Node) -> bool:
        """Whether `node` holds a `continue` of its own loop (not of a loop inside it)."""
        stack = [node]
        while stack:
            n = stack.pop()
            if n.type == "continue_statement":
                return True
            if n.type not in ("for_statement", "while_statement", "do_statement", "for_range_loop"):
                stack.extend(n.named_children)
        return False

    def for_statement(self, node: Node, depth: int) -> None:
        ranged = self.range_for(node)
        body = node.child_by_field_name("body")
        if ranged is not None:
            self.emit(depth, ranged)
            self.loop_body(body, depth)
            return
        init = node.child_by_field_name("initializer")
        update = node.child_by_field_name("update")
        if update is not None and self.continues(body):
            raise Untranslatable("continue in a for loop that is not a range")
        if init is not None:
            if init.type == "declaration":
                self.declaration(init, depth)
            else:
                self.expression_statement(init, depth)
        cond = (
            self.ex.value(node.child_by_field_name("condition")).text
            if node.child_by_field_name("condition")
            else "True"
        )
        self.emit(depth, f"while {cond}:")
        tail_start = len(self.out)
        if update is not None:
            self.expression_statement(update, depth + 1)
        tail = [ln.strip() for ln in self.out[tail_start:]]
        del self.out[tail_start:]
        self.loop_body(body, depth, tail)

    def range_for(self, node: Node) -> str | None:
        """`for (int i = a; i < b; i++)` whose body leaves `i` alone, as `for i in range(a, b):`."""
        init, cond, update = (node.child_by_field_name(f) for f in ("initializer", "condition", "update"))
        if init is None or cond is None or update is None or init.type != "declaration":
            return None
        decls = init.children_by_field_name("declarator")
        if len(decls) != 1 or decls[0].type != "init_declarator":
            return None
        var_node = decls[0].child_by_field_name("declarator")
        if (
            var_node.type != "identifier"
            or kind_of(self.text(init.child_by_field_name("type")), False, self.scope.imports) != "int"
        ):
            return None
        var = self.text(var_node)
        if cond.type != "binary_expression" or self.text(cond.child_by_field_name("left")) != var:
            return None
        op = self.text(cond.child_by_field_name("operator"))
        step = self.step(var, self.text(update))
        if (
            op not in ("<", "<=", ">", ">=", "!=")
            or step is None
            or self.assigns(node.child_by_field_name("body"), var)
        ):
            return None
        if (op in ("<", "<=") and step < 0) or (op in (">", ">=") and step > 0) or (op == "!=" and abs(step) != 1):
            return None
        start = self.ex.value(decls[0].child_by_field_name("value"))
        stop = self.ex.value(cond.child_by_field_name("right"))
        if stop.kind not in ("int", "any") or start.kind not in ("int", "any"):
            return None
        py = python_name(var, self.scope.variables)
        self.bind(var, py, "int")
        end = stop.text
        if op in ("<=", ">="):
            end = f"{wrap(stop, ADD)} {'+' if step > 0 else '-'} 1"
        args = [start.text, end] + ([str(step)] if step != 1 else [])
        if args[0] == "0" and step == 1:
            args = args[1:]
        return f"for {py} in range({', '.join(args)}):"

    @staticmethod
    def step(var: str, update: str) -> int | None:
        u = re.sub(r"\s+", "", update)
        if u in (f"{var}++", f"++{var}"):
            return 1
        if u in (f"{var}--", f"--{var}"):
            return -1
        m = re.fullmatch(rf"{re.escape(var)}(\+=|-=)([0-9]+)", u)
        if m and int(m[2]) > 0:
            return int(m[2]) if m[1] == "+=" else -int(m[2])
        return None

    def assigns(self, node: Node, var: str) -> bool:
        stack = [node]
        while stack:
            n = stack.pop()
            if n.type in ("assignment_expression", "update_expression"):
                target = n.child_by_field_name("left") or n.child_by_field_name("argument")
                if target is not None and self.text(target) == var:
                    return True
            if n.type == "pointer_expression":
                return True  # &i: anything may change it
            stack.extend(n.named_children)
        return False


def translate_section(source: str, scope: Scope) -> Translation:
    """The Python of one section (`State_S_OnEntry.mm`): a fresh set of locals, statics hoisted."""
    parsed = parse_statements(source)
    scope.locals = {}
    s = Statements(scope)
    code_rows = sorted(code_lines(parsed.whole, 1, len(parsed.lines)))
    if not parsed.ok:  # `}` too many: the section ends the function it is parsed in
        why = "C++ the parser cannot read"
        return Translation(marked("", why, "\n".join(parsed.lines).strip("\n")), len(code_rows),
                           [(r, why if i == 0 else "") for i, r in enumerate(code_rows)])  # fmt: skip
    s.block(parsed.root.children, 0)
    code = len(code_rows)
    while s.out and not s.out[-1].strip():
        s.out.pop()
    return Translation(s.out, code, s.left, s.statics)


def translate_guard(source: str, scope: Scope) -> Translation:
    """The Python expression of a guard (`State_S_Transition_N.expr`), or `False` and the
    marked lines when it cannot be translated (the transition then never fires: the machine
    does not build anyway while a marked line is left)."""
    scope.locals = {}
    if not source.strip():
        why = "the clfsm guard file is empty"
        return Translation([*marked("", why, ""), "False"], 1, [(1, why)])
    parsed = parse_expression(source)
    node = parsed.root
    comments = [f"# {ln}".rstrip() for c in _comments(parsed.whole) for ln in comment_lines(parsed.text(c))]
    code = sorted(code_lines(parsed.whole, 1, len(parsed.lines)))
    try:
        if not parsed.ok or node.has_error:
            raise Untranslatable("not one C++ expression the parser can read")
        if too_deep(node):
            raise Untranslatable(f"nested deeper than {MAX_DEPTH} levels")
        e = Expressions(scope).value(node)
        text = e.text[1:-1] if node.type == "parenthesized_expression" else e.text  # (guard): no parentheses needed
        return Translation([*comments, text], len(code))
    except Untranslatable as e:
        lines = marked("", str(e), source.strip("\n"))
        return Translation([*lines, "False"], len(code), [(ln, str(e) if i == 0 else "") for i, ln in enumerate(code)])


def _comments(node: Node) -> list[Node]:
    out, stack = [], [node]
    while stack:
        n = stack.pop()
        if n.type == "comment":
            out.append(n)
        stack.extend(reversed(n.children))
    return out
