"""The live server's resources, from outside, with real WebSocket clients on 127.0.0.1: every page has its own
request budget and its own bounded queue, so pages that never read or that flood are dropped without locking out
or starving the others, and the controlling page keeps its place (issue 22).

Every wait here is bounded (a deadline, a recv timeout); none asserts a speed.
"""

from __future__ import annotations

import base64
import json
import os
import socket
import threading
import time

import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from flexdigit.live.server import MAX_PAGES, PING_INTERVAL_S, PING_TIMEOUT_S, SLOW_DROP_S

from .live_helpers import LiveServer

#: How long a page that stopped reading may hold its place: found by the keepalive (a ping, unanswered), with a
#: margin for a busy 2-core machine. Before issue 22 such a page held it for uvicorn's 20 + 20 s.
DROPPED_WITHIN_S = PING_INTERVAL_S + PING_TIMEOUT_S + SLOW_DROP_S + 6.0
#: The test's controlling page sends ROUNDS bursts of SETPOINTS requests a second apart: inside its own budget
#: (40 at once, 20 a second), not inside what two flooding pages would leave of a shared one.
SETPOINTS, ROUNDS = 10, 3
#: How long the flooding pages send without pause (each dropped page connects again), s, at most: they stop when
#: the test page's rounds are done.
FLOOD_S = 30.0


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    srv = LiveServer(tmp_path_factory.mktemp("live-resources"))
    yield srv
    srv.stop()


def _url(server) -> tuple[str, str]:
    return server.url.replace("http://", "ws://") + "ws", server.url.rstrip("/")


def _page(server, **kwargs):
    ws_url, origin = _url(server)
    return connect(ws_url, origin=origin, open_timeout=10, **kwargs)


def _idle_page(server) -> socket.socket:
    """A client that opens the WebSocket (the server counts it as a page) and then never reads a byte."""
    sock = socket.create_connection(("127.0.0.1", server.port))
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: {_url(server)[1]}\r\n\r\n"
        ).encode()
    )
    return sock


def _frames(ws, n: int, timeout_s: float = 5.0) -> list[dict]:
    """The next ``n`` frames (each within ``timeout_s``): the page is being served."""
    out = []
    while len(out) < n:
        message = json.loads(ws.recv(timeout=timeout_s))
        if message["type"] == "frame":
            out.append(message)
    return out


def _closed_by_server(sock: socket.socket, deadline: float) -> bool:
    """Whether the server closed (or reset) ``sock`` before ``deadline`` (draining what it had sent)."""
    sock.settimeout(0.5)
    while time.monotonic() < deadline:
        try:
            if not sock.recv(1 << 20):
                return True
        except TimeoutError:
            continue
        except OSError:  # reset: the server aborted it
            return True
    return False


def _engage(ws, value: float) -> None:
    """Send a setpoint and wait for its ack, then for a frame that shows it engaged: the server acks a request when
    it is queued, and the loop applies it at its next tick, so a frame between the two may still say not engaged."""
    ws.send(json.dumps({"type": "setpoint", "value": value}))
    deadline = time.monotonic() + 10
    acked = False
    while time.monotonic() < deadline:
        message = json.loads(ws.recv(timeout=10))
        acked = acked or message["type"] == "ack"
        if acked and message.get("state", {}).get("engaged"):
            return
    raise AssertionError("the setpoint was not applied" if acked else "the setpoint was not acknowledged")


@pytest.mark.slow
def test_pages_that_never_read_cannot_lock_the_surgeons_page_out(server):
    idle = [_idle_page(server) for _ in range(MAX_PAGES)]  # every place taken by clients that never read
    try:
        time.sleep(0.5)
        deadline = time.monotonic() + DROPPED_WITHIN_S
        surgeon, refusals = None, 0
        while surgeon is None and time.monotonic() < deadline:  # the packaged page retries every half second
            try:
                surgeon = _page(server)
                json.loads(surgeon.recv(timeout=5))  # hello, or the refusal's close
            except (InvalidStatus, ConnectionClosed, TimeoutError):
                if surgeon is not None:
                    surgeon.close()
                surgeon, refusals = None, refusals + 1
                time.sleep(0.5)
        assert surgeon is not None, f"the surgeon's page was refused {refusals} times in {DROPPED_WITHIN_S:.0f} s"
        with surgeon:
            frames = _frames(surgeon, 30)
            while frames[-1]["state"]["clients"] > 1:  # the server counts the pages it serves: the idle go
                assert time.monotonic() < deadline + DROPPED_WITHIN_S, frames[-1]["state"]["clients"]
                frames += _frames(surgeon, 1)
        assert all(_closed_by_server(s, time.monotonic() + DROPPED_WITHIN_S) for s in idle)
    finally:
        for s in idle:
            s.close()


class _Reader(threading.Thread):
    """Reads a page's frames while the test does something else, as the surgeon's page does."""

    def __init__(self, ws) -> None:
        super().__init__(daemon=True)
        self.ws, self.frames, self.error, self.stop = ws, [], None, threading.Event()

    def run(self) -> None:
        try:
            while not self.stop.is_set():
                message = json.loads(self.ws.recv(timeout=5))
                if message["type"] == "frame":
                    self.frames.append(message)
        except Exception as exc:  # noqa: BLE001 - reported by the test
            self.error = exc


