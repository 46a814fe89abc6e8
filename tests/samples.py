"""The shipped message and service classes, and varied samples of them (deterministic for a
given random.Random): what the DDS type tests, the recorder's tap tests and the comparison with
rclpy's serialisation (tests/interop) all run through."""

from __future__ import annotations

import importlib
import random
from pathlib import Path

import llfsm.msgs
from llfsm.msgs._message import INT_RANGES, Message, Service, is_message_class, is_service_class

#: Every kind of interface module a shipped package may have.
KINDS = ("msg", "srv", "action")


def shipped_packages() -> list[str]:
    """The packages llfsm ships: the folders of generated modules in llfsm/msgs/."""
    root = Path(llfsm.msgs.__file__).parent
    return sorted(d.name for d in root.iterdir() if not d.name.startswith("_") and (d / "__init__.py").is_file())


def _modules(kinds: tuple[str, ...]) -> list[object]:
    out = []
    for pkg in shipped_packages():
        for kind in kinds:
            try:
                out.append(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"))
            except ModuleNotFoundError:
                continue
    return out


def shipped_classes() -> list[type[Message]]:
    """Every message class of the shipped packages (requests and responses included)."""
    out: list[type[Message]] = []
    for module in _modules(KINDS):
        name = module.__name__  # type: ignore[attr-defined]
        out += [o for o in vars(module).values() if is_message_class(o) and o.__module__ == name]
    return sorted(out, key=lambda c: c._TYPE)


def shipped_services() -> list[type[Service]]:
    """Every service class of the shipped packages (an action's SendGoal and GetResult too)."""
    out: list[type[Service]] = []
    for module in _modules(("srv", "action")):
        name = module.__name__  # type: ignore[attr-defined]
        out += [o for o in vars(module).values() if is_service_class(o) and o.__module__ == name]
    return sorted(out, key=lambda c: c._TYPE)


def _message_class(ros_type: str) -> type[Message]:
    pkg, kind, name = ros_type.split("/")
    return getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)  # type: ignore[no-any-return]


def _scalar(base: str, rng: random.Random) -> object:
    name, _, bound = base.partition("<=")
    if name in ("float64",):
        return rng.choice([0.0, -1.5, 3.141592653589793, 1e300, rng.uniform(-1e6, 1e6)])
    if name == "float32":
        return rng.choice([0.0, -1.5, 0.25, 1024.0])  # exactly representable in float32
    if name == "bool":
        return rng.random() < 0.5
    if name in INT_RANGES:
        lo, hi = INT_RANGES[name]
        return rng.choice([lo, hi, 0, rng.randint(lo, hi)])
    if name in ("string", "wstring"):
        n = int(bound) if bound else 12
        text = rng.choice(["", "a", "hello", "ünïcödé ✓", "x" * 40, "with\0nul?"[:4]])
        return text[:n]
    raise AssertionError(name)


def sample(cls: type[Message], rng: random.Random, depth: int = 0) -> Message:
    """A message with every field set to a varied value (deterministic for a given rng)."""
    msg = cls()
    for name, ros_type in cls._FIELDS:
        base, array = ros_type, None
        if ros_type.endswith("]"):
            base, _, array = ros_type[:-1].partition("[")

        def make(base: str = base) -> object:
            return sample(_message_class(base), rng, depth + 1) if "/" in base else _scalar(base, rng)

        if array is None:
            setattr(msg, name, make())
        elif array.startswith("<="):
            setattr(msg, name, [make() for _ in range(rng.randint(0, int(array[2:])))])
        elif array:
            setattr(msg, name, [make() for _ in range(int(array))])
        else:
            setattr(msg, name, [make() for _ in range(rng.randint(0, 3 if depth else 5))])
    return msg


#: The shipped message classes, once per process (importing them all takes a moment).
CLASSES = shipped_classes()
