"""The C++ parser the translator stands on: tree-sitter with its C++ grammar.

clfsm machines are C++ (often Objective-C++ files, `.mm`, holding plain C++), written with
`cout <<`, `std::string`, templates (`create_publisher<T>`) and `rclcpp::` names.  pycparser
reads C only, and a hand-written parser would be one more C++ grammar to keep; tree-sitter's
grammar is maintained, ships as wheels, recovers from errors (an Objective-C message or a
macro it does not know becomes an ERROR node in one statement, not a failed file) and parses
in linear time.  It is an optional dependency (`pip install 'llfsm[import]'`): only `llfsm
import` needs it, never `check`, `build` or `run`.

A section (`State_S_OnEntry.mm`) is a sequence of statements, which C++ allows only inside a
function, so it is parsed as the body of one (`_WRAP`); a guard as the operand of `return`.
Positions are given back in the section's own lines.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

#: What a section is wrapped in: the prefix ends its own line, so row r of the tree is line r
#: of the section (1-based).
_WRAP = ("void _llfsm_section() { ;\n", "\n}\n")  # `;` first: `{ {} }` must not read as an initialiser
_GUARD = ("bool _llfsm_guard() { return (\n", "\n); }\n")


class ParserMissing(RuntimeError):
    """tree-sitter (or its C++ grammar) is not installed."""


Node = Any  # tree_sitter.Node: the package is optional, so its types are not imported here


@dataclass(frozen=True)
class Parsed:
    """A parsed section or guard: the statements (or the expression) and the source lines."""

    root: Node
    lines: list[str]  # the source's lines, without line ends
    ok: bool = True  # False: the wrapper itself did not parse (the source broke out of it)
    whole: Node = None  # the whole tree (the root is the part translated)

    def text(self, node: Node) -> str:
        return str(node.text.decode("utf-8", "replace"))


_PARSER: Any = None


def parser() -> Any:
    """The one tree-sitter parser of this process (made on first use)."""
    global _PARSER
    if _PARSER is None:
        try:
            # deferred: optional dependency (the `import` extra); check, build and run never need it
            import tree_sitter
            import tree_sitter_cpp
        except ImportError as e:
            raise ParserMissing(
                "llfsm import needs tree-sitter and its C++ grammar: pip install 'llfsm[import]'"
            ) from e
        _PARSER = tree_sitter.Parser(tree_sitter.Language(tree_sitter_cpp.language()))
    return _PARSER


def _wrapped(source: str, prefix: str, suffix: str, kind: str) -> Parsed:
    """`source` parsed between `prefix` and `suffix` (one line each), and the body of the
    `kind` node they make.  Not ok unless that body ends at the suffix: a `}` too many in the
    source would close it early, and what followed would not be the source's any more."""
    tree = parser().parse((prefix + source + suffix).encode("utf-8"))
    lines = source.split("\n")
    body = None
    for child in tree.root_node.children:
        if child.type == kind:
            body = child.child_by_field_name("body")
    ok = body is not None and int(body.end_point[0]) == len(lines) + 1
    return Parsed(body if ok else tree.root_node, lines, ok, tree.root_node)


def parse_statements(source: str) -> Parsed:
    """`source` as the statements of a function body: the tree's compound statement."""
    return _wrapped(source, *_WRAP, "function_definition")


def parse_expression(source: str) -> Parsed:
    """`source` as one expression: the node inside `return (...)`.  Not ok when the source
    is not exactly one expression (it closed the parenthesis, or holds a statement)."""
    tree = parser().parse((_GUARD[0] + source + _GUARD[1]).encode("utf-8"))
    lines = source.split("\n")
    node, ok = None, False
    for child in tree.root_node.children:
        if child.type == "function_definition":
            body = child.child_by_field_name("body")
            stmts = [c for c in body.named_children if c.type != "comment"] if body is not None else []
            if len(stmts) == 1 and stmts[0].type == "return_statement" and stmts[0].named_children:
                paren = stmts[0].named_children[0]
                spans = paren.start_point[0] == 0 and int(paren.end_point[0]) == len(lines) + 1
                if paren.type == "parenthesized_expression" and spans and paren.named_child_count >= 1:
                    inner = [c for c in paren.named_children if c.type != "comment"]
                    node, ok = (inner[0], True) if len(inner) == 1 else (None, False)
    return Parsed(node if ok else tree.root_node, lines, ok, tree.root_node)


def parse_members(source: str) -> Parsed:
    """A variables header (`int count; ///< ...`) as the members of a class."""
    return _wrapped(source, "struct _llfsm_variables {\n", "\n};\n", "struct_specifier")


def parse_unit(source: str) -> Parsed:
    """An includes header as a translation unit (preprocessor lines, `using`, declarations)."""
    tree = parser().parse(("\n" + source).encode("utf-8"))
    return Parsed(tree.root_node, source.split("\n"), True, tree.root_node)


def line_of(node: Node) -> int:
    """The 1-based line of the source where `node` starts (the wrappers add one line)."""
    return int(node.start_point[0])


def end_line_of(node: Node) -> int:
    return int(node.end_point[0])


#: Deeper trees than this are refused (the translator walks expressions recursively): no
#: hand-written guard or statement nests a tenth as deep.
MAX_DEPTH = 150


def too_deep(node: Node, limit: int = MAX_DEPTH) -> bool:
    """Whether the tree under `node` is deeper than `limit` (an explicit stack: no recursion)."""
    stack = [(node, 0)]
    while stack:
        n, depth = stack.pop()
        if depth > limit:
            return True
        stack.extend((c, depth + 1) for c in n.children)
    return False


def leaves(node: Node) -> Iterator[Node]:
    """The tokens under `node`, in order (an explicit stack: deep code must not recurse)."""
    stack = [node]
    while stack:
        n = stack.pop()
        if n.child_count == 0:
            yield n
        else:
            stack.extend(reversed(n.children))


#: Tokens that make no line a line of code on their own.
_NOT_CODE = frozenset(
    {"comment", "{", "}", ";", "", "translation_unit", "compound_statement", "field_declaration_list"}
)


def code_lines(node: Node, first: int, last: int) -> set[int]:
    """The lines (1-based, within first..last) that hold code under `node`: a line with only
    comments, braces or semicolons is not a line of code (it says nothing to translate)."""
    rows: set[int] = set()
    for leaf in leaves(node):
        if leaf.type in _NOT_CODE or leaf.is_missing:
            continue
        for r in range(int(leaf.start_point[0]), int(leaf.end_point[0]) + 1):
            if first <= r <= last:
                rows.add(r)
    return rows
