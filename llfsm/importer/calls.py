"""Calls in C++ expressions: functions (C, CLMacros, rclcpp), methods of the types the
translator knows, and output (`cout <<`, a stringstream, printf, RCLCPP_INFO), as a part of
llfsm.importer.expressions.Expressions."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from ..runtime.machine import MACROS
from .cxx import Node
from .kinds import kind_of
from .literals import python_string, string_value
from .terms import ATOM, CMP, MUL, Expr, Scope, Untranslatable, split_template, wrap

#: CLMacros that llfsm has under the same name (docs/machine-format.md); those that take a
#: machine's name follow renamed machines.
_BY_NAME = frozenset({"suspend", "resume", "restart", "is_suspended", "is_running", "state_name_of"})
_MACROS = frozenset(MACROS) - {"suspend_self"}

_MATH = {"sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "exp", "log", "log10", "log2", "pow",
         "fmod", "hypot", "floor", "ceil", "trunc", "sinh", "cosh", "tanh", "cbrt"}  # fmt: skip
_STREAMS = {"cout": None, "std::cout": None, "cerr": "sys.stderr", "std::cerr": "sys.stderr",
            "clog": "sys.stderr", "std::clog": "sys.stderr"}  # fmt: skip
_ENDL = frozenset({"endl", "std::endl"})
_LOG_LEVELS = {"DEBUG": "debug", "INFO": "info", "WARN": "warning", "ERROR": "error", "FATAL": "fatal"}
CONTROL = frozenset({"suspend", "resume", "restart", "suspend_self"})
#: clfsm's controls by load index, and by command name (CLMacros.h)
_AT_INDEX = {"suspend_at": "suspend", "resume_at": "resume", "restart_at": "restart"}
_COMMANDS = {"CLSuspend": "suspend", "CLResume": "resume", "CLRestart": "restart"}
#: open(2)'s flags, as the os module names them
OPEN_FLAGS = frozenset({"O_CREAT", "O_RDONLY", "O_WRONLY", "O_RDWR", "O_TRUNC", "O_APPEND", "O_EXCL"})


class Calls:
    """The calls and the output of Expressions (a part of its class, in a module of its own)."""

    scope: Scope

    if TYPE_CHECKING:  # what Expressions gives its calls

        def text(self, node: Node) -> str: ...
        def expr(self, node: Node) -> Expr: ...
        def value(self, node: Node) -> Expr: ...
        def string(self, node: Node) -> str: ...
        def cast(self, type_text: str, value: Node) -> Expr: ...

    def arguments(self, call: Node) -> list[Node]:
        args = call.child_by_field_name("arguments")
        return [] if args is None else [a for a in args.named_children if a.type != "comment"]

    def args_text(self, nodes: list[Node]) -> list[str]:
        return [self.value(a).text for a in nodes]

    def machine_name(self, node: Node) -> str:
        """A machine's name given to the `suspend("...")` family: a literal naming a machine
        renamed on import is written with its new name."""
        if node.type == "string_literal":
            name = self.string(node)
            return '"' + python_string(self.scope.machines.get(name, name)) + '"'
        return self.value(node).text

    def _call_expression(self, node: Node) -> Expr:
        function = node.child_by_field_name("function")
        args = self.arguments(node)
        if function.type == "field_expression":
            return self.method(function, args)
        if function.type in ("primitive_type", "sized_type_specifier") and len(args) == 1:
            return self.cast(self.text(function), args[0])  # double(x): a functional cast
        if function.type not in ("identifier", "qualified_identifier", "template_function"):
            raise Untranslatable("a call of a computed function")
        name, targs = split_template(self.text(function))
        if name in ("static_cast", "std::static_cast") and len(targs) == 1 and len(args) == 1:
            return self.cast(targs[0], args[0])
        if self.scope.lookup(name) is not None:
            raise Untranslatable(f"a call of the variable {name}")
        return self.function(name, targs, args)

    def function(self, name: str, targs: list[str], args: list[Node]) -> Expr:
        imports = self.scope.imports
        bare = name[5:] if name.startswith("std::") else name
        if name in _BY_NAME:
            return Expr(
                f"{name}({', '.join(self.machine_name(a) for a in args)})",
                ATOM,
                "void" if name in CONTROL else "bool" if name.startswith("is_") else "str",
            )
        if name in _MACROS or name == "suspend_self":
            kind = {"state_name": "str", "machine_name": "str", "machine_id": "int"}.get(name, "bool")
            return Expr(f"{name}({', '.join(self.args_text(args))})", ATOM, "void" if name == "suspend_self" else kind)
        if name in _AT_INDEX or name == "control_machine_at_index":
            return self.at_index(name, args)
        if name == "timeout" and len(args) == 1:  # CLMacros: microseconds since the state was entered
            return Expr(f"after_us({self.value(args[0]).text})", ATOM, "bool")
        if bare == "fflush" and len(args) == 1 and self.text(args[0]) in ("stdout", "stderr"):
            imports.modules.add("sys")
            return Expr(f"sys.{self.text(args[0])}.flush()", ATOM, "void")
        if name == "machine_index" and not args:
            return Expr("machine_id()", ATOM, "int")
        if bare in ("open", "close") and name == bare and 1 <= len(args) <= 3:
            imports.modules.add("os")
            return Expr(f"os.{bare}({', '.join(self.args_text(args))})", ATOM, "int")
        if name == "current_time_in_microseconds" and not args:
            imports.modules.add("time")
            return Expr("time.time_ns() // 1000", MUL, "int")
        if bare in _MATH:
            imports.modules.add("math")
            return Expr(f"math.{bare}({', '.join(self.args_text(args))})", ATOM, "float")
        if bare in ("fabs", "abs", "labs"):
            return Expr(f"abs({', '.join(self.args_text(args))})", ATOM, "any")
        if bare in ("fmin", "fmax", "min", "max"):
            return Expr(f"{bare[-3:]}({', '.join(self.args_text(args))})", ATOM, "any")
        if bare in ("atoi", "atol", "stoi", "stol") and len(args) == 1:
            return Expr(f"int({self.value(args[0]).text})", ATOM, "int")
        if bare in ("atof", "stod", "stof") and len(args) == 1:
            return Expr(f"float({self.value(args[0]).text})", ATOM, "float")
        if bare == "strlen" and len(args) == 1:
            return Expr(f"len({self.value(args[0]).text})", ATOM, "int")
        if bare == "to_string" and len(args) == 1:
            arg = self.value(args[0])
            if arg.kind == "float":
                return Expr(f'"%f" % {wrap(arg, MUL, True)}', MUL, "str")
            return Expr(f"str({arg.text})", ATOM, "str")
        if bare == "string" and len(args) <= 1:
            if not args:
                return Expr('""', ATOM, "str")
            arg = self.value(args[0])
            return arg if arg.kind == "str" else Expr(f"str({arg.text})", ATOM, "str")
        if name.startswith("rclcpp::") or name == "std::make_shared":
            return self.ros_function(name, targs, args)
        message = kind_of(name, False, imports) if "::msg::" in name or "::srv::" in name else None
        if message is not None and message.startswith("msg:") and not args:
            return Expr(f"{message[4:]}()", ATOM, message)
        if name.startswith("RCLCPP_"):
            return self.log(name, args)
        if bare == "printf":
            return self.printf(args, end='""')
        if bare == "puts" and len(args) == 1:
            return Expr(f"print({self.value(args[0]).text})", ATOM, "void")
        if bare in ("sleep", "usleep", "nanosleep"):
            raise Untranslatable(f"{bare} holds up every machine: wait in a guard instead, with after_ms")
        if bare in ("exit", "abort", "_exit"):
            raise Untranslatable(
                "exit ends clfsm's whole process; an llfsm machine ends by reaching an accepting state"
            )
        raise Untranslatable(f"{name} is not a function llfsm knows")

    def at_index(self, name: str, args: list[Node]) -> Expr:
        """`resume_at(machine_index())`: a command for this machine itself, which llfsm names;
        any other index is a load order llfsm does not address machines by."""
        command = _AT_INDEX.get(name)
        index = args[0] if args else None
        if name == "control_machine_at_index" and len(args) == 2:
            command = _COMMANDS.get(self.text(args[1]).replace("FSM::", ""))
        elif len(args) != 1:
            command = None
        if command is None or index is None or re.sub(r"\s+", "", self.text(index)) != "machine_index()":
            raise Untranslatable(f"{name}: llfsm addresses machines by name, not by load index")
        return Expr(f"{command}(machine_name())", ATOM, "void")

    def ros_function(self, name: str, targs: list[str], args: list[Node]) -> Expr:
        imports = self.scope.imports
        if name.startswith("rclcpp::") or targs == ["rclcpp::Node"]:
            imports.ros = True
        if name == "rclcpp::init":
            return Expr("ros.init()", ATOM, "void")
        if name in ("rclcpp::ok", "rclcpp::shutdown") and not args:
            return Expr(f"ros.{name[8:]}()", ATOM, "bool")
        if name == "rclcpp::spin_until_future_complete" and len(args) == 2:
            return Expr(
                f"ros.spin_until_future_complete({', '.join(self.args_text(args))})", ATOM, "ros:FutureReturnCode"
            )
        node_made = name == "rclcpp::Node::make_shared" or (name == "std::make_shared" and targs == ["rclcpp::Node"])
        if node_made and 1 <= len(args) <= 2:
            parts = self.args_text(args)
            call = f"ros.Node({parts[0]})" if len(parts) == 1 else f"ros.Node({parts[0]}, namespace={parts[1]})"
            return Expr(call, ATOM, "ros:Node")
        if name == "std::make_shared" and len(targs) == 1 and not args:
            kind = kind_of(targs[0], False, imports)
            if kind is not None and kind.startswith("msg:"):
                return Expr(f"{kind[4:]}()", ATOM, kind)
        raise Untranslatable(f"{name} is not a function llfsm knows")

    def method(self, function: Node, args: list[Node]) -> Expr:
        base = self.value(function.child_by_field_name("argument"))
        name, targs = split_template(self.text(function.child_by_field_name("field")))
        kind = base.kind or ""
        b = wrap(base, ATOM)
        if kind == "ros:Node":
            if name in ("create_publisher", "create_client") and len(targs) == 1:
                type_kind = kind_of(targs[0], False, self.scope.imports)
                want = "msg:" if name == "create_publisher" else "srv:"
                if type_kind is None or not type_kind.startswith(want):
                    raise Untranslatable(f"{name} of the type {targs[0]}")
                handle = "ros:Publisher" if name == "create_publisher" else "ros:Client"
                return Expr(f"{b}.{name}({', '.join([type_kind[4:], *self.args_text(args)])})", ATOM, handle)
            if name == "get_logger" and not args:
                return Expr(f"{b}.get_logger()", ATOM, "ros:Logger")
            if name == "get_name" and not args:
                return Expr(f"{b}.get_name()", ATOM, "str")
        if kind == "ros:Publisher" and name == "publish" and len(args) == 1:
            return Expr(f"{b}.publish({self.value(args[0]).text})", ATOM, "void")
        if kind == "ros:Client" and name == "async_send_request" and len(args) == 1:
            return Expr(f"{b}.call_async({self.value(args[0]).text})", ATOM, "ros:Future")
        if kind == "ros:Client" and name == "service_is_ready" and not args:
            return Expr(f"{b}.service_is_ready()", ATOM, "bool")
        if kind == "ros:Future" and name == "get" and not args:
            return Expr(f"{b}.result()", ATOM, "any")
        if kind in ("str", "any") and not args:
            if name == "c_str":
                return Expr(base.text, base.prec, "str")
            if name in ("length", "size"):
                return Expr(f"len({base.text})", ATOM, "int")
            if name == "empty":
                return Expr(f"len({base.text}) == 0", CMP, "bool")
        if kind == "stream" and name == "str" and not args:
            return Expr(base.text, base.prec, "str")
        raise Untranslatable(f"the method {name} of a {kind or 'value'}")

    # -- output --------------------------------------------------------------------------------

    def stream_target(self, node: Node) -> str | None:
        """The leftmost operand of a `<<` chain when it is an output stream (`cout`, a
        stringstream variable), else None."""
        while node.type == "binary_expression" and self.text(node.child_by_field_name("operator")) == "<<":
            node = node.child_by_field_name("left")
        text = re.sub(r"\s+", "", self.text(node))
        if text in _STREAMS:
            return text
        found = self.scope.lookup(text) if node.type == "identifier" else None
        if found is not None and found[1] == "stream":
            return text
        return None

    def stream_items(self, node: Node) -> list[Node]:
        items: list[Node] = []
        while node.type == "binary_expression" and self.text(node.child_by_field_name("operator")) == "<<":
            items.append(node.child_by_field_name("right"))
            node = node.child_by_field_name("left")
        return items[::-1]

    def formatted(self, items: list[Node]) -> tuple[str, bool]:
        """An f-string of what `<<` writes (C++'s formatting: a bool as 1 or 0, a double as
        %g), and whether it ended with `endl` or a newline (taken off)."""
        parts: list[str] = []
        newline = False
        for i, item in enumerate(items):
            last = i == len(items) - 1
            if re.sub(r"\s+", "", self.text(item)) in _ENDL:
                if not last:
                    parts.append("\\n")
                newline = newline or last
                continue
            if item.type in ("string_literal", "concatenated_string", "char_literal"):
                value = (
                    self.string(item)
                    if item.type != "char_literal"
                    else string_value('"' + self.text(item)[1:-1] + '"')
                )
                parts.append(python_string(value, '"', fstring=True))
                continue
            e = self.value(item)
            if "\\" in e.text or ('"' in e.text and "'" in e.text):
                raise Untranslatable("an expression too involved for an f-string")
            inner = e.text.replace('"', "'")
            spec = {"bool": ":d", "float": ":g"}.get(e.kind or "", "")
            parts.append("{" + (f"({inner})" if inner.startswith("{") else inner) + spec + "}")
        text = "".join(parts)
        if text.endswith("\\n") and not newline:
            text, newline = text[:-2], True
        return ('f"' + text + '"') if "{" in text.replace("{{", "") else (
            '"' + text.replace("{{", "{").replace("}}", "}") + '"'
        ), newline

    def output(self, node: Node) -> list[str] | None:
        """A whole `<<` statement: `print(...)` for cout/cerr, `ss += ...` for a stringstream."""
        target = self.stream_target(node)
        if target is None:
            return None
        text, newline = self.formatted(self.stream_items(node))
        if target in _STREAMS:
            args = [text] if text != '""' or newline else []
            if not newline:
                args.append('end=""')
            if _STREAMS[target]:
                self.scope.imports.modules.add("sys")
                args.append(f"file={_STREAMS[target]}")
            return [f"print({', '.join(args)})"]
        name = self.scope.lookup(target)
        assert name is not None
        return [f'{name[0]} += {text[:-1]}\\n"' if newline else f"{name[0]} += {text}"]

    def printf(self, args: list[Node], end: str) -> Expr:
        if not args:
            raise Untranslatable("printf without a format")
        fmt = self.value(args[0]).text
        rest = self.args_text(args[1:])
        text = f"{fmt} % ({', '.join(rest)}{',' if len(rest) == 1 else ''})" if rest or "%" in fmt else fmt
        return Expr(f"print({text}, end={end})", ATOM, "void")

    def log(self, name: str, args: list[Node]) -> Expr:
        m = re.fullmatch(r"RCLCPP_(DEBUG|INFO|WARN|ERROR|FATAL)(_STREAM)?", name)
        if not m or len(args) < 2:
            raise Untranslatable(f"{name} is not a function llfsm knows")
        logger = self.value(args[0])
        if logger.kind != "ros:Logger":
            raise Untranslatable(f"{name} of something not a logger")
        level = _LOG_LEVELS[m[1]]
        if m[2]:
            if len(args) != 2:
                raise Untranslatable(f"{name} of several arguments")
            text, _ = self.formatted(self.stream_items(args[1]) if args[1].type == "binary_expression" else [args[1]])
            return Expr(f"{wrap(logger, ATOM)}.{level}({text})", ATOM, "void")
        fmt = self.value(args[1]).text
        rest = self.args_text(args[2:])
        text = f"{fmt} % ({', '.join(rest)}{',' if len(rest) == 1 else ''})" if rest or "%" in fmt else fmt
        return Expr(f"{wrap(logger, ATOM)}.{level}({text})", ATOM, "void")
