"""A property from its kind and text (SPEC 11, 16): the formula it stands for over its atoms,
and the atoms compiled (llfsm.props.atoms).  The kinds are llfsm.props.kinds's table."""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from typing import Any

from .atoms import MAX_TEXT, Atom, MachineInfo, PropertyError, compile_atom
from .formula import Formula, FormulaParser
from .kinds import BY_NAME, CONDITION, KINDS, PAIR, Kind


@dataclass
class Property:
    """One property: `formula` over its atoms (`("atom", k)` is the k-th of `atoms`)."""

    kind: str
    text: str
    name: str
    formula: Formula
    where: str = "--property"
    #: the atoms' texts, in the order `("atom", k)` numbers them inside `formula`
    atoms: list[str] = field(default_factory=list)
    #: a deadline in ns (`within:` of a leads_to), or None
    within: int | None = None

    @property
    def spec(self) -> Kind:
        return BY_NAME[self.kind]


def parse_property(
    kind: str,
    text: Any,
    machines: dict[str, MachineInfo],
    name: str | None = None,
    where: str = "--property",
    within: int | None = None,
) -> tuple[Property, list[Atom]]:
    """The property, and its atoms compiled (local numbering: `("atom", k)` is the k-th)."""
    spec = BY_NAME.get(kind)
    if spec is None:
        raise PropertyError(f"{where}: unknown kind {kind!r} (one of {', '.join(KINDS)})")
    if within is not None and not spec.takes_within:
        takes = ", ".join(k.name for k in BY_NAME.values() if k.takes_within)
        raise PropertyError(f"{where}: `within:` is a deadline for {takes}, not for {kind}")
    if spec.form == PAIR and isinstance(text, list):
        if len(text) != 2 or not all(isinstance(t, str) for t in text):
            raise PropertyError(f"{where}: {kind} takes two conditions, [A, B]")
        shown = f"{text[0]} leads to {text[1]}"
        parts = [str(t) for t in text]
    elif not isinstance(text, str):
        raise PropertyError(f"{where}: the {kind} property must be text")
    else:
        shown = " ".join(text.split())
        parts = [text]
    for t in parts:
        if len(t) > MAX_TEXT:
            raise PropertyError(f"{where}: a property of more than {MAX_TEXT:,} characters")
    texts: list[str] = []

    def atom(src: str) -> Formula:
        texts.append(src)
        return ("atom", len(texts) - 1)

    if spec.form == CONDITION:
        assert spec.formula is not None
        formula = spec.formula(atom(parts[0]))
    elif spec.form == PAIR:
        assert spec.formula is not None
        if len(parts) == 1:
            parts = _split_pair(parts[0], where, kind)
        formula = spec.formula(atom(parts[0]), atom(parts[1]))
    else:
        formula = FormulaParser(parts[0], kind, where, texts).parse()
    atoms = [compile_atom(t, machines, where) for t in texts]
    if within is not None:
        shown += f" within {_duration(within)}"
    prop = Property(kind, shown, name or f"{kind}: {shown}", formula, where, [a.text for a in atoms], within)
    return prop, atoms


def shared_atoms(local: list[Atom], atoms: list[Atom], by_text: dict[str, int]) -> list[int]:
    """The number in `atoms` of each of a property's atoms: properties that name the same
    condition share one atom, evaluated once (a new one is added, `by_text` keeping the index)."""
    ids = []
    for a in local:
        k = by_text.get(a.text)
        if k is None:
            k = by_text[a.text] = len(atoms)
            atoms.append(a)
        ids.append(k)
    return ids


def _split_pair(text: str, where: str, kind: str) -> list[str]:
    """`A, B` or `[A, B]` of a pair given as one text: the two conditions' texts."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as e:
        raise PropertyError(f"{where}: {kind}: {e.msg} (write two conditions: A, B)") from None
    except (RecursionError, MemoryError, ValueError):
        raise PropertyError(f"{where}: {kind}: too deeply nested") from None
    body = tree.body
    if not isinstance(body, ast.Tuple | ast.List) or len(body.elts) != 2:
        raise PropertyError(f"{where}: {kind} takes two conditions, written `A, B` or `[A, B]`")
    return [ast.get_source_segment(text.strip(), e) or ast.unparse(e) for e in body.elts]


def _duration(ns: int) -> str:
    """A deadline as a person writes it: 1.5 s, 200 ms, 3 us."""
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if ns >= scale:
            return f"{ns / scale:g} {unit}"
    return f"{ns} ns"


def duration_text(ns: int) -> str:
    """A duration as `llfsm run` reads it back exactly: 100ms, 2s, 250us, 7ns."""
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if ns % scale == 0:
            return f"{ns // scale}{unit}"
    return f"{ns}ns"
