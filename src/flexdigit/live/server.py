"""The live page's server: Starlette (ASGI) on uvicorn, one WebSocket, three packaged files.

Why this stack: a small, well-kept ASGI server with WebSockets streams the 50 Hz loop to a hand-written canvas page
in a few hundred lines with no build step and nothing fetched from the internet, where Bokeh or Panel would bring
a large JavaScript runtime and their own server for the same three plots.

Safety (issue 12):

- binds 127.0.0.1 unless told otherwise; another host needs ``allow_remote`` (``--allow-remote``) and a warning is
  printed;
- only the packaged assets are served, from a fixed table of three names read once from the package: no part of a
  request's path reaches the file system;
- the WebSocket checks its ``Origin`` against the server's own address and refuses anything else (a page on another
  site cannot drive the rig through the user's browser);
- every client message is size-limited, rate-limited (a token bucket) and validated and clamped
  (:func:`flexdigit.live.session.validate_request`); a bad one gets an error message back, never an exception;

Resources (issue 22): each page has its own budget and its own bounded queue, and nothing one page does can slow
or lock out another:

- the request budget is each page's own (:data:`RATE_PER_PAGE`); there is no shared one that two flooding pages
  could drain for everyone. A page that keeps sending past its budget (:data:`FLOOD_DROPPED` requests dropped
  beyond what the budget refills) is disconnected (close 1008);
- each page has one frame in flight at most: the next is built only when the last has gone out, and never while
  more than :data:`MAX_QUEUED_BYTES` wait in its connection's buffer (frames are skipped, not queued). A page that
  does not take a frame for :data:`SLOW_DROP_S` is disconnected, and so is one that does not answer the
  WebSocket ping within :data:`PING_TIMEOUT_S` (a client that never reads never answers: the kernel's socket
  buffers would otherwise hide it for a minute). Its place (one of :data:`MAX_PAGES`) is free again within
  seconds, so pages that stopped reading cannot keep the surgeon's page out;
- a page never loses its place to a newer one: the page holding the setpoint (the controlling page) stays
  connected however many others come and go, and a page beyond :data:`MAX_PAGES` is refused (1013, try again;
  the packaged page retries every half second).
- when the last page disconnects the digit is relaxed, and when the server stops (Ctrl-C, SIGTERM) the session
  sends the safe command, closes the port and closes the recording (:class:`~flexdigit.live.session.LiveSession`).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import json
import signal
import socket
import struct
import sys
import threading
import time
from importlib import resources
from typing import Any

from flexdigit.errors import ParameterError
from flexdigit.live.session import MAX_REQUEST_BYTES

__all__ = ["make_app", "serve", "bind", "check_host", "origin_allowed", "ASSETS", "TokenBucket"]

#: URL path -> (packaged file, media type). The only files the server ever sends.
ASSETS = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/app.js": ("app.js", "text/javascript; charset=utf-8"),
    "/app.css": ("app.css", "text/css; charset=utf-8"),
}
#: Page updates per second pushed to each client (the loop makes 50 samples a second; the shape comes at 25).
UPDATE_HZ = 30.0
#: Requests a second from one page (``burst`` at once). Each page's own: no budget is shared between pages.
RATE_PER_PAGE, BURST_PER_PAGE = 20.0, 40.0
#: Requests dropped past a page's budget (beyond what the budget refills) before the page is disconnected as
#: flooding; a burst of a hundred clicks is told to slow down, a page sending without pause is cut off.
FLOOD_DROPPED = 200.0
#: Bytes waiting in a page's connection buffer above which its frames are skipped rather than queued.
MAX_QUEUED_BYTES = 64 * 1024
#: A page that has not taken a frame (its buffer full) for this long, s, is disconnected.
SLOW_DROP_S = 3.0
#: WebSocket keepalive: a ping every PING_INTERVAL_S, unanswered after PING_TIMEOUT_S disconnects the page, s.
PING_INTERVAL_S, PING_TIMEOUT_S = 1.0, 2.0
#: Pages served at once; one more is refused (WebSocket close 1013, "try again later").
MAX_PAGES = 8
#: How long a flooding page has to reply to its close (1008) before it is dropped, s.
CLOSE_GRACE_S = 1.0
#: The largest WebSocket frame read at all (bytes): a bigger one closes the connection (1009) before it is buffered.
MAX_FRAME_BYTES = 4096


def _asset_bytes() -> dict[str, tuple[bytes, str]]:
    root = resources.files("flexdigit.live").joinpath("static")
    return {path: (root.joinpath(name).read_bytes(), media) for path, (name, media) in ASSETS.items()}


def check_host(host: str, allow_remote: bool = False) -> str:
    """Return ``host`` if it is a loopback address (or ``localhost``), or any address with ``allow_remote``."""
    if not isinstance(host, str) or not host:
        raise ParameterError(f"--host must be an address. Got {host!r}.")
    loopback = host == "localhost"
    try:
        loopback = loopback or ipaddress.ip_address(host).is_loopback
    except ValueError:
        if host != "localhost":
            raise ParameterError(f"--host must be an IP address or localhost. Got {host!r}.") from None
    if not loopback and not allow_remote:
        raise ParameterError(
            f"--host {host} would let other machines drive the rig; pass --allow-remote to mean it "
            "(the default 127.0.0.1 serves this machine only)"
        )
    return host


class TokenBucket:
    """At most ``rate`` messages a second on average, ``burst`` at once (monotonic clock, injectable)."""

    def __init__(self, rate: float = 20.0, burst: float = 40.0, clock=time.monotonic) -> None:
        self.rate, self.burst, self.clock = rate, burst, clock
        self.tokens, self.last = burst, clock()

    def take(self) -> bool:
        now = self.clock()
        self.tokens = min(self.burst, self.tokens + (now - self.last) * self.rate)
        self.last = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False


def _dumps(obj: Any) -> str:
    return json.dumps(obj, allow_nan=False, separators=(",", ":"))


def origin_allowed(origin: str | None, host_header: str | None, allowed_origins: set[str], any_address: bool) -> bool:
    """Whether a WebSocket from a page at ``origin`` may drive the rig.

    ``origin`` must be one of ``allowed_origins`` (the server's own addresses). A server bound to every address
    (``--host 0.0.0.0 --allow-remote``) cannot know the address a remote browser used, so there the page's own
    origin must be the address the request was sent to (``Host``), and that an IP address or this machine's
    name: a name that resolves here only by another site's doing (DNS rebinding) is refused.
    """
    if not origin:
        return False
    if origin in allowed_origins:
        return True
    if not any_address or not host_header or origin != f"http://{host_header}":
        return False
    from urllib.parse import urlsplit

    try:
        name = urlsplit(f"//{host_header}").hostname or ""
    except ValueError:
        return False
    try:
        ipaddress.ip_address(name)
        return True
    except ValueError:
        return name.lower() in {socket.gethostname().lower(), socket.getfqdn().lower()}


def make_app(session, allowed_origins: set[str], *, any_address: bool = False):
    """The Starlette app serving ``session`` to pages whose ``Origin`` is in ``allowed_origins`` (see
    :func:`origin_allowed` for a server bound to every address)."""
    from contextlib import asynccontextmanager

    from starlette.applications import Starlette
    from starlette.responses import Response
    from starlette.routing import Route, WebSocketRoute
    from starlette.websockets import WebSocket

    assets = _asset_bytes()
    # 'self' covers the page's own ws:// address (CSP level 3)
    csp = (
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
        "base-uri 'none'; form-action 'none'; frame-ancestors 'none'"
    )

    async def asset(request):
        body, media = assets[request.url.path]
        headers = {"Content-Security-Policy": csp, "X-Content-Type-Options": "nosniff", "Cache-Control": "no-store"}
        return Response(body, media_type=media, headers=headers)

    pages = [0]

    async def stream(websocket: WebSocket) -> None:
        headers = websocket.headers
        if not origin_allowed(headers.get("origin"), headers.get("host"), allowed_origins, any_address):
            await websocket.close(code=1008)  # policy violation: another site's page, or no Origin at all
            return
        if pages[0] >= MAX_PAGES:
            await websocket.accept()
            await websocket.close(code=1013, reason=f"at most {MAX_PAGES} pages at once")  # try again later
            return
        pages[0] += 1
        try:
            await websocket.accept()
        except BaseException:
            pages[0] -= 1
            raise
        session.connected()
        try:
            await _Page(websocket, session).serve()
        finally:
            pages[0] -= 1
            session.disconnected()

    @asynccontextmanager
    async def lifespan(app):
        session.start()
        try:
            yield
        finally:
            session.stop()

    routes = [Route(path, asset) for path in ASSETS] + [WebSocketRoute("/ws", stream)]
    return Starlette(routes=routes, lifespan=lifespan)


class _Page:
    """One accepted page's connection: its own request budget, its frames pushed one at a time, its requests
    answered one by one (issue 22: nothing one page does slows or locks out another)."""

    def __init__(self, websocket, session) -> None:
        self.websocket = websocket
        self.session = session
        self.bucket = TokenBucket(RATE_PER_PAGE, BURST_PER_PAGE)
        self.patience = TokenBucket(RATE_PER_PAGE, FLOOD_DROPPED)  # requests this page may have dropped
        self.told_at = -1.0  # when this page was last told to slow down (once a second at most)
        self.transport = _transport(websocket)

    async def serve(self) -> None:
        """Greet the page, push it frames and answer its requests until it goes away."""
        from starlette.websockets import WebSocketDisconnect

        sender = None
        try:
            await self.send(_dumps(self.session.hello()))
            sender = asyncio.create_task(self.push())
            await self.receive()
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass  # the page went away mid-send
        finally:
            if sender is not None:
                sender.cancel()

    def drop(self, why: str) -> None:
        """Disconnect this page at once: its buffer is not flushed first (a page that does not read never
        takes it), so its place and memory are free now; the receive loop then sees the disconnect."""
        transport = self.transport
        if transport is not None:
            sock = transport.get_extra_info("socket")
            if sock is not None:  # reset, not closed: the kernel drops the unsent frames now too
                with contextlib.suppress(OSError):
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            transport.abort()
        else:  # pragma: no cover - another ASGI server: close as politely as it allows
            asyncio.ensure_future(self.websocket.close(code=1008, reason=why))

    async def send(self, text: str) -> None:
        from starlette.websockets import WebSocketDisconnect

        try:
            # in this task (asyncio.timeout, not wait_for's task per message): a page's burst of requests is
            # answered in one pass of the event loop, so its reading, paused by uvicorn until the app has taken
            # its requests, resumes at once and the keepalive's pong behind them is read in time on a busy server
            async with asyncio.timeout(SLOW_DROP_S):
                await self.websocket.send_text(text)
        except TimeoutError:
            self.drop("not reading")
            raise WebSocketDisconnect(1008) from None

    async def error(self, message: str) -> None:
        await self.send(_dumps({"type": "error", "message": message}))

    async def push(self) -> None:
        """Send the page a frame every 1/:data:`UPDATE_HZ` s, one in flight at most, skipping frames while its
        buffer is full; drop the page when it has taken none for :data:`SLOW_DROP_S`. Ends quietly when the page
        has gone (closed, dropped or flooding) rather than leaving asyncio a task error to print."""
        from starlette.websockets import WebSocketDisconnect

        with contextlib.suppress(WebSocketDisconnect, RuntimeError, OSError):
            await self._push_frames()

    async def _push_frames(self) -> None:
        transport = self.transport
        since = -1
        period = 1.0 / UPDATE_HZ
        loop = asyncio.get_running_loop()
        next_at = loop.time()
        taken_at = loop.time()  # when this page last took a frame
        sent_map = None
        while True:
            if transport is not None and transport.is_closing():
                # closing (uvicorn's keepalive gave up on it, or the page said goodbye): a buffer the page does
                # not read would keep the connection, and its place, open until it drained
                self.drop("closing")
                return
            if transport is not None and transport.get_write_buffer_size() > MAX_QUEUED_BYTES:
                # behind: skip this frame (the next carries the samples since the last one sent)
                if loop.time() - taken_at > SLOW_DROP_S:
                    self.drop("not reading")
                    return
            else:
                frame = self.session.snapshot(since)
                if frame["samples"]:
                    since = frame["samples"][-1]["k"]
                if frame["locatability"] is sent_map:  # the map changes with the command only: send it once
                    frame["locatability"] = None
                else:
                    sent_map = frame["locatability"]
                await self.send(_dumps(frame))
                taken_at = loop.time()
            # absolute deadlines: the time a frame takes to build and send does not slow the rate
            next_at = max(next_at + period, loop.time())
            await asyncio.sleep(next_at - loop.time())

    async def receive(self) -> None:
        """Answer the page's requests until it disconnects or floods."""
        while True:
            message = await self.websocket.receive()
            if message["type"] == "websocket.disconnect":
                return
            if not self.bucket.take():
                if not self.patience.take():  # past its budget without pause: flooding
                    await self.close_flooding()
                    return
                await self.tell_to_slow_down()
                continue
            await self.answer(message.get("text"))

    async def close_flooding(self) -> None:
        """Tell a flooding page why (close 1008) and drop it once it has replied, or after :data:`CLOSE_GRACE_S`:
        uvicorn would read and parse its flood for 10 s more waiting for that reply, event-loop time the other
        pages' requests and keepalive answers wait behind."""
        reason = f"flooding: more than {RATE_PER_PAGE:g} requests a second"
        transport = self.transport
        with contextlib.suppress(TimeoutError, RuntimeError, OSError):
            async with asyncio.timeout(CLOSE_GRACE_S):
                await self.websocket.close(code=1008, reason=reason)
                while transport is not None and not transport.is_closing():
                    await asyncio.sleep(0.02)  # uvicorn closes the connection on the page's close reply
        if transport is not None:
            self.drop(reason)

    async def tell_to_slow_down(self) -> None:
        now = time.monotonic()
        if now - self.told_at >= 1.0:  # dropped; said once a second, not once per message
            self.told_at = now
            await self.error(f"too many requests (at most {RATE_PER_PAGE:g} a second); dropped until you slow down")

    async def answer(self, text: str | None) -> None:
        """Validate one request and pass it to the session; an ack, or one line saying what was wrong."""
        if text is None:
            await self.error("send JSON text, not binary")
            return
        if len(text) > MAX_REQUEST_BYTES:
            await self.error(f"request too long ({len(text)} bytes, at most {MAX_REQUEST_BYTES})")
            return
        try:
            accepted = self.session.request(json.loads(text))
        except (ValueError, ParameterError) as exc:
            await self.error(str(exc))
            return
        except Exception as exc:  # a request must never take the page's connection (or the server) down
            await self.error(f"request refused ({type(exc).__name__}: {exc})"[:300])
            return
        await self.send(_dumps({"type": "ack", "request": accepted}))


def _transport(websocket):
    """The asyncio transport under a Starlette WebSocket served by uvicorn (its ``receive`` is the protocol's bound
    method), to read how much waits in its buffer and to drop a page that stopped reading; None elsewhere."""
    protocol = getattr(getattr(websocket, "_receive", None), "__self__", None)
    transport = getattr(protocol, "transport", None)
    needed = ("abort", "get_write_buffer_size")
    return transport if all(callable(getattr(transport, n, None)) for n in needed) else None


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (port 0: any free one); refuses a port in use by name."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise OSError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    sock.listen(64)
    sock.setblocking(False)
    return sock


def serve(session, host: str = "127.0.0.1", port: int = 8050, *, allow_remote: bool = False, announce=None) -> None:
    """Serve ``session`` until Ctrl-C or SIGTERM; the session is started and stopped by the server's lifespan."""
    import uvicorn

    check_host(host, allow_remote)
    # the loop, the estimate and the server share the GIL: hand it over every millisecond (the default 5 ms is a
    # quarter of a frame) so the 20 ms loop keeps its deadlines while a page is being served
    sys.setswitchinterval(0.001)
    sock = bind(host, port)
    port = sock.getsockname()[1]
    shown = f"[{host}]" if ":" in host else host
    origins = {f"http://{shown}:{port}"}
    if host in ("127.0.0.1", "localhost", "::1"):
        origins |= {f"http://127.0.0.1:{port}", f"http://localhost:{port}", f"http://[::1]:{port}"}
    any_address = host in ("0.0.0.0", "::")
    app = make_app(session, origins, any_address=any_address)
    url = f"http://{shown}:{port}/"
    if announce is None:

        def announce(text: str) -> None:
            print(text, file=sys.stderr, flush=True)

    if not ipaddress.ip_address("127.0.0.1" if host == "localhost" else host).is_loopback:
        announce(f"WARNING: serving the rig to the network on {host}: anyone who can reach {url} can move the digit")
    announce(f"flexdigit live: {url} (backend {session.backend}); Ctrl-C to stop")
    config = uvicorn.Config(
        app,
        log_level="warning",
        ws="websockets-sansio",
        ws_max_size=MAX_FRAME_BYTES,
        # no permessage-deflate: compressing 30 frames of ~3 kB a second cost the server more CPU (~2 % of a core)
        # than anything but the shape estimate, to save bandwidth a page on this machine or its LAN does not miss
        ws_per_message_deflate=False,
        # a page that stops reading stops answering pings: found in seconds, not uvicorn's default 40 s (the
        # kernel's socket buffers take a minute of frames before a send would wait)
        ws_ping_interval=PING_INTERVAL_S,
        ws_ping_timeout=PING_TIMEOUT_S,
        lifespan="on",
        timeout_graceful_shutdown=2,
        access_log=False,
    )
    _server_class()(config, session).run(sockets=[sock])


def _server_class():
    """The server class, made on first use: uvicorn is imported only to serve."""
    import uvicorn

    class Server(uvicorn.Server):
        """uvicorn's server, shut down gracefully by SIGHUP too (a closed terminal, as SIGINT and SIGTERM), telling
        the session which signal stopped it (its recording's stop record names it). uvicorn raises the signal again
        once it has shut down: :func:`flexdigit.interrupts.stop_on_signals` makes it an ``Interrupted``."""

        def __init__(self, config, session) -> None:
            super().__init__(config)
            self.session = session

        def handle_exit(self, sig: int, frame) -> None:
            if self.session.stopped_by is None:
                self.session.stopped_by = signal.Signals(sig).name
            super().handle_exit(sig, frame)

        @contextlib.contextmanager
        def capture_signals(self):
            with super().capture_signals():  # SIGINT, SIGTERM; raised again after, in reverse order
                hup = getattr(signal, "SIGHUP", None)
                if hup is None or threading.current_thread() is not threading.main_thread():
                    yield
                    return
                previous = signal.getsignal(hup)
                if previous != signal.SIG_IGN:  # nohup: stays ignored
                    signal.signal(hup, self.handle_exit)
                try:
                    yield
                finally:
                    signal.signal(hup, previous)  # before uvicorn raises the captured signals again

    return Server
