"""C++ (clfsm) habits and their Python spelling, for the hints of `llfsm check` (docs/rules.md).

Machines ported from clfsm keep C++ lines, and a hint is only as good as the line it leads to:
`int count = 0;` in Variables.py must be answered with `count: int = 0` (what Variables.py
takes), not with a plain assignment that LF032 then refuses; `printf` with `print`, not with a
variable to declare.  So the hints are worked out from the line itself, with its string
literals blanked first (a `++` inside `"count++"` is text, not an operator), and the file it is
in (a variables file, or code).  Text only: nothing here parses beyond regular expressions.
"""

from __future__ import annotations

import re

#: Names from C, C++ and clfsm habits, and their Python spelling (a read of an undefined name).
CPP_NAMES = {
    "true": "True",
    "false": "False",
    "TRUE": "True",
    "FALSE": "False",
    "null": "None",
    "NULL": "None",
    "nullptr": "None",
    "this": "a machine variable's bare name (no `this->`)",
}

#: C and C++ functions (a call of an undefined name) and what Python calls instead.
C_FUNCTIONS = {
    "printf": '`print(...)` (with an f-string: `print(f"count {count}")`)',
    "puts": "`print(...)`",
    "fprintf": "`print(..., file=sys.stderr)` (import sys in Includes.py)",
    "sprintf": 'an f-string: `text = f"count {count}"`',
    "snprintf": 'an f-string: `text = f"count {count}"`',
    "strlen": "`len(...)`",
    "strcmp": "`a == b` (Python compares strings with ==)",
    "fabs": "`abs(...)`",
    "fmin": "`min(...)`",
    "fmax": "`max(...)`",
    "sqrt": "`math.sqrt(...)` (with `import math` in Includes.py)",
    "atan2": "`math.atan2(...)` (with `import math` in Includes.py)",
    "sin": "`math.sin(...)` (with `import math` in Includes.py)",
    "cos": "`math.cos(...)` (with `import math` in Includes.py)",
    "tan": "`math.tan(...)` (with `import math` in Includes.py)",
    "floor": "`math.floor(...)` (with `import math` in Includes.py)",
    "ceil": "`math.ceil(...)` (with `import math` in Includes.py)",
    "fmod": "`math.fmod(...)` or `%`",
    "rand": "`random.random()` or `random.randint(a, b)` (with `import random` in Includes.py)",
    "atoi": "`int(...)`",
    "atof": "`float(...)`",
    "stoi": "`int(...)`",
    "stod": "`float(...)`",
    "to_string": "`str(...)`",
    "sleep": "a guard such as `after(1)` (a section that sleeps holds up every machine)",
    "usleep": "a guard such as `after_us(500)` (a section that sleeps holds up every machine)",
    "RCLCPP_INFO": "`node.get_logger().info(...)`",
    "RCLCPP_WARN": "`node.get_logger().warning(...)`",
    "RCLCPP_ERROR": "`node.get_logger().error(...)`",
}

#: C++ type names and the Python annotation a variables file takes for them (also what
#: `llfsm import` declares them as: llfsm.importer.kinds).
C_TYPES = {
    "int": "int",
    "long": "int",
    "short": "int",
    "unsigned": "int",
    "signed": "int",
    "size_t": "int",
    "float": "float",
    "double": "float",
    "bool": "bool",
    "char": "str",
    "string": "str",
    "std::string": "str",
    "auto": "",
}
_DEFAULTS = {"int": "0", "float": "0.0", "bool": "False", "str": '""', "": "None"}
_TYPE_RE = r"(?:int|float|double|bool|char|long|short|auto|string|std::string|size_t|u?int(?:8|16|32|64)_t)"
_DECLARATION = re.compile(
    r"^\s*(?:(?:const|static|constexpr|unsigned|signed|long|volatile)\s+)*(?P<type>" + _TYPE_RE + r")\s*[*&]?\s+"
    r"(?P<v>[A-Za-z_]\w*)\s*(?:(?P<array>\[)|=\s*(?P<value>[^;]*?)\s*;?\s*$|;\s*$|$)"
)
_UNSIGNED_ALONE = re.compile(r"^\s*(?:const\s+|static\s+)*unsigned\s+(?P<v>[A-Za-z_]\w*)\s*(?:=|;|$)")
#: A string literal (with its escapes), blanked before the operators of a line are looked at.
_STRING = re.compile(r"""(?P<q>["'])(?:\\.|(?!(?P=q)).)*(?P=q)""")
#: `//` that starts a C++ comment: after `;` or at the line's start, or followed by words (a
#: sentence), or by nothing; `a // 2` stays Python's floor division.
_LINE_COMMENT = re.compile(r"(?:^|;)\s*//|//\s*(?:$|[A-Za-z_]\w*\s+[A-Za-z_(]|[-=*/]{2}|[^\w\s(\[{.+\-~'\"])")

