"""The world as a verification file declares it (SPEC 16; docs/verify.md, "The environment").

`environment:` says what a service answers (`responses`, and `may_fail`: it may not answer) and
what a topic's messages may hold (`values`).  verify then explores a machine's service calls
and subscription reads over those values instead of refusing them:

- **services**: a server of the environment stands on the bus under each declared name; a
  request (`call_async`, then `spin_until_future_complete` or `result()`; `call`) is answered,
  when the executor runs it (inside the spin call, or after the ringlet that made it, as
  between rounds in a run), with each response in turn, and with none at all when `may_fail`
  (the future stays pending: `spin_until_future_complete` returns TIMEOUT at once, as llfsm's
  bus says when nothing can answer; under `--period` no time passes for it);
- **topics**: before each ringlet of a machine, each subscription its variables hold on a
  declared topic may get nothing new or a new message with each of the values: a PULL reader's
  `latest` and `take()` then read it, a PUSH subscription's callback runs with it, as the
  executor does between rounds.

Each such choice is made inside the step, as the step asks for it (`Oracle.decide`); the
explorer tries every sequence of choices a step can make (`Oracle.next_forced`), numbers each
(a choice of the step's inputs and time, then the environment's choices in mixed radix), and
a replay makes the same ones, so a counterexample says which response or value was chosen at
each step.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from typing import Any

from ..msgs._yaml import ValuesError, set_fields
from ..props.file import Environment as Declared
from ..ros.task import Future


class EnvironmentError_(ValueError):
    """A declaration that names an unknown type or field: one line with the file and line."""


class Oracle:
    """The environment's choices inside one step, in the order the step asks for them."""

    def __init__(self) -> None:
        self.forced: list[int] = []
        self.made: list[tuple[int, int]] = []
        self.code: int | None = None  # replaying: the choices as one number
        self.said: list[str] = []
        self.describe = False

    def start(self, forced: Sequence[int] = (), code: int | None = None, describe: bool = False) -> None:
        self.forced, self.code, self.describe = list(forced), code, describe
        self.made = []
        self.said = []

    def decide(self, n: int, what: Callable[[int], str]) -> int:
        """One of n alternatives (0 first)."""
        if self.code is not None:
            self.code, d = divmod(self.code, n)
        else:
            k = len(self.made)
            d = self.forced[k] if k < len(self.forced) else 0
        self.made.append((d, n))
        if self.describe:
            self.said.append(what(d))
        return d

    def number(self) -> int:
        """The choices made, as one number (the first choice varying fastest)."""
        code = 0
        for d, n in reversed(self.made):
            code = code * n + d
        return code

    def next_forced(self) -> list[int] | None:
        """The choices of the next sequence to try (the last one with an alternative left moved
        on, those after it dropped), or None when every sequence has been tried."""
        for j in range(len(self.made) - 1, -1, -1):
            d, n = self.made[j]
            if d + 1 < n:
                return [x for x, _n in self.made[:j]] + [d + 1]
        return None


def _interface(type_name: str) -> Any:
    pkg, kind, name = type_name.split("/")
    try:
        cls = getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name, None)
    except ImportError:
        cls = None
    if cls is None:
        raise LookupError(f"unknown type {type_name}")
    return cls


def _message(cls: Any, values: dict[str, Any]) -> Any:
    msg = cls()
    set_fields(msg, values)
    return msg


def _shown(values: dict[str, Any]) -> str:
    return "{" + ", ".join(f"{k}: {v!r}" for k, v in values.items()) + "}" if values else "{} (the defaults)"


class EnvService:
    """A server of the environment: answers with the oracle's choice of its responses."""

    def __init__(self, name: str, srv: Any, responses: list[Any], texts: list[str], may_fail: bool, oracle: Oracle):
        self.srv_name = name
        self.type = srv
        self.node = None
        self.responses = responses
        self.texts = texts
        self.may_fail = may_fail
        self.oracle = oracle

    def _answer(self, request: Any) -> Any:
        n = len(self.responses) + int(self.may_fail)
        d = self.oracle.decide(n, self._said)
        if d == len(self.responses):
            return Future(self.srv_name)  # never done: the call gets no answer
        return self.responses[d]  # the bus hands the caller a copy (bus._Request)

    def _said(self, d: int) -> str:
        if d == len(self.responses):
            return f"{self.srv_name} did not answer (may_fail)"
        return f"{self.srv_name} answered response {d} {self.texts[d]}"


class EnvTopic:
    """A topic of the environment: the messages it may carry."""

    def __init__(self, name: str, cls: Any, values: list[Any], texts: list[str]) -> None:
        self.name = name
        self.cls = cls
        self.values = values
        self.texts = texts


class World:
    """The declared environment on verify's bus, with the oracle that makes its choices."""

    def __init__(self, declared: Declared, bus: Any) -> None:
        self.oracle = Oracle()
        self.services: dict[str, EnvService] = {}
        self.topics: dict[str, EnvTopic] = {}
        for name, s in declared.services.items():
            try:
                srv = _interface(s.type)
                responses = [_message(srv.Response, v) for v in s.responses]
            except (LookupError, ValuesError, AttributeError) as e:
                raise EnvironmentError_(f"{s.where}: service {name}: {e}") from None
            texts = [_shown(v) for v in s.responses]
            self.services[name] = EnvService(name, srv, responses, texts, s.may_fail, self.oracle)
            bus.services[name] = self.services[name]
        for name, t in declared.topics.items():
            try:
                cls = _interface(t.type)
                values = [_message(cls, v) for v in t.values]
            except (LookupError, ValuesError) as e:
                raise EnvironmentError_(f"{t.where}: topic {name}: {e}") from None
            self.topics[name] = EnvTopic(name, cls, values, [_shown(v) for v in t.values])

    def before_ringlet(self, m: Any, names: Sequence[str]) -> None:
        """New messages on the declared topics, for the subscriptions the machine's variables hold
        (each: nothing new, or each value), their PUSH callbacks run as between rounds."""
        if not self.topics:
            return
        seen: set[int] = set()
        for name in names:
            sub = getattr(m, name, None)
            topic = getattr(sub, "topic_name", None)
            if topic is None or id(sub) in seen or not hasattr(sub, "_deliver"):
                continue
            seen.add(id(sub))
            env = self.topics.get(topic)
            if env is None:
                continue

            def said(d: int, env: EnvTopic = env) -> str:
                return f"{env.name}: nothing new" if d == 0 else f"{env.name}: a message {env.texts[d - 1]}"

            d = self.oracle.decide(len(env.values) + 1, said)
            if d and sub is not None:
                sub._deliver(env.values[d - 1]._copy())  # a PUSH one queues it: the step runs it first
