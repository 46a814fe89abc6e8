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
from ..ros.bus import _Request
from ..ros.client import Client
from ..ros.executor import FutureReturnCode
from ..ros.subscription import Subscription
from ..ros.task import Future
from ..ros.transports.inproc import InProcess


class EnvironmentError_(ValueError):
    """A declaration that names an unknown type or field: one line with the file and line."""


class Oracle:
    """The environment's choices inside one step, in the order the step asks for them.  Asked
    at every step of an exploration with an environment, so each method is kept to a few
    operations (docs/verify.md, "Performance")."""

    __slots__ = ("code", "describe", "forced", "made", "said")

    def __init__(self) -> None:
        self.forced: Sequence[int] = ()
        self.made: list[tuple[int, int]] = []
        self.code: int | None = None  # replaying: the choices as one number
        self.said: list[str] = []
        self.describe = False

    def start(self, forced: Sequence[int] = (), code: int | None = None, describe: bool = False) -> None:
        """A step begins: make the choices `forced` (the first ones; 0 after them), or those
        numbered `code`; with `describe`, say each in `said` (which is kept as it was otherwise)."""
        self.forced, self.code, self.describe = forced, code, describe
        self.made = []
        if describe:
            self.said = []

    def decide(self, n: int, what: Callable[[int], str]) -> int:
        """One of n alternatives (0 first)."""
        made = self.made
        if self.code is not None:
            self.code, d = divmod(self.code, n)
        else:
            k = len(made)
            forced = self.forced
            d = forced[k] if k < len(forced) else 0
        made.append((d, n))
        if self.describe:
            self.said.append(what(d))
        return d

    def number(self) -> int:
        """The choices made, as one number (the first choice varying fastest)."""
        made = self.made
        if len(made) < 2:
            return made[0][0] if made else 0
        code = 0
        for d, n in reversed(made):
            code = code * n + d
        return code

    def next_forced(self) -> list[int] | None:
        """The choices of the next sequence to try (the last one with an alternative left moved
        on, those after it dropped), or None when every sequence has been tried."""
        made = self.made
        j = len(made) - 1
        while j >= 0:
            d, n = made[j]
            if d + 1 < n:
                if not j:
                    return [d + 1]  # one choice in the step, the usual case: no comprehension
                forced = [x for x, _n in made[:j]]
                forced.append(d + 1)
                return forced
            j -= 1
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

    def __init__(
        self, name: str, srv: Any, responses: list[Any], texts: list[str], may_fail: bool, oracle: Oracle, bus: Any
    ) -> None:
        self.srv_name = name
        self.type = srv
        self.node = None
        self.bus = bus
        self.responses = responses
        self.texts = texts
        self.may_fail = may_fail
        self.oracle = oracle
        self.answers = len(responses)
        self.choices = len(responses) + int(may_fail)
        #: what the oracle records of each choice, made once (`Oracle.made`'s items)
        self.made = tuple((d, self.choices) for d in range(self.choices))

    def _answer(self, request: Any) -> Any:
        d = self.oracle.decide(self.choices, self._said)
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

    def said(self, d: int) -> str:
        return f"{self.name}: nothing new" if d == 0 else f"{self.name}: a message {self.texts[d - 1]}"


class EnvFuture(Future):
    """A request to a service of the environment and the future its caller waits on, as one
    object: it waits in the executor's queue as the bus's own request (`llfsm.ros.bus._Request`)
    does, and is answered as that is when the executor runs it (`_run`): the oracle's choice, a
    copy of that response (or no answer, when `may_fail`).  One object instead of two, and the
    oracle's usual case (exploring: no replay, no description) written out, because a step of a
    machine that asks at every ringlet is mostly this (docs/verify.md, "The environment")."""

    __slots__ = ("_request", "_server")

    def __init__(self, service: str, request: Any, server: EnvService) -> None:
        self._remote = None
        self._done = False
        self._cancelled = False
        self._result = None
        self._exception = None
        self._callbacks = ()  # type: ignore[assignment]  # a list once a callback is added
        self._service = service
        self._request = request
        self._server = server

    def add_done_callback(self, fn: Callable[[Future], None]) -> None:
        if self._done:
            fn(self)
        elif self._callbacks:
            self._callbacks.append(fn)
        else:
            self._callbacks = [fn]

    def _run(self) -> None:
        if self._done:
            return  # cancelled before the executor came to it: no answer, no choice
        server = self._server
        if server.bus.services.get(self._service) is not server:  # pragma: no cover (verify refuses create_service)
            _Request(server.bus, self._service or "", self._request, self)._run()
            return
        oracle = server.oracle
        if oracle.code is None and not oracle.describe:  # Oracle.decide, exploring
            made = oracle.made
            forced = oracle.forced
            k = len(made)
            d = forced[k] if k < len(forced) else 0
            made.append(server.made[d])
        else:
            d = oracle.decide(server.choices, server._said)
        responses = server.responses
        if d < len(responses):
            if self._callbacks:
                self.set_result(responses[d]._copy())
            else:  # as set_result, with no callback to run: the usual case, a call to wait on
                self._result = responses[d]._copy()
                self._done = True
        # else: no answer (may_fail); the future stays pending


