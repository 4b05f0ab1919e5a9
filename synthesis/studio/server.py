"""The studio's web server: one page and a small JSON API, on 127.0.0.1 only, behind a random token.

Every request must carry the token (``?token=`` for the page and its assets, the ``X-Studio-Token``
header for the API), name this server in ``Host`` (127.0.0.1 or localhost and its port: a page of
another site that rebinds its DNS name to 127.0.0.1 is refused), and, when a browser sends an
``Origin``, come from this page's origin.  The page sends design values by name; it never sends a path:
the server names every file it writes, inside the folder chosen at start-up.
"""

from __future__ import annotations

import asyncio
import os
import re
import secrets
import signal
import socket
import threading
import time
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import uvicorn

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import JSONResponse, PlainTextResponse, Response
from starlette.routing import Route

from synthesis import kinds
from synthesis.core import interrupt
from synthesis.errors import AgrisynthError, OutputError
from synthesis.files import loads
from synthesis.result import create_new_text
from synthesis.studio.session import Session
from synthesis.studio.solver import GRACE, PAGE_MAX_STARTS, SolveJob

HOST = "127.0.0.1"
TOKEN_HEADER = "x-studio-token"
#: the page's own assets (shipped in the package: nothing is fetched from a network)
ASSETS = {"/studio.js": "application/javascript", "/studio.css": "text/css"}
#: the page may load and connect to nothing but this server
SECURITY_HEADERS = {
    "content-security-policy": "default-src 'none'; script-src 'self'; style-src 'self'; connect-src 'self'; "
                               "img-src 'self' data:; base-uri 'none'; form-action 'none'; frame-ancestors 'none'",
    "referrer-policy": "no-referrer", "x-content-type-options": "nosniff", "cache-control": "no-store",
    "x-frame-options": "DENY"}
#: largest request body read, bytes (design values are a few hundred)
MAX_BODY = 64 * 1024
#: most starts a solve from the page may ask for (an auto solve's budget too)
MAX_STARTS = PAGE_MAX_STARTS
#: seconds a request's body may take to arrive (a few hundred bytes from this machine take a millisecond): a client
#: that declares a body and never sends it is answered 408 and its connection closed, not held for ever
BODY_SECONDS = 10.0


