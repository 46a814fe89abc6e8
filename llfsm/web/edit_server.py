"""`llfsm edit`'s server (docs/edit.md): the view's server (llfsm.web.server.WebServer: its
thread, its security, its static files) with the editor's page and requests.

Requests are JSON POSTs; what changes on disk (by a page, by undo, by another program) goes to
every page over the WebSocket as `changed`.  All work on the machines (reading, `check`,
drawing, writing through llfsm.edit) happens on one worker thread, so two requests never
change a machine at once and the event loop never waits on the disk.  The folders are looked
at twice a second for another program's writes (a stat per file: no watcher library needed,
and nothing is missed on file systems without inotify).

Run starts `llfsm run ... --web 127.0.0.1:0` as a child process (machine code never runs in
the editor's process) and relays its page's messages to the editor's pages as `live`, and
the page's commands back to it (llfsm.web.run_relay).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import aiohttp
from aiohttp import WSMsgType, web

from .run_relay import RunError, RunRelay
from .server import WebServer
from .source import CommandError, dumps
from .workspace import UNCHECKED, Workspace, WorkspaceError, WriteConflict, digest

#: Seconds between two looks at the disk for another program's changes.
POLL = 0.5
#: Looks at the disk between two searches of the opened folders for new machines.
RESCAN_EVERY = 4


class EditServer(WebServer):
    """Serves a Workspace on a background thread (start() returns the page's URL)."""

    PAGE = "edit.html"
    #: A file of the largest size a machine's file may have (1 MiB), as JSON.
    MAX_BODY = 3 * 1024 * 1024

    def __init__(self, workspace: Workspace, host: str = "127.0.0.1", port: int = 0, token: str | None = None) -> None:
        super().__init__(workspace, host, port, token)
        self.workspace = workspace
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="llfsm-edit")
        self.run = RunRelay(self._broadcast)

    def start(self) -> str:
        url = super().start()
        # the page opens the first machine at once: check and draw it meanwhile
        first = next(iter(self.workspace.machines), None)
        if first is not None:
            self._worker.submit(self.workspace.full, first)
        return url

    def stop(self) -> None:
        loop = self._loop
        if loop is not None:
            try:
                asyncio.run_coroutine_threadsafe(self.run.stop(), loop).result(10)
            except Exception:  # stopping must never fail
                pass
        super().stop()
        self._worker.shutdown(wait=False, cancel_futures=True)

    def _routes(self, app: web.Application) -> None:
        for name, handler in {
            "machine": self._machine,
            "op": self._op,
            "write": self._write,
            "new": self._new,
            "undo": self._undo,
            "redo": self._redo,
            "run": self._run,
            "stop": self._stop_run,
            "command": self._command,
        }.items():
            app.router.add_post(f"/api/{name}", handler)
        app.router.add_post("/api/debug/{what}", self._debug)

    async def _farewell(self) -> None:
        await self._broadcast({"type": "bye"})

    async def _do(self, fn: Callable[..., Any], *args: Any) -> Any:
        return await asyncio.get_running_loop().run_in_executor(self._worker, fn, *args)

    # -- the WebSocket ---------------------------------------------------------------------------------
    def _greeting(self) -> dict[str, Any]:
        """The editor's first message to a page (and again when machines appear)."""
        ws = self.workspace
        return {
            "type": "hello",
            "page": "edit",
            "folders": [str(f) for f in ws.folders],
            "machines": ws.summary(),
            "undo": len(ws.undo_stack),
            "redo": len(ws.redo_stack),
            "run": self.run.status(),
        }

    async def _ws(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=20, max_msg_size=64 * 1024)
        await ws.prepare(request)
        await ws.send_str(dumps(await self._do(self._greeting)))
        self.clients.add(ws)
        try:
            async for msg in ws:  # the page only listens; requests come as POSTs
                if msg.type == WSMsgType.ERROR:
                    break
        finally:
            self.clients.discard(ws)
        return ws

    async def _push(self) -> None:
        """Look at the disk for another program's changes and tell the pages."""
        n = 0
        while True:
            await asyncio.sleep(POLL)
            n += 1
            try:
                changed = await self._do(self.workspace.poll)
                found = n % RESCAN_EVERY == 0 and await self._do(self.workspace.rescan)
                for key, files in changed.items():
                    await self._changed(key, files, "disk", "")
                if found:
                    await self._broadcast(await self._do(self._greeting))
            except Exception as e:  # said once; the next look goes on
                self._warn(f"watching the folders failed: {type(e).__name__}: {e}", "poll")

    async def _changed(self, key: str, files: list[str], origin: str, summary: str) -> None:
        ws = self.workspace
        await self._broadcast(
            {
                "type": "changed",
                "machine": key,
                "files": files,
                "origin": origin,
                "summary": summary,
                "undo": len(ws.undo_stack),
                "redo": len(ws.redo_stack),
                "machines": ws.summary(),
            }
        )

    # -- requests ----------------------------------------------------------------------------------------
    async def _editing(self, request: web.Request, action: Callable[[dict[str, Any]], Any]) -> web.Response:
        """Run a request's action on the worker; a refusal is 400 with its one line."""
        try:
            data = await self._json(request)
            return web.json_response({"success": True, **(await self._do(action, data))})
        except WriteConflict as e:
            return web.json_response(
                {
                    "success": False,
                    "conflict": True,
                    "file": e.name,
                    "disk": e.disk,
                    "version": digest(e.disk) if e.disk is not None else None,
                    "message": str(e),
                },
                status=409,
            )
        except (WorkspaceError, CommandError) as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)

    async def _after(self, result: dict[str, Any], origin: str = "page") -> None:
        """Every page hears of what a request changed (a write that changed nothing: nobody)."""
        if result.get("files") or result.get("new"):
            await self._changed(result["key"], result.get("files", []), origin, result.get("message", ""))

    async def _machine(self, request: web.Request) -> web.Response:
        return await self._editing(request, lambda d: {"machine": self.workspace.full(d.get("machine"))})

    def _changing(self, d: dict[str, Any], summary: str, files: list[str]) -> dict[str, Any]:
        key = self.workspace.machine(d.get("machine")).key
        return {"key": key, "message": summary, "files": files, "machine": self.workspace.full(key)}

    async def _op(self, request: web.Request) -> web.Response:
        def act(d: dict[str, Any]) -> dict[str, Any]:
            args = d.get("args", {})
            if not isinstance(args, dict) or not isinstance(d.get("op"), str):
                raise WorkspaceError("an operation has a name (op) and arguments (args)")
            return self._changing(d, *self.workspace.operate(d.get("machine"), d["op"], args))

        return await self._answered(request, act)

    async def _write(self, request: web.Request) -> web.Response:
        def act(d: dict[str, Any]) -> dict[str, Any]:
            summary, files = self.workspace.write(
                d.get("machine"), d.get("file"), d.get("text"), d.get("base", UNCHECKED)
            )
            return self._changing(d, summary, files)

        return await self._answered(request, act)

    async def _new(self, request: web.Request) -> web.Response:
        def act(d: dict[str, Any]) -> dict[str, Any]:
            key = self.workspace.new_machine(d.get("name"), d.get("folder", 0), d.get("states"))
            return {
                "key": key,
                "message": f"made machine {key}",
                "new": True,
                "files": [],
                "machine": self.workspace.full(key),
            }

        return await self._answered(request, act)

    async def _undo(self, request: web.Request) -> web.Response:
        return await self._answered(request, lambda d: self._stepped(*self.workspace.undo()))

    async def _redo(self, request: web.Request) -> web.Response:
        return await self._answered(request, lambda d: self._stepped(*self.workspace.redo()))

    def _stepped(self, key: str, summary: str, files: list[str]) -> dict[str, Any]:
        full = self.workspace.full(key) if key in self.workspace.machines else None
        return {"key": key, "message": summary, "files": files, "machine": full}

    async def _answered(self, request: web.Request, act: Callable[[dict[str, Any]], dict[str, Any]]) -> web.Response:
        """A changing request: answered to its page, then `changed` to every page."""
        box: dict[str, Any] = {}

        def run(d: dict[str, Any]) -> dict[str, Any]:
            box.update(act(d))
            return box

        response = await self._editing(request, run)
        if box:
            await self._after(box)
        return response

    # -- Run and Stop ------------------------------------------------------------------------------------
    async def _run(self, request: web.Request) -> web.Response:
        try:
            d = await self._json(request)
            keys = d.get("machines") or list(self.workspace.machines)
            if not isinstance(keys, list):
                raise WorkspaceError("machines is a list of the open machines' names")
            paths = [self.workspace.machine(k).path for k in keys]
            status = await self.run.start(paths, d.get("clock", "wall"), d.get("nodes", []), d.get("duration"))
        except (WorkspaceError, CommandError, RunError) as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)
        return web.json_response({"success": True, "message": "running", "run": status})

    async def _stop_run(self, request: web.Request) -> web.Response:
        await self.run.stop()
        return web.json_response({"success": True, "message": "stopped", "run": self.run.status()})

    async def _debug(self, request: web.Request) -> web.Response:
        """The debugger's controls of the run Run started (relayed as they are: the child's
        page server checks them)."""
        what = request.match_info["what"]
        try:
            d = await self._json(request)
            result = await self.run.debug(what, d)
        except (CommandError, RunError) as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)
        except aiohttp.ContentTypeError:  # the child knows no such request
            return web.json_response({"success": False, "message": f"unknown request {what!r}"}, status=404)
        return web.json_response(result)

    async def _command(self, request: web.Request) -> web.Response:
        try:
            d = await self._json(request)
            result = await self.run.command(d)
        except (CommandError, RunError) as e:
            return web.json_response({"success": False, "message": str(e)}, status=400)
        return web.json_response(result)
