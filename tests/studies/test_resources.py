"""A study's resources: every network wait on a ``--scheduler`` is bounded and ends in one line naming the address
(a server that accepts and stays silent, answers garbage or answers HTTP), a real scheduler still passes, and
``--workers`` beyond what the machine can run is refused saying the limit (issue 22)."""

from __future__ import annotations

import json
import os
import socket
import struct
import subprocess
import sys
import threading

import msgpack
import pytest

from flexdigit._system import worker_limit
from flexdigit.cli import main
from flexdigit.studies.execution import SCHEDULER_TIMEOUT_S, WORKER_BYTES, check_scheduler_greets

from .test_execution import SPEC

#: How long `study` may take to give up on a scheduler that does not answer: its timeout, the imports and the
#: spec, with a margin for a loaded 2-core machine. Without the check it never gave up (past 180 s).
GIVES_UP_WITHIN_S = SCHEDULER_TIMEOUT_S + 60.0
#: What the fake schedulers send on accepting a connection.
_HELLO = msgpack.dumps({"compression": None, "python": [3, 11, 7], "pickle-protocol": 5})
_FRAMES = struct.pack("<QQ", 1, len(_HELLO)) + _HELLO
REPLIES = {
    "silent": b"",
    # a scheduler's greeting, framed as distributed frames it, and then nothing: its answer to the client never comes
    "greets": struct.pack("<Q", len(_FRAMES)) + _FRAMES,
    "garbage": b"\xff" * 64,
    "http": b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
}


class FakeScheduler:
    """A TCP server in a thread: accepts every connection, sends ``reply`` (maybe nothing) and never closes it."""

    def __init__(self, reply: bytes) -> None:
        self.reply, self.conns = reply, []
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            if self.reply:
                conn.sendall(self.reply)

    def close(self) -> None:
        self.sock.close()
        for conn in self.conns:
            conn.close()


@pytest.fixture(params=sorted(REPLIES))
def fake(request):
    server = FakeScheduler(REPLIES[request.param])
    yield request.param, server
    server.close()


def test_a_server_that_is_no_scheduler_is_named_within_the_timeout(fake):
    kind, server = fake
    if kind == "greets":
        check_scheduler_greets(server.address, timeout_s=1.0)  # it looks like one, to this check
        return
    with pytest.raises(OSError) as err:
        check_scheduler_greets(server.address, timeout_s=1.0)
    text = str(err.value)
    assert text.startswith(f"{server.address}: not a Dask scheduler"), text
    assert ("no greeting within 1 s" in text) == (kind == "silent"), text


@pytest.mark.slow
def test_study_on_a_server_that_is_no_scheduler_ends_in_one_line(fake, tmp_path):
    kind, server = fake
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    args = ["study", "sensitivity", str(spec), "--out", str(tmp_path / "out"), "--scheduler", server.address]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "flexdigit.cli", *args, "--no-progress", "--json"],
            capture_output=True,
            text=True,
            timeout=GIVES_UP_WITHIN_S,
            env=env,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"study on a {kind} server still waiting after {GIVES_UP_WITHIN_S:.0f} s")
    assert proc.returncode == 2, proc.stderr[-2000:]
    out = json.loads(proc.stdout)
    named = "cannot reach the Dask scheduler at " if kind == "greets" else ""
    assert out["error"].startswith(f"{named}{server.address}"), out
    assert out["error_type"] != "MemoryError"
    assert "internal error" not in out["error"]
    assert "Traceback" not in proc.stderr


@pytest.mark.slow
def test_a_real_scheduler_passes_the_check():
    from distributed import LocalCluster

    from flexdigit.studies.execution import dask_client

    with LocalCluster(n_workers=0, processes=False, protocol="tcp", host="127.0.0.1", dashboard_address=":0") as c:
        check_scheduler_greets(c.scheduler_address)  # no error: it greeted as a scheduler does
        with dask_client(c.scheduler_address, 0) as client:
            assert client.scheduler_info()["address"] == c.scheduler_address


def test_workers_beyond_the_machine_are_refused_saying_the_limit(tmp_path, capsys):
    limit, why = worker_limit(WORKER_BYTES)
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    args = ["study", "sensitivity", str(spec), "--out", str(tmp_path / "out"), "--workers", "1000", "--json"]
    assert main(args) == 2
    error = json.loads(capsys.readouterr().out)["error"]
    assert error.startswith("--workers 1000 is more than this machine can run at once")
    assert f"at most {limit} ({why})" in error
    assert "refused" in error
    assert not (tmp_path / "out").exists()  # refused before anything started


def test_a_journal_line_nested_too_deep_is_named(tmp_path):
    from flexdigit.errors import DataFileError
    from flexdigit.studies.execution import JOURNAL_NAME, Journal

    path = tmp_path / JOURNAL_NAME
    Journal(path, {"fingerprint": "f"})  # a header
    with path.open("a") as fh:
        fh.write("[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(DataFileError, match=rf"{JOURNAL_NAME}: line 2 is not a row record"):
        Journal(path, {"fingerprint": "f"})


def test_a_design_spec_given_to_a_sensitivity_study_is_named(tmp_path, capsys):
    # no uncertain parameters: SALib failed on the empty problem with an IndexError, reported as an internal error
    out = tmp_path / "out"
    assert main(["study", "sensitivity", "thesis-design", "--out", str(out), "--workers", "0", "--json"]) == 2
    error = json.loads(capsys.readouterr().out)["error"]
    assert error.startswith("study 'thesis-design' declares no uncertain parameters"), error
