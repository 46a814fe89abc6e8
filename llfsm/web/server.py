"""The web view's server: aiohttp on a thread of its own, one page, one WebSocket (docs/view.md).

The server thread has its own event loop; the scheduler never waits on it.  While at least one
page is connected, the server samples its source at most `RATE` times a second and pushes what
changed, as the channel's protocol says (llfsm.web.channel: a hello with everything, then
deltas; docs/view.md, "The page's channel"); a closed tab stops the sampling; a page that reads
slowly is dropped, never waited for.  What the page asks for (commands, publishing, service calls) arrives as
JSON POSTs and goes to the source, which hands it to the scheduler's thread.

Security: it binds 127.0.0.1 unless told otherwise; on any other address every request must
carry the token of the printed URL (the page's query string, then a cookie); without a token,
only loopback Host names are served (no DNS rebinding).  A WebSocket or POST whose Origin is not
the page's own is refused (403), POSTs must be JSON (a cross-site form cannot send that), and
message values are parsed as YAML and checked by the message classes, as `llfsm topic pub`
parses them (llfsm.msgs._yaml).

What the page is sent may come from any peer on a DDS domain (`llfsm view`), so nothing a source
returns may stop the server (issue 18): diagrams (and the graph of nodes and topics) are drawn
on a worker thread, never on the event loop (a big one takes a while even bounded, and pages
and snapshots go on meanwhile); a machine that cannot be drawn is left out of the page with one
warning and the others are drawn; a snapshot that fails is skipped with one warning and the
push loop goes on.  A page is sent a machine's name, description text and SVG only, not the
description itself.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import ipaddress
import secrets
import socket
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from importlib import resources
from typing import Any

from aiohttp import WSMsgType, web

from ..diagram import svg as diagram
from . import debugging, rosgraph
from .channel import PROTOCOL, Channel, full
from .source import CommandError, dumps

#: Snapshots pushed per second at most.
RATE = 20
#: Seconds between two hellos sent because the machines changed (a peer replacing its
#: description in a loop must not have every page rebuilt 20 times a second).
HELLO_PERIOD = 1.0
COOKIE = "llfsm_token"
LOOPBACK_NAMES = {"localhost", "127.0.0.1", "::1", "[::1]"}
_STATIC = {"app.js": "text/javascript", "style.css": "text/css"}
#: What the front end's build (frontend/, `make`) writes into static/app/.
_APP = {"app.js": "text/javascript", "app.css": "text/css"}
#: The debugger's page (the application, at /debug: llfsm.web.debugging).
DEBUG_PAGE = "debug.html"
APP_MISSING = "llfsm/web/static/app/app.js is missing"


class AddressError(Exception):
    """The address given to --web cannot be served (one line for the user)."""


def parse_address(text: str) -> tuple[str, int]:
    """`[HOST:]PORT` -> (host, port); the host defaults to 127.0.0.1; `[::1]:8080` for IPv6."""
    text = text.strip()
    host, sep, port_text = text.rpartition(":")
    if not sep:
        host, port_text = "127.0.0.1", text
    host = host.strip("[]") or "127.0.0.1"
    try:
        port = int(port_text)
    except ValueError:
        raise AddressError(f"--web {text}: expected [HOST:]PORT, such as 8080 or 0.0.0.0:8080") from None
    if not 0 <= port <= 65535:
        raise AddressError(f"--web {text}: the port must be 0..65535 (0: any free port)")
    return host, port


def is_loopback(host: str) -> bool:
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class WebServer:
    """Serves a source (llfsm.web.source.RunSource, or a graph source) on a background thread.
    llfsm.web.edit_server.EditServer serves `llfsm edit` with the same lifecycle and security,
    its own page (`PAGE`) and routes (`_routes`)."""

    #: The page's HTML (in static/).
    PAGE = "index.html"
    #: The largest request body accepted (a bigger one is refused, 413, before it is read).
    MAX_BODY = 256 * 1024

    def __init__(self, source: Any, host: str = "127.0.0.1", port: int = 0, token: str | None = None) -> None:
        self.source = source
        self.host = host
        self.port = port
        #: Required on any address but loopback.
        self.token = token if token is not None else (None if is_loopback(host) else secrets.token_urlsafe(18))
        self.clients: set[web.WebSocketResponse] = set()
        #: Snapshots per second at most.
        self.rate = RATE
        self.url = ""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._runner: web.AppRunner | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._wake: asyncio.Event | None = None
        self._nudged: asyncio.Event | None = None
        self._pusher: asyncio.Task[None] | None = None
        #: Lays diagrams out off the event loop (one at a time: they share a cache).
        self._drawer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="llfsm-web-draw")
        self._warned: set[str] = set()
        #: The deltas every page is sent, from one baseline (llfsm.web.channel).
        self.channel = Channel()
        self._locks: dict[web.WebSocketResponse, asyncio.Lock] = {}  # each page's, for its order

    # -- lifecycle (caller's thread) -----------------------------------------------------------------
    def start(self) -> str:
        """Bind (errors here, before the run starts), serve on a thread; returns the page's URL."""
        try:
            infos = socket.getaddrinfo(self.host, self.port, type=socket.SOCK_STREAM)
        except socket.gaierror as e:
            raise AddressError(f"--web {self.host}:{self.port}: {e.strerror}") from None
        family, _, _, _, addr = infos[0]
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(addr)
        except OSError as e:
            sock.close()
            raise AddressError(f"--web {self.host}:{self.port}: {e.strerror}") from None
        sock.listen(64)
        sock.setblocking(False)
        self.port = sock.getsockname()[1]
        shown = f"[{self.host}]" if ":" in self.host else self.host
        self.url = f"http://{shown}:{self.port}/" + (f"?token={self.token}" if self.token else "")
        self._thread = threading.Thread(target=self._serve, args=(sock,), name="llfsm-web", daemon=True)
        self._thread.start()
        self._ready.wait(10)
        if self._error is not None:
            raise AddressError(f"--web: the server did not start: {self._error}")
        return self.url

    def stop(self) -> None:
        """End the page's session: a last snapshot says the run ended, then everything closes."""
        loop, thread = self._loop, self._thread
        if loop is None or thread is None:
            return
        self.source.ended = True
        try:
            asyncio.run_coroutine_threadsafe(self._shutdown(), loop).result(5)
        except Exception:  # stopping must never fail the run
            pass
        loop.call_soon_threadsafe(loop.stop)
        thread.join(5)
        self._drawer.shutdown(wait=False, cancel_futures=True)

    def _warn(self, text: str, key: str | None = None) -> None:
        """One line per key in the run's log (the source's, which knows the log), never raising."""
        warn = getattr(self.source, "warn", None)
        if warn is not None:
            warn(text, key)
            return
        key = text if key is None else key
        if key not in self._warned:
            self._warned.add(key)
            print(f"llfsm: web view: {text}", file=sys.stderr, flush=True)

    def _serve(self, sock: socket.socket) -> None:
        loop = self._loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(self._start(sock))
        except BaseException as e:  # reported by start()
            self._error = e
            self._ready.set()
            return
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            loop.close()

    async def _start(self, sock: socket.socket) -> None:
        app = web.Application(middlewares=[self._guard], client_max_size=self.MAX_BODY)
        app.router.add_get("/", self._index)
        app.router.add_get("/debug", self._debug_page)
        app.router.add_get("/static/app/{name}", self._app_asset)
        app.router.add_get("/static/{name}", self._static)
        app.router.add_get("/ws", self._ws)
        app.router.add_get("/favicon.ico", _no_icon)
        self._routes(app)
        self._runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=1.0)
        await self._runner.setup()
        await web.SockSite(self._runner, sock).start()
        self._wake = asyncio.Event()
        self._pusher = asyncio.get_running_loop().create_task(self._push())
        debug = getattr(self.source, "debug", None)
        if debug is not None and hasattr(debug, "on_change"):
            debug.on_change = self.nudge

    def _routes(self, app: web.Application) -> None:
        """The view's requests (the editor's server has its own)."""
        app.router.add_post("/api/command", self._command)
        app.router.add_post("/api/publish", self._publish)
        app.router.add_post("/api/call", self._call)
        app.router.add_post("/api/parameters", self._parameters)
        app.router.add_post("/api/parameter", self._set_parameter)
        debugging.routes(app, lambda: getattr(self.source, "debug", None), self._answer)

    async def _farewell(self) -> None:
        """The last message to the pages as the server stops (the view's: the run ended)."""
        delta = self.channel.delta(self._state())
        if delta is not None:
            await self._broadcast(delta)

    async def _shutdown(self) -> None:
        try:
            await self._farewell()
        except Exception:
            pass
        if self._pusher is not None:
            self._pusher.cancel()
        for ws in list(self.clients):
            await ws.close()
        if self._runner is not None:
            await self._runner.cleanup()

    # -- security ------------------------------------------------------------------------------------------
    def _token_ok(self, request: web.Request) -> bool:
        if self.token is None:
            return True
        given = request.query.get("token") or request.cookies.get(COOKIE) or request.headers.get("X-LLFSM-Token")
        return given is not None and hmac.compare_digest(given.encode(), self.token.encode())

    @web.middleware
    async def _guard(self, request: web.Request, handler: Any) -> web.StreamResponse:
        if self.token is None and request.url.host not in LOOPBACK_NAMES and not is_loopback(request.url.host or ""):
            return _refuse(403, "this page is served to loopback addresses only")
        if not self._token_ok(request):
            return _refuse(403, "a valid token is required: open the URL the run printed")
        if request.method == "POST" or request.path == "/ws":
            origin = request.headers.get("Origin")
            if origin is not None and origin != f"http://{request.host}":
                return _refuse(403, "cross-origin request refused")
        if request.method == "POST" and request.content_type != "application/json":
            return _refuse(415, "send JSON")
        response = await handler(request)
        if self.token is not None and request.query.get("token") and request.path == "/":
            response.set_cookie(COOKIE, self.token, httponly=True, samesite="Strict", path="/")
        if not isinstance(response, web.WebSocketResponse):
            host = request.host
            # the editor's code editors (CodeMirror) add their style sheets with the page's nonce,
            # and the browser's own editing of their text may write style attributes (never
            # markup of ours: the page sets no style attribute and strips them from diagrams)
            nonce = request.get("csp_nonce")
            styles = f"'self' 'nonce-{nonce}'; style-src-attr 'unsafe-inline'" if nonce else "'self'"
            response.headers["Content-Security-Policy"] = (
                f"default-src 'self'; img-src 'self' data:; style-src {styles}; script-src 'self'; "
                f"connect-src 'self' ws://{host}; frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
            )
            response.headers["X-Content-Type-Options"] = "nosniff"
            response.headers["Referrer-Policy"] = "no-referrer"
            response.headers["Cache-Control"] = "no-store"
        return response

    # -- the page --------------------------------------------------------------------------------------------
    async def _index(self, request: web.Request) -> web.Response:
        # a source may have a page of its own (`llfsm replay`: the debugger's page)
        return self._page(request, getattr(self.source, "page", None) or self.PAGE)

    async def _debug_page(self, request: web.Request) -> web.Response:
        """The debugger's page (docs/debug.md), beside the live view of a run or of the graph."""
        if getattr(self.source, "debug", None) is None:
            raise web.HTTPNotFound()
        return self._page(request, DEBUG_PAGE)

    def _page(self, request: web.Request, name: str) -> web.Response:
        text = (resources.files(__package__) / "static" / name).read_text(encoding="utf-8")
        if "{{nonce}}" in text:  # a page that adds style sheets from script: a fresh nonce each time
            request["csp_nonce"] = nonce = secrets.token_urlsafe(16)
            text = text.replace("{{nonce}}", nonce)
        return web.Response(text=text, content_type="text/html", charset="utf-8")

    async def _app_asset(self, request: web.Request) -> web.Response:
        """The application built from frontend/ (`make`): only the names the build writes."""
        name = request.match_info["name"]
        kind = _APP.get(name)
        if kind is None:
            raise web.HTTPNotFound()
        try:
            data = (resources.files(__package__) / "static" / "app" / name).read_bytes()
        except OSError:
            return _refuse(503, f"the page was not built: run `make` in llfsm's checkout ({APP_MISSING})")
        return web.Response(body=data, content_type=kind, charset="utf-8")

    async def _static(self, request: web.Request) -> web.Response:
        name = request.match_info["name"]
        kind = _STATIC.get(name)
        if kind is None:
            raise web.HTTPNotFound()
        data = (resources.files(__package__) / "static" / name).read_bytes()
        return web.Response(body=data, content_type=kind, charset="utf-8")

    async def _hello(self, fresh: bool = True) -> dict[str, Any]:
        """A hello (the page's first message, and every one after the machines changed): the
        machines' diagrams, drawn on the worker thread, the graph, and the whole state.  A fresh
        one (to every page) samples the source and makes that the channel's baseline; one for a
        page that joins is sent the baseline the other pages have, so the next delta fits."""
        descriptions = self._descriptions()
        loop = asyncio.get_running_loop()
        machines = await loop.run_in_executor(self._drawer, self._draw, descriptions)
        graph = await self._graph_message(self._graph())
        base = self.channel.baseline
        snapshot = self.channel.reset(self._state()) if fresh or base is None else full(base, self.channel.seq)
        current = {m.get("name"): m.get("state") for m in snapshot["machines"]["upsert"] if isinstance(m, dict)}
        for m in machines:
            m["svg"] = diagram.mark(m["svg"], current.get(m["name"]))
        return {"type": "hello", "protocol": PROTOCOL, "machines": machines, "graph": graph, "snapshot": snapshot}

    def _graph(self) -> rosgraph.RosGraph | None:
        """The source's graph of nodes and topics (None for a source that has none)."""
        read = getattr(self.source, "graph", None)
        if read is None:
            return None
        try:
            graph: rosgraph.RosGraph = read()
            return graph
        except Exception as e:  # the page keeps the last graph it was sent
            self._warn(f"the graph could not be read: {type(e).__name__}: {e}", "graph")
            return None

    async def _graph_message(self, g: rosgraph.RosGraph | None) -> dict[str, Any] | None:
        """The graph's drawing (on the worker thread: a big graph takes a while) and lists."""
        if g is None:
            return None
        loop = asyncio.get_running_loop()
        try:
            drawn = await loop.run_in_executor(self._drawer, rosgraph.svg, rosgraph.visible(g))
        except Exception as e:  # the lists still go; the drawing says it could not be made
            self._warn(f"the graph could not be drawn: {type(e).__name__}: {e}", "graph draw")
            drawn = ""
        return {"svg": drawn, **g.data()}

    def _draw(self, descriptions: list[Any]) -> list[dict[str, Any]]:
        """(worker thread) Each machine's name, description text and SVG; one that cannot be
        drawn is left out, said once, and never stops the others."""
        # deferred: here, on the worker: pydantic (the description model) takes a while to import
        from ..diagram.description import DescriptionError, Input

        out = []
        for d in descriptions:
            name = d.get("name") if isinstance(d, dict) else None
            shown = name if isinstance(name, str) else "?"
            try:
                svg = diagram.svg(d)
            except DescriptionError as e:
                self._warn(f"machine {shown!r} not shown: its description does not fit: {e}", f"draw {shown}")
                continue
            except Exception as e:  # a bug of ours: this machine is not drawn, the page goes on
                self._warn(f"machine {shown!r} not shown: drawing failed: {type(e).__name__}: {e}", f"draw {shown}")
                continue
            text = d.get("description")
            machine, participant = d.get("machine", name), d.get("participant", "")
            # drawn, so it fits the model: its inputs too (SPEC 11), one line each
            inputs = [Input.model_validate(i).text() for i in d.get("inputs") or ()]
            out.append(
                {
                    "name": name,
                    "machine": machine if isinstance(machine, str) else shown,
                    "participant": participant if isinstance(participant, str) else "",
                    "description": text if isinstance(text, str) else "",
                    "svg": svg,
                    "inputs": inputs,
                }
            )
        return out

    def _descriptions(self) -> list[Any]:
        try:
            return list(self.source.machines())
        except Exception as e:
            self._warn(f"the machines could not be listed: {type(e).__name__}: {e}", "machines")
            return []

    def _state(self) -> dict[str, Any]:
        try:
            state: dict[str, Any] = self.source.state()
            return state
        except Exception as e:  # this sample is skipped; the next one is taken as usual
            self._warn(f"a snapshot failed: {type(e).__name__}: {e}", "snapshot")
            raise _NoSnapshot from None

    async def _ws(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=20, max_msg_size=64 * 1024)
        try:
            if not await self._greet(ws, request):
                return ws
        except ConnectionError:  # the page left right after the handshake (a tab closed, a browser exiting)
            return ws
        try:
            async for msg in ws:  # the page only listens here; commands come as POSTs
                if msg.type == WSMsgType.ERROR:
                    break
        finally:
            self._drop(ws)
        return ws

    async def _greet(self, ws: web.WebSocketResponse, request: web.Request) -> bool:
        """The handshake and the hello; then the page is one of the clients the push loop feeds.
        False when there was nothing to greet it with (the WebSocket is closed)."""
        await ws.prepare(request)
        for _ in range(max(1, int(5 * self.rate))):  # five seconds of tries (a bench sets a float rate)
            try:
                hello = await self._hello(fresh=False)
                break
            except _NoSnapshot:  # the source failed to be sampled just now: try again soon
                await asyncio.sleep(1 / self.rate)
        else:  # said already (once); the page shows itself closed, and may reconnect
            await ws.close()
            return False
        # one of the pages from here on: the next delta is computed from the baseline its hello
        # holds, and its lock, taken before any broadcast can see it, sends the hello first
        async with self._locks.setdefault(ws, asyncio.Lock()):
            self.clients.add(ws)
            if self._wake is not None:
                self._wake.set()
            try:
                await ws.send_str(dumps(hello))
            except BaseException:
                self._drop(ws)
                raise
        return True

    async def _push(self) -> None:
        """Sample and push at most RATE times a second, only while a page is connected.  When
        the machines change (`llfsm view`: a run started, a description was replaced), the
        pages are sent a new hello once its diagrams are drawn, snapshots going on meanwhile.
        Nothing that goes wrong in one round ends the loop."""
        assert self._wake is not None
        machines = self._descriptions()
        hello: asyncio.Task[None] | None = None
        loop = asyncio.get_running_loop()
        hello_at = -HELLO_PERIOD
        graph = self._graph()
        graph_task: asyncio.Task[None] | None = None
        graph_at = -HELLO_PERIOD
        nudged = self._nudged = asyncio.Event()
        while True:
            # at most `rate` times a second, or at once when the run says something changed
            # (the debugger paused or went on: a step shows without waiting for the next sample)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(nudged.wait(), 1 / self.rate)
            nudged.clear()
            if not self.clients:
                self._wake.clear()
                await self._wake.wait()
                continue
            try:
                now = self._descriptions()
                changed = len(now) != len(machines) or any(a is not b for a, b in zip(now, machines, strict=True))
                if changed and (hello is None or hello.done()) and loop.time() - hello_at >= HELLO_PERIOD:
                    machines = now  # objects, not names: a description replaced is drawn afresh
                    hello_at = loop.time()
                    hello = loop.create_task(self._send_hello())
                g = self._graph()
                if (
                    g is not None
                    and g != graph
                    and (graph_task is None or graph_task.done())
                    and loop.time() - graph_at >= HELLO_PERIOD
                ):
                    graph, graph_at = g, loop.time()
                    graph_task = loop.create_task(self._send_graph(g))
                delta = self.channel.delta(self._state())
                if delta is not None:
                    await self._broadcast(delta)
            except _NoSnapshot:
                continue
            except Exception as e:  # said once; the next round goes on
                self._warn(f"the page's update failed: {type(e).__name__}: {e}", "push")

    def nudge(self) -> None:
        """Push a snapshot now, not at the next sample (any thread: the run's debugger calls it
        when it pauses or goes on)."""
        loop, nudged = self._loop, self._nudged
        if loop is not None and nudged is not None:
            loop.call_soon_threadsafe(nudged.set)

    async def _send_hello(self) -> None:
        try:
            await self._broadcast(await self._hello())
        except _NoSnapshot:
            pass
        except Exception as e:
            self._warn(f"the page's diagrams could not be sent: {type(e).__name__}: {e}", "hello")

    async def _send_graph(self, g: rosgraph.RosGraph) -> None:
        try:
            message = await self._graph_message(g)
            if message is not None:
                await self._broadcast({"type": "graph", **message})
        except Exception as e:
            self._warn(f"the page's graph could not be sent: {type(e).__name__}: {e}", "graph send")

    async def _broadcast(self, data: dict[str, Any]) -> None:
        await self._broadcast_text(dumps(data))

    async def _broadcast_text(self, text: str) -> None:
        """To every page, in the order messages were made (each page's lock keeps it)."""
        for gone in [ws for ws in self._locks if ws not in self.clients and not self._locks[ws].locked()]:
            del self._locks[gone]  # a page a subclass dropped itself (the editor's)
        for ws in list(self.clients):
            async with self._locks.setdefault(ws, asyncio.Lock()):
                if ws not in self.clients:
                    continue
                try:
                    await asyncio.wait_for(ws.send_str(text), 2)
                except Exception:  # a page gone or too slow: drop it, never wait for it
                    self._drop(ws)
                    asyncio.get_running_loop().create_task(ws.close())

    def _drop(self, ws: web.WebSocketResponse) -> None:
        self.clients.discard(ws)
        self._locks.pop(ws, None)

    # -- what the page asks for --------------------------------------------------------------------------------
    async def _json(self, request: web.Request) -> dict[str, Any]:
        try:
            data = await request.json()
        except ValueError:
            raise CommandError("the request is not JSON") from None
        if not isinstance(data, dict):
            raise CommandError("the request must be a JSON object")
        return data

    async def _answer(self, request: web.Request, action: Any) -> web.Response:
        try:
            data = await self._json(request)
            result = await action(data)
        except CommandError as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)
        if self._wake is not None:
            self._wake.set()
        return web.json_response(result)

    async def _command(self, request: web.Request) -> web.Response:
        async def command(d: dict[str, Any]) -> dict[str, Any]:
            answer: dict[str, Any] = await self.source.command(_text(d, "machine"), _text(d, "command"))
            # the last delta sent before this answer: the page knows a later one was sampled after it
            return {**answer, "seq": self.channel.seq}

        return await self._answer(request, command)

    async def _publish(self, request: web.Request) -> web.Response:
        return await self._answer(
            request, lambda d: self.source.publish(_text(d, "topic"), _text(d, "type"), _text(d, "values"))
        )

    async def _call(self, request: web.Request) -> web.Response:
        return await self._answer(
            request, lambda d: self.source.call(_text(d, "service"), _text(d, "type"), _text(d, "values"))
        )

    async def _parameters(self, request: web.Request) -> web.Response:
        return await self._answer(request, lambda d: self.source.parameters(_text(d, "node")))

    async def _set_parameter(self, request: web.Request) -> web.Response:
        return await self._answer(
            request, lambda d: self.source.set_parameter(_text(d, "node"), _text(d, "name"), _text(d, "value"))
        )


class _NoSnapshot(Exception):
    """The source could not be sampled this time (said once by WebServer._state)."""


async def _no_icon(request: web.Request) -> web.Response:
    return web.Response(status=204)


def _text(data: dict[str, Any], key: str) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise CommandError(f"{key} must be a string")
    return value


def _refuse(status: int, message: str) -> web.Response:
    return web.json_response({"success": False, "message": message}, status=status)