#: Other C++ habits, tried in order on the line of a syntax error (strings and `//` comment removed).
_HINTS: list[tuple[re.Pattern[str], str]] = [
    (re.compile(r"/\*|\*/"), "comments start with `#` in Python (no /* */)"),
    (re.compile(r"\b(?P<v>[A-Za-z_]\w*)\s*\+\+|\+\+\s*(?P<w>[A-Za-z_]\w*)"), "Python has no `++`: write `{v} += 1`"),
    (
        re.compile(r"\b(?P<v>[A-Za-z_]\w*)\s*--(?!-)|(?<!-)--\s*(?P<w>[A-Za-z_]\w*)"),
        "Python has no `--`: write `{v} -= 1`",
    ),
    (re.compile(r"&&"), "Python writes `and` for `&&`"),
    (re.compile(r"\|\|"), "Python writes `or` for `||`"),
    (re.compile(r"\belse\s+if\b"), "Python writes `elif` for `else if`"),
    (re.compile(r"^\s*(?:if|while|for)\b.*\{\s*$|^\s*\}"), "Python blocks are a colon and indentation, not `{{ }}`"),
    (re.compile(r"->"), "Python reaches attributes with `.`, not `->`"),
    (re.compile(r"(?<![=!<>])!(?!=)\s*[A-Za-z_(]"), "Python writes `not x` for `!x`"),
]


def is_variables_file(name: str) -> bool:
    """Variables.py or State_S_Variables.py: the files of `name: type = value` lines."""
    return name == "Variables.py" or (name.startswith("State_") and name.endswith("_Variables.py"))


def blank_strings(line: str) -> str:
    """`line` with the inside of its string literals and its `#` comment replaced by spaces,
    so that what a string says is never taken for an operator."""
    out = _STRING.sub(lambda m: m["q"] + " " * (len(m[0]) - 2) + m["q"], line)
    hash_at = out.find("#")
    return out if hash_at < 0 else out[:hash_at]


def syntax_hint(line: str, file: str = "") -> str | None:
    """The Python spelling of the C++ habits on the line of a syntax error in `file`, if any:
    a `//` comment first (it hides nothing else: `count++; // one more` has two), then a
    declaration, else the first other habit found."""
    if len(line) > 10_000:
        return None
    code = blank_strings(line)
    hints = []
    comment = _LINE_COMMENT.search(code)
    if comment is not None:
        hints.append("comments start with `#` in Python, not `//`")
        code = code[: comment.start()]
        line = line[: comment.start()]
    declared = _declaration(line, code, file)
    if declared is not None:
        hints.append(declared)
    else:
        for rx, hint in _HINTS:
            m = rx.search(code)
            if m:
                groups = m.groupdict()
                hints.append(hint.format(v=groups.get("v") or groups.get("w") or "x"))
                break
    return "; ".join(hints) or None


def _declaration(line: str, code: str, file: str) -> str | None:
    """The hint for a C++ declaration (`int count = 0;`): in a variables file the annotated line
    it takes, elsewhere a plain assignment (and where a machine variable is declared)."""
    m = _DECLARATION.match(code)
    if m is not None:
        ctype = m["type"]
        annotation = "int" if re.fullmatch(r"u?int(?:8|16|32|64)_t", ctype) else C_TYPES[ctype]
        value = _python_value(line[m.start("value") : m.end("value")]) if m["value"] is not None else None
    else:
        m = _UNSIGNED_ALONE.match(code)
        if m is None:
            return None
        annotation, value = "int", None
    name = m["v"]
    if m.groupdict().get("array"):
        annotation, value = "list", "[]"
    if not annotation:  # auto: the annotation the value's literal has
        annotation = _literal_type(value) if value is not None else "object"
    shown = value if value is not None else _DEFAULTS.get(annotation, "None")
    declared = f"{name}: {annotation} = {shown}"
    if is_variables_file(file):
        return f"Python declares a variable as `{declared}` (no C++ type before the name, no `;`)"
    assign = f"{name} = {value}" if value is not None else f"{name} = ..."
    return (
        f"Python declares no types in code: write `{assign}`; a machine variable is declared in "
        f"Variables.py as `{declared}`"
    )


_C_LITERALS = {"true": "True", "false": "False", "NULL": "None", "nullptr": "None"}


def _python_value(text: str) -> str:
    """A C++ initialiser as Python writes it: `false` -> False, `0.5f` -> 0.5, `'c'` -> "c"."""
    text = text.strip()
    if text in _C_LITERALS:
        return _C_LITERALS[text]
    number = re.fullmatch(r"([+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?)[fFlLuU]*", text)
    if number:
        return number[1]
    char = re.fullmatch(r"'(\\?.)'", text)
    if char:
        return f'"{char[1]}"'
    return text


def _literal_type(value: str) -> str:
    if value in ("True", "False"):
        return "bool"
    if re.fullmatch(r"[+-]?\d+", value):
        return "int"
    if re.fullmatch(r"[+-]?(?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?", value):
        return "float"
    if value[:1] in "\"'":
        return "str"
    return "object"