class EnvClient(Client):
    """A client of a declared service on verify's bus: `call_async` queues an `EnvFuture`.  The
    request is not copied (a server of the environment never reads it; the bus copies it for a
    server of this process that does).  Anything else (a request of the wrong type, a name no
    server of the environment holds now) goes to the bus's own `call_async`."""

    __slots__ = ()

    def call_async(self, request: Any) -> Future:
        bus = self._bus
        service = self.srv_name
        server = bus.services.get(service)
        if server.__class__ is not EnvService or request.__class__ is not self.srv_type.Request:
            return Client.call_async(self, request)
        future = _new(EnvFuture)  # EnvFuture(service, request, server), without the call
        future._remote = None
        future._done = False
        future._cancelled = False
        future._result = None
        future._exception = None
        future._callbacks = ()
        future._service = service
        future._request = request
        future._server = server
        bus.ready.append(future)  # as Executor.queue
        bus.ctx.wake = 0
        return future


_new = object.__new__


class Declaring(InProcess):
    """verify's transport when the specialised loop explores with declared services: the
    in-process one, which also makes each client of a declared name an `EnvClient` as it is
    created (the transport is what a client asks about reaching servers)."""

    def __init__(self, names: set[str]) -> None:
        self.names = names

    def client(self, cli: Any) -> None:
        if cli.__class__ is Client and cli.srv_name in self.names:
            cli.__class__ = EnvClient
        return None


class World:
    """The declared environment on verify's bus, with the oracle that makes its choices.

    **Its services' requests, without the executor's loop.**  A service call of machine code is
    most of what a step with an environment does, and the executor's general machinery (a
    request queued, the spin loop's checks, the server looked up, its answer tested for a
    future) would be most of that.  So on verify's bus (never a run's) a client of a declared
    service is an `EnvClient` (made so by the bus's transport, `Declaring`, as it is created) whose
    `call_async` queues the request as an `EnvFuture` (so does `call`, for a client made before
    the world was), and `spin_until`, when the executor's next work is that very request, runs
    it at once: what the executor's loop would do first, since verify's bus has no timers
    (verify refuses them), no transport and nothing else ahead of it in the queue.  Otherwise
    (anything queued ahead, `ros.ok()` false, a request left pending, a call to any other
    service) the bus's own methods run, so what machine code sees (a pending future
    until the executor's turn, INTERRUPTED, TIMEOUT, the order of callbacks and answers, hence
    the order of the oracle's choices) is unchanged.  `direct=False` (verify's generic step,
    `Options.generic`) leaves the bus as it is: tests/test_verify_environment.py compares the two.
    """

    def __init__(self, declared: Declared, bus: Any, direct: bool = True) -> None:
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
            self.services[name] = EnvService(name, srv, responses, texts, s.may_fail, self.oracle, bus)
            bus.services[name] = self.services[name]
        for name, t in declared.topics.items():
            try:
                cls = _interface(t.type)
                values = [_message(cls, v) for v in t.values]
            except (LookupError, ValuesError) as e:
                raise EnvironmentError_(f"{t.where}: topic {name}: {e}") from None
            self.topics[name] = EnvTopic(name, cls, values, [_shown(v) for v in t.values])
        if self.services and direct:
            self._take_requests(bus)
        self._subscription = Subscription

    def _take_requests(self, bus: Any) -> None:
        """`call` and `spin_until` of verify's bus, for the declared services (see the class)."""
        services, ready, ctx, oracle = bus.services, bus.ready, bus.ctx, self.oracle
        call, spin_until = bus.call, bus.spin_until
        success = FutureReturnCode.SUCCESS

        def call_env(service: str, request: Any) -> Future:  # a client made before the world was
            server = services.get(service)
            if server.__class__ is not EnvService:
                return call(service, request)
            future = EnvFuture(service, request, server)
            ready.append(future)  # as Executor.queue
            ctx.wake = 0
            return future

        def spin_env(future: Any, timeout_ns: int | None) -> Any:
            # the request is the executor's next work (so an EnvFuture: nothing else of the bus's
            # queue is a future), and its loop would run it first: no timer (verify refuses
            # them), ros.ok() (Executor.ok, written out); then EnvFuture._run, written out for the
            # usual case (exploring, the server of the environment on the bus); the cheapest
            # tests first, since every step of a machine that asks makes them all
            if (
                ready
                and ready[0] is future
                and not future._done
                and oracle.code is None
                and not oracle.describe
                and bus.initialised
                and not bus.shut
                and not ctx.interrupted
                and not bus.timers
            ):
                server = future._server
                if services.get(future._service) is server:
                    ready.popleft()  # as Executor._run_ready
                    made = oracle.made
                    forced = oracle.forced
                    k = len(made)
                    d = forced[k] if k < len(forced) else 0
                    made.append(server.made[d])
                    if d < server.answers:
                        if future._callbacks:
                            future.set_result(server.responses[d]._copy())
                        else:
                            future._result = server.responses[d]._copy()
                            future._done = True
                            if not bus.last:
                                return success
                    if bus.last:
                        bus._run_last()
                    if future._done:
                        return success
            return spin_until(future, timeout_ns)

        bus.call = call_env
        bus.spin_until = spin_env

    def before_ringlet(self, m: Any, names: Sequence[str]) -> None:
        """New messages on the declared topics, for the subscriptions the machine's variables hold
        (each: nothing new, or each value), their PUSH callbacks run as between rounds."""
        if not self.topics:
            return
        seen: set[int] = set()
        subscription = self._subscription
        for name in names:
            sub = getattr(m, name, None)
            if not isinstance(sub, subscription) or id(sub) in seen:
                continue
            topic = sub.topic_name
            seen.add(id(sub))
            env = self.topics.get(topic)
            if env is None:
                continue
            d = self.oracle.decide(len(env.values) + 1, env.said)
            if d:
                sub._deliver(env.values[d - 1]._copy())  # a PUSH one queues it: the step runs it first
