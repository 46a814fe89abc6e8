"""Which annotations a machine variable may have to be a parameter of its machine's node
(machine.yaml's `parameters:`), and the rclpy parameter type each becomes.

`check` (rule module llfsm.lang.check.parameters) refuses the others; the compiler writes the
type into the generated class (`PARAMETERS`), where llfsm.ros.control declares the parameter
with it, so a set of another type is refused as rclpy refuses it.  Text and `ast` only: nothing
here imports the bus.  See docs/parameters.md.
"""

from __future__ import annotations

import ast

#: Annotation (as `ast.unparse` writes it) -> rclpy's Parameter.Type name.
PARAMETER_TYPES = {
    "bool": "BOOL",
    "int": "INTEGER",
    "float": "DOUBLE",
    "str": "STRING",
    "list[bool]": "BOOL_ARRAY",
    "list[int]": "INTEGER_ARRAY",
    "list[float]": "DOUBLE_ARRAY",
    "list[str]": "STRING_ARRAY",
}


def parameter_type(annotation: str) -> str | None:
    """The parameter type of a variable annotated `annotation`, or None if none fits."""
    try:
        tree = ast.parse(annotation.strip(), mode="eval")
    except SyntaxError:
        return None
    text = ast.unparse(tree.body)
    if text.startswith(("List[", "typing.List[")):
        text = "list[" + text.split("[", 1)[1]
    return PARAMETER_TYPES.get(text)
