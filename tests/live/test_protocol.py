"""The live server's WebSocket protocol as docs/guide/live.md documents it, spoken by a client that is not the page: the
``websockets`` library, written from docs/guide/live.md's "The page's protocol" section alone.

What a hostile or careless client may send (numbers beyond a float, frames too big to buffer, floods over many
connections, too many pages) is refused or clamped, and the server goes on serving; references are docs/guide/live.md's
stated limits (512-byte requests, 4 KiB frames, 20 requests a second per page, each page its own budget, a page
flooding past it closed, 8 pages, the hello's setpoint range) and the twin's own state (the weight it was given).
"""

from __future__ import annotations

import contextlib
import json
import time

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from flexdigit.live.server import origin_allowed

from .live_helpers import LiveServer

#: The limits of docs/guide/live.md (the test reads them as a client would, not from the code).
REQUEST_BYTES, FRAME_BYTES, PAGE_RATE, PAGE_BURST, PAGES = 512, 4096, 20, 40, 8


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    srv = LiveServer(tmp_path_factory.mktemp("protocol"))
    yield srv
    srv.stop()


def _connect(server):
    return connect(server.url.replace("http://", "ws://") + "ws", origin=server.url.rstrip("/"), max_size=None)


def _reply(ws, request: str | bytes, timeout_s: float = 10.0) -> dict:
    """Send one request; the next ack or error (frames in between are skipped)."""
    ws.send(request)
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        message = json.loads(ws.recv(timeout=timeout_s))
        if message["type"] in ("ack", "error"):
            return message
    raise AssertionError(f"no reply to {request!r:.80}")


def _hello(ws) -> dict:
    message = json.loads(ws.recv(timeout=10))
    assert message["type"] == "hello"
    return message


@pytest.mark.slow
def test_hostile_values_get_an_error_and_the_connection_stays(server):
    with _connect(server) as ws:
        hello = _hello(ws)
        lo, hi = hello["setpoint_range"]
        hostile = {
            '{"type":"setpoint","value":' + "9" * 400 + "}": "finite",  # beyond a float: was a dropped connection
            '{"type":"load","position_m":-' + "9" * 400 + ',"mass_g":25,"kind":"weight"}': "finite",
            '{"type":"setpoint","value":NaN}': "finite",
            '{"type":"setpoint","value":-Infinity}': "finite",
            '{"type":"setpoint","value":"30"}': "real number",
            '{"type":"setpoint","value":30,"sneaky":1}': "no field 'sneaky'",
            '{"type":"pause","paused":"yes"}': "true or false",
            '{"type":"speed","speed":10}': "replay",  # a twin has no playback speed
            "[" * 200 + "]" * 200: "JSON object",
            "\u00e9t\u00e9": "",  # not JSON
        }
        for request, says in hostile.items():
            reply = _reply(ws, request)
            assert reply["type"] == "error", (request[:60], reply)
            assert says in reply["message"], (request[:60], reply)
            assert len(reply["message"]) < 300  # a 400-digit number is named, not echoed
        assert _reply(ws, b"\x00binary")["type"] == "error"
        big = json.dumps({"type": "clear", "pad": "x" * REQUEST_BYTES})
        assert "too long" in _reply(ws, big)["message"]
        for value, applied in ((1e6, hi), (-1e6, lo), (12.5, 12.5)):
            assert _reply(ws, json.dumps({"type": "setpoint", "value": value}))["request"]["value"] == applied
        _reply(ws, json.dumps({"type": "setpoint", "value": 0}))


@pytest.mark.slow
def test_a_frame_too_big_to_buffer_closes_only_that_connection(server):
    with _connect(server) as ws:
        _hello(ws)
        ws.send("x" * (4 * FRAME_BYTES))
        with pytest.raises(ConnectionClosed) as closed:
            while True:
                ws.recv(timeout=10)
        assert closed.value.rcvd.code == 1009  # message too big
    with _connect(server) as ws:  # the server goes on
        _hello(ws)
        assert _reply(ws, '{"type":"clear"}')["type"] == "ack"


