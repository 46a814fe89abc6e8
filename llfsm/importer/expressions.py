"""C++ expressions to Python expressions, on tree-sitter's tree (llfsm.importer.cxx).

Each expression comes back with its Python precedence (so parentheses are written where
Python needs them and nowhere else) and its kind (llfsm.importer.kinds), which decides what
an operator or a method means.  What has no clear Python meaning raises `Untranslatable`
with the reason, and the statement that holds it is left for a person.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from .calls import CONTROL, OPEN_FLAGS, Calls
from .cxx import Node
from .literals import LiteralError, number, python_string, string_value
from .terms import (
    ADD,
    AND,
    ATOM,
    BAND,
    BOR,
    CMP,
    MUL,
    NOT,
    OR,
    SHIFT,
    TERNARY,
    UNARY,
    XOR,
    Expr,
    Scope,
    Untranslatable,
    split_template,
    wrap,
)

_BINARY = {"||": ("or", OR), "&&": ("and", AND), "|": ("|", BOR), "^": ("^", XOR), "&": ("&", BAND),
           "==": ("==", CMP), "!=": ("!=", CMP), "<": ("<", CMP), ">": (">", CMP), "<=": ("<=", CMP),
           ">=": (">=", CMP), "<<": ("<<", SHIFT), ">>": (">>", SHIFT), "+": ("+", ADD), "-": ("-", ADD),
           "*": ("*", MUL), "/": ("/", MUL), "%": ("%", MUL)}  # fmt: skip

_CASTS = {"int": "int", "long": "int", "short": "int", "unsigned": "int", "size_t": "int", "double": "float",
          "float": "float", "bool": "bool", "longlong": "int", "unsignedint": "int", "unsignedlong": "int",
          "longdouble": "float", "int64_t": "int", "int32_t": "int", "uint32_t": "int", "uint64_t": "int",
          "int16_t": "int", "uint16_t": "int", "int8_t": "int", "uint8_t": "int"}  # fmt: skip


class Expressions(Calls):
    """Translates the expressions of one section, guard or initialiser."""

    def __init__(self, scope: Scope) -> None:
        self.scope = scope

    def text(self, node: Node) -> str:
        return str(node.text.decode("utf-8", "replace"))

    def expr(self, node: Node) -> Expr:
        if node.has_error:
            raise Untranslatable("C++ the parser cannot read")
        handler: Callable[[Node], Expr] | None = getattr(self, "_" + node.type, None)
        if handler is None:
            raise Untranslatable(f"{node.type.replace('_', ' ')}")
        return handler(node)

    def value(self, node: Node) -> Expr:
        """An expression used as a value: a statement-only form (a print) is refused."""
        e = self.expr(node)
        if e.kind == "void":
            raise Untranslatable("a value that has none")
        return e

    # -- atoms ---------------------------------------------------------------------------------

    def _parenthesized_expression(self, node: Node) -> Expr:
        inner = self.expr(node.named_children[0])
        return Expr(f"({inner.text})", ATOM, inner.kind)

    def _number_literal(self, node: Node) -> Expr:
        try:
            text, kind = number(self.text(node))
        except LiteralError as e:
            raise Untranslatable(str(e)) from None
        return Expr(text, UNARY if text[0] in "+-" else ATOM, kind)

    def _true(self, node: Node) -> Expr:
        return Expr("True", ATOM, "bool")

    def _false(self, node: Node) -> Expr:
        return Expr("False", ATOM, "bool")

    def _null(self, node: Node) -> Expr:
        return Expr("None", ATOM, "any")

    def _string_literal(self, node: Node) -> Expr:
        return Expr('"' + python_string(self.string(node)) + '"', ATOM, "str")

    def _concatenated_string(self, node: Node) -> Expr:
        return Expr('"' + python_string(self.string(node)) + '"', ATOM, "str")

    def _char_literal(self, node: Node) -> Expr:
        try:
            value = string_value('"' + self.text(node)[1:-1] + '"')
        except LiteralError as e:
            raise Untranslatable(str(e)) from None
        return Expr('"' + python_string(value) + '"', ATOM, "str")

    def string(self, node: Node) -> str:
        """The value of a string literal (adjacent literals joined)."""
        parts = node.named_children if node.type == "concatenated_string" else [node]
        try:
            return "".join(string_value(self.text(p)) for p in parts if p.type == "string_literal")
        except LiteralError as e:
            raise Untranslatable(str(e)) from None

    def _identifier(self, node: Node) -> Expr:
        name = self.text(node)
        found = self.scope.lookup(name)
        if found is not None:
            py, kind = found
            if kind is None:
                raise Untranslatable(f"{name} is of a type left untranslated")
            return Expr(py, ATOM, kind)
        if name == "M_PI":
            self.scope.imports.modules.add("math")
            return Expr("math.pi", ATOM, "float")
        if name in ("NULL", "nullptr"):
            return Expr("None", ATOM, "any")
        if name in OPEN_FLAGS:
            self.scope.imports.modules.add("os")
            return Expr(f"os.{name}", ATOM, "int")
        if name in ("TRUE", "YES"):
            return Expr("True", ATOM, "bool")
        if name in ("FALSE", "NO"):
            return Expr("False", ATOM, "bool")
        raise Untranslatable(f"{name} is not a name llfsm knows")

    def _qualified_identifier(self, node: Node) -> Expr:
        name, _ = split_template(self.text(node))
        m = re.fullmatch(r"rclcpp::FutureReturnCode::(SUCCESS|INTERRUPTED|TIMEOUT)", name)
        if m:
            self.scope.imports.ros = True
            return Expr(f"ros.FutureReturnCode.{m[1]}", ATOM, "ros:FutureReturnCode")
        if name == "std::string::npos":
            raise Untranslatable("std::string::npos")
        raise Untranslatable(f"{name} is not a name llfsm knows")

    # -- operators -----------------------------------------------------------------------------

    def _binary_expression(self, node: Node) -> Expr:
        op = self.text(node.child_by_field_name("operator"))
        left_node, right_node = node.child_by_field_name("left"), node.child_by_field_name("right")
        if op == "<<":
            stream = self.stream_target(node)
            if stream is not None:
                raise Untranslatable("an output stream used as a value")
        special = self.control_comparison(op, left_node, right_node)
        if special is not None:
            return special
        if op not in _BINARY:
            raise Untranslatable(f"the operator {op}")
        left, right = self.value(left_node), self.value(right_node)
        py, prec = _BINARY[op]
        kind = self.result_kind(op, left.kind, right.kind)
        if op == "/" and left.kind == "int" and right.kind == "int":
            # C divides integers towards zero; Python's // rounds down
            return Expr(f"int({left.text} / {right.text})", ATOM, "int")
        if op in ("/", "%") and (left.kind, right.kind) == ("any", "any"):
            raise Untranslatable(f"{op} of two values whose types are unknown")
        if op == "%" and "float" in (left.kind, right.kind):
            self.scope.imports.modules.add("math")
            return Expr(f"math.fmod({left.text}, {right.text})", ATOM, "float")
        if op == "+" and "str" in (left.kind, right.kind) and {left.kind, right.kind} - {"str", "any"}:
            raise Untranslatable("+ of a string and a number")
        return Expr(f"{wrap(left, prec)} {py} {wrap(right, prec, strict=True)}", prec, kind)

    @staticmethod
    def result_kind(op: str, a: str | None, b: str | None) -> str | None:
        if op in ("||", "&&", "==", "!=", "<", ">", "<=", ">="):
            return "bool"
        if "str" in (a, b):
            return "str"
        if "float" in (a, b):
            return "float"
        if a == b and a in ("int", "bool"):
            return "int"
        return "any"

    def control_comparison(self, op: str, left: Node, right: Node) -> Expr | None:
        """`suspend_self() != CLError` (the command was taken: always, in llfsm, whose
        control macros return None) and `status(m) == CLSuspend` (is_suspended)."""
        if op not in ("==", "!="):
            return None
        rtext = self.text(right).replace("FSM::", "")
        if left.type != "call_expression" or rtext not in ("CLError", "CLSuspend"):
            return None
        fname = self.text(left.child_by_field_name("function"))
        if rtext == "CLError" and fname in CONTROL:
            call = self.expr(left)
            # llfsm's control macros return None: the command is always taken
            return Expr(f"{call.text} {'is' if op == '!=' else 'is not'} None", CMP, "bool")
        if rtext == "CLSuspend" and fname == "status":
            args = self.arguments(left)
            if len(args) != 1:
                return None
            machine = self.machine_name(args[0])
            return Expr(f"{'' if op == '==' else 'not '}is_suspended({machine})", ATOM if op == "==" else NOT, "bool")
        return None

    def _unary_expression(self, node: Node) -> Expr:
        op = self.text(node.child_by_field_name("operator"))
        arg = self.value(node.child_by_field_name("argument"))
        if op == "!":
            return Expr(f"not {wrap(arg, NOT)}", NOT, "bool")
        if op in ("-", "+", "~"):
            return Expr(f"{op}{wrap(arg, UNARY)}", UNARY, arg.kind)
        raise Untranslatable(f"the operator {op}")

    def _pointer_expression(self, node: Node) -> Expr:
        raise Untranslatable("a pointer or address")

    def _conditional_expression(self, node: Node) -> Expr:
        cond = self.value(node.child_by_field_name("condition"))
        yes = self.value(node.child_by_field_name("consequence"))
        no = self.value(node.child_by_field_name("alternative"))
        kind = yes.kind if yes.kind == no.kind else "any"
        return Expr(
            f"{wrap(yes, TERNARY, True)} if {wrap(cond, TERNARY, True)} else {wrap(no, TERNARY)}", TERNARY, kind
        )

    def _cast_expression(self, node: Node) -> Expr:
        return self.cast(self.text(node.child_by_field_name("type")), node.child_by_field_name("value"))

    def cast(self, type_text: str, value: Node) -> Expr:
        t = re.sub(r"\s+|\bconst\b", "", type_text)
        if t not in _CASTS:
            raise Untranslatable(f"a cast to {type_text}")
        inner = self.value(value)
        target = _CASTS[t]
        if inner.kind == target:
            return inner
        return Expr(f"{target}({inner.text})", ATOM, target)

    def _field_expression(self, node: Node) -> Expr:
        base = self.value(node.child_by_field_name("argument"))
        name = self.text(node.child_by_field_name("field"))
        if (base.kind is not None and base.kind.startswith("msg:")) or base.kind == "any":
            return Expr(f"{wrap(base, ATOM)}.{name}", ATOM, "any")
        raise Untranslatable(f"the member {name} of a {base.kind or 'value'}")

    def _subscript_expression(self, node: Node) -> Expr:
        base = self.value(node.child_by_field_name("argument"))
        index_node = node.child_by_field_name("indices") or node.child_by_field_name("index")
        if index_node is None or (not (base.kind or "").startswith("list:") and base.kind != "any"):
            raise Untranslatable("an index into something not a list")
        items = (
            [c for c in index_node.named_children if c.type != "comment"]
            if index_node.type.endswith("list")
            else [index_node]
        )
        if len(items) != 1:
            raise Untranslatable("an index of several values")
        index = self.value(items[0])
        elem = base.kind[5:] if base.kind and base.kind.startswith("list:") else "any"
        return Expr(f"{wrap(base, ATOM)}[{index.text}]", ATOM, elem or "any")

    # -- calls ---------------------------------------------------------------------------------