@pytest.mark.slow
def test_the_controlling_page_keeps_its_place_and_its_frames(server):
    with _page(server) as surgeon:
        _engage(surgeon, 20.0)
        reader = _Reader(surgeon)
        reader.start()
        idle = [_idle_page(server) for _ in range(MAX_PAGES + 4)]  # more than there are places
        try:
            deadline = time.monotonic() + DROPPED_WITHIN_S
            dropped = [_closed_by_server(s, deadline) for s in idle]
            time.sleep(1.0)  # frames after the last drop
        finally:
            reader.stop.set()
            reader.join(10)
            for s in idle:
                s.close()
    assert reader.error is None, reader.error
    assert all(dropped)
    frames = reader.frames
    ks = [s["k"] for f in frames for s in f["samples"]]
    assert ks == sorted(set(ks))  # every sample once, in order: no frame lost or sent twice
    assert all(f["state"]["engaged"] for f in frames)  # its setpoint held throughout
    assert frames[-1]["state"]["clients"] == 1
    assert len(frames) >= 30  # served while they came and went (at 30 frames a second, this took seconds)


def _flood_once(server, stop_at: float, reads: bool) -> str:
    """One client sending without pause until the server closes it (or ``stop_at``); how it ended. ``reads``: a
    page's script flooding, its browser still reading meanwhile and answering the close; else a client that never
    reads (websockets' stops once 16 frames wait unread, as the flooding clients here did before), may never see the
    close and floods on; it gives up its own wait for the server's close after a second."""
    with _page(server, max_queue=None if reads else 16, close_timeout=10.0 if reads else 1.0) as ws:
        try:
            while time.monotonic() < stop_at:
                ws.send(json.dumps({"type": "clear"}))
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline:
                ws.recv(timeout=5)
            return "never dropped"
        except ConnectionClosed as exc:
            return f"closed {exc.rcvd.code if exc.rcvd else None}"
        except TimeoutError:
            return "never dropped"


@pytest.mark.slow
def test_flooding_pages_are_dropped_and_do_not_starve_the_others(server):
    ended: dict[bool, list[str]] = {True: [], False: []}  # reads -> how each of its connections ended
    rounds_done = threading.Event()

    def flood(reads: bool) -> None:
        # dropped, the client connects again and floods on: the floods last the whole of the surgeon's rounds
        stop_at = time.monotonic() + FLOOD_S
        while not rounds_done.is_set() and time.monotonic() < stop_at:
            ended[reads].append(_flood_once(server, stop_at, reads))

    # the surgeon's page answers the server's pings whenever it is not reading, as a browser's network stack does
    # (websockets' client stops reading its socket, pongs included, once 16 frames wait unread: between rounds here)
    with _page(server, max_queue=None) as surgeon:
        json.loads(surgeon.recv(timeout=10))
        floods = [threading.Thread(target=flood, args=(reads,), daemon=True) for reads in (True, False)]
        for t in floods:
            t.start()
        time.sleep(1.0)  # the floods under way
        replies = []
        for round_ in range(ROUNDS):  # bursts inside the page's own budget (40 at once, 20 a second)
            for k in range(SETPOINTS):
                surgeon.send(json.dumps({"type": "setpoint", "value": 10.0 + k}))
            # a dropped request gets no reply (a refusal is said once a second): bounded, generous for a loaded machine
            deadline = time.monotonic() + 30
            while len(replies) < SETPOINTS * (round_ + 1) and time.monotonic() < deadline:
                message = json.loads(surgeon.recv(timeout=5))
                if message["type"] in ("ack", "error"):
                    replies.append(message)
            time.sleep(1.0)
        rounds_done.set()
        for t in floods:
            t.join(60)
    assert [r["type"] for r in replies] == ["ack"] * (ROUNDS * SETPOINTS), [
        r.get("message") for r in replies if "message" in r
    ]
    assert set(ended[True]) == {"closed 1008"}, ended  # every flooding page told why and dropped
    assert set(ended[False]) <= {"closed 1008", "closed None"}, ended  # dropped, told or not: none floods on


def test_the_sessions_request_queue_is_bounded_and_the_relax_never_lost(tmp_path):
    # a loop that is stuck (not started here) takes no requests: pages within their budgets cannot pile them up
    from flexdigit.errors import ParameterError
    from flexdigit.live.session import LiveSession
    from flexdigit.rig.sample_log import LOG_FORMAT

    log = tmp_path / "run.jsonl"
    lines = [{"format": LOG_FORMAT, "controller": None, "period_s": 0.02}]
    lines += [{"k": k, "t": 0.02 * k, "gauges_v": [1.0, 1.1, 1.2], "pot_v": None, "command": 8} for k in range(20)]
    log.write_text("".join(json.dumps(x) + "\n" for x in lines))
    session = LiveSession(f"replay://{log}")
    try:
        session.connected()
        for _ in range(session.MAX_PENDING_REQUESTS):
            session.request({"type": "pause", "paused": True})
        with pytest.raises(ParameterError, match="the rig loop is behind"):
            session.request({"type": "pause", "paused": False})
        session.disconnected()  # the last page leaves with the queue full
        session.engaged = True
        session._apply_requests()
        assert session.paused
        assert not session.engaged  # every queued request applied, then the relax
        assert session._requests.empty()
    finally:
        session.stop()