@pytest.mark.slow
def test_a_flood_over_many_connections_is_limited_per_page_and_cut_off(server):
    import threading

    stack = contextlib.ExitStack()
    pages = [stack.enter_context(_connect(server)) for _ in range(4)]
    replies: list[tuple[int, str, float]] = []  # (page, type, when received)
    closed: list[int | None] = []  # the close code each page got

    def listen(i, ws) -> None:
        deadline = time.monotonic() + 6
        while time.monotonic() < deadline:
            try:
                message = json.loads(ws.recv(timeout=1))
            except TimeoutError:
                continue
            except ConnectionClosed as exc:
                closed.append(exc.rcvd.code if exc.rcvd else None)
                return
            if message["type"] in ("ack", "error"):
                replies.append((i, message["type"], time.monotonic()))

    try:
        for ws in pages:
            _hello(ws)
        listeners = [threading.Thread(target=listen, args=(i, ws)) for i, ws in enumerate(pages)]
        start = time.monotonic()
        for thread in listeners:
            thread.start()
        with contextlib.suppress(ConnectionClosed):
            for _ in range(300):
                for ws in pages:
                    ws.send('{"type":"clear"}')
        for thread in listeners:
            thread.join()
    finally:
        stack.close()
    for i in range(len(pages)):
        acks = [t for page, kind, t in replies if page == i and kind == "ack"]
        errors = [t for page, kind, t in replies if page == i and kind == "error"]
        taken = max(acks) - start  # every ack was granted before it arrived: a bound on the time it was served
        # its own bucket: its burst plus its rate over that time; told to slow down about once a second
        assert PAGE_BURST // 2 <= len(acks) <= PAGE_BURST + PAGE_RATE * taken + 2, (i, len(acks), taken)
        assert len(errors) <= taken + 2, (i, len(errors), taken)
    assert closed == [1008] * len(pages)  # 300 at once is 260 past the budget: flooding, cut off
    time.sleep(2.5)  # the buckets refill
    with _connect(server) as ws:
        _hello(ws)
        assert _reply(ws, '{"type":"clear"}')["type"] == "ack"


@pytest.mark.slow
def test_at_most_eight_pages_at_once(server):
    with contextlib.ExitStack() as stack:
        for _ in range(PAGES):
            _hello(stack.enter_context(_connect(server)))
        with _connect(server) as extra:
            with pytest.raises(ConnectionClosed) as closed:
                extra.recv(timeout=10)
            assert closed.value.rcvd.code == 1013  # try again later
    # once the server has seen the eight go (in its own time on a loaded machine), a page is welcome again
    deadline = time.monotonic() + 30
    while True:
        try:
            with _connect(server) as ws:
                assert _hello(ws)["kind"] == "twin"
            break
        except ConnectionClosed as refused:
            assert refused.rcvd.code == 1013, refused  # only "try again later" while the eight are still counted
            assert time.monotonic() < deadline, "a page is still refused 30 s after the eight left"
            time.sleep(0.1)


def test_a_server_bound_to_every_address_takes_pages_from_the_address_they_used():
    own = {"http://0.0.0.0:8050"}
    # a browser on another machine opened http://192.168.1.5:8050/: its Origin is that address, so is its Host
    assert origin_allowed("http://192.168.1.5:8050", "192.168.1.5:8050", own, any_address=True)
    assert origin_allowed("http://[fe80::1]:8050", "[fe80::1]:8050", own, any_address=True)
    # another site's page (its Origin is not the Host it sent to), a name resolved by another site (DNS rebinding)
    assert not origin_allowed("http://evil.example", "192.168.1.5:8050", own, any_address=True)
    assert not origin_allowed("http://evil.example:8050", "evil.example:8050", own, any_address=True)
    assert not origin_allowed(None, "192.168.1.5:8050", own, any_address=True)
    # a loopback server knows its own addresses: only those
    assert not origin_allowed("http://192.168.1.5:8050", "192.168.1.5:8050", {"http://127.0.0.1:8050"}, False)
    assert origin_allowed("http://127.0.0.1:8050", "127.0.0.1:8050", {"http://127.0.0.1:8050"}, False)
