"""The editor's Run and Stop (docs/edit.md): `llfsm run ... --web 127.0.0.1:0` as a child
process, its page's messages relayed to the editor's pages.

Machine code runs in the child, never in the editor's process, and Stop ends it whatever the
code does.  The child's own page server speaks the live view's protocol (docs/view.md); each
of its messages reaches the editor's pages as `{"type": "live", "data": MESSAGE}`, so the
editor's diagrams become the live view, and the page's commands (Suspend, Resume, Restart)
go back to the child's `/api/command`, its debugger's controls to `/api/debug/...`.  The child
binds loopback with no token, as any run does; only this process talks to it.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import sys
from collections import deque
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import aiohttp

#: `--node` names are words (they become arguments, never a shell's).
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")
#: Seconds the child may take to print its page's address.
START_TIMEOUT = 60.0
#: Lines of the child's output kept (and sent to pages as they come).
OUTPUT_LINES = 200
#: A sim-clock run without a duration would run flat out forever.
SIM_DEFAULT_DURATION = 10.0


class RunError(Exception):
    """Run or a command could not be done (one line for the page)."""


class RunRelay:
    """At most one child run at a time."""

    def __init__(self, broadcast: Callable[[dict[str, Any]], Awaitable[None]]) -> None:
        self._broadcast = broadcast
        self.proc: asyncio.subprocess.Process | None = None
        self.url = ""
        self.state = "idle"
        self.message = ""
        self.machines: list[str] = []
        self.output: deque[str] = deque(maxlen=OUTPUT_LINES)
        self._tasks: list[asyncio.Task[None]] = []
        self._session: aiohttp.ClientSession | None = None

    def status(self) -> dict[str, Any]:
        return {"state": self.state, "message": self.message, "machines": self.machines, "output": list(self.output)}

    async def start(self, paths: list[Path], clock: object, nodes: object, duration: object) -> dict[str, Any]:
        if clock not in ("sim", "wall"):
            raise RunError("the clock is sim or wall")
        if not isinstance(nodes, list) or not all(isinstance(n, str) and _WORD.fullmatch(n) for n in nodes):
            raise RunError("nodes are names such as turtlesim")
        if duration in (None, ""):
            duration = SIM_DEFAULT_DURATION if clock == "sim" else None
        if duration is not None and (
            isinstance(duration, bool) or not isinstance(duration, int | float) or not 0 < duration <= 86400
        ):
            raise RunError("the duration is a number of seconds, at most a day")
        if not paths:
            raise RunError("no machine is open")
        await self.stop()
        argv = [sys.executable, "-m", "llfsm", "run", "--clock", str(clock), *map(str, paths)]
        for n in nodes:
            argv += ["--node", n]
        if duration is not None:
            argv += ["--duration", f"{float(duration)}s"]
        argv += ["--web", "127.0.0.1:0"]
        self.output.clear()
        self.machines = [p.name.removesuffix(".machine") for p in paths]
        self.state, self.message = "starting", ""
        self.proc = await asyncio.create_subprocess_exec(
            *argv, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
        )
        assert self.proc.stdout is not None and self.proc.stderr is not None
        try:
            self.url = await asyncio.wait_for(self._address(self.proc.stderr), START_TIMEOUT)
        except (TimeoutError, RunError) as e:
            await self.stop()
            self.state = "failed"
            self.message = str(e) or "the run did not start"
            raise RunError(self.message) from None
        self.state = "running"
        self._tasks = [
            asyncio.get_running_loop().create_task(self._lines(self.proc.stdout)),
            asyncio.get_running_loop().create_task(self._lines(self.proc.stderr)),
            asyncio.get_running_loop().create_task(self._relay()),
        ]
        await self._tell()
        return self.status()

    async def _address(self, stream: asyncio.StreamReader) -> str:
        """The child's page address, from its stderr (what it says before is kept as output)."""
        while True:
            raw = await stream.readline()
            if not raw:
                said = "; ".join(list(self.output)[-3:])
                raise RunError(f"the run ended before it served its page: {said}" if said else "the run ended")
            line = raw.decode("utf-8", "replace").rstrip()
            m = re.search(r"http://\S+", line)
            if m:
                return m.group(0)
            self.output.append(line)

    async def _lines(self, stream: asyncio.StreamReader) -> None:
        while True:
            raw = await stream.readline()
            if not raw:
                return
            line = raw.decode("utf-8", "replace").rstrip()[:1000]
            self.output.append(line)
            await self._broadcast({"type": "output", "line": line})

    async def _relay(self) -> None:
        """The child's page messages to ours, until its server closes (the run ended)."""
        ws_url = self.url.replace("http://", "ws://", 1).split("?", 1)[0].rstrip("/") + "/ws"
        self._session = aiohttp.ClientSession()
        try:
            async with self._session.ws_connect(ws_url, max_msg_size=64 << 20) as ws:
                async for msg in ws:
                    if msg.type != aiohttp.WSMsgType.TEXT:
                        break
                    await self._broadcast({"type": "live", "data": json.loads(msg.data)})
        except (aiohttp.ClientError, OSError, ValueError) as e:
            self.message = f"the run's page could not be followed: {e}"
        finally:
            await self._session.close()
            self._session = None
        if self.proc is not None:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.proc.wait(), 5)
        code = self.proc.returncode if self.proc is not None else None
        if self.state == "running":
            self.state = "ended"
            self.message = self.message or (
                f"the run ended (exit status {code})" if code is not None else "the run ended"
            )
            await self._tell()

    async def command(self, data: dict[str, Any]) -> dict[str, Any]:
        """A page's Suspend / Resume / Restart, to the running child's page server."""
        body = {"machine": str(data.get("machine", "")), "command": str(data.get("command", ""))}
        return await self._forward("/api/command", body)

    async def debug(self, what: str, data: dict[str, Any]) -> dict[str, Any]:
        """A page's debugger control (Pause, Step ringlet, a breakpoint, a value set, the History
        slider: docs/debug.md), to the running child's `/api/debug/WHAT`."""
        return await self._forward(f"/api/debug/{what}", data)

    async def _forward(self, path: str, body: dict[str, Any]) -> dict[str, Any]:
        if self.state != "running" or not self.url:
            raise RunError("nothing is running: press Run first")
        async with (
            aiohttp.ClientSession() as s,
            s.post(self.url.split("?", 1)[0].rstrip("/") + path, json=body) as r,
        ):
            result: dict[str, Any] = await r.json()
            return result

    async def stop(self) -> None:
        proc, self.proc = self.proc, None
        stopping = self.state in ("running", "starting")
        if stopping:
            self.state = "stopping"  # the relay, seeing the child's page close, must not call it ended
        if proc is not None and proc.returncode is None:
            proc.terminate()
            try:
                await asyncio.wait_for(proc.wait(), 10)
            except TimeoutError:
                proc.kill()
                await proc.wait()
        for t in self._tasks:
            t.cancel()
        self._tasks = []
        if stopping:
            self.state, self.message = "stopped", "stopped by Stop"
            await self._tell()

    async def _tell(self) -> None:
        await self._broadcast({"type": "run", **self.status()})
