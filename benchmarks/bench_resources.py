"""Bounded resources (issue 22), the figures behind the reliability claims of docs/guide/reliability.md:

- ``surgeon locked out``: with every one of the live server's 8 places taken by clients that never read, how long
  the surgeon's page (retrying every half second, as the packaged page does) waits to be served, and the frames a
  second it then receives (30 sent). Before issue 22: 40-45 s (uvicorn's keepalive), at 0 frames a second;
- ``replay memory``: bytes a replay holds per recorded sample of a loop log (and at its peak while reading).
  Before: 790 held, 910 at the peak;
- ``scheduler gives up``: seconds until ``study --scheduler`` on a server that accepts and stays silent ends in
  one line. Before: never (past 180 s).

``python -m benchmarks bench_resources``.
"""

from __future__ import annotations

import base64
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import tracemalloc
from pathlib import Path

from benchmarks.bench_live import _start_server

IDLE_PAGES = 8
REPLAY_SAMPLES = 200_000


def _idle_page(port: int, origin: str) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n\r\n"
        ).encode()
    )
    return sock


def surgeon_locked_out() -> tuple[float, float]:
    from websockets.exceptions import ConnectionClosed, InvalidStatus
    from websockets.sync.client import connect

    with tempfile.TemporaryDirectory() as tmp:
        proc, url, _ = _start_server(Path(tmp) / "live.err")
        try:
            port, origin = int(url.rsplit(":", 1)[1].strip("/")), url.rstrip("/")
            time.sleep(1.0)
            idle = [_idle_page(port, origin) for _ in range(IDLE_PAGES)]
            start, surgeon = time.monotonic(), None
            while surgeon is None and time.monotonic() - start < 90:
                try:
                    surgeon = connect(url.replace("http://", "ws://") + "ws", origin=origin)
                    json.loads(surgeon.recv(timeout=5))
                except (InvalidStatus, ConnectionClosed, TimeoutError):
                    surgeon = None
                    time.sleep(0.5)
            waited = time.monotonic() - start
            frames, t0 = 0, time.monotonic()
            while frames < 90:
                frames += json.loads(surgeon.recv(timeout=5))["type"] == "frame"
            rate = frames / (time.monotonic() - t0)
            surgeon.close()
            for s in idle:
                s.close()
            return waited, rate
        finally:
            proc.send_signal(signal.SIGINT)
            proc.wait(30)


def replay_memory() -> tuple[float, float]:
    from flexdigit.rig.backends.replay_backend import ReplayRig
    from flexdigit.rig.sample_log import LOG_FORMAT

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.jsonl"
        with path.open("w") as fh:
            fh.write(json.dumps({"format": LOG_FORMAT, "controller": None, "period_s": 0.02}) + "\n")
            for k in range(REPLAY_SAMPLES):
                sample = {"k": k, "t": round(0.02 * k, 4), "gauges_v": [1.0, 1.1, 1.2], "pot_v": 2.5, "command": 8}
                fh.write(json.dumps(sample) + "\n")
        tracemalloc.start()
        try:
            rig = ReplayRig(str(path))
            held, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
        del rig
    return held / REPLAY_SAMPLES, peak / REPLAY_SAMPLES


def scheduler_gives_up() -> float:
    server = socket.create_server(("127.0.0.1", 0))
    conns: list[socket.socket] = []
    threading.Thread(target=lambda: [conns.append(server.accept()[0]) for _ in iter(int, 1)], daemon=True).start()
    with tempfile.TemporaryDirectory() as tmp:
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        start = time.monotonic()
        done = subprocess.run(
            [sys.executable, "-m", "flexdigit.cli", "study", "sensitivity", "thesis-tolerances", "--out", f"{tmp}/out"]
            + ["--scheduler", address, "--no-progress", "--json"],
            capture_output=True,
            timeout=300,
            text=True,
        )
        took = time.monotonic() - start
    if address not in done.stdout:
        raise RuntimeError(f"study did not name the scheduler: {done.stdout[-300:]}")
    return took


def run() -> list[dict]:
    waited, rate = surgeon_locked_out()
    held, peak = replay_memory()
    gave_up = scheduler_gives_up()
    return [
        {"name": f"surgeon locked out by {IDLE_PAGES} pages that never read", "value": waited, "unit": "s",
         "goal": "<= 5 s", "note": f"then {rate:.0f} frames/s (30 sent); before issue 22: 40-45 s at 0 frames/s"},
        {"name": "replay memory held per recorded sample", "value": held, "unit": "B", "goal": "< 200 B",
         "note": f"peak while reading {peak:.0f} B; before: 790 held, 910 peak (the log: 120 B a line)"},
        {"name": "study --scheduler on a silent server: gives up after", "value": gave_up, "unit": "s",
         "goal": "< 15 s", "note": "5 s timeout, the rest imports and the spec; before: never (past 180 s)"},
    ]  # fmt: skip


if __name__ == "__main__":
    for row in run():
        print(row)
