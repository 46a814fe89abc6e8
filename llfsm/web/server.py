"""The web view's server: aiohttp on a thread of its own, one page, one WebSocket.

The server thread has its own event loop; the scheduler never waits on it.  While at least one
page is connected, the server samples its source at most `RATE` times a second and pushes the
snapshot if it changed (a closed tab stops the sampling; a page that reads slowly is dropped,
never waited for).  What the page asks for (commands, publishing, service calls) arrives as
JSON POSTs and goes to the source, which hands it to the scheduler's thread.

Security: it binds 127.0.0.1 unless told otherwise; on any other address every request must
carry the token of the printed URL (the page's query string, then a cookie); without a token,
only loopback Host names are served (no DNS rebinding).  A WebSocket or POST whose Origin is not
the page's own is refused (403), POSTs must be JSON (a cross-site form cannot send that), and
message values are parsed as YAML and checked by the message classes (llfsm.web.values).
"""

from __future__ import annotations

import asyncio
import hmac
import ipaddress
import secrets
import socket
import threading
from importlib import resources
from typing import Any

from aiohttp import WSMsgType, web

from . import diagram, values
from .source import CommandError, dumps

#: Snapshots pushed per second at most.
RATE = 20
COOKIE = "llfsm_token"
LOOPBACK_NAMES = {"localhost", "127.0.0.1", "::1", "[::1]"}
_STATIC = {"app.js": "text/javascript", "style.css": "text/css"}


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
    """Serves a source (llfsm.web.source.RunSource, or a graph source) on a background thread."""

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
        self._pusher: asyncio.Task[None] | None = None

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
        app = web.Application(middlewares=[self._guard], client_max_size=256 * 1024)
        app.router.add_get("/", self._index)
        app.router.add_get("/static/{name}", self._static)
        app.router.add_get("/ws", self._ws)
        app.router.add_get("/favicon.ico", _no_icon)
        app.router.add_post("/api/command", self._command)
        app.router.add_post("/api/publish", self._publish)
        app.router.add_post("/api/call", self._call)
        self._runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=1.0)
        await self._runner.setup()
        await web.SockSite(self._runner, sock).start()
        self._wake = asyncio.Event()
        self._pusher = asyncio.get_running_loop().create_task(self._push())

    async def _shutdown(self) -> None:
        try:
            await self._broadcast(self._snapshot())
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
            response.headers["Content-Security-Policy"] = (
                "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
                f"connect-src 'self' ws://{host}; frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
            )
            response.headers["X-Content-Type-Options"] = "nosniff"
            response.headers["Referrer-Policy"] = "no-referrer"
            response.headers["Cache-Control"] = "no-store"
        return response

    # -- the page --------------------------------------------------------------------------------------------
    async def _index(self, request: web.Request) -> web.Response:
        text = (resources.files(__package__) / "static" / "index.html").read_text(encoding="utf-8")
        return web.Response(text=text, content_type="text/html", charset="utf-8")

    async def _static(self, request: web.Request) -> web.Response:
        name = request.match_info["name"]
        kind = _STATIC.get(name)
        if kind is None:
            raise web.HTTPNotFound()
        data = (resources.files(__package__) / "static" / name).read_bytes()
        return web.Response(body=data, content_type=kind, charset="utf-8")

    def _hello(self) -> dict[str, Any]:
        snap = self._snapshot()
        current = {m["name"]: m["state"] for m in snap["machines"]}
        return {
            "type": "hello",
            "machines": [{**d, "svg": diagram.svg(d, current.get(d["name"]))} for d in self.source.machines()],
            "snapshot": snap,
        }

    def _machine_names(self) -> tuple[str, ...]:
        return tuple(d["name"] for d in self.source.machines())

    def _snapshot(self) -> dict[str, Any]:
        return {"type": "snapshot", **self.source.sample()}

    async def _ws(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=20, max_msg_size=64 * 1024)
        await ws.prepare(request)
        await ws.send_str(dumps(self._hello()))
        self.clients.add(ws)
        if self._wake is not None:
            self._wake.set()
        try:
            async for msg in ws:  # the page only listens here; commands come as POSTs
                if msg.type == WSMsgType.ERROR:
                    break
        finally:
            self.clients.discard(ws)
        return ws

    async def _push(self) -> None:
        """Sample and push at most RATE times a second, only while a page is connected."""
        last = ""
        assert self._wake is not None
        machines = self._machine_names()
        while True:
            await asyncio.sleep(1 / self.rate)
            if not self.clients:
                self._wake.clear()
                await self._wake.wait()
                last = ""
                continue
            names = self._machine_names()
            if names != machines:  # machines came (llfsm view): the pages draw them afresh
                machines = names
                await self._broadcast(self._hello())
            text = dumps(self._snapshot())
            if text != last:
                last = text
                await self._broadcast_text(text)

    async def _broadcast(self, data: dict[str, Any]) -> None:
        await self._broadcast_text(dumps(data))

    async def _broadcast_text(self, text: str) -> None:
        for ws in list(self.clients):
            try:
                await asyncio.wait_for(ws.send_str(text), 2)
            except Exception:  # a page gone or too slow: drop it, never wait for it
                self.clients.discard(ws)
                asyncio.get_running_loop().create_task(ws.close())

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
        except (CommandError, values.BadValue) as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)
        if self._wake is not None:
            self._wake.set()
        return web.json_response(result)

    async def _command(self, request: web.Request) -> web.Response:
        return await self._answer(request, lambda d: self.source.command(_text(d, "machine"), _text(d, "command")))

    async def _publish(self, request: web.Request) -> web.Response:
        return await self._answer(
            request, lambda d: self.source.publish(_text(d, "topic"), _text(d, "type"), _text(d, "values"))
        )

    async def _call(self, request: web.Request) -> web.Response:
        return await self._answer(
            request, lambda d: self.source.call(_text(d, "service"), _text(d, "type"), _text(d, "values"))
        )


async def _no_icon(request: web.Request) -> web.Response:
    return web.Response(status=204)


def _text(data: dict[str, Any], key: str) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise CommandError(f"{key} must be a string")
    return value


def _refuse(status: int, message: str) -> web.Response:
    return web.json_response({"success": False, "message": message}, status=status)
