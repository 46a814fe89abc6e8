"""machine.yaml and layout.yaml edited as a person would edit them: comments, quoting, flow or
block lists and the file's own indentation kept (ruamel.yaml's round trip), only what the edit
changes changed.

ruamel.yaml writes one indentation for a whole file, so the file's own is found first: the
settings under which the unedited document dumps back to exactly its text (the usual `  - name:`
under `states:` and the other common ones are tried; a file none reproduces gets the closest).
"""

from __future__ import annotations

import difflib
import io
from typing import Any

from ruamel.yaml import YAML
from ruamel.yaml.comments import CommentedMap, CommentedSeq
from ruamel.yaml.error import YAMLError

from ..lang.reader import YAML_LOADER, structure_refusal
from .change import EditError

#: (mapping, sequence, offset) indentations tried, the most common first.
_INDENTS = ((2, 4, 2), (2, 2, 0), (4, 6, 4), (4, 4, 0), (4, 4, 2), (3, 3, 0), (2, 3, 1))


class YamlDoc:
    """One YAML file, loaded for a round trip.  `data` is the document (a CommentedMap for a
    mapping); `dump()` writes it back with the file's own indentation."""

    def __init__(self, text: str, name: str) -> None:
        self.name = name
        self.text = text
        try:
            refusal = structure_refusal(text, YAML_LOADER)  # anchors, aliases, deep nesting
        except Exception:  # the round-trip loader below says where the text is not YAML
            refusal = None
        if refusal is not None:
            raise EditError(f"{name}:{refusal[1]}: {refusal[3]}; fix it first (llfsm check)")
        self._indent = _INDENTS[0]
        try:
            self.data: Any = self._yaml().load(text)
        except YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            line = f":{mark.line + 1}" if mark is not None else ""
            problem = getattr(e, "problem", None) or type(e).__name__
            raise EditError(f"{name}{line}: invalid YAML ({problem}); fix it first (llfsm check)") from None
        except (RecursionError, ValueError) as e:
            raise EditError(f"{name}: cannot be read ({type(e).__name__}); fix it first (llfsm check)") from None
        if text.strip():
            self._indent = self._own_indent()

    def _yaml(self) -> YAML:
        y = YAML()  # round trip
        y.preserve_quotes = True
        y.width = 4096  # never fold a long line the author wrote on one
        m, s, o = self._indent
        y.indent(mapping=m, sequence=s, offset=o)
        return y

    def _own_indent(self) -> tuple[int, int, int]:
        best, best_ratio = self._indent, -1.0
        lines = self.text.splitlines()
        for indent in _INDENTS:
            self._indent = indent
            out = self.dump()
            if out == self.text:
                return indent
            ratio = difflib.SequenceMatcher(None, lines, out.splitlines(), autojunk=False).ratio()
            if ratio > best_ratio:
                best, best_ratio = indent, ratio
        return best

    def dump(self) -> str:
        out = io.StringIO()
        self._yaml().dump(self.data, out)
        return out.getvalue()


def line_of(node: Any, key: Any = None) -> int:
    """1-based line of a mapping (or of one of its keys) or sequence in the loaded file; 0 if unknown."""
    lc = getattr(node, "lc", None)
    if lc is None:
        return 0
    try:
        return int(lc.key(key)[0] if key is not None else lc.line) + 1
    except (KeyError, TypeError, AttributeError, IndexError):
        return 0


def flow_seq(items: list[Any]) -> CommentedSeq:
    seq = CommentedSeq(items)
    seq.fa.set_flow_style()
    return seq


def new_map(pairs: list[tuple[str, Any]], flow: bool) -> CommentedMap:
    m = CommentedMap(pairs)
    if flow:
        m.fa.set_flow_style()
    else:
        m.fa.set_block_style()
    return m


def is_flow(node: Any) -> bool:
    fa = getattr(node, "fa", None)
    return bool(fa is not None and fa.flow_style())