class Refused(Exception):
    """A request this studio will not serve (wrong Host, Origin or token; a second solve): answered with
    ``status`` and the one-line message, never reaching the session."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


class Studio:
    """The session, the folder it writes into, the one solve job, and the ASGI app serving them."""

    def __init__(self, spec: Path, out: Path, port: int = 0, token: str | None = None):
        self.session = Session.open(spec)
        self.out = Path(out).resolve()
        self.token = token or secrets.token_urlsafe(24)
        # proto IPPROTO_TCP (not 0): asyncio turns Nagle's algorithm off only on sockets saying so; with it on,
        # each keep-alive answer waited ~40 ms for the browser's delayed ACK
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_STREAM, socket.IPPROTO_TCP)
        try:
            self.socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self.socket.bind((HOST, port))
        except OSError:
            self.socket.close()
            raise
        self.port = self.socket.getsockname()[1]
        # created only once the port is ours: a studio that cannot listen leaves no folder behind
        try:
            self.out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            self.socket.close()
            raise OutputError(f"--out {out}: cannot create the studio's folder ({exc.strerror})") from None
        self.job: SolveJob | None = None
        self.grace = GRACE                        # seconds a cancelled worker gets before it is killed
        self.body_seconds = BODY_SECONDS          # seconds a request's body may take to arrive
        self._solving = threading.Lock()          # "is a solve running?" and starting one are one step
        self._evaluating = threading.Lock()       # one evaluation at a time (two cores; CasADi calls)
        self._writing = threading.Lock()          # file names are picked and written one at a time
        self.app = self._guarded(Starlette(routes=[
            Route("/", self.page),
            *(Route(path, self.asset) for path in ASSETS),
            Route("/api/session", self.describe),
            Route("/api/evaluate", self.evaluate, methods=["POST"]),
            Route("/api/save", self.save, methods=["POST"]),
            Route("/api/solve", self.solve_status, methods=["GET"]),
            Route("/api/solve", self.solve, methods=["POST"]),
            Route("/api/solve/cancel", self.cancel, methods=["POST"]),
        ]))

    @property
    def url(self) -> str:
        return f"http://{HOST}:{self.port}/?token={self.token}"

    # -- the guard ------------------------------------------------------------------------------------------
    def _allowed_hosts(self) -> set[str]:
        names = {HOST, "localhost"}
        hosts = {f"{name}:{self.port}" for name in names}
        if self.port == 80:                # a browser leaves out the scheme's default port in Host and Origin
            hosts |= names
        return hosts

    def _check(self, scope) -> None:
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        host = headers.get("host", "")
        if host not in self._allowed_hosts():
            raise Refused(403, f"refused: Host {host[:80]!r} is not this studio ({HOST}:{self.port})")
        origin = headers.get("origin")
        if origin is not None and origin not in {f"http://{h}" for h in self._allowed_hosts()}:
            raise Refused(403, f"refused: Origin {origin[:80]!r} is not this studio's page")
        query = dict(p.split("=", 1) for p in scope.get("query_string", b"").decode("latin-1").split("&") if "=" in p)
        given = headers.get(TOKEN_HEADER) or query.get("token") or ""
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            raise Refused(403, "refused: missing or wrong studio token (open the address `agrisynth studio` printed)")

    def _guarded(self, app):
        async def guarded(scope, receive, send):
            if scope["type"] == "http":
                try:
                    self._check(scope)
                except Refused as exc:
                    response = PlainTextResponse(str(exc) + "\n", status_code=exc.status, headers=SECURITY_HEADERS)
                    await response(scope, receive, send)
                    return
            elif scope["type"] == "websocket":
                return
            await app(scope, receive, send)
        return guarded

    # -- the page -------------------------------------------------------------------------------------------
    def _asset(self, name: str) -> str:
        return resources.files("synthesis.studio").joinpath("static", name).read_text(encoding="utf-8")

    async def page(self, request: Request) -> Response:
        page = self._asset("index.html").replace("__TOKEN__", self.token)
        return Response(page, media_type="text/html; charset=utf-8", headers=SECURITY_HEADERS)

    async def asset(self, request: Request) -> Response:
        path = request.url.path
        return Response(self._asset(path.lstrip("/")), media_type=ASSETS[path], headers=SECURITY_HEADERS)

    # -- the API --------------------------------------------------------------------------------------------
    @staticmethod
    def _answer(data: Any, status: int = 200) -> JSONResponse:
        return JSONResponse(data, status_code=status, headers=SECURITY_HEADERS)

    async def _body(self, request: Request, keys: frozenset[str]) -> dict:
        if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
            raise AgrisynthError("request: expected Content-Type application/json")
        declared = request.headers.get("content-length", "")
        if declared.isdigit() and int(declared) > MAX_BODY:
            raise AgrisynthError(f"request: body of {declared} bytes is larger than {MAX_BODY}")
        try:
            raw = await asyncio.wait_for(self._received(request), self.body_seconds)
        except asyncio.TimeoutError:
            raise Refused(408, f"request: the body did not arrive within {self.body_seconds:g} s") from None
        try:
            data = loads(raw)
        except ValueError as exc:       # not JSON, NaN, nested too deeply (a RecursionError was a 500)
            raise AgrisynthError(f"request: not JSON ({str(exc)[:60]})") from None
        if not isinstance(data, dict):
            raise AgrisynthError("request: expected a JSON object")
        unknown = sorted(str(k)[:40] for k in data if k not in keys)
        if unknown:
            raise AgrisynthError(f"request: unknown key {unknown[0]!r} (expected: {', '.join(sorted(keys)) or 'none'})")
        return data

    @staticmethod
    async def _received(request: Request) -> bytes:
        """The request's body, read only up to MAX_BODY + 1 bytes (a larger one is refused, not held)."""
        raw = bytearray()
        async for chunk in request.stream():
            raw += chunk
            if len(raw) > MAX_BODY:
                raise AgrisynthError(f"request: body of more than {MAX_BODY} bytes (at most {MAX_BODY})")
        return bytes(raw)

    async def _handle(self, request: Request, work, keys: frozenset[str] = frozenset()) -> JSONResponse:
        """Run ``work(body)`` off the event loop; ``keys``: the only keys a POST body may have."""
        try:
            body = await self._body(request, keys) if request.method == "POST" else {}
            return self._answer(await run_in_threadpool(work, body))
        except Refused as exc:
            response = self._answer({"error": str(exc)}, exc.status)
            if exc.status == 408:       # the rest of the body may still come: the connection is not reused
                response.headers["connection"] = "close"
            return response
        except AgrisynthError as exc:
            return self._answer({"error": str(exc)}, 400)
        except Exception as exc:          # a bug, not bad input: one line to the page, never a traceback
            first = (str(exc).splitlines() or [""])[0][:200]
            return self._answer({"error": f"internal error: {type(exc).__name__}: {first}"}, 500)

    async def describe(self, request: Request) -> JSONResponse:
        return await self._handle(request, lambda body: self.session.describe() | {"folder": str(self.out)})

    async def evaluate(self, request: Request) -> JSONResponse:
        def work(body):
            with self._evaluating:
                return self.session.evaluate(body.get("values", {}), body.get("grid", "fine"))
        return await self._handle(request, work, frozenset({"values", "grid"}))

    def _free_name(self, what: str) -> str:
        """``<spec name>_<what>_<n>``: the first n with neither a spec file nor a folder of that name."""
        base = re.sub(r"[^A-Za-z0-9_.-]", "_", self.session.loaded.name)[:80]
        n = 1
        # lexists: a dangling link holds its name too (exists() said it free, and the write found it taken for ever)
        while (os.path.lexists(self.out / f"{base}_{what}_{n}.toml")
               or os.path.lexists(self.out / f"{base}_{what}_{n}")):
            n += 1
        return f"{base}_{what}_{n}"

    def _write_spec(self, values: dict[str, float], what: str, note: str) -> tuple[str, Path]:
        """The spec of ``values`` written under the first free name; a name another process (a second studio with
        the same --out) takes between the look and the write is left to it, and the next one tried."""
        with self._writing:
            while True:
                name = self._free_name(what)
                path = self.out / f"{name}.toml"
                try:
                    create_new_text(path, self.session.spec_text(values, name, note, self.out))
                except FileExistsError:
                    continue
                return name, path

    async def save(self, request: Request) -> JSONResponse:
        def work(body):
            values = self.session.values_of(body.get("values", {}))
            name, path = self._write_spec(values, "saved", "saved from agrisynth studio: the free variables' "
                                                           "start values are the page's values")
            return {"file": path.name, "name": name, "folder": str(self.out)}
        return await self._handle(request, work, frozenset({"values"}))

    async def solve(self, request: Request) -> JSONResponse:
        def work(body):
            if not self.session.free:
                raise AgrisynthError(f"kind {self.session.kind}: the spec has no free design variable to solve for")
            if not kinds.get(self.session.kind).solves:
                raise AgrisynthError(f"kind {self.session.kind} has nothing to optimise (check-only)")
            starts = body.get("starts", 1)
            if isinstance(starts, str) and starts.strip().lower() == "auto":
                starts = "auto"             # --starts auto: batches until the confidence rule or its budget
            elif not isinstance(starts, int) or isinstance(starts, bool) or not 1 <= starts <= MAX_STARTS:
                raise AgrisynthError(f"starts: expected a whole number 1..{MAX_STARTS} or auto (the page's cap; "
                                     f"`agrisynth solve` takes more), got {str(starts)[:20]!r}")
            values = self.session.values_of(body.get("values", {}))
            with self._solving:
                if self.job is not None and self.job.running:
                    raise Refused(409, f"a solve is running ({self.job.run_name}); cancel it or wait")
                name, path = self._write_spec(values, "solve", "solved from here by agrisynth studio: start 0 is "
                                                               "the page's values")
                self.job = SolveJob(name, path, self.out, starts)
                self.job.start()
                return self.job.status()
        return await self._handle(request, work, frozenset({"values", "starts"}))

    async def solve_status(self, request: Request) -> JSONResponse:
        return await self._handle(request, lambda body: self.job.status() if self.job else {"state": "idle"})

    async def cancel(self, request: Request) -> JSONResponse:
        """Ask the running solve to stop and answer at once ("cancelling"); the page polls /api/solve."""
        def work(body):
            if self.job is None:
                return {"state": "idle"}
            self.job.cancel(self.grace)
            return self.job.status()
        return await self._handle(request, work)

    # -- serving --------------------------------------------------------------------------------------------
    def stop_job(self) -> None:
        """Cancel a running solve and return once its worker is gone (killed after the grace period if it does
        not stop): every way the studio ends goes through here, so no worker outlives it."""
        job = self.job
        if job is not None and job.running:
            job.cancel(self.grace)
            job.wait(self.grace + 5)

    def start_in_thread(self) -> "threading.Thread":
        """Serve from a background thread (tests, benchmarks); returns once the server listens."""
        self._server = self.server()
        self._thread = threading.Thread(target=self._server.run, kwargs={"sockets": [self.socket]}, daemon=True)
        self._thread.start()
        while not self._server.started:
            if not self._thread.is_alive():
                raise RuntimeError("the studio server did not start")
            time.sleep(0.01)
        return self._thread

    def stop(self) -> None:
        """Stop serving (the server's shutdown cancels a running solve) and wait until it has."""
        if getattr(self, "_server", None) is not None:
            self._server.should_exit = True
            self._thread.join(self.grace + 30)
        self.stop_job()

    def server(self, on_listening: Callable[[], None] | None = None):
        """The uvicorn server of the app; ``on_listening`` is called once its socket listens (the address printed
        then is answered at once)."""
        studio = self

        class Server(uvicorn.Server):
            #: signals the studio was started with ignored (serve sets it): they stay ignored
            ignored_signals: frozenset = frozenset()

            def handle_exit(self, sig, frame) -> None:
                # uvicorn takes SIGINT and SIGTERM even when the parent ignored them, then re-raises them under
                # the restored (ignored) disposition: the process ended with exit 0 and no word instead of
                # keeping on serving, as a process that ignores a signal does (`agrisynth studio spec &` from
                # a script ignores SIGINT)
                if sig not in self.ignored_signals:
                    super().handle_exit(sig, frame)

            async def startup(self, sockets=None) -> None:
                await super().startup(sockets)
                if self.started and on_listening is not None:
                    on_listening()

            async def shutdown(self, sockets=None) -> None:
                # here, not after run() returns: on SIGTERM uvicorn re-raises the signal as soon as it has shut
                # down, which ends the process before any code after run() would cancel the solve
                await super().shutdown(sockets)
                await asyncio.to_thread(studio.stop_job)

        config = uvicorn.Config(self.app, log_level="warning", access_log=False, lifespan="off", ws="none")
        return Server(config)

    def serve(self, on_listening: Callable[[], None] | None = None) -> None:
        """Serve until Ctrl-C, SIGTERM or SIGHUP; a running solve is cancelled on the way out, then the signal
        has its usual effect (Ctrl-C: KeyboardInterrupt; SIGTERM, SIGHUP: the process ends by it).  ``on_listening``:
        called once the socket listens (where the command prints the page's address).  A signal the
        studio was started with ignored stays ignored: under ``nohup`` (SIGHUP ignored) it keeps serving when its
        terminal closes."""
        # the program's start-up handlers give way: the studio's signals act as the process was started with (uvicorn
        # takes SIGINT and SIGTERM while it serves and re-raises them under these dispositions)
        interrupt.restore()
        server = self.server(on_listening)
        server.ignored_signals = frozenset(sig for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
                                           if signal.getsignal(sig) is signal.SIG_IGN)
        # uvicorn shuts down gracefully on SIGINT and SIGTERM only; a closed terminal (SIGHUP) would otherwise
        # end the studio at once and leave its worker running.  An ignored SIGHUP is the user's choice (nohup:
        # outlive the terminal), so it stays ignored
        hung_up = []

        def hang_up(sig, frame):
            hung_up.append(sig)
            server.should_exit = True

        on_hang_up = signal.SIGHUP not in server.ignored_signals
        previous = signal.signal(signal.SIGHUP, hang_up) if on_hang_up else None
        try:
            server.run(sockets=[self.socket])
        finally:
            self.stop_job()
            if on_hang_up:
                signal.signal(signal.SIGHUP, signal.SIG_DFL if previous is None else previous)
        if hung_up:
            signal.raise_signal(signal.SIGHUP)
